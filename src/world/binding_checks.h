#pragma once
// The checks of what an articulation's scene entry names in its compiled MJCF, besides its
// controller (controller_factory.h) and keyframes (scene_checks.cc): the cameras it streams
// (its `cameras:` list; the `cameras:` section's streams are the camera module's check), its
// `twist:` block (a free base), and its `input:`
// bindings' actuators (its own actuators, by short name; a joint's or another articulation's name
// is named as such). Run by CheckCompiledScene, so `validate` reports what `run` and `view`
// refuse, at the scene file's line. Thread: main (before the physics thread starts).
#include <mujoco/mujoco.h>

#include "urlab/core/diagnostics.h"
#include "urlab/mjcf/compose.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

void CheckArticulationBindings(const SceneConfig& scene, const ArticulationConfig& config,
                               const mjcf::ArticulationLayout& layout, const mjModel* m,
                               Diagnostics& sink);

}  // namespace urlab::world
