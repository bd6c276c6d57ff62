#include "viewer/viewer_core.h"

#include <GLFW/glfw3.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <ctime>

#include "urlab/core/error.h"
#include "urlab/ops/controllers.h"
#include "urlab/ops/error.h"
#include "urlab/ops/simulation.h"
#include "viewer/framing.h"
#include "viewer/panel.h"

namespace urlab::viewer::internal {

namespace {

using Clock = std::chrono::steady_clock;

// Room in the abstract scene for the model's geoms plus the debug drawing's lines.
constexpr int kMaxGeom = 40000;
// Longest a perturbation force is applied for without a new frame (a stalled viewer must not
// push a body forever).
constexpr double kMaxPerturbSeconds = 0.1;

// The layer a toggle hotkey flips.
std::optional<DebugLayer> LayerOf(Action a) {
  switch (a) {
    case Action::kToggleContacts:
      return DebugLayer::kContacts;
    case Action::kToggleVisual:
      return DebugLayer::kVisual;
    case Action::kToggleCollision:
      return DebugLayer::kCollision;
    case Action::kToggleJoints:
      return DebugLayer::kJoints;
    case Action::kTogglePropCollision:
      return DebugLayer::kPropCollision;
    default:
      return std::nullopt;
  }
}

}  // namespace

ViewerCore::ViewerCore(ViewerOptions options, const world::Manager* manager,
                       std::shared_ptr<replay::PlaybackSlot> playback)
    : options_(std::move(options)),
      layout_(options_.panel),
      manager_(manager),
      playback_(std::move(playback)) {}

ViewerCore::~ViewerCore() { End(); }

void ViewerCore::Begin(world::Session& session) {
  session_ = session.shared_from_this();
  physics::PhysicsEngine& engine = session.engine();
  start_ = last_present_ = fps_window_start_ = Clock::now();
  input_.Build(session);  // scene errors before a window opens
  // The window first: without a display nothing else is set up.
  window_ = std::make_unique<Window>(options_.width, options_.height, options_.title, this,
                                     options_.panel);
  view_ = std::make_unique<SceneView>(engine.model(), kMaxGeom);  // engine not running yet
  SeparateCoplanarPlanes(view_->model());
  const bool software = window_->software_renderer();
  quality_ = ResolveQuality(options_, QualityOf(session.scene_config()), software);
  {
    int fw = 0, fh = 0;
    window_->FramebufferSize(&fw, &fh);
    const bool scaled = quality_.scale != 1.0;
    view_->MakeContext(quality_.shadow_size,
                       scaled ? static_cast<int>(std::ceil(fw * quality_.scale)) : 0,
                       scaled ? static_cast<int>(std::ceil(fh * quality_.scale)) : 0);
  }
  ApplyQuality(quality_, &view_->scene());
  spdlog::info(
      "viewer: {}x{} window, OpenGL {}; shadows {}, reflections {}, sky {}, render scale {}{}",
      options_.width, options_.height, window_->GlVersion(), quality_.shadows ? "on" : "off",
      quality_.reflections ? "on" : "off", quality_.skybox ? "on" : "off", quality_.scale,
      software ? fmt::format(" (software renderer: {} shadow map)",
                             view_->model()->vis.quality.shadowsize)
               : "");
  BuildTables();
  plots_.Configure(view_->model());
  for (const std::string& name : options_.plots) {
    const auto& all = plots_.available();
    const auto it =
        std::find_if(all.begin(), all.end(), [&](const Signal& s) { return s.name == name; });
    if (it == all.end()) {
      std::string known;
      for (std::size_t i = 0; i < all.size() && i < 12; ++i) {
        known += (i ? ", " : "") + all[i].name;
      }
      throw Error(fmt::format("viewer: --plot: no signal '{}' (signals: {}{})", name, known,
                              all.size() > 12 ? ", ..." : ""));
    }
    if (!plots_.Choose(static_cast<int>(it - all.begin()), true)) {
      throw Error(fmt::format("viewer: --plot: at most {} signals", Plots::kMaxChosen));
    }
    overlays_.plots = true;
  }
  if (options_.debug_all) {
    for (DebugLayer l :
         {DebugLayer::kContacts, DebugLayer::kCollision, DebugLayer::kJoints, DebugLayer::kSites}) {
      debug_.Global(l) = true;
    }
  }
  panel_ = std::make_unique<Panel>();
  if (!options_.video.empty()) {
    int w = 0, h = 0;
    window_->FramebufferSize(&w, &h);
    video_ = std::make_unique<render::VideoWriter>(options_.video, w, h, options_.video_fps);
  }
  state_ = engine.SubscribeState("viewer");
  // The state before the first step (the engine does not run yet): the first frame drawn, and
  // the first video frame or an --at 0 screenshot.
  engine.WithLockedData([this, &engine](mjModel* m, mjData* d) {
    initial_frame_ = physics::StateFrame::SizedFor(m);
    initial_frame_.CopyFrom(m, d);
    initial_frame_.time = d->time;
    initial_frame_.step = engine.step_count();
  });
  frame_ = &initial_frame_;
  view_->Update(initial_frame_);
  FrameAll();
  if (video_ || !options_.screenshot.empty()) {
    // The simulation waits for each video frame and the screenshot (frame_gate.h).
    gate_ = std::make_shared<FrameGate>();
    if (video_) gate_->StartVideo(engine.step_count(), engine.timestep(), options_.video_fps);
    if (!options_.screenshot.empty()) gate_->StartShot(options_.screenshot_at);
    gate_id_ = engine.AddPreStepCallback([g = gate_, &engine](const mjModel*, mjData* d) {
      g->BeforeStep(engine.step_count(), d->time);
    });
  }
  capture_ = std::make_shared<DebugCapture>();
  capture_id_ =
      engine.AddPostStepCallback([c = capture_](const mjModel* m, mjData* d) { c->Capture(m, d); });
}

void ViewerCore::End() {
  if (!session_) return;
  physics::PhysicsEngine& engine = session_->engine();
  possession_.Release();
  const double seconds = Now();
  if (window_) {
    int w = 0, h = 0;
    window_->FramebufferSize(&w, &h);
    spdlog::info("viewer: {} frames in {:.1f} s ({:.1f} frames/s at {}x{})", frames_drawn_, seconds,
                 seconds > 0 ? static_cast<double>(frames_drawn_) / seconds : 0.0, w, h);
  }
  if (capture_id_) engine.RemoveCallback(capture_id_);
  capture_id_ = 0;
  if (gate_) gate_->Open();  // before the callback goes: the physics thread may be waiting
  if (gate_id_) engine.RemoveCallback(gate_id_);
  gate_id_ = 0;
  if (video_) {
    const int frames = video_->frames();
    const int status = video_->Close();
    if (status == 0) {
      spdlog::info("viewer: video {} ({} frames)", video_->path(), frames);
    } else {
      video_error_ = fmt::format("ffmpeg failed (exit {}) writing {} after {} frames", status,
                                 video_->path(), frames);
      spdlog::error("viewer: {}", video_error_);
    }
    video_.reset();
  }
  panel_.reset();
  view_.reset();  // frees the GPU context while the window's context is current
  window_.reset();
  frame_ = nullptr;
  state_.reset();  // the engine drops it when it is destroyed; nothing reads it any more
  session_.reset();
}

void ViewerCore::BuildTables() {
  const mjModel* m = view_->model();
  const auto& arts = session_->articulations();
  tables_.body_articulation.assign(static_cast<std::size_t>(m->nbody), -1);
  for (int b = 1; b < m->nbody; ++b) {
    const char* name = mj_id2name(m, mjOBJ_BODY, b);
    const world::Articulation* owner = name ? session_->OwnerOf(name) : nullptr;
    int index = owner ? static_cast<int>(owner - arts.data()) : -1;
    if (index < 0) index = tables_.body_articulation[static_cast<std::size_t>(m->body_parentid[b])];
    tables_.body_articulation[static_cast<std::size_t>(b)] = index;
  }
  tables_.prop_geom.assign(static_cast<std::size_t>(m->ngeom), false);
  // Hotkey 5 draws the collision parts of the scene's Quick Convert props.
  for (const world::PropLayout& p : session_->props()) {
    for (int g : p.part_geoms) {
      if (g >= 0 && g < m->ngeom) tables_.prop_geom[static_cast<std::size_t>(g)] = true;
    }
  }
  DebugSettings::Layers own{};
  own[static_cast<std::size_t>(DebugLayer::kVisual)] = true;
  debug_.articulation.assign(arts.size(), own);
  // The orbit camera circles every articulation's root body (its first child of the world).
  std::vector<int> roots;
  for (std::size_t a = 0; a < arts.size(); ++a) {
    for (int b = 1; b < m->nbody; ++b) {
      if (m->body_parentid[b] == 0 &&
          tables_.body_articulation[static_cast<std::size_t>(b)] == static_cast<int>(a)) {
        roots.push_back(b);
        break;
      }
    }
  }
  cinematic_.Configure(CinematicOf(session_->scene_config()), std::move(roots));
}

void ViewerCore::SelectArticulation(int index) {
  if (index >= 0 && static_cast<std::size_t>(index) < session_->articulations().size()) {
    selected_articulation_ = index;
  }
}

double ViewerCore::Now() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void ViewerCore::WindowSize(int* w, int* h) const { window_->WindowSize(w, h); }

WindowRect ViewerCore::ViewportRect() const {
  int w = 0, h = 0;
  window_->WindowSize(&w, &h);
  return layout_.Viewport(static_cast<float>(w), static_cast<float>(h));
}

void ViewerCore::FrameAll() {
  const WindowRect vp = ViewportRect();
  FrameScene(view_->model(), view_->data(), vp.h > 0 ? vp.w / vp.h : 1.0, &view_->camera());
}

bool ViewerCore::stop_requested() const {
  return (window_ && window_->should_close()) || screenshot_done_ || !reload_request_.empty();
}

// ---------------------------------------------------------------------------------------------
// Input

void ViewerCore::Input() {
  if (!window_) return;
  window_->PollEvents();
  possession_.Update();
  input_.Update();
}

void ViewerCore::OnKey(int key, int action, int mods) {
  // Releases always reach the possessed robot (a key let go over the panel must not stick).
  if (action == GLFW_RELEASE && (possession_.OnKey(key, action) || input_.OnKey(key, action))) {
    return;
  }
  if (action != GLFW_PRESS) return;
  if (window_ && window_->imgui_wants_keyboard()) return;
  // With Ctrl or Alt held a key is a command (Ctrl+S, Alt+0), never a driving key.
  const bool command = (mods & (kCtrl | kAlt)) != 0;
  if (!command && (possession_.OnKey(key, action) || input_.OnKey(key, action))) return;
  if (const std::optional<TimelineAction> t = TimelineActionOfKey(key); t && !command) {
    if (PerformTimeline(*t)) return;
  }
  if (const Hotkey* h = FindHotkey(key, mods)) {
    Perform(h->action);
    return;
  }
  const int held = mods & (kShift | kCtrl | kAlt);
  // Alt + 0-5: geom group; Alt + Shift + 0-5: site group (simulate's 0-5 and Shift + 0-5).
  if ((held == kAlt || held == (kAlt | kShift)) && key >= GLFW_KEY_0 &&
      key < GLFW_KEY_0 + mjNGROUP) {
    mjtByte* groups = held == kAlt ? view_->option().geomgroup : view_->option().sitegroup;
    const int g = key - GLFW_KEY_0;
    groups[g] = !groups[g];
    SetStatus(fmt::format("{} group {} {}", held == kAlt ? "geom" : "site", g,
                          groups[g] ? "shown" : "hidden"));
    return;
  }
  // Shift + a letter: the visualisation flag with that shortcut in MuJoCo's mjVISSTRING.
  if (held == kShift && key >= GLFW_KEY_A && key <= GLFW_KEY_Z) {
    const char letter = static_cast<char>('A' + (key - GLFW_KEY_A));
    for (int i = 0; i < mjNVISFLAG; ++i) {
      if (mjVISSTRING[i][2][0] == letter && mjVISSTRING[i][2][1] == 0) {
        mjtByte& f = view_->option().flags[i];
        f = !f;
        SetStatus(fmt::format("{} {}", mjVISSTRING[i][0], f ? "on" : "off"));
        return;
      }
    }
  }
}

bool ViewerCore::replay_mode() const {
  return playback_ && playback_->With([](const replay::Playback* p) { return p != nullptr; });
}

bool ViewerCore::PerformTimeline(TimelineAction action) {
  if (!playback_) return false;
  return playback_->With([action](const replay::Playback* p) {
    if (!p) return false;
    const std::string what = Timeline::Perform(*p, action);
    if (!what.empty()) spdlog::info("viewer: {}", what);
    return true;
  });
}

void ViewerCore::OnMouseButton(int button, int action, int mods) {
  const WindowRect vp = ViewportRect();
  if (action == GLFW_PRESS &&
      ((window_ && window_->imgui_wants_mouse()) || !vp.Contains(cursor_x_, cursor_y_))) {
    return;
  }
  // Viewport coordinates: the camera and selection see the viewport, not the window.
  mouse_.Button(*view_, button, action, mods, cursor_x_ - vp.x, cursor_y_ - vp.y,
                static_cast<int>(vp.w), static_cast<int>(vp.h), Now());
}

void ViewerCore::OnCursor(double x, double y) {
  cursor_x_ = x;
  cursor_y_ = y;
  const WindowRect vp = ViewportRect();
  mouse_.Move(*view_, x - vp.x, y - vp.y, static_cast<int>(vp.w), static_cast<int>(vp.h));
}

void ViewerCore::OnScroll(double /*dx*/, double dy) {
  if (window_ && window_->imgui_wants_mouse()) return;
  mouse_.Scroll(*view_, dy);
}

void ViewerCore::Perform(Action action) {
  if (const std::optional<DebugLayer> layer = LayerOf(action)) {
    bool& on = debug_.Global(*layer);
    on = !on;
    spdlog::info("viewer: {} {}", DebugLayerName(*layer), on ? "on" : "off");
    return;
  }
  physics::PhysicsEngine& engine = session_->engine();
  switch (action) {
    case Action::kTogglePause:  // in replay mode the replay pauses (the engine runs the player)
      if (!PerformTimeline(TimelineAction::kPlayPause))
        ops::SetPaused(*session_, !engine.paused(), ops::When::kNow);
      break;
    case Action::kReset:
      ops::Reset(*session_, {});
      break;
    case Action::kScreenshot: {
      const std::time_t t = std::time(nullptr);
      char stamp[32];
      std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&t));
      RequestScreenshot(fmt::format("urlab-{}.png", stamp));
      break;
    }
    case Action::kFreeCamera:
      if (possession_.active()) TogglePossess();
      cinematic_.Stop();
      camera_ = -1;
      view_->camera().type = mjCAMERA_FREE;
      break;
    case Action::kTogglePossess:
      TogglePossess();
      break;
    case Action::kTogglePanel:
      layout_.SetCollapsed(!layout_.collapsed());
      break;
    case Action::kStep:
      Step();
      break;
    case Action::kNextCamera:
    case Action::kPrevCamera: {
      const int n = view_->model()->ncam + 1;  // the free camera, then the model's
      const int delta = action == Action::kNextCamera ? 1 : n - 1;
      SetCamera((camera_ + 1 + delta) % n - 1);
      const char* name = camera_ >= 0 ? mj_id2name(view_->model(), mjOBJ_CAMERA, camera_) : nullptr;
      SetStatus(camera_ < 0 ? std::string("free camera")
                            : fmt::format("camera {} ({})", camera_, name ? name : "unnamed"));
      break;
    }
    case Action::kToggleHelp:
      overlays_.help = !overlays_.help;
      break;
    case Action::kToggleInfo:
      overlays_.info = !overlays_.info;
      break;
    case Action::kToggleProfiler:
      overlays_.profiler = !overlays_.profiler;
      break;
    case Action::kTogglePlots:
      overlays_.plots = !overlays_.plots;
      break;
    case Action::kSaveXml:
    case Action::kSaveMjb:
    case Action::kPrintModel:
    case Action::kPrintData:
      try {
        if (action == Action::kSaveXml) SaveXml();
        if (action == Action::kSaveMjb) SaveMjb();
        if (action == Action::kPrintModel) PrintModel();
        if (action == Action::kPrintData) PrintData();
      } catch (const Error& e) {
        SetStatus(e.what());
      }
      break;
    case Action::kReload:
      ReloadKeepingState();
      break;
    case Action::kLoadKey:
      LoadKey();
      break;
    case Action::kSaveKey:
      SaveKey();
      break;
    case Action::kCopyPose:
      CopyPose();
      break;
    case Action::kFrameScene:
      if (possession_.active()) TogglePossess();
      cinematic_.Stop();
      FrameAll();
      break;
    case Action::kToggleCinematic: {
      const CinematicMode mode = cinematic_.Next();
      if (mode != CinematicMode::kOff && possession_.active()) TogglePossess();
      if (mode == CinematicMode::kOff) view_->camera().type = mjCAMERA_FREE;
      spdlog::info("viewer: cinematic camera {}", ToString(mode));
      break;
    }
    case Action::kFireLaunchers: {  // every launcher once
      if (session_->launchers().empty()) spdlog::info("viewer: this scene has no launchers");
      for (const world::LauncherLayout& l : session_->launchers())
        ops::FireLauncher(*session_, l.name);
      break;
    }
    default:
      break;
  }
}

void ViewerCore::TogglePossess() {
  if (possession_.active()) {
    const std::string name =
        session_->articulations()[static_cast<std::size_t>(possession_.articulation())].name();
    possession_.Release();
    view_->camera().type = mjCAMERA_FREE;
    spdlog::info("viewer: released '{}'", name);
    return;
  }
  cinematic_.Stop();  // the chase camera takes over
  const world::Articulation& art =
      session_->articulations()[static_cast<std::size_t>(selected_articulation_)];
  control::TwistController* twist = art.control->twist();
  const std::string why = WhyNotPossessable(view_->model(), twist, art.control->num_actuators());
  if (!twist || !why.empty()) {
    SetStatus(fmt::format("'{}': {}", art.name(), why));
    return;
  }
  possession_.Possess(selected_articulation_, twist);
  const control::TwistSettings& s = twist->settings();
  spdlog::info(
      "viewer: possessing '{}' (W/S, A/D, Q/E or a gamepad; 0-9 actions; max {} m/s, {} m/s, {} "
      "rad/s)",
      art.name(), s.max_vx, s.max_vy, s.max_yaw_rate);
}

void ViewerCore::SetOptions(const ops::OptionsChange& change) {
  try {
    ops::SetOptions(*session_, change);
  } catch (const ops::OpError& e) {
    SetStatus(e.what());
    return;
  }
  ops::ApplyOptions(change, view_->model()->opt);
}

void ViewerCore::SetOptions(std::function<void(mjOption&)> fn, std::string label) {
  fn(view_->model()->opt);
  session_->engine().Submit(physics::cmd::SetOptions{std::move(fn), std::move(label)});
}

// ---------------------------------------------------------------------------------------------
// Drawing

void ViewerCore::ApplyPerturbation() {
  mjvPerturb& pert = view_->perturb();
  const auto now = Clock::now();
  const double dt =
      std::min(std::chrono::duration<double>(now - last_present_).count(), kMaxPerturbSeconds);
  last_present_ = now;
  if (!pert.active || pert.select <= 0) return;
  const mjModel* m = view_->model();
  mjData* d = view_->data();
  mjtNum* row = d->xfrc_applied + 6 * pert.select;
  mju_zero(row, 6);
  mjv_applyPerturbForce(m, d, &pert);
  physics::cmd::ApplyForce force;
  force.body = pert.select;
  std::copy_n(row, 3, force.force.begin());
  std::copy_n(row + 3, 3, force.torque.begin());
  const double timestep = session_->engine().timestep();
  force.steps = std::max(1, static_cast<int>(std::ceil(dt / timestep)));
  try {
    session_->engine().Submit(std::move(force));
  } catch (const Error& e) {
    spdlog::warn("viewer: perturbation not applied: {}", e.what());
  }
}

bool ViewerCore::TakeNewModelValues() {
  // The model's values changed (an edit, a reload keeping the state). They are copied on the
  // physics thread by a command, not under WithLockedData here: the physics thread may be
  // waiting for this thread to draw a video frame (frame_gate.h) with the step mutex held.
  physics::PhysicsEngine& engine = session_->engine();
  if (const std::uint64_t g = engine.model_generation(); g != model_generation_ && !model_copy_) {
    model_generation_ = g;
    if (!model_staging_) {
      model_staging_ = std::make_shared<physics::Model>(
          physics::ModelPtr(mj_copyModel(nullptr, view_->model())));
      if (!*model_staging_) throw Error("viewer: cannot copy the model");
    }
    model_copy_ = engine.Submit(
        physics::cmd::Inspect{[staging = model_staging_](const mjModel* m, const mjData*) {
                                physics::CopyModelValuesInPlace(staging->get(), m);
                              },
                              "viewer: the model's new values"});
  }
  if (!model_copy_ || engine.last_applied_command() < model_copy_) return false;
  model_copy_ = 0;
  view_->ReplaceModelValues(model_staging_->get());
  SeparateCoplanarPlanes(view_->model());
  return true;
}

void ViewerCore::Present() {
  if (!window_) return;
  if (!lowered_) {
    // The first frame runs after the physics thread started (Manager::BeginPlay starts it after
    // every subsystem began): from now on this thread draws at a lower priority, so that on a
    // machine with few cores a slow frame takes time from the viewer, not from the physics.
    lowered_ = true;
    LowerRenderThreadPriority();
  }
  const bool refresh = TakeNewModelValues();
  if (state_->has_new() || !frame_ || refresh) {
    frame_ = state_->Latest();
    if (frame_) view_->Update(*frame_);
  }
  if (frame_) plots_.Sample(*frame_);
  capture_->Take(&contacts_);
  bool want_contacts = debug_.Global(DebugLayer::kContacts);
  for (const auto& own : debug_.articulation) {
    want_contacts = want_contacts || own[static_cast<std::size_t>(DebugLayer::kContacts)];
  }
  // The last capture stays (drawing filters it by the toggles): turning contacts on shows them
  // at once, refreshed from the next capture.
  if (want_contacts) capture_->Request();
  // Contact points and forces lie inside the bodies touching: moving bodies turn translucent
  // while they are drawn (MuJoCo's own transparency flag).
  if (want_contacts != transparent_for_contacts_) {  // the flag stays the user's otherwise
    view_->option().flags[mjVIS_TRANSPARENT] = want_contacts;
    transparent_for_contacts_ = want_contacts;
  }
  ApplyPerturbation();
  possession_.UpdateCamera(view_->data(), &view_->camera());
  cinematic_.Apply(view_->model(), view_->data(), frame_ ? frame_->time : 0.0, &view_->camera());
  view_->UpdateScene();
  HideVisualGeoms(view_->model(), debug_, tables_, &view_->scene());
  AddDebugGeoms(view_->model(), view_->data(), debug_, tables_, contacts_, &view_->scene());
  int w = 0, h = 0, ww = 0, wh = 0;
  window_->FramebufferSize(&w, &h);
  window_->WindowSize(&ww, &wh);
  const bool imgui = window_->has_imgui();
  if (imgui) {
    // The panel first: a splitter dragged this frame moves the viewport drawn this frame.
    window_->BeginImGui();
    panel_->Draw(*this);
    if (playback_) {
      const WindowRect vp = ViewportRect();
      playback_->With([&](const replay::Playback* p) {
        if (!p) return;
        timeline_.Draw(*p, vp.x, static_cast<float>(wh) - Timeline::kHeight,
                       std::max(200.0f, vp.w));
      });
    }
  }
  window_->Clear(0.11f, 0.12f, 0.14f);
  last_viewport_ = ToFramebuffer(ViewportRect(), ww, wh, w, h);
  view_->Render(last_viewport_, quality_.scale,
                view_->scene().flags[mjRND_SKYBOX] && !HasSkyboxTexture(view_->model()));
  DrawOverlays(last_viewport_);
  if (imgui) window_->EndImGui();
  if (gate_ && !screenshot_done_ && frame_ && gate_->ShotDue(frame_->time) &&
      pending_screenshot_.empty()) {
    pending_screenshot_ = options_.screenshot;
  }
  Capture();
  if (keep_frame_) {
    pixels_.resize(static_cast<std::size_t>(3 * w * h));
    view_->ReadPixels(w, h, pixels_.data());
    kept_ = FromBottomUp(w, h, pixels_.data());
  }
  window_->SwapBuffers();
  ++frames_drawn_;
  ++fps_window_frames_;
  const auto now = Clock::now();
  const double window = std::chrono::duration<double>(now - fps_window_start_).count();
  if (window >= 1.0) {
    fps_ = static_cast<double>(fps_window_frames_) / window;
    fps_window_frames_ = 0;
    fps_window_start_ = now;
  }
}

void ViewerCore::Capture() {
  // Video frames are due by simulated time (the gate holds the physics thread until they are
  // written), never by wall time.
  const int video_due = video_ && gate_ && frame_ ? gate_->VideoFramesDue(frame_->step) : 0;
  if (pending_screenshot_.empty() && video_due == 0) return;
  int w = 0, h = 0;
  window_->FramebufferSize(&w, &h);
  pixels_.resize(static_cast<std::size_t>(3 * w * h));
  view_->ReadPixels(w, h, pixels_.data());
  if (!pending_screenshot_.empty()) {
    const std::string path = std::move(pending_screenshot_);
    pending_screenshot_.clear();
    try {
      WritePng(path, FromBottomUp(w, h, pixels_.data()));
      last_screenshot_ = path;
      spdlog::info("viewer: screenshot {} ({}x{}, t={:.3f} s)", path, w, h,
                   frame_ ? frame_->time : 0.0);
    } catch (const Error& e) {
      spdlog::error("viewer: {}", e.what());
    }
    if (path == options_.screenshot) {
      screenshot_done_ = true;
      if (gate_) gate_->ShotTaken();
    }
  }
  if (video_due > 0) {
    for (int i = 0; i < video_due; ++i) video_->Write(pixels_.data());
    gate_->VideoWritten(frame_->step);
  }
}

Image ViewerCore::ReadPixels() {
  // The back buffer is undefined after a swap: draw the frame again and keep it before swapping.
  keep_frame_ = true;
  Present();
  keep_frame_ = false;
  return std::move(kept_);
}

}  // namespace urlab::viewer::internal
