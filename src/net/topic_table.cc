#include "net/topic_table.h"

#include "urlab/physics/free_base.h"
#include "urlab/wire/wire.h"
#include "urlab/world/names.h"

namespace urlab::net {

std::vector<ArticulationTopics> BuildTopicTables(world::Session& session) {
  std::vector<ArticulationTopics> out;
  const mjModel* m = session.engine().model();
  for (const world::Articulation& a : session.articulations()) {
    ArticulationTopics t;
    t.name = a.name();
    t.control = a.control;
    t.control_topic = wire::ControlTopic(t.name);
    t.set_gains_topic = wire::SetGainsTopic(t.name);
    t.twist = a.control->twist();
    t.twist_topic = wire::TwistTopic(t.name);
    t.actions_topic = wire::ActionsTopic(t.name);
    const physics::ArticulationBindings& b = *a.bindings;
    t.free_joint = physics::FreeBaseIndex(b);
    for (std::size_t i = 0; i < b.joints().size(); ++i) {
      const physics::JointView& j = b.joints().all()[i];
      const std::string& short_name = b.joints().short_names()[i];
      JointTopicEntry e;
      e.topic = j.type == mjJNT_FREE ? wire::BaseStateTopic(t.name, short_name)
                                     : wire::JointTopic(t.name, short_name);
      e.id = j.id;
      e.type = j.type;
      e.qpos_adr = j.qpos_adr;
      e.dof_adr = j.dof_adr;
      for (int k = 0; k < j.qpos_size; ++k) t.qpos_adrs.push_back(j.qpos_adr + k);
      for (int k = 0; k < j.dof_size; ++k) t.dof_adrs.push_back(j.dof_adr + k);
      t.joint_names.push_back(short_name);
      t.joints.push_back(std::move(e));
    }
    for (std::size_t i = 0; i < b.sensors().size(); ++i) {
      const physics::SensorView& s = b.sensors().all()[i];
      t.sensors.push_back(
          {wire::SensorTopic(t.name, b.sensors().short_names()[i]), s.id, s.adr, s.dim});
      t.sensor_names.push_back(b.sensors().short_names()[i]);
    }
    for (std::size_t i = 0; i < b.bodies().size(); ++i) {
      t.body_ids.push_back(b.bodies().all()[i].id);
      t.body_names.push_back(b.bodies().short_names()[i]);
    }
    for (const physics::ActuatorView& v : b.actuators().all()) {
      if (v.act_adr >= 0) t.act_adrs.push_back(v.act_adr);
    }
    const std::vector<int>& ids = a.control->actuator_ids();
    const control::Controller* controller = a.control->controller();
    const bool positions = controller && controller->TargetsArePositions();
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const int id = ids[i];
      t.actuator_ids.push_back(id);
      t.actuator_names.push_back(world::ShortNameOf(m, mjOBJ_ACTUATOR, id, a.prefix));
      // The range of the target the articulation's controller takes (a PD controller's is the
      // joint's range, not the actuator's ctrlrange).
      double range[2] = {-100.0, 100.0};
      control::MakeActuatorBinding(m, id).TargetRange(positions, range);
      t.mins.push_back(range[0]);
      t.maxs.push_back(range[1]);
    }
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace urlab::net
