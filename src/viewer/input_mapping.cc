#include "viewer/input_mapping.h"

#include <GLFW/glfw3.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <string>

#include "urlab/core/error.h"
#include "urlab/ops/error.h"
#include "urlab/ops/targets.h"

namespace urlab::viewer::internal {

namespace {

struct NamedKey {
  const char* name;  // lower case
  int key;
};
constexpr NamedKey kNamedKeys[] = {
    {"space", GLFW_KEY_SPACE},
    {"enter", GLFW_KEY_ENTER},
    {"backspace", GLFW_KEY_BACKSPACE},
    {"up", GLFW_KEY_UP},
    {"down", GLFW_KEY_DOWN},
    {"left", GLFW_KEY_LEFT},
    {"right", GLFW_KEY_RIGHT},
    {"insert", GLFW_KEY_INSERT},
    {"delete", GLFW_KEY_DELETE},
    {"home", GLFW_KEY_HOME},
    {"end", GLFW_KEY_END},
    {"page_up", GLFW_KEY_PAGE_UP},
    {"page_down", GLFW_KEY_PAGE_DOWN},
    {"left_shift", GLFW_KEY_LEFT_SHIFT},
    {"right_shift", GLFW_KEY_RIGHT_SHIFT},
    {"left_control", GLFW_KEY_LEFT_CONTROL},
    {"right_control", GLFW_KEY_RIGHT_CONTROL},
    {"comma", GLFW_KEY_COMMA},
    {"period", GLFW_KEY_PERIOD},
    {"minus", GLFW_KEY_MINUS},
    {"equal", GLFW_KEY_EQUAL},
    {"semicolon", GLFW_KEY_SEMICOLON},
    {"slash", GLFW_KEY_SLASH},
    {"left_bracket", GLFW_KEY_LEFT_BRACKET},
    {"right_bracket", GLFW_KEY_RIGHT_BRACKET},
};

constexpr float kDeadZone = 0.15f;  // gamepad axes inside it count as zero

}  // namespace

int KeyCode(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower.size() == 1) {
    const char c = lower[0];
    if (c >= 'a' && c <= 'z') return GLFW_KEY_A + (c - 'a');
    if (c >= '0' && c <= '9') return GLFW_KEY_0 + (c - '0');
  }
  for (const NamedKey& k : kNamedKeys) {
    if (lower == k.name) return k.key;
  }
  return -1;
}

void InputMapping::Build(world::Session& session) {
  session_ = &session;
  bound_.clear();
  target_of_.clear();
  targets_.clear();
  for (const world::Articulation& art : session.articulations()) {
    for (const world::InputBindingConfig& c : art.config.input) {
      Bound b;
      b.control = art.control;
      b.index = art.control->IndexOf(c.actuator);
      if (b.index < 0) {
        throw InputError(
            c.where, art.name() + ".input: no actuator '" + c.actuator + "' in the articulation");
      }
      if (!c.key.empty()) {
        b.key = KeyCode(c.key);
        if (b.key < 0) {
          throw InputError(c.where, art.name() + ".input: unknown key '" + c.key +
                                        "' (a letter, a digit, Space, Enter, Up, Down, Left, "
                                        "Right, ...)");
        }
      }
      b.axis = c.gamepad_axis;
      b.button = c.gamepad_button;
      b.scale = c.scale;
      const auto it = std::find_if(targets_.begin(), targets_.end(), [&](const Target& t) {
        return t.control == b.control && t.index == b.index;
      });
      const auto target = static_cast<int>(it - targets_.begin());
      if (it == targets_.end()) targets_.push_back({b.control, b.index, &art.name()});
      target_of_.push_back(target);
      bound_.push_back(b);
    }
  }
}

bool InputMapping::OnKey(int key, int action) {
  if (action == GLFW_REPEAT) return false;
  const bool mapped =
      std::any_of(bound_.begin(), bound_.end(), [key](const Bound& b) { return b.key == key; });
  if (!mapped) return false;
  const auto it = std::find(held_.begin(), held_.end(), key);
  if (action == GLFW_PRESS && it == held_.end()) held_.push_back(key);
  if (action == GLFW_RELEASE && it != held_.end()) held_.erase(it);
  return true;
}

void InputMapping::Update() {
  if (bound_.empty()) return;
  GLFWgamepadstate pad{};
  bool have_pad = false;
  for (int jid = GLFW_JOYSTICK_1; jid <= GLFW_JOYSTICK_LAST && !have_pad; ++jid) {
    have_pad = glfwJoystickIsGamepad(jid) && glfwGetGamepadState(jid, &pad);
  }
  std::vector<double> values(targets_.size(), 0.0);
  for (std::size_t i = 0; i < bound_.size(); ++i) {
    const Bound& b = bound_[i];
    double v = 0;
    if (b.key >= 0) {
      v = std::find(held_.begin(), held_.end(), b.key) != held_.end() ? 1 : 0;
    } else if (have_pad && b.axis >= 0) {
      const float a = pad.axes[b.axis];
      v = std::abs(a) > kDeadZone ? a : 0;
    } else if (have_pad && b.button >= 0) {
      v = pad.buttons[b.button] == GLFW_PRESS ? 1 : 0;
    }
    values[static_cast<std::size_t>(target_of_[i])] += v * b.scale;
  }
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    Target& target = targets_[t];
    if (values[t] == target.last) continue;  // (nothing is published until an input moves)
    const int id = target.control->actuator_ids()[static_cast<std::size_t>(target.index)];
    try {
      ops::SetTargets(
          *session_,
          {.source = control::ControlSource::kInput,
           .articulations = {{.articulation = *target.articulation, .by_id = {{id, values[t]}}}}});
    } catch (const ops::OpError& e) {
      // (a sum of scales out of the targets' range: refused, said once per change)
      spdlog::warn("input mapping: {}", e.what());
    }
    target.last = values[t];
  }
}

}  // namespace urlab::viewer::internal
