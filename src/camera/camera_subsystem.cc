#include "urlab/camera/camera_subsystem.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
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
  o.config = scene.cameras;
  const std::string& port = scene.network.camera_base_port;
  char* end = nullptr;
  const long p = std::strtol(port.c_str(), &end, 10);
  if (port.empty() || *end != '\0' || p < 1 || p > 65535) {
    throw InputError({scene.path, 0},
                     "network.camera_base_port must be a TCP port number, not '" + port + "'");
  }
  o.base_port = static_cast<int>(p);
  for (const std::string& e :
       {scene.network.state, scene.network.control, scene.network.info, scene.network.rpc}) {
    const auto colon = e.rfind(':');
    if (colon == std::string::npos) continue;
    const int used = std::atoi(e.c_str() + colon + 1);
    if (used > 0) o.reserved_ports.push_back(used);
  }
  return o;
}

struct CameraSubsystem::Impl {
  struct Camera {
    internal::PlannedCamera plan;
    render::ImageRequest request;
    std::vector<std::size_t> streams;  // indices into infos
    Clock::duration period{};
    Clock::time_point next_due{};
    std::uint64_t frames = 0;
  };

  std::vector<world::CameraStreamInfo> infos;
  std::vector<std::string> modes;  // per stream
  std::vector<Camera> cameras;
  std::vector<int> geom_groups;
  std::shared_ptr<physics::StateSubscription> subscription;
  const mjModel* model = nullptr;
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
  std::uint64_t request_gen = 0;              // requests made so far

  std::atomic<std::uint64_t> renders{0}, published{0}, dropped{0};
  std::atomic<double> render_ms_total{0};

  // ---- Render thread only ----
  std::unique_ptr<render::OffscreenGl> gl;
  std::unique_ptr<render::CameraRenderer> renderer;
  std::optional<zmq::context_t> context;
  std::vector<zmq::socket_t> sockets;  // per stream (empty when not publishing)
  render::CameraImages images;
  std::uint64_t updated_frame = 0;

  void Init(const CameraOptions& options);
  void Run();
  void RenderCamera(Camera& cam, const physics::StateFrame& frame, std::int64_t state_wall);
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
  for (std::size_t k = 0; k < cam.streams.size(); ++k) Publish(cam.streams[k], out[k]);
  {
    std::lock_guard lock(mu);
    for (std::size_t k = 0; k < cam.streams.size(); ++k) latest[cam.streams[k]] = out[k];
  }
  frames_cv.notify_all();
}

void CameraSubsystem::Impl::Run() {
  const auto start = Clock::now();
  for (auto& cam : cameras) cam.next_due = start;
  while (!stop.load(std::memory_order_acquire)) {
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
          if (requested_step[s] > latest[s].step || (requested_step[s] && !latest[s].bytes)) {
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
    }
    auto until = Clock::time_point::max();
    for (const auto& cam : cameras) {
      if (AnyStreaming(cam)) until = std::min(until, cam.next_due);
    }
    if (!frame || waiting_for_state) until = std::min(until, Clock::now() + kSyncPoll);
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
    d.max_width = std::max(d.max_width, p.width);
    d.max_height = std::max(d.max_height, p.height);
    d.cameras.push_back(std::move(cam));
  }
  d.latest.resize(d.infos.size());
  d.requested_step.assign(d.infos.size(), 0);
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
  auto ready = [&] { return d.latest[index].bytes && d.latest[index].step >= step; };
  if (!ready()) {
    d.requested_step[index] = std::max(d.requested_step[index], step);
    ++d.request_gen;
    d.wake_cv.notify_all();
    d.frames_cv.wait_for(lock, timeout, [&] { return ready() || d.stop.load(); });
    if (ready() || d.requested_step[index] <= d.latest[index].step) d.requested_step[index] = 0;
  }
  if (!ready()) return false;
  out = d.latest[index];
  return true;
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
