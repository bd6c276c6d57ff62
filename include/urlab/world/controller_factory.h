#pragma once
// Builds an articulation's controller from its scene description (ControllerConfig): PD with
// default and per-joint gains, passthrough, keyframe sequencer, gait (control/gait.h: walks at
// the twist; its standing pose is the articulation's keyframe, else its first), or none (targets
// go straight to d->ctrl). Thread: main, before the physics loop runs the articulation's
// controls.
#include <mujoco/mujoco.h>

#include "urlab/control/articulation_control.h"
#include "urlab/control/controllers.h"
#include "urlab/core/diagnostics.h"
#include "urlab/physics/views.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

// control::PdGains with the fields `config` sets replacing those of `base`.
control::PdGains MergeGains(const control::PdGains& base, const PdGains& config);

// Every problem of `config.controller` against model `m` for the articulation with `prefix`:
// per-joint gains naming no actuated joint or actuator of the articulation (matched exactly as
// InstallController matches them), gains on a controller without gains, keyframe steps naming
// no keyframe of the articulation, a gait on a robot whose legs it cannot find, a twist mode
// that contradicts the controller (gait without a gait controller, hover or policy with one).
// Each is an error at the controller's (or, for the twist, the articulation's) file:line.
void CheckController(const ArticulationConfig& config, const mjModel* m, const std::string& prefix,
                     Diagnostics& sink);

// Installs on `control` (bound to model `m`, articulation prefix control.prefix()) the controller
// `config.controller` describes. Per-joint gains are keyed by joint or actuator short name;
// keyframe steps name keyframes of the articulation's MJCF. Throws the first error of
// CheckController (InputError at the controller's file:line).
void InstallController(const ArticulationConfig& config, control::ArticulationControl& control,
                       const mjModel* m);

// Gives an articulation with a free base its twist controller (detached until possessed or
// driven by set_twist) with the scene's maxima and gains (config.twist) and its mode: the
// scene's, else gait under a gait controller (which it then drives), else policy. Throws
// InputError at the articulation's file:line for a twist block on an articulation without a free
// base. Call after InstallController.
void InstallTwist(const ArticulationConfig& config, const physics::ArticulationBindings& bindings,
                  control::ArticulationControl& control, const mjModel* m);

}  // namespace urlab::world
