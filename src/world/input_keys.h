#pragma once
// The keyboard key names a scene's `input:` bindings may use ("J", "7", "Space", "Up", ...),
// as data, so that loading a scene refuses an unknown key at its file:line whether or not a
// window ever opens (the viewer maps the same names to GLFW key codes, viewer/input_mapping.h).
// Thread: any (constant data).
#include <string>
#include <string_view>

namespace urlab::world {

// True for a single letter or digit (any case) or one of kNamedKeys (any case).
bool IsKnownKeyName(std::string_view name);

// The named keys besides letters and digits, lower case.
inline constexpr const char* kNamedKeys[] = {
    "space",        "enter",         "backspace", "up",           "down",
    "left",         "right",         "insert",    "delete",       "home",
    "end",          "page_up",       "page_down", "left_shift",   "right_shift",
    "left_control", "right_control", "comma",     "period",       "minus",
    "equal",        "semicolon",     "slash",     "left_bracket", "right_bracket"};

// "a letter, a digit, space, enter, ..." for error messages.
std::string KnownKeyNamesText();

}  // namespace urlab::world
