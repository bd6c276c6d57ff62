#pragma once
// The name tables of a recorded model: joints (with their articulation and short name), actuators,
// sensors and mocap bodies, with the sizes a recording's frames are laid out by. A recording
// stores them in its header, so a file can be read, exported and imported against without
// compiling the model. Pure data; any thread.
#include <mujoco/mujoco.h>

#include <string>
#include <string_view>
#include <vector>

#include "urlab/physics/state_frame.h"

namespace urlab::replay {

// Values a joint of MuJoCo type `type` (mjtJoint) holds in qpos (7 free, 4 ball, else 1), in
// qvel (6, 3, 1), and its MJCF name ("free", "ball", "slide", "hinge").
int JointQposWidth(int type);
int JointDofWidth(int type);
const char* JointTypeName(int type);

struct JointEntry {
  std::string name;          // full (prefixed) name, e.g. "g1_left_knee"
  std::string articulation;  // owning articulation ("g1"), "" when none matches
  std::string short_name;    // name without "{articulation}_", the full name when none
  int type = 0;              // mjtJoint: mjJNT_FREE, mjJNT_BALL, mjJNT_SLIDE, mjJNT_HINGE
  int qposadr = 0;
  int dofadr = 0;
  int nq = 0;  // 7 free, 4 ball, 1 otherwise
  int nv = 0;  // 6 free, 3 ball, 1 otherwise
  bool operator==(const JointEntry&) const = default;
};

// A named run of values inside a vector (an actuator in ctrl, a sensor in sensordata, a mocap
// body's index).
struct NamedRange {
  std::string name;
  int adr = 0;
  int dim = 1;
  bool operator==(const NamedRange&) const = default;
};

struct ModelTables {
  int nq = 0, nv = 0, na = 0, nu = 0, nbody = 0, nmocap = 0, nsensordata = 0;
  double timestep = 0;
  std::vector<std::string> articulations;  // names, in scene order
  std::vector<JointEntry> joints;          // in joint id order
  std::vector<NamedRange> actuators;       // adr: index in ctrl
  std::vector<NamedRange> sensors;         // adr/dim: range in sensordata
  std::vector<NamedRange> mocap_bodies;    // adr: mocap index; name: the body's name
  std::vector<std::string> bodies;         // body names by id ("" when unnamed)
  // The command-frame groups frames carry (the engine's command layout; empty: none recorded).
  std::vector<physics::CommandGroupLayout> command_groups;

  // The tables of `m`; a joint belongs to the articulation whose "{name}_" prefixes it (the
  // longest such prefix).
  static ModelTables Of(const mjModel* m, const std::vector<std::string>& articulations = {});
  // The joint with this full name, or else this short name when exactly one joint has it;
  // nullptr when none (or when the short name is ambiguous).
  const JointEntry* FindJoint(std::string_view name) const;
  // True when every size and name agrees.
  bool operator==(const ModelTables&) const = default;
};

}  // namespace urlab::replay
