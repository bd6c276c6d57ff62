#pragma once
// Layout: where the panel and the 3D viewport sit in the window. The panel is docked at the
// left edge; the viewport is the rest of the window (MuJoCo renders into that rectangle only,
// so the camera is centred on what is visible). A splitter between them changes the panel's
// width; the panel collapses to a thin strip (H, or its "<" button).
//
// Threading contract: main thread only (plain data and arithmetic).
#include <mujoco/mujoco.h>

namespace urlab::viewer::internal {

// A rectangle in window coordinates (screen pixels, origin top-left).
struct WindowRect {
  float x = 0, y = 0, w = 0, h = 0;
  bool Contains(double px, double py) const {
    return px >= x && px < x + w && py >= y && py < y + h;
  }
};

class Layout {
 public:
  static constexpr float kDefaultWidth = 360;  // panel width at start (screen pixels)
  static constexpr float kMinWidth = 220;
  static constexpr float kSplitter = 6;         // the draggable bar right of the panel
  static constexpr float kCollapsedWidth = 22;  // the strip a collapsed panel leaves
  static constexpr float kMaxFraction = 0.7f;   // of the window's width

  // `panel`: false when there is no panel at all (the viewport is the whole window).
  explicit Layout(bool panel = true) : panel_(panel) {}

  bool has_panel() const { return panel_; }
  bool collapsed() const { return collapsed_; }
  void SetCollapsed(bool c) { collapsed_ = c; }
  // The panel's width as asked for (clamped when the rectangles are computed).
  float width() const { return width_; }
  void SetWidth(float w) { width_ = w; }

  // The panel's rectangle (zero width without a panel; the strip while collapsed).
  WindowRect Panel(float window_w, float window_h) const;
  // The splitter's rectangle (zero width without a panel or while collapsed).
  WindowRect Splitter(float window_w, float window_h) const;
  // The 3D viewport: right of the panel and the splitter, to the window's right edge.
  WindowRect Viewport(float window_w, float window_h) const;

 private:
  float Clamped(float window_w) const;
  bool panel_;
  bool collapsed_ = false;
  float width_ = kDefaultWidth;
};

// `r` (window coordinates) in framebuffer pixels with OpenGL's bottom-left origin, as mjr_render
// takes its viewport; the framebuffer may be larger than the window (HiDPI).
mjrRect ToFramebuffer(const WindowRect& r, int window_w, int window_h, int fb_w, int fb_h);

}  // namespace urlab::viewer::internal
