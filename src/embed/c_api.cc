// liburlab_batch.so's C interface (urlab/embed/urlab_batch.h) over InProcessBatch: every C++
// exception becomes -1 (or NULL) and its message; nothing throws across the boundary.
#include <mujoco/mujoco.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/embed/in_process_batch.h"
#include "urlab/embed/urlab_batch.h"

struct urlab_batch {
  std::mutex lock;  // a handle's calls take turns
  std::unique_ptr<urlab::embed::InProcessBatch> batch;
};

namespace {

void SetError(char* error, std::size_t size, const std::string& text) {
  if (!error || size == 0) return;
  const std::size_t n = std::min(text.size(), size - 1);
  std::memcpy(error, text.data(), n);
  error[n] = '\0';
}

// Runs `fn`, turning any exception into -1 and its message.
template <typename Fn>
int Guard(char* error, std::size_t error_size, Fn&& fn) {
  try {
    fn();
    return 0;
  } catch (const std::bad_alloc&) {
    SetError(error, error_size, "out of memory");
  } catch (const std::exception& e) {
    SetError(error, error_size, e.what());
  } catch (...) {
    SetError(error, error_size, "unknown error");
  }
  return -1;
}

void CopyOut(const urlab::world::BatchResult& r, urlab_batch_outputs* out) {
  if (!out) return;
  if (out->obs) std::copy(r.obs.begin(), r.obs.end(), out->obs);
  if (out->done) std::copy(r.done.begin(), r.done.end(), out->done);
  if (out->reset) std::copy(r.reset.begin(), r.reset.end(), out->reset);
  if (out->time) std::copy(r.time.begin(), r.time.end(), out->time);
  if (out->episode_steps)
    std::copy(r.episode_steps.begin(), r.episode_steps.end(), out->episode_steps);
  out->seconds = r.seconds;
}

void StartLogging(const char* level) {
  if (level) {
    const std::string_view l = level;
    if (l != "trace" && l != "debug" && l != "info" && l != "warn" && l != "error" && l != "off") {
      throw urlab::Error("log_level: '" + std::string(l) +
                         "' is not one of trace, debug, info, warn, error, off");
    }
  }
  // Logs go to the host program's stderr, as the `urlab` tool's do; quiet unless asked.
  if (!spdlog::get("urlab")) spdlog::set_default_logger(spdlog::stderr_color_mt("urlab"));
  spdlog::set_pattern("[%H:%M:%S.%e] [urlab] [%^%l%$] %v");
  urlab::SetLogLevel(level ? level : "warn");
}

}  // namespace

extern "C" {

int urlab_batch_abi(void) { return URLAB_BATCH_ABI; }

urlab_batch* urlab_batch_open(const char* scene, const urlab_batch_options* options, char* error,
                              std::size_t error_size) {
  urlab_batch* handle = nullptr;
  Guard(error, error_size, [&] {
    if (!scene) throw urlab::Error("no scene file given");
    if (!options) throw urlab::Error("no options given");
    StartLogging(options->log_level);
    urlab::InstallMujocoHandlers();
    urlab::embed::InProcessOptions o;
    o.envs = options->envs;
    o.threads = options->threads;
    o.auto_reset = options->auto_reset != 0;
    o.max_episode_steps = options->max_episode_steps;
    o.reset_noise = options->reset_noise;
    o.raw_actions = options->raw_actions != 0;
    if (options->has_seed) o.seed = options->seed;
    auto h = std::make_unique<urlab_batch>();
    h->batch = std::make_unique<urlab::embed::InProcessBatch>(scene, o);
    handle = h.release();
  });
  return handle;
}

void urlab_batch_close(urlab_batch* batch) {
  if (!batch) return;
  {
    std::lock_guard<std::mutex> hold(batch->lock);
    try {
      batch->batch.reset();
    } catch (...) {  // a destructor's failure leaves nothing to report it to
    }
  }
  delete batch;
}

int urlab_batch_get_sizes(urlab_batch* batch, urlab_batch_sizes* sizes) {
  if (!batch || !sizes) return -1;
  std::lock_guard<std::mutex> hold(batch->lock);
  const urlab::embed::InProcessBatch& b = *batch->batch;
  *sizes = {b.envs(), b.threads(),     b.action_size(),      b.nq(),
            b.nv(),   b.nsensordata(), b.observation_size(), b.timestep()};
  return 0;
}

int urlab_batch_action_bounds(urlab_batch* batch, double* low, double* high) {
  if (!batch || !low || !high) return -1;
  std::lock_guard<std::mutex> hold(batch->lock);
  std::copy(batch->batch->action_low().begin(), batch->batch->action_low().end(), low);
  std::copy(batch->batch->action_high().begin(), batch->batch->action_high().end(), high);
  return 0;
}

std::size_t urlab_batch_actuator_names(urlab_batch* batch, char* names, std::size_t size) {
  if (!batch) return 0;
  std::string all;
  {
    std::lock_guard<std::mutex> hold(batch->lock);
    for (const std::string& n : batch->batch->actuator_names()) all += n + '\0';
  }
  if (names && size > 0) std::memcpy(names, all.data(), std::min(size, all.size()));
  return all.size();
}

int urlab_batch_step(urlab_batch* batch, const double* actions, const uint8_t* reset, int n_steps,
                     urlab_batch_outputs* out, char* error, std::size_t error_size) {
  if (!batch) return -1;
  std::lock_guard<std::mutex> hold(batch->lock);
  return Guard(error, error_size, [&] {
    urlab::embed::InProcessBatch& b = *batch->batch;
    const std::size_t n = static_cast<std::size_t>(b.envs());
    if (!actions) throw urlab::Error("actions: no array given");
    const std::span<const double> a(actions, n * static_cast<std::size_t>(b.action_size()));
    std::span<const std::uint8_t> r;
    if (reset) r = std::span<const std::uint8_t>(reset, n);
    CopyOut(b.Step(a, r, n_steps), out);
  });
}

int urlab_batch_reset(urlab_batch* batch, const int* envs, int count, const uint64_t* seeds,
                      const uint8_t* has_seed, urlab_batch_outputs* out, char* error,
                      std::size_t error_size) {
  if (!batch) return -1;
  std::lock_guard<std::mutex> hold(batch->lock);
  return Guard(error, error_size, [&] {
    urlab::embed::InProcessBatch& b = *batch->batch;
    if (count < 0) throw urlab::Error("envs: a negative count (" + std::to_string(count) + ")");
    if (count > 0 && !envs) throw urlab::Error("envs: no array given");
    const std::size_t listed =
        count > 0 ? static_cast<std::size_t>(count) : static_cast<std::size_t>(b.envs());
    std::vector<std::optional<std::uint64_t>> s;
    if (seeds) {
      s.resize(listed);
      for (std::size_t k = 0; k < listed; ++k) {
        if (!has_seed || has_seed[k]) s[k] = seeds[k];
      }
    }
    const std::span<const int> e = count > 0
                                       ? std::span<const int>(envs, static_cast<std::size_t>(count))
                                       : std::span<const int>();
    CopyOut(b.Reset(e, s), out);
  });
}

int urlab_batch_set_auto_reset(urlab_batch* batch, int on) {
  if (!batch) return -1;
  std::lock_guard<std::mutex> hold(batch->lock);
  batch->batch->SetAutoReset(on != 0);
  return 0;
}

int urlab_batch_mujoco_version(void) { return mj_version(); }

void* urlab_batch_copy_model(urlab_batch* batch, int env, char* error, std::size_t error_size) {
  void* model = nullptr;
  if (!batch) return nullptr;
  std::lock_guard<std::mutex> hold(batch->lock);
  Guard(error, error_size, [&] { model = batch->batch->CopyModel(env); });
  return model;
}

int urlab_batch_copy_data(urlab_batch* batch, int env, void* data, char* error,
                          std::size_t error_size) {
  if (!batch) return -1;
  std::lock_guard<std::mutex> hold(batch->lock);
  return Guard(error, error_size, [&] { batch->batch->CopyData(env, data); });
}

}  // extern "C"
