#pragma once
// Comparing two compiled models and their trajectories bit for bit (round-trip and determinism
// checks). Thread: any; each call owns its own mjData.
#include <mujoco/mujoco.h>

#include <string>

namespace urlab::physics {

// "" when the two models have the same sizes, else a description of the first difference.
std::string CompareSizes(const mjModel* a, const mjModel* b);

// Steps both models `steps` times with zero control from their default initial state and
// returns "" when qpos and qvel are bit-identical after every step, else where they first differ.
std::string CompareTrajectories(const mjModel* a, const mjModel* b, int steps);

}  // namespace urlab::physics
