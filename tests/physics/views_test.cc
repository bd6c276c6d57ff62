#include "urlab/physics/views.h"

#include <gtest/gtest.h>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "urlab/physics/model.h"

namespace urlab::physics {
namespace {

using testing::kArmXml;

class ViewsTest : public urlab::testing::MujocoTest {
 protected:
  void SetUp() override {
    model_ = CompileXmlString(kArmXml);
    data_ = MakeData(model_.get());
    mj_forward(m(), d());
  }
  mjModel* m() { return model_.get(); }
  mjData* d() { return data_.get(); }
  ModelPtr model_;
  DataPtr data_;
};

TEST_F(ViewsTest, BindsByIdFirst) {
  const int elbow = mj_name2id(m(), mjOBJ_JOINT, "arm_elbow");
  JointView j = Bind<JointView>(m(), d(), "arm_", "elbow", elbow);
  EXPECT_EQ(j.id, elbow);
  EXPECT_EQ(j.name, "arm_elbow");
  EXPECT_EQ(j.qpos, d()->qpos + m()->jnt_qposadr[elbow]);
  EXPECT_EQ(j.qvel, d()->qvel + m()->jnt_dofadr[elbow]);
  EXPECT_EQ(j.qpos_size, 1);
  EXPECT_TRUE(j.limited);
  EXPECT_DOUBLE_EQ(j.range[1], 2.5);
  EXPECT_DOUBLE_EQ(*j.damping, 0.1);
  // Id with an empty name is trusted when in range.
  EXPECT_EQ(Bind<JointView>(m(), d(), "", "", elbow).id, elbow);
}

TEST_F(ViewsTest, FallsBackToNameForStaleOrOutOfRangeIds) {
  const int elbow = mj_name2id(m(), mjOBJ_JOINT, "arm_elbow");
  EXPECT_EQ(Bind<JointView>(m(), d(), "arm_", "elbow", 999).id, elbow);  // out of range
  EXPECT_EQ(Bind<JointView>(m(), d(), "arm_", "elbow", -7).id, elbow);   // negative
  EXPECT_EQ(Bind<JointView>(m(), d(), "arm_", "elbow", 0).id, elbow);    // names another joint
  EXPECT_EQ(Bind<JointView>(m(), d(), "arm_", "elbow").id, elbow);       // no hint
}

TEST_F(ViewsTest, ReportsMissingElements) {
  EXPECT_FALSE(TryBind<BodyView>(m(), d(), "arm_", "nope").has_value());
  EXPECT_FALSE(TryBind<BodyView>(m(), d(), "", "", 999).has_value());
  try {
    Bind<ActuatorView>(m(), d(), "arm_", "missing", 42);
    FAIL() << "expected BindError";
  } catch (const BindError& e) {
    EXPECT_NE(std::string(e.what()).find("'arm_missing'"), std::string::npos) << e.what();
  }
}

TEST_F(ViewsTest, EveryViewPointsIntoTheRightArrays) {
  BodyView upper = Bind<BodyView>(m(), d(), "arm_", "upper");
  EXPECT_EQ(upper.xpos, d()->xpos + 3 * upper.id);
  EXPECT_DOUBLE_EQ(upper.xpos[2], 0.5);
  EXPECT_EQ(upper.mocap_id, -1);
  EXPECT_EQ(Bind<BodyView>(m(), d(), "arm_", "target").mocap_id, 0);
  EXPECT_EQ(upper.Bodies(), std::vector<int>{mj_name2id(m(), mjOBJ_BODY, "arm_lower")});
  EXPECT_EQ(upper.Joints(), std::vector<int>{mj_name2id(m(), mjOBJ_JOINT, "arm_shoulder")});
  EXPECT_EQ(upper.Geoms(), std::vector<int>{mj_name2id(m(), mjOBJ_GEOM, "arm_upper_geom")});

  GeomView g = Bind<GeomView>(m(), d(), "arm_", "lower_geom");
  EXPECT_EQ(*g.type, mjGEOM_CAPSULE);
  EXPECT_DOUBLE_EQ(g.size[0], 0.025);

  ActuatorView motor = Bind<ActuatorView>(m(), d(), "arm_", "shoulder_motor");
  EXPECT_EQ(motor.ctrl, d()->ctrl + motor.id);
  EXPECT_DOUBLE_EQ(motor.ctrlrange[1], 50);
  EXPECT_EQ(motor.act, nullptr);
  EXPECT_EQ(motor.trnid, mj_name2id(m(), mjOBJ_JOINT, "arm_shoulder"));
  ActuatorView filtered = Bind<ActuatorView>(m(), d(), "arm_", "filtered");
  EXPECT_EQ(filtered.act_adr, 0);
  EXPECT_EQ(filtered.act, d()->act);

  SensorView tip = Bind<SensorView>(m(), d(), "arm_", "tip_pos");
  EXPECT_EQ(tip.dim, 3);
  SiteView site = Bind<SiteView>(m(), d(), "arm_", "tip");
  for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(tip.values[k], site.xpos[k]);
  EXPECT_EQ(site.body_id, mj_name2id(m(), mjOBJ_BODY, "arm_lower"));

  TendonView t = Bind<TendonView>(m(), d(), "arm_", "coupling");
  d()->qpos[0] = 0.3;
  d()->qpos[1] = 0.1;
  mj_forward(m(), d());
  EXPECT_NEAR(*t.length, 0.2, 1e-12);
}

TEST_F(ViewsTest, ArticulationBindingsEnumerateByPrefix) {
  ArticulationBindings arm(m(), d(), "arm_");
  EXPECT_EQ(arm.bodies().size(), 3u);  // target, upper, lower; not "box" or "world"
  EXPECT_EQ(arm.joints().size(), 2u);
  EXPECT_EQ(arm.actuators().size(), 3u);
  EXPECT_EQ(arm.sensors().size(), 3u);
  EXPECT_EQ(arm.tendons().size(), 1u);
  EXPECT_EQ(arm.sites().size(), 2u);
  EXPECT_EQ(arm.geoms().size(), 2u);
  EXPECT_EQ(arm.keyframes().size(), 2u);

  const JointView* elbow = arm.joints().Find("elbow");
  ASSERT_NE(elbow, nullptr);
  EXPECT_EQ(elbow->name, "arm_elbow");
  EXPECT_EQ(arm.joints().ById(elbow->id), elbow);
  EXPECT_EQ(arm.joints().Find("arm_elbow"), nullptr);  // short names only
  EXPECT_EQ(arm.joints().ById(mj_name2id(m(), mjOBJ_JOINT, "box_free")), nullptr);
  EXPECT_EQ(arm.joints().ById(-1), nullptr);
  EXPECT_EQ(arm.joints().ById(1000), nullptr);
  EXPECT_EQ(arm.actuators().short_names(),
            (std::vector<std::string>{"shoulder_motor", "elbow_servo", "filtered"}));
  for (std::size_t i = 1; i < arm.actuators().size(); ++i) {
    EXPECT_LT(arm.actuators().all()[i - 1].id, arm.actuators().all()[i].id);
  }
  ArticulationBindings box(m(), d(), "box");
  EXPECT_EQ(box.joints().size(), 1u);
  EXPECT_EQ(box.joints().Find("_free")->qpos_size, 7);
}

}  // namespace
}  // namespace urlab::physics
