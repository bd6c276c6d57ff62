#pragma once
// ViewerCore: the viewer subsystem's implementation. It owns the window, the viewer's own model
// and data (SceneView), the debug capture and settings, the mouse control and the panel's state;
// it turns input into commands for the physics thread and draws each frame from the newest state
// frame of its own subscription.
//
// Threading contract
// - Main thread: everything here (construction, Begin, Input, Present, End, the InputHandler
//   events, Perform and the accessors).
// - Physics thread: only the DebugCapture's post-step callback (debug_capture.h) and, with
//   --video or --screenshot, the FrameGate's pre-step wait (frame_gate.h).
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "render/video_writer.h"
#include "urlab/ops/state.h"
#include "urlab/physics/engine.h"
#include "urlab/replay/playback.h"
#include "urlab/viewer/viewer.h"
#include "urlab/world/session.h"
#include "viewer/cinematic.h"
#include "viewer/debug_capture.h"
#include "viewer/debug_draw.h"
#include "viewer/frame_gate.h"
#include "viewer/hotkeys.h"
#include "viewer/image_io.h"
#include "viewer/input_mapping.h"
#include "viewer/layout.h"
#include "viewer/mouse.h"
#include "viewer/plots.h"
#include "viewer/possess.h"
#include "viewer/profiler.h"
#include "viewer/render_quality.h"
#include "viewer/scene_view.h"
#include "viewer/timeline.h"
#include "viewer/window.h"

namespace urlab::world {
class Manager;
}

namespace urlab::viewer::internal {

class Panel;

class ViewerCore : public InputHandler {
 public:
  ViewerCore(ViewerOptions options, const world::Manager* manager,
             std::shared_ptr<replay::PlaybackSlot> playback = nullptr);
  ~ViewerCore() override;

  // Subsystem hooks (see ViewerSubsystem).
  void Begin(world::Session& session);
  void Input();
  void Present();
  void End();

  // Window events (GLFW codes); tests call them to inject input.
  void OnKey(int key, int action, int mods) override;
  void OnMouseButton(int button, int action, int mods) override;
  void OnCursor(double x, double y) override;
  void OnScroll(double dx, double dy) override;
  // Does what a hotkey does.
  void Perform(Action action);
  // Does a replay timeline action; false when no replay plays (replay mode is off).
  bool PerformTimeline(TimelineAction action);
  // True while a replay plays through the slot the viewer was given.
  bool replay_mode() const;
  // The help overlay's two columns (keys, what they do); a replay's timeline keys first.
  std::pair<std::string, std::string> HelpText() const;
  Timeline& timeline() { return timeline_; }

  // ---- State (main thread) ----
  bool stop_requested() const;
  // Draws a frame (as Present does) and returns it as the window shows it.
  Image ReadPixels();
  SceneView& view() { return *view_; }
  Window& window() { return *window_; }
  // The simulate panel, nullptr without one (ViewerOptions::panel off).
  Panel* panel() { return window_ && window_->has_imgui() ? panel_.get() : nullptr; }
  world::Session& session() { return *session_; }
  DebugSettings& debug() { return debug_; }
  const DebugTables& tables() const { return tables_; }
  DebugCapture& capture() { return *capture_; }
  const std::vector<CapturedContact>& contacts() const { return contacts_; }
  const physics::StateFrame* frame() const { return frame_; }
  const world::Manager* manager() const { return manager_; }
  // The recorder the panel drives (nullptr: none). Main thread, before Begin.
  void SetRecorder(replay::RecorderSubsystem* recorder) { recorder_ = recorder; }
  replay::RecorderSubsystem* recorder() const { return recorder_; }
  // Frames drawn, and the frame rate over the last second.
  std::uint64_t frames_drawn() const { return frames_drawn_; }
  // After End: why the video is not complete (ffmpeg failed), "" when it is or there is none.
  const std::string& video_error() const { return video_error_; }
  double fps() const { return fps_; }
  // The articulation the panel shows (index into session().articulations()).
  int selected_articulation() const { return selected_articulation_; }
  void SelectArticulation(int index);
  // Possession of the selected articulation (Tab, the panel's Possess button).
  const Possession& possession() const { return possession_; }
  // The cinematic camera (O).
  const Cinematic& cinematic() const { return cinematic_; }
  // The window's size in screen coordinates (input events use them).
  void WindowSize(int* w, int* h) const;
  // Takes a screenshot of the next drawn frame into `path`.
  void RequestScreenshot(std::string path) { pending_screenshot_ = std::move(path); }
  const std::string& last_screenshot() const { return last_screenshot_; }
  // Applies physics options to the simulation (a queued command) and to the viewer's copy.
  void SetOptions(std::function<void(mjOption&)> fn, std::string label);
  // The options the step server's set_sim_options changes, through the same operation (its
  // checks; a refusal becomes the status line and changes nothing).
  void SetOptions(const ops::OptionsChange& change);
  // Seconds since Begin (the clock double-clicks use).
  double Now() const;

  // Where the panel and the 3D viewport are (layout.h); the panel's splitter changes it.
  Layout& layout() { return layout_; }
  // The 3D viewport in window coordinates, and in framebuffer pixels as last drawn.
  WindowRect ViewportRect() const;
  const mjrRect& last_viewport() const { return last_viewport_; }
  // Render quality in effect (the panel's Rendering section changes the scene's flags).
  RenderQuality& quality() { return quality_; }
  // Points the free camera at the whole scene (the default camera).
  void FrameAll();

  // ---- What MuJoCo's simulate offers (viewer_tools.cc) ----
  struct Overlays {
    bool help = false, info = false, profiler = false, plots = false;
  };
  Overlays& overlays() { return overlays_; }
  Plots& plots() { return plots_; }
  Profiler& profiler() { return profiler_; }
  // The model camera in use (-1: the free camera); [ and ] cycle through them.
  int camera() const { return camera_; }
  void SetCamera(int id);
  // The model keyframe that Load key, Save key act on.
  int key() const { return key_; }
  void SetKey(int k);
  // What the last file or tool action did (the panel's status line).
  const std::string& status() const { return status_; }
  // Turns one of MuJoCo's physics flags on or off (mjtDisableBit / mjtEnableBit index `i`): a
  // SetOptions command, as the panel and the Physics menu do it.
  void SetDisableFlag(int i, bool disabled);
  void SetEnableFlag(int i, bool enabled);
  // One physics step, while paused (a queued Step command).
  void Step();
  // Files, written by the output rule into ViewerOptions::files_dir; each returns the path and
  // says so in the status line (throws Error when it cannot write).
  std::string SaveXml();     // the composed scene's MJCF as compiled
  std::string SaveMjb();     // the running model (options changed at run time included)
  std::string PrintModel();  // mj_printModel of the running model
  std::string PrintData();   // mj_printData of the viewer's copy of the newest state
  // The current state as a <key> element: on the clipboard and returned.
  std::string CopyPose();
  // Puts keyframe key() into the simulation (qpos, qvel, ctrl, time, mocap poses: queued
  // commands) / stores the current state into it (the viewer's copy of the model, which Save
  // XML/MJB do not write: they save the compiled scene).
  void LoadKey();
  void SaveKey();
  // Ends play so that the host plays `path` (reload: the scene's own file).
  void RequestReload(std::string path);
  // Reload (Ctrl+L): the scene's files read again into the running model keeping the state
  // (world::Session::ReloadKeepingState); when that cannot be, or while a replay plays,
  // RequestReload("") (a restart).
  void ReloadKeepingState();
  const std::string& reload_request() const { return reload_request_; }
  void OnDrop(const std::vector<std::string>& paths) override;

 private:
  // Present: the engine's model values into view_ once they changed; true when they were taken.
  bool TakeNewModelValues();
  void BuildTables();
  void ApplyPerturbation();
  void TogglePossess();
  void Capture();  // screenshots and video frames of the frame just drawn
  void DrawOverlays(const mjrRect& viewport);  // help, info, profiler, plots (viewer_tools.cc)
  std::string OutputPath(const std::string& name) const;
  void SetStatus(std::string text);

  ViewerOptions options_;
  Layout layout_;
  RenderQuality quality_;
  mjrRect last_viewport_ = {0, 0, 0, 0};
  const world::Manager* manager_;
  replay::RecorderSubsystem* recorder_ = nullptr;
  std::shared_ptr<world::Session> session_;
  std::unique_ptr<Window> window_;
  std::unique_ptr<SceneView> view_;
  std::unique_ptr<Panel> panel_;
  std::shared_ptr<physics::StateSubscription> state_;
  const physics::StateFrame* frame_ = nullptr;
  std::shared_ptr<DebugCapture> capture_;
  physics::PhysicsEngine::CallbackId capture_id_ = 0;
  DebugSettings debug_;
  DebugTables tables_;
  std::vector<CapturedContact> contacts_;
  MouseControl mouse_;
  Possession possession_;
  Cinematic cinematic_;
  InputMapping input_;
  double cursor_x_ = 0, cursor_y_ = 0;
  int selected_articulation_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_present_;
  std::chrono::steady_clock::time_point fps_window_start_;
  std::uint64_t fps_window_frames_ = 0;
  std::uint64_t frames_drawn_ = 0;
  double fps_ = 0;
  std::string pending_screenshot_;
  std::string last_screenshot_;
  bool screenshot_done_ = false;
  bool lowered_ = false;  // the main thread's priority was lowered (first Present)
  std::shared_ptr<replay::PlaybackSlot> playback_;  // replay mode (null: never)
  Timeline timeline_;
  std::unique_ptr<render::VideoWriter> video_;
  std::string video_error_;
  // Holds the physics thread for each video frame and the screenshot (null without either).
  std::shared_ptr<FrameGate> gate_;
  physics::PhysicsEngine::CallbackId gate_id_ = 0;
  // The engine's model generation view_'s values were asked for, the command copying them into
  // model_staging_ (0: none pending) and that copy (TakeNewModelValues).
  std::uint64_t model_generation_ = 0;
  std::uint64_t model_copy_ = 0;
  std::shared_ptr<physics::Model> model_staging_;
  physics::StateFrame initial_frame_;  // the state before the first step, drawn until one comes
  std::vector<std::uint8_t> pixels_;   // scratch for read-backs
  bool keep_frame_ = false;            // ReadPixels: keep the frame being drawn in kept_
  Image kept_;
  Overlays overlays_;
  Plots plots_;
  Profiler profiler_;
  int camera_ = -1;
  int key_ = 0;
  std::string status_;
  std::string reload_request_;
  bool transparent_for_contacts_ = false;  // mjVIS_TRANSPARENT set for the contact layer
};

}  // namespace urlab::viewer::internal
