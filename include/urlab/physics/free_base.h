#pragma once
// Which joint of an articulation is its free base.
//
// An articulation's file may hold more than its robot: a loose ball, a box to push. MuJoCo gives
// every such object a free joint on a top-level body, just like a floating robot's root. The
// articulation's base is its main top-level body: the one with the most of the articulation's
// bodies under it (the first of those in the model's order on a tie). The articulation has a free
// base when that body's joint is free. A free object beside a fixed arm does not make the arm
// float, and a ball declared before a legged robot does not become the robot's base.
//
// Threading: reads the model only; any thread.
#include <mujoco/mujoco.h>

#include <string_view>

#include "urlab/physics/views.h"

namespace urlab::physics {

// The id of the free joint that is the base of the articulation whose names carry `prefix`, or
// -1 for a fixed base.
int FreeBaseJoint(const mjModel* m, std::string_view prefix);

// The same as an index into bindings.joints(), or -1.
int FreeBaseIndex(const ArticulationBindings& bindings);

}  // namespace urlab::physics
