#pragma once
// Timeline: the replay timeline of the viewer's replay mode, shown while a replay plays (`urlab
// replay FILE --view`, or a step server client's replay_load + replay_start in a running
// viewer): play and pause, speed, scrubbing, single steps, loop, and jumps to the recording's
// keyframes and to its resets (any recorded jump). Drawn with Dear ImGui along the bottom of the
// window, driven by its buttons and by keys; it acts only through the Player's controls, which
// any thread may call (the player runs in the engine's step handler on the physics thread).
//
// Threading contract: main thread only (Draw between Window::BeginImGui and EndImGui).
#include <optional>
#include <span>
#include <string>

#include "urlab/replay/playback.h"

namespace urlab::viewer::internal {

enum class TimelineAction {
  kPlayPause,
  kStepBack,
  kStepForward,
  kStart,
  kEnd,
  kPrevKeyframe,
  kNextKeyframe,
  kPrevJump,
  kNextJump,
  kSlower,
  kFaster,
  kToggleLoop,
};

// The key (GLFW code) bound to each action, and its label, for the panel's help and the keys.
struct TimelineKey {
  int key;
  const char* label;
  TimelineAction action;
  const char* what;
};
std::span<const TimelineKey> TimelineKeys();
std::optional<TimelineAction> TimelineActionOfKey(int key);

class Timeline {
 public:
  static constexpr float kHeight = 104;  // screen pixels, at the window's bottom edge

  // Does `action` on the playback; returns a line saying what it did (for the log).
  static std::string Perform(const replay::Playback& playback, TimelineAction action);

  // Draws the timeline in a window at (x, y) of `width`.
  void Draw(const replay::Playback& playback, float x, float y, float width);

  // The scrub bar as last drawn (window coordinates), for tests that drag it.
  struct Rect {
    float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  };
  const Rect& scrub_bar() const { return scrub_; }

 private:
  Rect scrub_;
};

}  // namespace urlab::viewer::internal
