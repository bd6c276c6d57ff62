#include "world/scene_names.h"

#include <fmt/format.h>

namespace urlab::world {

namespace {

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.';
}

std::string Describe(char c) {
  switch (c) {
    case '\n':
      return "a newline";
    case '\r':
      return "a carriage return";
    case '\t':
      return "a tab";
    case ' ':
      return "a space";
    default:
      break;
  }
  const auto u = static_cast<unsigned char>(c);
  if (u < 0x20 || u == 0x7f) return fmt::format("the control character 0x{:02x}", u);
  if (u >= 0x80) return "a non-ASCII character";
  return fmt::format("'{}'", c);
}

}  // namespace

std::string SceneNameProblem(std::string_view name) {
  if (name.empty()) return "is empty";
  for (char c : name) {
    if (!IsNameChar(c)) return "contains " + Describe(c);
  }
  const char first = name.front();
  if (!((first >= 'a' && first <= 'z') || (first >= 'A' && first <= 'Z') || first == '_')) {
    return "must start with a letter or '_'";
  }
  return "";
}

}  // namespace urlab::world
