#pragma once
// The viewer's hotkeys as one table (the description's UMjInputHandler key map), separate from
// what the actions do (ViewerCore::Perform). Thread: any (constant data).
#include <span>

namespace urlab::viewer::internal {

enum class Action {
  kToggleContacts,       // 1
  kToggleVisual,         // 2
  kToggleCollision,      // 3
  kToggleJoints,         // 4
  kTogglePropCollision,  // 5
  kTogglePause,          // P
  kReset,                // R
  kToggleCinematic,      // O: orbit and keyframe cameras
  kFireLaunchers,        // F
  kScreenshot,           // F12
  kTogglePossess,        // Tab: possess the selected articulation / release
  kFreeCamera,           // Escape: stop tracking, free camera
};

struct Hotkey {
  int key;            // GLFW key code
  const char* label;  // as the panel shows it
  Action action;
  const char* help;
};

// Every hotkey (keys not held by a possessed robot's driving keys).
std::span<const Hotkey> Hotkeys();
// The action bound to `key`, nullptr when none.
const Hotkey* FindHotkey(int key);

}  // namespace urlab::viewer::internal
