#pragma once
// Controllers: PD gains, the control source, the twist of a free base, impulse launchers. One
// typed function per operation with one validation (ops::OpError with the wire code, nothing
// applied), called alike by the step server (configure_controller, set_control_source,
// set_twist, fire_launcher), the streaming topic {art}/set_gains, and the viewer's panel
// (control source, Fire) and hotkeys (F).
//
// Gains go through the command frames: kp and kv are patched into every source's frame channel
// of the articulation (control/command_frame.h), so the frame the physics thread applies, and
// the recorder records with every step (the applied commands' kp/kv), carries them whatever
// source is active. The controller's own gains follow (what it reports, and what a frame without
// overrides leaves in effect); torque_limit, which a frame does not carry, is only the
// controller's.
//
// Thread: any (frame channels, source switches and the launcher counter are thread-safe; see
// control/articulation_control.h and world/session.h).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "urlab/control/controller.h"
#include "urlab/control/twist.h"
#include "urlab/ops/error.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// The actuator of `a` that `name` reaches (its index in the articulation's actuator order), -1
// when none: an actuator's full or short name, else the full or short name of the joint a
// joint-transmission actuator drives (the first such actuator). Gains (SetGains) and targets
// (ops/targets.h) resolve names through this one rule.
int ActuatorIndex(const mjModel* m, const world::Articulation& a, std::string_view name);

// Absent fields stay as they are.
struct GainChange {
  std::optional<double> kp, kv, torque_limit;
};
struct GainsRequest {
  GainChange all;  // every actuator of the articulation, then
  std::vector<std::pair<std::string, GainChange>> named;  // by actuator or joint name
};
struct ActuatorGains {
  std::string actuator;  // short name
  double kp, kv, torque_limit;
};
// Patches the PD gains of `articulation` as a whole: no_controller unless its controller has PD
// gains; controller_schema_violation for a name that reaches no actuator or a value that is not
// a finite number >= 0. Returns every actuator's gains now in effect.
std::vector<ActuatorGains> SetGains(world::Session& session, std::string_view articulation,
                                    const GainsRequest& request);
// Every actuator's gains in effect (no_controller as above).
std::vector<ActuatorGains> Gains(world::Session& session, std::string_view articulation);

// The scene's global control source, or one articulation's override (`articulation` non-empty).
// bad_value for an unknown source name, unknown_articulation.
void SetControlSource(world::Session& session, std::string_view source,
                      std::string_view articulation = {});

// The twist controller of a free-base articulation (no_twist_controller for a fixed base).
control::TwistController& RequireTwist(world::Session& session, std::string_view articulation);
// Attaches the twist controller of a free-base articulation and sets its planar twist
// (no_twist_controller for a fixed base). Returns the twist applied (clamped to its settings).
control::Twist SetTwist(world::Session& session, std::string_view articulation,
                        const control::Twist& twist);

// Fires launcher `name` (unknown_launcher): its next projectile leaves the muzzle in one queued
// command (world::Session::FireLauncher).
world::Session::Launch FireLauncher(world::Session& session, std::string_view name);

}  // namespace urlab::ops
