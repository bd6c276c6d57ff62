#include "world/input_keys.h"

#include <algorithm>
#include <cctype>

namespace urlab::world {

bool IsKnownKeyName(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower.size() == 1) {
    const char c = lower[0];
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
  }
  return std::any_of(std::begin(kNamedKeys), std::end(kNamedKeys),
                     [&](const char* k) { return lower == k; });
}

std::string KnownKeyNamesText() {
  std::string out = "a letter, a digit";
  for (const char* k : kNamedKeys) out += std::string(", ") + k;
  return out;
}

}  // namespace urlab::world
