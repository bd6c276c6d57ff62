#pragma once
// Targets: the values an articulation's controller is asked to reach (the targets of a command
// frame, control/command_frame.h) and external forces on its bodies for a number of steps. One
// operation with one validation for every path that sets them: the step server's `step`
// (per_articulation ctrl, ctrl_map, xfrc_applied), the streaming {art}/control topic, the
// viewer's actuator sliders and its input mapping.
//
// A request is checked whole first (TargetsError: an OpError with the wire code and a fault the
// control topic counts its drops by; nothing applied): unknown articulations, actuators and
// bodies, counts, and every value against its range (ops/value_ranges.h: NaN and infinities are
// out of every range). Then each articulation's targets are one patch of the source's frame
// channel (a whole frame: every value of the request or none) and each force one ApplyForce
// command. CheckTargets and ApplyTargets are the two halves for a caller that checks something of
// its own in between (the step server's queue limit); SetTargets does both.
//
// Thread: any (frame channels take their writer mutex; commands are queued).
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "urlab/control/articulation_control.h"
#include "urlab/ops/error.h"
#include "urlab/physics/commands.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// A force and torque (world frame, at the body's centre of mass) on one body.
struct Wrench {
  std::string body;            // a body of the articulation, by short or full name
  std::vector<double> values;  // force x y z, torque x y z
};

struct ArticulationTargets {
  std::string articulation;
  // Every actuator's target in the articulation's actuator order (dim_mismatch otherwise).
  std::optional<std::vector<double>> ctrl;
  // Targets by name: an actuator's short or full name, or the joint an actuator drives.
  std::vector<std::pair<std::string, double>> by_name;
  // Targets by model actuator id (the control topic's ids; the viewer's sliders).
  std::vector<std::pair<int, double>> by_id;
  std::vector<Wrench> wrenches;
  // The step's control_mode: true (raw) makes the targets the actuators' controls (the controller
  // does not run), false (controller) makes them the controller's targets again; it stays until
  // changed (control/command_frame.h). Absent: unchanged.
  std::optional<bool> raw;
};

struct TargetsRequest {
  control::ControlSource source = control::ControlSource::kNetwork;
  std::vector<ArticulationTargets> articulations;
  int force_steps = 1;  // each wrench acts for this many physics steps, then is cleared
};

// Why a request was refused (the code says it to a client; the control topic, which has no reply,
// counts its drops by this).
enum class TargetsFault {
  kUnknownArticulation,  // unknown_articulation
  kCount,                // dim_mismatch: ctrl or a wrench of the wrong size, more targets than
                         // actuators
  kUnknownActuator,      // bad_value: a name or id that reaches no actuator of the articulation
  kOutOfRange,           // bad_value: a value outside its range (NaN and infinities included)
  kUnknownBody,          // unknown_body
};
struct TargetsError : OpError {
  TargetsError(TargetsFault fault_, std::string code_, std::string message_)
      : OpError(std::move(code_), std::move(message_)), fault(fault_) {}
  TargetsFault fault;
};

// A checked request: what ApplyTargets publishes and queues.
struct CheckedTargets {
  struct Patch {
    control::ArticulationControl* control = nullptr;
    std::vector<std::pair<int, double>> values;  // {index in the actuator order, target}
    std::optional<bool> raw;                     // ArticulationTargets::raw
  };
  control::ControlSource source = control::ControlSource::kNetwork;
  std::vector<Patch> patches;  // one per articulation of the request, in its order
  std::vector<physics::cmd::ApplyForce> forces;
};

// Checks `request` whole into *out (reusing its storage: a caller that checks many requests
// allocates nothing once warmed up). Throws TargetsError; *out is then unspecified.
void CheckTargets(const world::Session& session, const TargetsRequest& request,
                  CheckedTargets* out);
CheckedTargets CheckTargets(const world::Session& session, const TargetsRequest& request);
// Publishes each articulation's patch on the source's channel (one with no values and no
// control_mode publishes nothing)
// and queues the forces.
void ApplyTargets(world::Session& session, const CheckedTargets& checked);
// Both.
void SetTargets(world::Session& session, const TargetsRequest& request);

}  // namespace urlab::ops
