#pragma once
// What the network publishes and accepts for each articulation, resolved once at BeginPlay from
// the session's bindings: joint and sensor topics with their state addresses, actuator ids and
// ranges for discovery (names are resolved by the operations). Immutable afterwards, so the I/O
// thread reads it without locks.
#include <cstdint>
#include <string>
#include <vector>

#include "urlab/world/session.h"

namespace urlab::net {

struct JointTopicEntry {
  std::string topic;
  int id = -1;
  int type = mjJNT_HINGE;
  int qpos_adr = 0, dof_adr = 0;
};

struct SensorTopicEntry {
  std::string topic;
  int id = -1;
  int adr = 0, dim = 0;
};

struct ArticulationTopics {
  std::string name;  // the articulation ({art})
  std::string control_topic, set_gains_topic;
  std::vector<JointTopicEntry> joints;    // hinge/slide/ball on /joint/, free on /base_state/
  std::vector<SensorTopicEntry> sensors;  // in id order
  // Actuators in the articulation's order (the command frame's order).
  std::vector<int> actuator_ids;
  std::vector<std::string> actuator_names;  // short names (world/names.h)
  // The target range (ActuatorBinding::TargetRange: a PD actuator's is its joint's range), or
  // -100/100 when unbounded.
  std::vector<double> mins, maxs;
  control::ArticulationControl* control = nullptr;
  // The twist controller (free bases only, else nullptr): {art}/twist every step while attached,
  // {art}/actions while an action bit is held.
  control::TwistController* twist = nullptr;
  std::string twist_topic, actions_topic;
  // For observations: the articulation's state addresses (joint order), activations, bodies,
  // and sensors by short name.
  std::vector<int> qpos_adrs, dof_adrs, act_adrs, body_ids;
  std::vector<std::string> joint_names, body_names, sensor_names;  // short names
  int free_joint = -1;  // index into joints of the root free joint, -1 when fixed base
};

// Builds the tables of every articulation of `session` (main thread, before the engine runs).
std::vector<ArticulationTopics> BuildTopicTables(world::Session& session);

}  // namespace urlab::net
