// The step server's batch operations: many environments of one run stepped together
// (`urlab run --envs N`, world::BatchSubsystem). Arrays travel packed (msgpack `bin`,
// little-endian; `<field>_base64` in JSON text): actions and observations as f64, done and reset
// flags as one byte per environment, episode steps as u32 (docs/network.md, "Batched
// environments").
#include <mujoco/mujoco.h>

#include <chrono>
#include <cstring>
#include <memory>

#include "net/request_fields.h"
#include "net/step_server.h"
#include "net/value_ranges.h"
#include "urlab/ops/batch.h"
#include "urlab/world/batch_subsystem.h"

namespace urlab::net {

using namespace request;

namespace {

template <typename T>
Json Packed(const std::vector<T>& v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
  return Json::binary(std::vector<std::uint8_t>(p, p + v.size() * sizeof(T)));
}

// `field` as doubles: packed little-endian f64 bytes, or an array of numbers.
std::vector<double> Doubles(const Json& v, const char* field) {
  if (v.is_binary()) {
    const auto& bytes = v.get_binary();
    if (bytes.size() % sizeof(double) != 0) {
      Fail("dim_mismatch", std::string(field) + ": " + std::to_string(bytes.size()) +
                               " bytes is not a whole number of f64 values");
    }
    std::vector<double> out(bytes.size() / sizeof(double));
    if (!out.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
    return out;
  }
  if (!v.is_array()) {
    Fail("bad_value", std::string("'") + field + "' must be packed f64 bytes or an array");
  }
  std::vector<double> out;
  out.reserve(v.size());
  for (const Json& x : v) {
    if (!x.is_number()) Fail("bad_value", std::string("'") + field + "' must hold numbers");
    out.push_back(x.get<double>());
  }
  return out;
}

// Environment flags: one byte per environment, or an array of booleans / 0 and 1.
std::vector<std::uint8_t> Flags(const Json& v, const char* field) {
  if (v.is_binary()) {
    std::vector<std::uint8_t> out(v.get_binary().begin(), v.get_binary().end());
    for (std::uint8_t& f : out) f = f != 0;
    return out;
  }
  if (!v.is_array()) Fail("bad_value", std::string("'") + field + "' must be bytes or an array");
  std::vector<std::uint8_t> out;
  for (const Json& x : v) {
    if (x.is_boolean()) {
      out.push_back(x.get<bool>() ? 1 : 0);
    } else if (x.is_number_integer() &&
               (x.get<std::int64_t>() == 0 || x.get<std::int64_t>() == 1)) {
      out.push_back(static_cast<std::uint8_t>(x.get<std::int64_t>()));
    } else {
      Fail("bad_value", std::string("'") + field + "' must hold true/false (or 0/1)");
    }
  }
  return out;
}

std::uint64_t Seed(const Json& v, const char* what) {
  if (!v.is_number_integer()) Fail("bad_value", std::string(what) + " must be a whole number");
  const double x = v.is_number_unsigned() ? static_cast<double>(v.get<std::uint64_t>())
                                          : static_cast<double>(v.get<std::int64_t>());
  CheckRange(x, "seed", what);
  return v.is_number_unsigned() ? v.get<std::uint64_t>()
                                : static_cast<std::uint64_t>(v.get<std::int64_t>());
}

void AddResult(Json& reply, const world::BatchResult& out) {
  reply["obs"] = Packed(out.obs);
  reply["done"] = Packed(out.done);
  reply["reset"] = Packed(out.reset);
  reply["time"] = Packed(out.time);
  reply["episode_steps"] = Packed(out.episode_steps);
  reply["step_seconds"] = out.seconds;
}

}  // namespace

world::BatchSubsystem& StepServer::RequireBatch() {
  if (!batch_) {
    Fail("no_batch", "this server runs no batch of environments (urlab run --envs N)");
  }
  return *batch_;
}

StepServer::Json StepServer::BatchHello() const {
  if (!batch_) return nullptr;
  return Json{{"envs", batch_->envs()}, {"threads", batch_->threads()}};
}

StepServer::Outcome StepServer::BatchInfo(Request&) {
  world::BatchSubsystem& b = RequireBatch();
  const mjModel* m = session_.engine().model();
  Json actuators = Json::array();
  for (int i = 0; i < m->nu; ++i) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, i);
    actuators.push_back(name ? name : "");
  }
  Json sensors = Json::array();
  for (int i = 0; i < m->nsensor; ++i) {
    const char* name = mj_id2name(m, mjOBJ_SENSOR, i);
    sensors.push_back(
        Json{{"name", name ? name : ""}, {"adr", m->sensor_adr[i]}, {"dim", m->sensor_dim[i]}});
  }
  Json layout = Json::array(
      {Json{{"name", "qpos"}, {"offset", 0}, {"size", b.nq()}},
       Json{{"name", "qvel"}, {"offset", b.nq()}, {"size", b.nv()}},
       Json{{"name", "sensordata"}, {"offset", b.nq() + b.nv()}, {"size", b.nsensordata()}}});
  return {Json{{"op", "batch_info_ok"},
               {"envs", b.envs()},
               {"threads", b.threads()},
               {"nu", b.action_size()},
               {"nq", b.nq()},
               {"nv", b.nv()},
               {"nsensordata", b.nsensordata()},
               {"obs_size", b.observation_size()},
               {"obs_layout", std::move(layout)},
               {"action_low", Packed(b.action_low())},
               {"action_high", Packed(b.action_high())},
               {"actuators", std::move(actuators)},
               {"sensors", std::move(sensors)},
               {"auto_reset", b.auto_reset()},
               {"max_episode_steps", b.max_episode_steps()},
               {"reset_noise", b.reset_noise()},
               {"timestep", session_.engine().timestep()},
               {"mode", mode_},
               {"env_steps", b.env_steps()},
               {"busy_seconds", b.busy_seconds()}}};
}

StepServer::Outcome StepServer::BatchStep(Request& r) {
  world::BatchSubsystem& b = RequireBatch();
  if (mode_ != "direct") {
    Fail("bad_mode",
         "batch_step steps in lockstep: set_mode direct first (the mode is " + mode_ + ")");
  }
  for (const Pending& p : pending_) {
    if (p.op.starts_with("batch_")) {
      Fail("queue_full", "one batch request at a time: wait for the reply to the previous one");
    }
  }
  auto job = std::make_shared<world::BatchStepJob>();
  if (const auto it = r.body.find("n_steps"); it != r.body.end()) {
    job->n = static_cast<int>(RangedNumber(*it, "n_steps"));
  }
  job->actions = Doubles(r.body["actions"], "actions");
  if (const auto it = r.body.find("reset"); it != r.body.end() && !it->is_null()) {
    job->reset = Flags(*it, "reset");
  }
  ops::CheckBatchStep(b, job->actions, job->reset);
  const std::uint64_t queued = QueuedSteps(r.client->id);
  if (queued + static_cast<std::uint64_t>(job->n) > options_.limits.max_queued_steps) {
    Fail("queue_full", "this session has " + std::to_string(queued) + " steps queued already");
  }
  Outcome out;
  out.reply = Json{{"op", "batch_step_ok"}, {"envs", b.envs()}};
  const bool here = BatchStepHere(b, job);
  if (!here) out.wait_for = b.SubmitStep(job, &out.steps);
  out.on_applied = [this, job, here](Json& reply) {
    if (!job->out.complete) Fail("cancelled", "the batch step did not complete");
    // The physics thread's windows teach the estimate too (their wall time on that thread).
    if (!here) batch_step_cost_.Measured(job->out.seconds / job->n);
    batch_->NoteCompleted(job->out);
    AddResult(reply, job->out);
  };
  return out;
}

bool StepServer::BatchStepHere(world::BatchSubsystem& b,
                               const std::shared_ptr<world::BatchStepJob>& job) {
  // Like StepHere: only with nothing queued before it (a reply waiting for a command must not be
  // overtaken), and only a window this thread can afford at the measured cost per step.
  const double budget = std::chrono::duration<double>(kMaxBatchHere).count();
  if (!pending_.empty() || !batch_step_cost_.Affordable(job->n, budget)) return false;
  try {
    if (!b.StepHere(job)) return false;
  } catch (const std::exception& e) {
    Fail("bad_value", e.what());
  }
  batch_step_cost_.Measured(job->out.seconds / job->n);
  return true;
}

StepServer::Outcome StepServer::BatchReset(Request& r) {
  world::BatchSubsystem& b = RequireBatch();
  for (const Pending& p : pending_) {
    if (p.op.starts_with("batch_")) {
      Fail("queue_full", "one batch request at a time: wait for the reply to the previous one");
    }
  }
  auto job = std::make_shared<world::BatchResetJob>();
  if (const auto it = r.body.find("envs"); it != r.body.end() && !it->is_null()) {
    if (!it->is_array()) Fail("bad_value", "'envs' must be an array of environment indices");
    for (const Json& e : *it) {
      if (!e.is_number_integer() || e.get<std::int64_t>() < 0 ||
          e.get<std::int64_t>() >= b.envs()) {
        Fail("bad_value", "envs: " + e.dump() + " is not an environment of this run (0.." +
                              std::to_string(b.envs() - 1) + ")");
      }
      job->envs.push_back(static_cast<int>(e.get<std::int64_t>()));
    }
  }
  std::vector<int> envs = job->envs;
  if (envs.empty()) {
    for (int i = 0; i < b.envs(); ++i) envs.push_back(i);
  }
  const auto seed = r.body.find("seed");
  const auto seeds = r.body.find("seeds");
  if (seed != r.body.end() && !seed->is_null() && seeds != r.body.end() && !seeds->is_null()) {
    Fail("bad_value",
         "give 'seed' (environment i gets seed + i) or 'seeds' (one per environment), "
         "not both");
  }
  if (seed != r.body.end() && !seed->is_null()) {
    const std::uint64_t s = Seed(*seed, "seed");
    for (int env : envs) job->seeds.push_back(s + static_cast<std::uint64_t>(env));
  } else if (seeds != r.body.end() && !seeds->is_null()) {
    if (!seeds->is_array() || seeds->size() != envs.size()) {
      Fail("dim_mismatch", "seeds must hold one seed (or null) per environment reset (" +
                               std::to_string(envs.size()) + ")");
    }
    for (const Json& s : *seeds) {
      job->seeds.push_back(s.is_null() ? std::optional<std::uint64_t>()
                                       : std::optional<std::uint64_t>(Seed(s, "seeds")));
    }
  }
  std::optional<bool> auto_reset;
  if (const auto it = r.body.find("auto_reset"); it != r.body.end() && !it->is_null()) {
    auto_reset = Bool(*it, "auto_reset");
  }
  job->envs = envs;
  Outcome out;
  out.wait_for = b.SubmitReset(job);
  if (auto_reset) b.SetAutoReset(*auto_reset);
  out.reply = Json{{"op", "batch_reset_ok"}, {"envs", b.envs()}, {"auto_reset", b.auto_reset()}};
  out.on_applied = [job](Json& reply) { AddResult(reply, job->out); };
  return out;
}

}  // namespace urlab::net
