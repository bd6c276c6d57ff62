#pragma once
// Filling a renderer's own mjData from a published state frame (the viewer and the cameras):
// (time, qpos, qvel, act, ctrl, mocap poses, applied forces), then positions only (kinematics,
// camera and light poses, flex vertices, tendons): what drawing reads, never dynamics or
// collision.
//
// Threading contract: none of its own; `d` belongs to the calling thread.
#include <mujoco/mujoco.h>

#include "urlab/physics/state_frame.h"

namespace urlab::render {

void CopyFrameToData(const mjModel* m, mjData* d, const physics::StateFrame& frame);

}  // namespace urlab::render
