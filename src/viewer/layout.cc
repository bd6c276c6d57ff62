#include "viewer/layout.h"

#include <algorithm>
#include <cmath>

namespace urlab::viewer::internal {

float Layout::Clamped(float window_w) const {
  const float hi = std::max(kMinWidth, kMaxFraction * window_w);
  return std::clamp(width_, kMinWidth, hi);
}

WindowRect Layout::Panel(float window_w, float window_h) const {
  if (!panel_) return {0, 0, 0, window_h};
  return {0, 0, collapsed_ ? kCollapsedWidth : Clamped(window_w), window_h};
}

WindowRect Layout::Splitter(float window_w, float window_h) const {
  if (!panel_ || collapsed_) return {Panel(window_w, window_h).w, 0, 0, window_h};
  return {Panel(window_w, window_h).w, 0, kSplitter, window_h};
}

WindowRect Layout::Viewport(float window_w, float window_h) const {
  const WindowRect s = Splitter(window_w, window_h);
  const float x = s.x + s.w;
  return {x, 0, std::max(1.0f, window_w - x), window_h};
}

mjrRect ToFramebuffer(const WindowRect& r, int window_w, int window_h, int fb_w, int fb_h) {
  const double sx = window_w > 0 ? static_cast<double>(fb_w) / window_w : 1.0;
  const double sy = window_h > 0 ? static_cast<double>(fb_h) / window_h : 1.0;
  const int left = static_cast<int>(std::lround(r.x * sx));
  const int right = static_cast<int>(std::lround((r.x + r.w) * sx));
  const int top = static_cast<int>(std::lround(r.y * sy));
  const int bottom = static_cast<int>(std::lround((r.y + r.h) * sy));
  return {left, fb_h - bottom, std::max(1, right - left), std::max(1, bottom - top)};
}

}  // namespace urlab::viewer::internal
