#include "urlab/camera/camera_subsystem.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <future>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "camera/camera_plan.h"
#include "render/camera_renderer.h"
#include "render/gl_context.h"
#include "render/render_thread.h"
#include "urlab/core/error.h"
#include "urlab/world/session.h"

namespace urlab::camera {

namespace {

using Clock = std::chrono::steady_clock;

// Frames a stream's socket queues for a slow client before it drops (latest frame wins).
constexpr int kSendHighWaterMark = 2;
// Ports tried upward from the first free candidate for each stream (docs/protocol.md: up to 10).
constexpr int kBindTries = 10;
// While a step waits for a frame of a state not yet published, the render thread polls this often.
constexpr auto kSyncPoll = std::chrono::microseconds(200);

std::int64_t WallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string StreamName(const std::string& camera, const std::string& mode) {
  return mode == "rgb" ? camera : camera + "/" + mode;
}

}  // namespace

CameraOptions CameraOptionsFromScene(const world::SceneConfig& scene) {
  CameraOptions o;
  o.config = CamerasOf(scene);
  return o;
}

struct CameraSubsystem::Impl {
  // A rendered frame of every stream of one camera, waiting for its release step.
  struct Held {
    std::int64_t release = 0;
    std::vector<world::CameraFrame> frames;  // per stream of the camera
  };
  struct Camera {
    internal::PlannedCamera plan;
    std::string key;  // "{articulation}/{camera}"
    render::ImageRequest request;
    std::vector<std::size_t> streams;  // indices into infos
    Clock::duration period{};
    Clock::time_point next_due{};
    std::uint64_t frames = 0;
    // ---- Emulated delay (render thread; `setting` and `pending` also under mu) ----
    physics::LatencySetting setting;  // as given (Delay reports it)
    physics::DelaySpec pending;       // set by SetDelay, taken by the render thread
    bool pending_set = false;
    physics::DelaySpec delay;  // in effect (render thread)
    std::int64_t last_release = -1, last_change = -1;
    std::deque<Held> held;
  };

  std::vector<world::CameraStreamInfo> infos;
  std::vector<std::string> modes;  // per stream
  std::vector<Camera> cameras;
  std::vector<int> geom_groups;
  std::shared_ptr<physics::StateSubscription> subscription;
  const mjModel* model = nullptr;
  physics::PhysicsEngine* engine = nullptr;  // the session's (it outlives the render thread)
  render::RenderSettings settings;
  render::GlBackend backend = render::GlBackend::kAuto;
  int max_width = 1, max_height = 1;

  std::thread thread;
  std::atomic<bool> stop{false};
  std::string backend_name;  // set before BeginPlay returns

  // Guards latest, requests; frames_cv announces new frames, wake_cv wakes the render thread.
  mutable std::mutex mu;
  std::condition_variable frames_cv, wake_cv;
  std::vector<world::CameraFrame> latest;  // per stream
  // Per stream: published (set_camera_streaming; any thread).
  std::unique_ptr<std::atomic<bool>[]> streaming;
  // Render thread: per stream, subscribers to its header topic (the XPUB's subscriptions).
  std::vector<int> header_subscribers;
  std::vector<std::uint8_t> headed;  // a frame behind its header, reused
  bool AnyStreaming(const Camera& cam) const {
    for (std::size_t s : cam.streams) {
      if (streaming[s].load(std::memory_order_relaxed)) return true;
    }
    return false;
  }
  std::vector<std::uint64_t> requested_step;  // per stream: a waiter's step, 0 for none
  std::vector<std::uint64_t> rendered_step;   // per stream: the step of its newest render
  // Per stream: the newest step whose releases the render thread has made (delayed cameras).
  std::vector<std::uint64_t> released_through;
  std::vector<bool> delayed;      // per stream: its camera has a delay
  double timestep = 0;            // the model's, resolving delays in seconds
  std::uint64_t request_gen = 0;  // requests made so far

  std::atomic<std::uint64_t> renders{0}, published{0}, dropped{0};
  std::atomic<double> render_ms_total{0};

  // ---- Render thread only ----
  std::unique_ptr<render::OffscreenGl> gl;
  std::unique_ptr<render::CameraRenderer> renderer;
  std::optional<zmq::context_t> context;
  std::vector<zmq::socket_t> sockets;  // per stream (empty when not publishing)
  render::CameraImages images;
  std::uint64_t updated_frame = 0;
  // The engine's model generation the renderer's values were asked for, the command copying
  // them into model_staging (0: none pending) and that copy.
  std::uint64_t model_generation = 0;
  std::uint64_t model_copy = 0;
  std::shared_ptr<physics::Model> model_staging;

  void Init(const CameraOptions& options);
  // The running model's new values (an edit, a reload keeping the state) into the renderer,
  // copied on the physics thread by a command (render thread).
  void TakeNewModelValues();
  void Run();
  void RenderCamera(Camera& cam, const physics::StateFrame& frame, std::int64_t state_wall);
  // Delivers frames: to the topics and as the streams' latest.
  void Deliver(Camera& cam, std::vector<world::CameraFrame>& frames);
  // Takes a delay setting SetDelay left for the camera (render thread).
  void TakeSetting(Camera& cam);
  // Takes a new setting and releases the held frames due at `step`.
  void Release(Camera& cam, std::uint64_t step);
  Camera& Find(const std::string& key);
  void Publish(std::size_t stream, const world::CameraFrame& frame);
};

void CameraSubsystem::Impl::Init(const CameraOptions& options) {
  render::PrepareRenderThread(options.render_nice);
  gl = render::OffscreenGl::Create(backend);
  backend_name = gl->Describe();
  renderer = std::make_unique<render::CameraRenderer>(model, max_width, max_height, settings);
  renderer->MakeContext();
  renderer->SetGeomGroups(geom_groups);
  if (!options.publish) return;
  context.emplace(1);
  int port = options.base_port;
  for (std::size_t i = 0; i < infos.size(); ++i) {
    // XPUB: the subscriptions tell whether anyone wants the header topic.
    zmq::socket_t s(*context, zmq::socket_type::xpub);
    s.set(zmq::sockopt::linger, 0);
    s.set(zmq::sockopt::sndhwm, kSendHighWaterMark);
    std::string bound;
    if (options.base_port == 0) {  // ephemeral ports (tests, benchmarks)
      s.bind(fmt::format("tcp://{}:*", options.bind_host));
      bound = s.get(zmq::sockopt::last_endpoint);
    }
    for (int t = 0; options.base_port != 0 && t < kBindTries && bound.empty(); ++t, ++port) {
      if (std::find(options.reserved_ports.begin(), options.reserved_ports.end(), port) !=
          options.reserved_ports.end()) {
        continue;
      }
      try {
        s.bind(fmt::format("tcp://{}:{}", options.bind_host, port));
        bound = fmt::format("tcp://{}:{}", options.advertise_host, port);
      } catch (const zmq::error_t&) {
      }
    }
    if (bound.empty()) {
      spdlog::error("cameras: no free port for {} in {}..{}; the stream is not published",
                    infos[i].topic, port - kBindTries, port - 1);
    }
    infos[i].endpoint = bound;
    sockets.push_back(std::move(s));
  }
}

void CameraSubsystem::Impl::Publish(std::size_t i, const world::CameraFrame& f) {
  if (i >= sockets.size() || infos[i].endpoint.empty()) return;
  if (!streaming[i].load(std::memory_order_relaxed)) return;
  const world::CameraStreamInfo& info = infos[i];
  // Subscriptions since the last frame: 1 + prefix subscribes, 0 + prefix unsubscribes (ZeroMQ
  // passes on the first subscription to a prefix and the last unsubscription only). A
  // subscription to everything does not ask for the header topic.
  zmq::message_t sub;
  while (sockets[i].recv(sub, zmq::recv_flags::dontwait)) {
    if (sub.size() == 0) continue;
    const auto* b = static_cast<const char*>(sub.data());
    const std::string_view prefix(b + 1, sub.size() - 1);
    if (!info.header_topic.starts_with(prefix) || prefix.empty()) continue;
    header_subscribers[i] += b[0] == 1 ? 1 : b[0] == 0 ? -1 : 0;
  }
  nlohmann::ordered_json meta;
  meta["frame_id"] = f.frame_id;
  meta["step"] = f.step;
  meta["sim_time"] = f.sim_time;
  meta["state_wall_ns"] = f.state_wall_ns;
  meta["render_wall_ns"] = f.render_wall_ns;
  meta["render_ms"] = f.render_ms;
  meta["width"] = f.width;
  meta["height"] = f.height;
  meta["mode"] = info.mode;
  const std::string text = meta.dump();
  zmq::socket_t& s = sockets[i];
  std::array<zmq::const_buffer, 2> meta_parts = {zmq::buffer(info.meta_topic), zmq::buffer(text)};
  std::array<zmq::const_buffer, 2> frame_parts = {zmq::buffer(info.topic), zmq::buffer(*f.bytes)};
  // PUB sockets drop rather than block at the high-water mark; dontwait makes sure of it.
  if (!zmq::send_multipart(s, meta_parts, zmq::send_flags::dontwait) ||
      !zmq::send_multipart(s, frame_parts, zmq::send_flags::dontwait)) {
    dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (header_subscribers[i] > 0) {  // the frame behind its header, for those who asked
    headed.resize(world::kFrameHeaderBytes + f.bytes->size());
    world::WriteFrameHeader(headed.data(), f.frame_id, f.sim_time, f.step);
    std::memcpy(headed.data() + world::kFrameHeaderBytes, f.bytes->data(), f.bytes->size());
    std::array<zmq::const_buffer, 2> parts = {zmq::buffer(info.header_topic), zmq::buffer(headed)};
    if (!zmq::send_multipart(s, parts, zmq::send_flags::dontwait)) {
      dropped.fetch_add(1, std::memory_order_relaxed);
    }
  }
  published.fetch_add(1, std::memory_order_relaxed);
}

void CameraSubsystem::Impl::RenderCamera(Camera& cam, const physics::StateFrame& frame,
                                         std::int64_t state_wall) {
  const auto t0 = Clock::now();
  renderer->Render(cam.plan.camera_id, cam.plan.width, cam.plan.height, cam.request, images);
  ++cam.frames;
  std::vector<world::CameraFrame> out(cam.streams.size());
  for (std::size_t k = 0; k < cam.streams.size(); ++k) {
    const std::string& mode = modes[cam.streams[k]];
    auto bytes = std::make_shared<std::vector<std::uint8_t>>();
    if (mode == "rgb") {
      render::RgbToBgra(images.rgb, *bytes);
    } else if (mode == "depth") {
      bytes->resize(images.depth.size() * sizeof(float));
      std::memcpy(bytes->data(), images.depth.data(), bytes->size());
    } else if (mode == "segmentation") {
      render::IdsToBgra(images.geom_ids, *bytes);
    } else {
      render::IdsToBgra(images.group_ids, *bytes);
    }
    world::CameraFrame& f = out[k];
    f.frame_id = cam.frames;
    f.step = frame.step;
    f.sim_time = frame.time;
    f.state_wall_ns = state_wall;
    f.width = cam.plan.width;
    f.height = cam.plan.height;
    f.bytes = std::move(bytes);
  }
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  const std::int64_t ready = WallNs();
  for (auto& f : out) {
    f.render_ms = ms;
    f.render_wall_ns = ready;
  }
  renders.fetch_add(1, std::memory_order_relaxed);
  render_ms_total.store(render_ms_total.load(std::memory_order_relaxed) + ms,
                        std::memory_order_relaxed);
  {
    std::lock_guard lock(mu);
    for (std::size_t s : cam.streams) rendered_step[s] = frame.step;
  }
  TakeSetting(cam);  // a setting given while this frame rendered applies to it
  if (!cam.delay.active()) {
    Deliver(cam, out);
    return;
  }
  // Held until step + delay + jitter (never before its own step, never before an older frame).
  // The jitter is a function of the seed and the step, so however often the thread renders one
  // state, a lockstep run releases the same frames at the same steps for the same seed.
  const auto t = static_cast<std::int64_t>(frame.step);
  int j = 0;
  if (cam.delay.jitter > 0) {
    std::uint64_t state = physics::DeriveSeed(cam.delay.seed, frame.step);
    const auto span = static_cast<std::uint64_t>(2 * cam.delay.jitter + 1);
    j = static_cast<int>(
            static_cast<std::uint64_t>(physics::UnitDouble(&state) * static_cast<double>(span))) -
        cam.delay.jitter;
  }
  const std::int64_t release = std::max({t, t + cam.delay.delay + j, cam.last_release});
  cam.last_release = release;
  cam.held.push_back({release, std::move(out)});
}

void CameraSubsystem::Impl::Deliver(Camera& cam, std::vector<world::CameraFrame>& frames) {
  for (std::size_t k = 0; k < cam.streams.size(); ++k) Publish(cam.streams[k], frames[k]);
  {
    std::lock_guard lock(mu);
    for (std::size_t k = 0; k < cam.streams.size(); ++k) latest[cam.streams[k]] = frames[k];
  }
  frames_cv.notify_all();
}

void CameraSubsystem::Impl::TakeSetting(Camera& cam) {
  std::lock_guard lock(mu);
  if (!cam.pending_set) return;
  // A new setting restarts the camera's line: the frames held are dropped.
  cam.delay = cam.pending;
  cam.pending_set = false;
  cam.last_release = cam.last_change = -1;
  cam.held.clear();
  for (std::size_t s : cam.streams) delayed[s] = cam.delay.active();
}

void CameraSubsystem::Impl::Release(Camera& cam, std::uint64_t step) {
  TakeSetting(cam);
  const auto t = static_cast<std::int64_t>(step);
  const bool may_change = cam.delay.min_interval <= 1 || cam.last_change < 0 ||
                          t - cam.last_change >= cam.delay.min_interval;
  // The newest frame due is delivered; older ones due at the same step are superseded.
  std::optional<Held> due;
  while (may_change && !cam.held.empty() && cam.held.front().release <= t) {
    due = std::move(cam.held.front());
    cam.held.pop_front();
  }
  if (due) {
    cam.last_change = t;
    Deliver(cam, due->frames);
  }
  if (cam.delay.active()) {
    {
      std::lock_guard lock(mu);
      for (std::size_t s : cam.streams) released_through[s] = std::max(released_through[s], step);
    }
    frames_cv.notify_all();
  }
}

void CameraSubsystem::Impl::TakeNewModelValues() {
  if (const std::uint64_t g = engine->model_generation(); g != model_generation && !model_copy) {
    model_generation = g;
    if (!model_staging) {
      model_staging = std::make_shared<physics::Model>(
          physics::ModelPtr(mj_copyModel(nullptr, renderer->model())));
      if (!*model_staging) throw Error("cameras: cannot copy the model");
    }
    model_copy = engine->Submit(
        physics::cmd::Inspect{[staging = model_staging](const mjModel* m, const mjData*) {
                                physics::CopyModelValuesInPlace(staging->get(), m);
                              },
                              "cameras: the model's new values"});
  }
  if (!model_copy || engine->last_applied_command() < model_copy) return;
  model_copy = 0;
  renderer->ReplaceModelValues(model_staging->get());
  updated_frame = 0;  // positions again, from the new values
}

void CameraSubsystem::Impl::Run() {
  const auto start = Clock::now();
  for (auto& cam : cameras) cam.next_due = start;
  while (!stop.load(std::memory_order_acquire)) {
    try {
      TakeNewModelValues();
    } catch (const std::exception& e) {
      spdlog::error("cameras: {}", e.what());
    }
    const auto now = Clock::now();
    // Which cameras are due: by their rate, or because a waiter asks for a newer step.
    std::vector<std::uint64_t> wanted(cameras.size(), 0);
    bool waiting_for_state = false;
    std::uint64_t seen_gen = 0;
    {
      std::lock_guard lock(mu);
      seen_gen = request_gen;
      for (std::size_t c = 0; c < cameras.size(); ++c) {
        for (std::size_t s : cameras[c].streams) {
          if (requested_step[s] > rendered_step[s] ||
              (requested_step[s] && !latest[s].bytes && !delayed[s])) {
            wanted[c] = std::max(wanted[c], requested_step[s]);
          }
        }
      }
    }
    const physics::StateFrame* frame = subscription->Latest();
    const std::int64_t state_wall = WallNs();
    if (frame) {
      for (std::size_t c = 0; c < cameras.size(); ++c) {
        Camera& cam = cameras[c];
        const bool due = now >= cam.next_due && AnyStreaming(cam);
        const bool sync = wanted[c] != 0 && frame->step >= wanted[c];
        if (wanted[c] != 0 && frame->step < wanted[c]) waiting_for_state = true;
        if (!due && !sync) continue;
        if (updated_frame != frame->frame) {
          renderer->Update(*frame);
          updated_frame = frame->frame;
        }
        try {
          RenderCamera(cam, *frame, state_wall);
        } catch (const std::exception& e) {
          spdlog::error("cameras: {}/{}: {}", cam.plan.articulation, cam.plan.camera, e.what());
        }
        if (due) {
          cam.next_due += cam.period;
          if (cam.next_due < Clock::now()) cam.next_due = Clock::now() + cam.period;  // behind
        }
      }
      for (Camera& cam : cameras) Release(cam, frame->step);
    }
    auto until = Clock::time_point::max();
    for (const auto& cam : cameras) {
      if (AnyStreaming(cam)) until = std::min(until, cam.next_due);
    }
    bool holding = false;  // a delayed camera waits for the steps that release its frames
    for (const auto& cam : cameras) holding |= !cam.held.empty();
    if (!frame || waiting_for_state || holding) {
      until = std::min(until, Clock::now() + kSyncPoll);
    }
    std::unique_lock lock(mu);
    wake_cv.wait_until(lock, until, [&] {
      return stop.load(std::memory_order_acquire) || request_gen != seen_gen;
    });
  }
  renderer.reset();
  gl.reset();
  sockets.clear();
  context.reset();
}

CameraSubsystem::CameraSubsystem(CameraOptions options)
    : options_(std::move(options)), impl_(std::make_unique<Impl>()) {}

CameraSubsystem::~CameraSubsystem() {
  if (impl_->thread.joinable()) {
    impl_->stop = true;
    impl_->wake_cv.notify_all();
    impl_->thread.join();
  }
}

void CameraSubsystem::BeginPlay(world::Session& session) {
  Impl& d = *impl_;
  const auto plan = internal::PlanCameras(session, options_.config);
  if (plan.empty()) {
    if (!options_.config.enabled) spdlog::info("cameras: streaming is off (cameras.enabled)");
    return;
  }
  d.model = session.engine().model();
  d.engine = &session.engine();
  d.geom_groups = internal::GeomArticulations(session);
  d.settings = {options_.config.shadows, options_.config.reflections, options_.config.samples};
  d.backend = render::ParseGlBackend(options_.config.gl, "cameras.gl");
  std::vector<std::string> geom_names, art_names;
  for (int g = 0; g < d.model->ngeom; ++g) {
    const char* n = mj_id2name(d.model, mjOBJ_GEOM, g);
    geom_names.push_back(n ? n : fmt::format("geom{}", g));
  }
  for (const auto& a : session.articulations()) art_names.push_back(a.name());
  for (const auto& p : plan) {
    Impl::Camera cam;
    cam.plan = p;
    cam.period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / p.rate));
    cam.key = p.articulation + "/" + p.camera;
    for (const std::string& mode : p.modes) {
      world::CameraStreamInfo info;
      info.articulation = p.articulation;
      info.camera = p.camera;
      info.mode = mode;
      info.stream = StreamName(p.camera, mode);
      info.topic = p.articulation + "/camera/" + info.stream + " ";
      info.meta_topic = p.articulation + "/camera_meta/" + info.stream;
      info.header_topic = p.articulation + "/camera_ucm1/" + info.stream + " ";
      info.width = p.width;
      info.height = p.height;
      info.rate = p.rate;
      if (mode == "segmentation") info.id_names = geom_names;
      if (mode == "instance") info.id_names = art_names;
      cam.request.rgb |= mode == "rgb";
      cam.request.depth |= mode == "depth";
      cam.request.segmentation |= mode == "segmentation" || mode == "instance";
      cam.streams.push_back(d.infos.size());
      d.infos.push_back(std::move(info));
      d.modes.push_back(mode);
    }
    if (p.latency) {  // the scene's delay: taken by the render thread before its first frame
      cam.setting = *p.latency;
      cam.pending = physics::ResolveLatency(
          *p.latency, d.model->opt.timestep,
          world::CameraDelaySeed(session.latency_seed(), cam.streams.front()));
      cam.pending_set = true;
    }
    d.max_width = std::max(d.max_width, p.width);
    d.max_height = std::max(d.max_height, p.height);
    d.cameras.push_back(std::move(cam));
  }
  d.latest.resize(d.infos.size());
  d.requested_step.assign(d.infos.size(), 0);
  d.rendered_step.assign(d.infos.size(), 0);
  d.released_through.assign(d.infos.size(), 0);
  d.delayed.assign(d.infos.size(), false);
  for (const auto& cam : d.cameras) {
    for (std::size_t i : cam.streams) d.delayed[i] = cam.pending_set && cam.pending.active();
  }
  d.timestep = d.model->opt.timestep;
  d.streaming = std::make_unique<std::atomic<bool>[]>(d.infos.size());
  for (std::size_t i = 0; i < d.infos.size(); ++i) d.streaming[i] = true;
  d.header_subscribers.assign(d.infos.size(), 0);
  d.subscription = session.engine().SubscribeState("cameras");
  std::promise<void> ready;
  auto started = ready.get_future();
  d.thread = std::thread([this, &ready] {
    try {
      impl_->Init(options_);
      ready.set_value();
    } catch (...) {
      ready.set_exception(std::current_exception());
      return;
    }
    impl_->Run();
  });
  try {
    started.get();
  } catch (...) {
    d.thread.join();
    throw;
  }
  for (const auto& info : d.infos) {
    spdlog::info("cameras: {} {}x{} at {} Hz on {} ({})", info.topic, info.width, info.height,
                 info.rate, info.endpoint.empty() ? "no socket" : info.endpoint, d.backend_name);
  }
}

void CameraSubsystem::EndPlay(world::Session& /*session*/) {
  if (!impl_->thread.joinable()) return;
  impl_->stop = true;
  impl_->wake_cv.notify_all();
  impl_->frames_cv.notify_all();
  impl_->thread.join();
}

const std::vector<world::CameraStreamInfo>& CameraSubsystem::Streams() const {
  return impl_->infos;
}

void CameraSubsystem::SetStreaming(std::size_t index, bool on) {
  if (index >= impl_->infos.size()) return;
  impl_->streaming[index].store(on, std::memory_order_relaxed);
  std::lock_guard lock(impl_->mu);  // a camera turned on renders at once
  ++impl_->request_gen;
  impl_->wake_cv.notify_all();
}

bool CameraSubsystem::Streaming(std::size_t index) const {
  return index < impl_->infos.size() && impl_->streaming[index].load(std::memory_order_relaxed);
}

bool CameraSubsystem::Latest(std::size_t index, world::CameraFrame& out) const {
  std::lock_guard lock(impl_->mu);
  if (index >= impl_->latest.size() || !impl_->latest[index].bytes) return false;
  out = impl_->latest[index];
  return true;
}

bool CameraSubsystem::WaitForStep(std::size_t index, std::uint64_t step,
                                  std::chrono::milliseconds timeout, world::CameraFrame& out) {
  Impl& d = *impl_;
  std::unique_lock lock(d.mu);
  if (index >= d.latest.size()) return false;
  // Undelayed: a frame of `step` or later. Delayed: the releases of `step` are made (the frame of
  // `step` rendered and held, what is due by then delivered).
  auto ready = [&] {
    if (d.delayed[index])
      return d.released_through[index] >= step && d.rendered_step[index] >= step;
    return d.latest[index].bytes && d.latest[index].step >= step;
  };
  if (!ready()) {
    d.requested_step[index] = std::max(d.requested_step[index], step);
    ++d.request_gen;
    d.wake_cv.notify_all();
    d.frames_cv.wait_for(lock, timeout, [&] { return ready() || d.stop.load(); });
    if (ready() || d.requested_step[index] <= d.rendered_step[index]) d.requested_step[index] = 0;
  }
  if (!ready() || !d.latest[index].bytes) return false;
  out = d.latest[index];
  return true;
}

CameraSubsystem::Impl::Camera& CameraSubsystem::Impl::Find(const std::string& key) {
  for (Camera& cam : cameras) {
    if (cam.key == key) return cam;
  }
  std::string known;
  for (const Camera& cam : cameras) known += (known.empty() ? "" : ", ") + cam.key;
  throw Error("unknown camera '" + key +
              "' (streamed cameras: " + (known.empty() ? std::string("none") : known) + ")");
}

void CameraSubsystem::SetDelay(const std::string& camera, const physics::LatencySetting& setting,
                               std::uint64_t seed) {
  Impl& d = *impl_;
  std::lock_guard lock(d.mu);
  Impl::Camera& cam = d.Find(camera);
  cam.setting = setting;
  cam.pending = physics::ResolveLatency(setting, d.timestep, seed);
  cam.pending_set = true;
  // Until the render thread takes it, waits follow the new setting.
  for (std::size_t s : cam.streams) d.delayed[s] = cam.pending.active();
  ++d.request_gen;  // wakes the render thread, which takes the setting
  d.wake_cv.notify_all();
}

physics::LatencySetting CameraSubsystem::Delay(const std::string& camera) const {
  std::lock_guard lock(impl_->mu);
  return impl_->Find(camera).setting;
}

CameraCounters CameraSubsystem::counters() const {
  CameraCounters c;
  c.renders = impl_->renders.load();
  c.published = impl_->published.load();
  c.dropped = impl_->dropped.load();
  c.render_ms_total = impl_->render_ms_total.load();
  return c;
}

std::string CameraSubsystem::backend() const {
  return impl_->thread.joinable() ? impl_->backend_name : std::string();
}

}  // namespace urlab::camera
