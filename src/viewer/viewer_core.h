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
#include <vector>

#include "render/video_writer.h"
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
#include "viewer/mouse.h"
#include "viewer/possess.h"
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
  // Seconds since Begin (the clock double-clicks use).
  double Now() const;

 private:
  void BuildTables();
  void ApplyPerturbation();
  void TogglePossess();
  void Capture();  // screenshots and video frames of the frame just drawn

  ViewerOptions options_;
  const world::Manager* manager_;
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
  physics::StateFrame initial_frame_;  // the state before the first step, drawn until one comes
  std::vector<std::uint8_t> pixels_;   // scratch for read-backs
  bool keep_frame_ = false;            // ReadPixels: keep the frame being drawn in kept_
  Image kept_;
};

}  // namespace urlab::viewer::internal
