#pragma once
// Exports: the composed scene as MJCF, written by MuJoCo from the scene's spec with the physics
// options in effect now (changed at run time by the viewer's panel or set_sim_options).
//
// Threading: SceneXml on the main thread (it reads the scene's spec) but not from inside a
// physics callback (it copies the model under the step mutex); ChangedOptions touches only its
// arguments.
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "urlab/world/session.h"

namespace urlab::ops {

// The MJCF attribute names of the options of `now` that differ from `compiled`, in the order of
// mjcf::OptionText's keys (e.g. "gravity", "timestep", "flag.contact"); empty when none.
std::vector<std::string> ChangedOptions(const mjOption& compiled, const mjOption& now);

// The composed scene's MJCF with the options in effect now (the viewer's Save XML), asset paths
// relative to `relative_to` (absolute when empty). `changed`, when given, receives
// ChangedOptions.
std::string SceneXml(world::Session& session, const std::string& relative_to = {},
                     std::vector<std::string>* changed = nullptr);

}  // namespace urlab::ops
