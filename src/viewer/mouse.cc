#include "viewer/mouse.h"

#include <GLFW/glfw3.h>

namespace urlab::viewer::internal {

int MouseControl::BodyAt(SceneView& view, double x, double y, int window_w, int window_h,
                         mjtNum point[3]) {
  if (window_w <= 0 || window_h <= 0) return 0;
  int geom = -1, flex = -1, skin = -1;
  const int body = mjv_select(view.model(), view.data(), &view.option(),
                              static_cast<mjtNum>(window_w) / window_h, x / window_w,
                              (window_h - y) / window_h, &view.scene(), point, &geom, &flex, &skin);
  return body < 0 ? 0 : body;
}

void MouseControl::Button(SceneView& view, int button, int action, int mods, double x, double y,
                          int window_w, int window_h, double now) {
  const bool press = action == GLFW_PRESS;
  shift_ = (mods & GLFW_MOD_SHIFT) != 0;
  const bool ctrl = (mods & GLFW_MOD_CONTROL) != 0;
  if (button == GLFW_MOUSE_BUTTON_LEFT) left_ = press;
  if (button == GLFW_MOUSE_BUTTON_RIGHT) right_ = press;
  if (button == GLFW_MOUSE_BUTTON_MIDDLE) middle_ = press;
  last_x_ = x;
  last_y_ = y;
  mjvPerturb& pert = view.perturb();
  if (!press) {
    if (!left_ && !right_) pert.active = 0;
    return;
  }
  if (button < 0 || button > 2) return;
  const bool double_click = last_press_[button] >= 0 && now - last_press_[button] < kDoubleClick;
  last_press_[button] = double_click ? -1 : now;
  if (double_click) {
    mjtNum point[3] = {0, 0, 0};
    const int body = BodyAt(view, x, y, window_w, window_h, point);
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
      pert.select = body;
      pert.skinselect = -1;
      pert.active = 0;
      if (body > 0) {
        mjtNum local[3], diff[3];
        const mjData* d = view.data();
        mju_sub3(diff, point, d->xpos + 3 * body);
        mju_mulMatTVec(local, d->xmat + 9 * body, diff, 3, 3);
        mju_copy3(pert.localpos, local);
      }
    } else if (button == GLFW_MOUSE_BUTTON_RIGHT && body > 0) {
      mjvCamera& cam = view.camera();
      if (ctrl) {
        cam.type = mjCAMERA_TRACKING;
        cam.trackbodyid = body;
        cam.fixedcamid = -1;
      } else {
        mju_copy3(cam.lookat, point);
      }
    }
    return;
  }
  // Ctrl + drag on a selected body starts a perturbation.
  if (ctrl && pert.select > 0 && button != GLFW_MOUSE_BUTTON_MIDDLE) {
    pert.active = button == GLFW_MOUSE_BUTTON_LEFT ? mjPERT_ROTATE : mjPERT_TRANSLATE;
    mjv_initPerturb(view.model(), view.data(), &view.scene(), &pert);
  }
}

void MouseControl::Move(SceneView& view, double x, double y, int window_w, int window_h) {
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x;
  last_y_ = y;
  if (!dragging() || window_h <= 0) return;
  (void)window_w;
  int action = mjMOUSE_ZOOM;
  if (right_) {
    action = shift_ ? mjMOUSE_MOVE_H : mjMOUSE_MOVE_V;
  } else if (left_) {
    action = shift_ ? mjMOUSE_ROTATE_H : mjMOUSE_ROTATE_V;
  }
  const mjtNum rx = dx / window_h, ry = dy / window_h;
  mjvPerturb& pert = view.perturb();
  if (pert.active) {
    mjv_movePerturb(view.model(), view.data(), action, rx, ry, &view.scene(), &pert);
  } else {
    mjv_moveCamera(view.model(), action, rx, ry, &view.camera());
  }
}

void MouseControl::Scroll(SceneView& view, double dy) {
  mjv_moveCamera(view.model(), mjMOUSE_ZOOM, 0, -0.05 * dy, &view.camera());
}

}  // namespace urlab::viewer::internal
