#pragma once
// Panel: the simulate panel (the description's WBP_MjSimulate) drawn with Dear ImGui: the
// simulation's state and speed, physics options, the selected articulation's control source,
// actuator sliders (locked, showing the received values, while the network drives it), joint
// and sensor readouts, keyframes (Reset, Hold, Stop), debug drawing toggles (global and per
// articulation), recording and snapshots, the other subsystems' status, and the hotkeys. It
// reads the viewer's own copy of the state, never live mjData, and acts through commands and
// the UI control source's command frames.
//
// Threading contract: main thread only, between Window::BeginImGui and EndImGui.
#include <optional>
#include <string>
#include <vector>

#include "urlab/physics/state.h"

namespace urlab::viewer::internal {

class ViewerCore;

class Panel {
 public:
  // Draws the panel docked at the window's left edge (ViewerCore::layout()), the splitter right
  // of it (drag: the panel's width) or, collapsed, a strip with a button that opens it again.
  void Draw(ViewerCore& core);
  // Where each actuator slider of the selected articulation was last drawn (window
  // coordinates: the slider's frame from x0 to x1, without its label, at height y), for tests
  // that drag them.
  struct SliderRect {
    float x0 = 0, x1 = 0, y = 0;
  };
  const std::vector<SliderRect>& sliders() const { return sliders_; }
  // The centre of each launcher's Fire button as last drawn (window coordinates), for tests.
  struct Point {
    float x = 0, y = 0;
  };
  const std::vector<Point>& fire_buttons() const { return fire_buttons_; }

 private:
  void DrawSplitter(ViewerCore& core, float window_w, float window_h);
  void DrawSimulation(ViewerCore& core);
  void DrawLaunchers(ViewerCore& core);
  void DrawOptions(ViewerCore& core);
  void DrawArticulation(ViewerCore& core);
  void DrawDebug(ViewerCore& core);
  void DrawRendering(ViewerCore& core);
  void DrawRecording(ViewerCore& core);
  void DrawSubsystems(ViewerCore& core);
  void DrawHelp(ViewerCore& core);
  // simulate's sections (panel_simulate.cc).
  void DrawMenuBar(ViewerCore& core);
  void DrawFileAndKeys(ViewerCore& core);
  void DrawCameras(ViewerCore& core);
  void DrawVisualisation(ViewerCore& core);
  void DrawGroups(ViewerCore& core);
  void DrawPhysicsFlags(ViewerCore& core);
  void DrawPlotChoice(ViewerCore& core);

  int keyframe_ = 0;
  std::optional<physics::PhysicsState> snapshot_;
  std::string record_path_ = "viewer.urrec";
  std::string message_;
  std::vector<SliderRect> sliders_;
  std::vector<Point> fire_buttons_;
};

}  // namespace urlab::viewer::internal
