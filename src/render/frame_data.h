#pragma once
// A renderer's own copies kept in step with the engine (the viewer and the cameras): its mjData
// filled from a published state frame
// (time, qpos, qvel, act, ctrl, mocap poses, applied forces), then positions only (kinematics,
// camera and light poses, flex vertices, tendons): what drawing reads, never dynamics or
// collision.
//
// Threading contract: none of its own; `d` belongs to the calling thread.
#include <mujoco/mujoco.h>

#include "urlab/physics/state_frame.h"

namespace urlab::render {

void CopyFrameToData(const mjModel* m, mjData* d, const physics::StateFrame& frame);

// A new model's values (the engine's after a runtime edit: same sizes) into a renderer's own
// copy `m`, keeping its visual settings (the off-screen size and samples, shadow size set for its
// context); with `context` (current on this thread) the textures, meshes and heightfields are
// uploaded again.
void ReplaceModelValues(mjModel* m, const mjModel* source, const mjrContext* context);

}  // namespace urlab::render
