#include "viewer/hotkeys.h"

#include <GLFW/glfw3.h>

#include <algorithm>

namespace urlab::viewer::internal {

namespace {

constexpr Hotkey kHotkeys[] = {
    {GLFW_KEY_1, "1", Action::kToggleContacts, "contact points and forces"},
    {GLFW_KEY_2, "2", Action::kToggleVisual, "visual meshes"},
    {GLFW_KEY_3, "3", Action::kToggleCollision, "articulation collision wireframes"},
    {GLFW_KEY_4, "4", Action::kToggleJoints, "joint axes and range arcs"},
    {GLFW_KEY_5, "5", Action::kTogglePropCollision, "converted-prop collision wireframes"},
    {GLFW_KEY_P, "P", Action::kTogglePause, "pause / resume"},
    {GLFW_KEY_R, "R", Action::kReset, "reset to the initial state"},
    {GLFW_KEY_O, "O", Action::kToggleCinematic, "orbit and keyframe cameras"},
    {GLFW_KEY_F, "F", Action::kFireLaunchers, "fire the impulse launchers"},
    {GLFW_KEY_F12, "F12", Action::kScreenshot, "screenshot (PNG in the working folder)"},
    {GLFW_KEY_TAB, "Tab", Action::kTogglePossess, "possess the selected articulation / release"},
    {GLFW_KEY_ESCAPE, "Esc", Action::kFreeCamera, "free camera (stop tracking)"},
};

}  // namespace

std::span<const Hotkey> Hotkeys() { return kHotkeys; }

const Hotkey* FindHotkey(int key) {
  const auto* it = std::find_if(std::begin(kHotkeys), std::end(kHotkeys),
                                [key](const Hotkey& h) { return h.key == key; });
  return it == std::end(kHotkeys) ? nullptr : it;
}

}  // namespace urlab::viewer::internal
