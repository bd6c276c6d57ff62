#include "urlab/camera/camera_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <future>
#include <nlohmann/json.hpp>
#include <thread>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "render/camera_renderer.h"
#include "render/gl_context.h"
#include "render/render_thread.h"
#include "urlab/camera/camera_subsystem.h"
#include "urlab/core/error.h"
#include "urlab/world/loop_bench.h"
#include "urlab/world/manager.h"
#include "urlab/world/scene_checks.h"

namespace urlab::camera {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kRenderNice = 5;  // as the camera subsystem's default

// The camera to measure: "articulation/camera" -> (articulation, camera, id in `m`).
struct Target {
  std::string articulation, camera;
  int id = -1;
};

Target FindTarget(const world::SceneConfig& scene, const mjModel* m, const std::string& wanted) {
  for (const auto& art : scene.articulations) {
    const std::string prefix = art.name + "_";
    for (int i = 0; i < m->ncam; ++i) {
      const char* name = mj_id2name(m, mjOBJ_CAMERA, i);
      if (!name || std::string(name).rfind(prefix, 0) != 0) continue;
      Target t{art.name, std::string(name).substr(prefix.size()), i};
      if (wanted.empty() || wanted == t.articulation + "/" + t.camera) return t;
    }
  }
  throw InputError({scene.path, 0}, wanted.empty()
                                        ? std::string("the scene has no camera to measure")
                                        : "the scene has no camera '" + wanted + "'");
}

// Renders `seconds` worth of frames of one kind; frames per second.
double MeasureFps(render::CameraRenderer& renderer, int camera, int w, int h,
                  const render::ImageRequest& request, double seconds) {
  render::CameraImages images;
  renderer.Render(camera, w, h, request, images);  // warm up (shader compilation, buffers)
  int frames = 0;
  const auto start = Clock::now();
  const auto end =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  while (Clock::now() < end) {
    renderer.Render(camera, w, h, request, images);
    ++frames;
  }
  return frames / std::chrono::duration<double>(Clock::now() - start).count();
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

// A thread rendering one camera at `rate` from the newest state while `on` (the loop ratio).
class PacedRenderer {
 public:
  PacedRenderer(const mjModel* model, std::shared_ptr<physics::StateSubscription> sub,
                const Target& target, const CameraBenchOptions& o)
      : model_(model), sub_(std::move(sub)), target_(target), options_(o) {}
  ~PacedRenderer() { Stop(); }
  void Start() {
    stop_ = false;
    std::promise<void> ready;
    auto started = ready.get_future();
    thread_ = std::thread([this, &ready] {
      render::PrepareRenderThread(kRenderNice);
      auto gl = render::OffscreenGl::Create();
      render::CameraRenderer renderer(model_, options_.width, options_.height, {});
      renderer.MakeContext();
      ready.set_value();
      const auto period = std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(1.0 / options_.rate));
      render::CameraImages images;
      std::vector<std::uint8_t> wire;
      auto next = Clock::now();
      while (!stop_) {
        if (const physics::StateFrame* f = sub_->Latest()) {
          renderer.Update(*f);
          renderer.Render(target_.id, options_.width, options_.height, {.rgb = true}, images);
          render::RgbToBgra(images.rgb, wire);
          ++frames_;
        }
        next += period;
        std::this_thread::sleep_until(next);
      }
    });
    started.wait();
  }
  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::uint64_t frames() const { return frames_; }

 private:
  const mjModel* model_;
  std::shared_ptr<physics::StateSubscription> sub_;
  Target target_;
  CameraBenchOptions options_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> frames_{0};
};

}  // namespace

CameraBenchResult RunCameraBench(const world::SceneConfig& scene_in, const CameraBenchOptions& o) {
  auto report = [&](const std::string& line) {
    if (o.report) o.report(line);
  };
  world::SceneConfig scene = scene_in;
  scene.save_debug_xml.clear();
  const world::CompiledScene compiled = world::BuildCheckedScene(scene);
  const Target target = FindTarget(scene, compiled.model.get(), o.camera);
  CameraBenchResult r;

  // 1. Frames per second, on a render thread of its own.
  std::thread([&] {
    render::PrepareRenderThread(0);
    auto gl = render::OffscreenGl::Create();
    r.backend = gl->Describe();
    render::CameraRenderer renderer(compiled.model.get(), o.width, o.height, {});
    renderer.MakeContext();
    auto data = physics::MakeData(compiled.model.get());
    mj_forward(compiled.model.get(), data.get());
    auto frame = physics::StateFrame::SizedFor(compiled.model.get());
    frame.CopyFrom(compiled.model.get(), data.get());
    renderer.Update(frame);
    r.fps_rgb = MeasureFps(renderer, target.id, o.width, o.height, {.rgb = true}, o.fps_seconds);
    r.fps_rgb_depth = MeasureFps(renderer, target.id, o.width, o.height,
                                 {.rgb = true, .depth = true}, o.fps_seconds);
    r.fps_segmentation =
        MeasureFps(renderer, target.id, o.width, o.height, {.segmentation = true}, o.fps_seconds);
  }).join();
  report(
      fmt::format("camera {}/{} {}x{} on {}: rgb {:.1f} fps, rgb+depth {:.1f} fps, "
                  "segmentation {:.1f} fps",
                  target.articulation, target.camera, o.width, o.height, r.backend, r.fps_rgb,
                  r.fps_rgb_depth, r.fps_segmentation));

  // 2. Latency through the camera subsystem and ZeroMQ, the simulation running in real time.
  {
    world::SceneConfig s = scene;
    CamerasConfig& cameras = EditCameras(s);
    cameras.enabled = true;
    cameras.width = o.width;
    cameras.height = o.height;
    cameras.rate = o.rate;
    cameras.modes = {"rgb"};
    for (auto& a : s.articulations) {
      a.all_cameras = false;
      a.cameras.clear();
    }
    cameras.cameras.clear();
    cameras.cameras[target.articulation + "/" + target.camera] = {};
    CameraOptions co;
    co.config = cameras;
    co.base_port = 0;  // ephemeral
    co.bind_host = "127.0.0.1";
    world::Manager manager;
    auto* cams =
        static_cast<CameraSubsystem*>(&manager.AddSubsystem(std::make_unique<CameraSubsystem>(co)));
    manager.BeginPlay(s);
    const world::CameraStreamInfo& info = cams->Streams().front();
    zmq::context_t ctx(1);
    zmq::socket_t sub(ctx, zmq::socket_type::sub);
    sub.set(zmq::sockopt::linger, 0);
    sub.set(zmq::sockopt::subscribe, info.topic);
    sub.set(zmq::sockopt::subscribe, info.meta_topic);
    sub.connect(info.endpoint);
    std::vector<double> latencies;
    std::int64_t state_wall = 0;  // of the meta just received, 0: none
    const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(o.latency_seconds));
    while (Clock::now() < end) {
      manager.Tick();
      std::vector<zmq::message_t> parts;
      zmq::pollitem_t item{sub.handle(), 0, ZMQ_POLLIN, 0};
      if (zmq::poll(&item, 1, std::chrono::milliseconds(10)) <= 0) continue;
      while (zmq::recv_multipart(sub, std::back_inserter(parts), zmq::recv_flags::dontwait)) {
        const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                     std::chrono::system_clock::now().time_since_epoch())
                                     .count();
        if (parts.size() == 2 && parts[0].to_string_view() == info.meta_topic) {
          state_wall = nlohmann::json::parse(parts[1].to_string_view())["state_wall_ns"];
        } else if (state_wall != 0) {
          latencies.push_back(static_cast<double>(now - state_wall) / 1e6);
          state_wall = 0;
        }
        parts.clear();
      }
    }
    manager.EndPlay();
    r.latency_samples = static_cast<int>(latencies.size());
    r.latency_p50_ms = Percentile(latencies, 0.5);
    r.latency_p99_ms = Percentile(latencies, 0.99);
    report(fmt::format(
        "streaming {}x{} rgb at {} Hz: {} frames received, latency (state taken to "
        "client receive) p50 {:.2f} ms, p99 {:.2f} ms",
        o.width, o.height, o.rate, r.latency_samples, r.latency_p50_ms, r.latency_p99_ms));
  }

  // 3. The physics loop with the camera rendering at `rate` beside it, against without.
  {
    // The whole scene (the camera may belong to any articulation); the first one is driven.
    world::SceneConfig s = scene;
    const world::CompiledScene one = world::BuildCheckedScene(s);
    const Target t = FindTarget(s, one.model.get(),
                                o.camera.empty() ? "" : target.articulation + "/" + target.camera);
    world::LoopBenchOptions lo;
    lo.steps = o.loop_steps;
    lo.trials = o.loop_trials;
    world::DriveFirstArticulation(s, one, &lo);
    std::unique_ptr<PacedRenderer> paced;
    lo.attach = [&](physics::PhysicsEngine& engine) {
      paced =
          std::make_unique<PacedRenderer>(engine.model(), engine.SubscribeState("camera"), t, o);
    };
    lo.toggle = [&](bool on) {
      if (on) {
        paced->Start();
      } else {
        paced->Stop();
      }
    };
    lo.report = o.report;
    const world::LoopBenchResult lr = world::RunLoopBench(one.model, lo);
    r.loop_ratio = lr.attached_ratio;
    r.loop_median_ratio = lr.attached_median_ratio;
    report(fmt::format(
        "physics loop with one {}x{} camera at {} Hz / without: best {:.3f}, "
        "median {:.3f} ({} frames rendered)",
        o.width, o.height, o.rate, r.loop_ratio, r.loop_median_ratio, paced ? paced->frames() : 0));
  }
  return r;
}

}  // namespace urlab::camera
