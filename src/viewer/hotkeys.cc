#include "viewer/hotkeys.h"

#include <GLFW/glfw3.h>

#include <algorithm>

namespace urlab::viewer::internal {

namespace {

constexpr Hotkey kHotkeys[] = {
    {GLFW_KEY_1, 0, "1", Action::kToggleContacts, "contact points and forces"},
    {GLFW_KEY_2, 0, "2", Action::kToggleVisual, "visual meshes"},
    {GLFW_KEY_3, 0, "3", Action::kToggleCollision, "articulation collision wireframes"},
    {GLFW_KEY_4, 0, "4", Action::kToggleJoints, "joint axes and range arcs"},
    {GLFW_KEY_5, 0, "5", Action::kTogglePropCollision, "converted-prop collision wireframes"},
    {GLFW_KEY_P, 0, "P", Action::kTogglePause, "pause / resume"},
    {GLFW_KEY_RIGHT, 0, "Right", Action::kStep, "one physics step (while paused)"},
    {GLFW_KEY_R, 0, "R", Action::kReset, "reset to the initial state"},
    {GLFW_KEY_O, 0, "O", Action::kToggleCinematic, "orbit and keyframe cameras"},
    {GLFW_KEY_F, 0, "F", Action::kFireLaunchers, "fire the impulse launchers"},
    {GLFW_KEY_F12, 0, "F12", Action::kScreenshot, "screenshot (PNG in the working folder)"},
    {GLFW_KEY_TAB, 0, "Tab", Action::kTogglePossess, "possess the selected articulation / release"},
    {GLFW_KEY_ESCAPE, 0, "Esc", Action::kFreeCamera, "free camera (stop tracking)"},
    {GLFW_KEY_RIGHT_BRACKET, 0, "]", Action::kNextCamera, "next camera (free, model cameras)"},
    {GLFW_KEY_LEFT_BRACKET, 0, "[", Action::kPrevCamera, "previous camera"},
    {GLFW_KEY_A, kCtrl, "Ctrl+A", Action::kFrameScene, "frame the whole scene"},
    {GLFW_KEY_H, 0, "H", Action::kTogglePanel, "hide / show the panel"},
    {GLFW_KEY_F1, 0, "F1", Action::kToggleHelp, "help overlay"},
    {GLFW_KEY_F2, 0, "F2", Action::kToggleInfo, "info overlay"},
    {GLFW_KEY_F3, 0, "F3", Action::kToggleProfiler, "profiler"},
    {GLFW_KEY_F4, 0, "F4", Action::kTogglePlots, "plots (choose signals in the panel)"},
    {GLFW_KEY_S, kCtrl, "Ctrl+S", Action::kSaveXml, "save the composed scene as MJCF"},
    {GLFW_KEY_S, kCtrl | kShift, "Ctrl+Shift+S", Action::kSaveMjb, "save the model as MJB"},
    {GLFW_KEY_M, kCtrl, "Ctrl+M", Action::kPrintModel, "print the model (text file)"},
    {GLFW_KEY_D, kCtrl, "Ctrl+D", Action::kPrintData, "print the data (text file)"},
    {GLFW_KEY_L, kCtrl, "Ctrl+L", Action::kReload,
     "reload the scene's files (new values keep the state)"},
    {GLFW_KEY_K, kCtrl, "Ctrl+K", Action::kLoadKey, "load the selected keyframe"},
    {GLFW_KEY_K, kCtrl | kShift, "Ctrl+Shift+K", Action::kSaveKey,
     "save the state into the selected keyframe"},
    {GLFW_KEY_C, kCtrl, "Ctrl+C", Action::kCopyPose, "copy the pose as a <key> (clipboard)"},
};

}  // namespace

std::span<const Hotkey> Hotkeys() { return kHotkeys; }

const Hotkey* FindHotkey(int key, int mods) {
  mods &= kShift | kCtrl | kAlt;
  const auto* it = std::find_if(std::begin(kHotkeys), std::end(kHotkeys),
                                [&](const Hotkey& h) { return h.key == key && h.mods == mods; });
  return it == std::end(kHotkeys) ? nullptr : it;
}

const char* KeyLabel(Action action) {
  for (const Hotkey& h : kHotkeys) {
    if (h.action == action) return h.label;
  }
  return "";
}

}  // namespace urlab::viewer::internal
