#pragma once
// What the 2026 dialect's hello_ok adds to ours (docs/protocol.md, "The 2026 dialect"): the
// `entities` array (one element per articulation, with its identity, control mode, controller
// and its schema, actuator kinds, original names, cameras as a map and the free-base fields;
// then one per free body of no articulation, net/free_bodies.h),
// `global_cameras`, and on request the `raw_joints` / `raw_actuators` tables of the compiled
// model. Every element of `entities` carries its own raw tables (raw_model, raw_joints,
// raw_actuators, raw_sensors): the 2026 client builds its name maps from them, unasked. Built
// from the step server's tables and the compiled model.
// Thread: the step server's I/O thread (reads the controllers' gains through ops::Gains).
#include <mujoco/mujoco.h>

#include <vector>

#include "net/free_bodies.h"
#include "net/msgpack_codec.h"
#include "net/topic_table.h"
#include "urlab/world/camera_streams.h"
#include "urlab/world/session.h"

namespace urlab::net::dialect2026 {

// The entities array; `ours` is hello's `articulations` array in our vocabulary (the same order
// as `tables`), whose joints, actuators and sensors each element carries too. The free bodies
// follow the articulations: the same fields (no controller, actuators or cameras: empty), the
// free base being the body itself, its state at offset 0 of `scene[name].qpos` / `.qvel`.
Json Entities(world::Session& session, const std::vector<ArticulationTopics>& tables,
              const std::vector<FreeBodyEntry>& free_bodies, const world::CameraStreams* cameras,
              const Json& ours);
// Cameras that belong to no articulation, as a map like camera_topics.
Json GlobalCameras(const mjModel* m, const world::CameraStreams* cameras);
// One articulation's raw tables, in the order of its own vectors (arts[prefix].qpos, .ctrl,
// .sensors), names short, ids and addresses the compiled model's:
// joints {name, id, type (mjtJoint), qpos_adr, qvel_adr, range, body_id, qpos_index, qvel_index},
// actuators {name, id, ctrlrange, gear [6], joint (short; null without one), index},
// sensors {name, id, type (mjtSensor), adr, dim}.
struct RawTables {
  Json joints = Json::array(), actuators = Json::array(), sensors = Json::array();
};
RawTables EntityRawTables(const mjModel* m, const ArticulationTopics& t);
// Every joint: {name (short), id, type (mjtJoint), qpos_adr, qvel_adr, range, body_id}.
Json RawJoints(const world::Session& session);
// Every actuator: {name (short), id, ctrlrange, gear, joint (short; null without one)}.
Json RawActuators(const world::Session& session);
// The kind of actuator `id`: position, velocity, motor or general.
const char* ActuatorKind(const mjModel* m, int id);

}  // namespace urlab::net::dialect2026
