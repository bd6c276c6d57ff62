#pragma once
// The characters a scene's own names (articulations, props, terrain, launchers) may hold. A name
// becomes the prefix "{name}_" of every MJCF element it brings, the first part of its ZeroMQ
// topics ("{name}/joints") and of camera keys ("{name}/camera"), and appears in log lines, so it
// is kept to ASCII letters, digits, '_', '-' and '.', starting with a letter or '_' (no spaces,
// '/', newlines or other control characters). Thread: any (pure).
#include <string>
#include <string_view>

namespace urlab::world {

// Why `name` is not a valid scene name ("" when it is): e.g. "contains a newline".
std::string SceneNameProblem(std::string_view name);

// The rule as text, for messages and docs.
inline constexpr const char* kSceneNameRule =
    "ASCII letters, digits, '_', '-' and '.', starting with a letter or '_'";

}  // namespace urlab::world
