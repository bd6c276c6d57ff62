#include "urlab/replay/tables.h"

#include <gtest/gtest.h>

#include "mujoco_test.h"
#include "urlab/physics/model.h"

namespace urlab::replay {
namespace {

constexpr char kTwoArms[] = R"(<mujoco><worldbody>
  <body name="a_base"><freejoint name="a_root"/><geom size="0.1"/>
    <body name="a_link"><joint name="a_elbow"/><geom size="0.1"/></body></body>
  <body name="b_base"><joint name="b_elbow" type="slide"/><geom size="0.1"/>
    <body><joint name="b_ball" type="ball"/><geom size="0.1"/></body></body>
  <body name="target" mocap="true"/>
</worldbody>
<actuator><motor name="a_m" joint="a_elbow"/><motor name="b_m" joint="b_elbow"/></actuator>
<sensor><jointpos name="a_s" joint="a_elbow"/><framequat name="b_q" objtype="body" objname="b_base"/></sensor>
</mujoco>)";

TEST(ModelTablesTest, NamesSizesAndShortNames) {
  physics::ModelPtr m = physics::CompileXmlString(kTwoArms);
  const ModelTables t = ModelTables::Of(m.get(), {"a", "b"});
  EXPECT_EQ(t.nq, 7 + 1 + 1 + 4);
  EXPECT_EQ(t.nv, 6 + 1 + 1 + 3);
  ASSERT_EQ(t.joints.size(), 4u);
  EXPECT_EQ(t.joints[0].short_name, "root");
  EXPECT_EQ(t.joints[0].articulation, "a");
  EXPECT_EQ(t.joints[0].nq, 7);
  EXPECT_EQ(t.joints[3].nq, 4);
  EXPECT_EQ(t.joints[3].qposadr, 9);
  EXPECT_EQ(t.FindJoint("elbow"), nullptr);  // a_elbow and b_elbow: ambiguous
  ASSERT_NE(t.FindJoint("root"), nullptr);
  EXPECT_EQ(t.FindJoint("b_elbow")->type, mjJNT_SLIDE);
  ASSERT_EQ(t.sensors.size(), 2u);
  EXPECT_EQ(t.sensors[1].adr, 1);
  EXPECT_EQ(t.sensors[1].dim, 4);
  ASSERT_EQ(t.mocap_bodies.size(), 1u);
  EXPECT_EQ(t.mocap_bodies[0].name, "target");
  EXPECT_EQ(t, ModelTables::Of(m.get(), {"a", "b"}));
  EXPECT_NE(t, ModelTables::Of(m.get(), {"a"}));
}

}  // namespace
}  // namespace urlab::replay
