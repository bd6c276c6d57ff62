#pragma once
// The viewer's hotkeys as one table (the description's UMjInputHandler key map, with the keys
// of MuJoCo's simulate where ours do not already use them), separate from what the actions do
// (ViewerCore::Perform). Besides the table: Shift + a visualisation flag's letter (MuJoCo's
// mjVISSTRING shortcut) toggles that flag, Alt + 0-5 a geom group and Alt + Shift + 0-5 a site
// group (ViewerCore::OnKey). Thread: any (constant data).
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
  kTogglePanel,          // H: hide / show the panel
  kFrameScene,           // Ctrl+A: the camera frames the whole scene again
  kStep,                 // Right: one physics step while paused
  kNextCamera,           // ]: the next of free camera and the model's cameras
  kPrevCamera,           // [
  kToggleHelp,           // F1: the help overlay
  kToggleInfo,           // F2: the info overlay
  kToggleProfiler,       // F3: the profiler
  kTogglePlots,          // F4: the plots
  kSaveXml,              // Ctrl+S
  kSaveMjb,              // Ctrl+Shift+S
  kPrintModel,           // Ctrl+M
  kPrintData,            // Ctrl+D
  kReload,               // Ctrl+L: read the scene again
  kLoadKey,              // Ctrl+K: the selected keyframe into the simulation
  kSaveKey,              // Ctrl+Shift+K: the current state into the selected keyframe
  kCopyPose,             // Ctrl+C: the current pose as a <key> element (clipboard)
};

// Modifier bits as GLFW reports them (GLFW_MOD_SHIFT, _CONTROL, _ALT).
inline constexpr int kShift = 0x1, kCtrl = 0x2, kAlt = 0x4;

struct Hotkey {
  int key;            // GLFW key code
  int mods;           // modifiers that must be held (exactly, among Shift, Ctrl and Alt)
  const char* label;  // as the panel and the help overlay show it
  Action action;
  const char* help;
};

// Every hotkey (keys not held by a possessed robot's driving keys).
std::span<const Hotkey> Hotkeys();
// The action bound to `key` with `mods` held, nullptr when none.
const Hotkey* FindHotkey(int key, int mods = 0);
// The key label of an action ("Ctrl+S"), "" when it has none.
const char* KeyLabel(Action action);

}  // namespace urlab::viewer::internal
