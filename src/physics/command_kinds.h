#pragma once
// Dispatch over the command kinds declared in command_kinds.cc (CommandName is in commands.h).
#include <cstdint>

#include "urlab/physics/step_core.h"

namespace urlab::physics {

// Any thread: throws Error / StateError when `c` cannot apply to a model shaped like `m` (bad id,
// wrong size, non-finite value, empty function).
void ValidateCommand(const Command& c, const mjModel* m);
// Inside StepCore (its thread): applies `c` and returns the Discontinuity flags it caused. Throws
// what applying throws.
std::uint32_t ApplyCommand(Command& c, StepCore& core);

}  // namespace urlab::physics
