#pragma once
// Mouse camera and perturbation, as MuJoCo's simulate does them: left drag rotates the camera
// (Shift: about the vertical), right drag moves it (Shift: horizontally), middle drag or the
// wheel zooms; double-click left selects the body under the cursor, double-click right looks at
// the point under the cursor, Ctrl + double-click right tracks the body under it; with a body
// selected, Ctrl + left drag rotates and Ctrl + right drag pulls it (the perturbation, whose
// force the viewer sends to the physics thread).
//
// Threading contract: main thread only.
#include "viewer/scene_view.h"

namespace urlab::viewer::internal {

class MouseControl {
 public:
  // A button press or release at window position (x, y) of a window_w x window_h window; `now`
  // in seconds (double-clicks are two presses within kDoubleClick).
  void Button(SceneView& view, int button, int action, int mods, double x, double y, int window_w,
              int window_h, double now);
  void Move(SceneView& view, double x, double y, int window_w, int window_h);
  void Scroll(SceneView& view, double dy);
  // The body under window position (x, y), 0 for none (the world); *point receives the 3D point.
  static int BodyAt(SceneView& view, double x, double y, int window_w, int window_h,
                    mjtNum point[3]);
  bool dragging() const { return left_ || right_ || middle_; }

  static constexpr double kDoubleClick = 0.3;

 private:
  bool left_ = false, right_ = false, middle_ = false;
  bool shift_ = false;
  double last_x_ = 0, last_y_ = 0;
  double last_press_[3] = {-1, -1, -1};
};

}  // namespace urlab::viewer::internal
