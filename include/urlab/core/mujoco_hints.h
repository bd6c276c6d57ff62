#pragma once
// What a user can do about a MuJoCo error or warning: a small table of message fragments and
// remedies (src/core/mujoco_hints.cc), e.g. raising size.nstack after "Stack overflow".
// Thread: any (constant data).
#include <string>
#include <string_view>

namespace urlab {

// The remedy for a MuJoCo message, "" when the table has none.
std::string MujocoHint(std::string_view message);

}  // namespace urlab
