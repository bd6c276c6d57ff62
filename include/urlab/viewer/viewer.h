#pragma once
// ViewerSubsystem: the desktop window of a running world (the description's MjSimulate widget,
// UMjDebugVisualizer and UMjInputHandler): MuJoCo's renderer in a GLFW window with a Dear ImGui
// simulate panel, debug drawing, hotkeys, mouse camera and perturbation. It renders from its own
// copy of the model and its own mjData, filled from a state subscription (never live mjData), so
// a slow frame never slows the physics thread; everything it asks of the simulation (pause,
// reset, keyframes, perturbation forces, options) goes to the physics thread as queued commands,
// and the panel's sliders publish command frames on the UI control source.
//
// Threading contract
// - Main thread (GLFW requires it): construction, the Subsystem hooks, SetManager, the test
//   accessors (ReadPixels, core()). The window's events are polled in the kInput phase and the
//   frame is drawn in kPresent.
// - Physics thread: the debug capture's post-step callback (registered in BeginPlay, removed in
//   EndPlay), which copies contacts into the viewer's own buffer under its own mutex.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "urlab/world/subsystem.h"

namespace urlab::world {
class Manager;
}
namespace urlab::replay {
class PlaybackSlot;
class RecorderSubsystem;
}  // namespace urlab::replay

namespace urlab::viewer {

namespace internal {
class ViewerCore;
}

struct ViewerOptions {
  int width = 1280;  // window size in screen pixels
  int height = 720;
  std::string title = "URLab";
  bool panel = true;  // the simulate panel (ImGui)
  // Take a PNG of the window when the simulation time reaches `screenshot_at` seconds, then ask
  // the host to stop (RequestsStop). "" : none.
  std::string screenshot;
  double screenshot_at = 0;
  // Turn on debug drawing at start: contact forces, collision wireframes, joint axes, sites.
  bool debug_all = false;
  // Record the window to this video file (.mp4 or .webm) through ffmpeg. "" : none.
  std::string video;
  int video_fps = 30;
  // Render quality; unset: the scene's `viewer:` section, else the viewer's defaults (shadows,
  // reflections and the sky on, scale 1).
  std::optional<bool> shadows, reflections, skybox;
  std::optional<double> render_scale;  // 0.25 to 2: 3D view pixels per window pixel
  // Signals plotted from the start (F4 shows them): joint names, "SENSOR" or "SENSOR[k]", and
  // "ACTUATOR force", as the panel's Plots section lists them; an unknown name is an error.
  std::vector<std::string> plots;
  // Folder for the files the viewer writes (save XML/MJB, print model/data); "" : the working
  // folder.
  std::string files_dir;
  // Why Reload (Ctrl+L) may not bring the file's values into the running simulation keeping its
  // state ("": it may; e.g. a run of several environments, whose batch keeps its own model):
  // then it restarts the scene, saying this.
  std::string reload_restarts_because;
};

// RGB pixels, rows top-down.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  const std::uint8_t* at(int x, int y) const { return &rgb[3 * (y * width + x)]; }
};

class ViewerSubsystem : public world::Subsystem {
 public:
  explicit ViewerSubsystem(ViewerOptions options = {});
  ~ViewerSubsystem() override;

  std::string_view name() const override { return "viewer"; }
  // Opens the window (throws Error when no display or no OpenGL context is available), copies the
  // model, subscribes to state, registers the debug capture.
  void BeginPlay(world::Session& session) override;
  void Tick(world::Session& session, world::TickPhase phase) override;
  void EndPlay(world::Session& session) override;
  std::vector<world::StatusLine> Status() const override;
  // The window was closed, or the screenshot was taken.
  bool RequestsStop() const override;

  // A scene the user asked to open instead (reload, or a file dropped on the window): the
  // host ends play and plays this file ("" when none). Main thread.
  const std::string& reload_request() const { return reload_request_; }

  // After EndPlay: why the --video file is not complete ("" when it is, or there is none), for the
  // command's exit code. Main thread.
  const std::string& video_error() const { return video_error_; }

  // The manager whose other subsystems the panel shows (their Status).
  // Main thread, before BeginPlay; optional.
  void SetManager(const world::Manager* manager) { manager_ = manager; }
  // The recorder the panel's Record and Stop recording drive (nullptr: none; the panel says so).
  // Main thread, before BeginPlay; optional.
  void SetRecorder(replay::RecorderSubsystem* recorder) { recorder_ = recorder; }
  // Replay mode: while the slot holds a playback (the step server's replay_start, `urlab replay
  // --view`), the viewer shows the replay timeline and its keys drive the player; P pauses the
  // replay. Main thread, before BeginPlay; optional.
  void SetPlayback(std::shared_ptr<replay::PlaybackSlot> slot) { playback_ = std::move(slot); }

  // The last drawn frame as the window shows it (scene and panel). Main thread, while playing.
  Image ReadPixels();
  // The implementation, for tests that inject input events and read its state. Main thread.
  internal::ViewerCore& core();

 private:
  ViewerOptions options_;
  const world::Manager* manager_ = nullptr;
  replay::RecorderSubsystem* recorder_ = nullptr;
  std::shared_ptr<replay::PlaybackSlot> playback_;
  std::unique_ptr<internal::ViewerCore> core_;
  std::string video_error_;
  std::string reload_request_;
};

}  // namespace urlab::viewer
