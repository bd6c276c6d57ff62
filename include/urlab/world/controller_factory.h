#pragma once
// Builds an articulation's controller from its scene description (ControllerConfig): PD with
// default and per-joint gains, passthrough, keyframe sequencer, or none (targets go straight to
// d->ctrl). Thread: main, before the physics loop runs the articulation's controls.
#include <mujoco/mujoco.h>

#include "urlab/control/articulation_control.h"
#include "urlab/control/controllers.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

// control::PdGains with the fields `config` sets replacing those of `base`.
control::PdGains MergeGains(const control::PdGains& base, const PdGains& config);

// Installs on `control` (bound to model `m`, articulation prefix control.prefix()) the controller
// `config.controller` describes. Per-joint gains are keyed by joint or actuator short name;
// keyframe steps name keyframes of the articulation's MJCF. Throws InputError at the
// controller's file:line for an unknown joint, actuator or keyframe.
void InstallController(const ArticulationConfig& config, control::ArticulationControl& control,
                       const mjModel* m);

}  // namespace urlab::world
