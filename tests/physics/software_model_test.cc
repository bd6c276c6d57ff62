// The runtime's share of the dialect bridge beyond sensors: gravity compensation and dead-band
// tendon springs through mjcb_passive (one registry per model with the software sensors), and
// the site equalities' data written after compilation. Values against hand-computed physics;
// reference3x_test compares them with MuJoCo 3.x.
#include <cmath>

#include "compiled_model_test.h"
#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"
#include "urlab/physics/software_sensors.h"

namespace urlab {
namespace {

constexpr const char* kModel = R"(<mujoco>
  <option gravity="0 0 -10"/>
  <worldbody>
    <site name="anchor" pos="0 0 2"/>
    <body name="ball" pos="0 0 1">
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom size="0.1" mass="2"/>
      <site name="top" pos="0 0 0.1"/>
    </body>
    <body name="arm" pos="1 0 1">
      <joint name="h" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05" mass="1"/>
      <site name="end" pos="0.5 0 0"/>
    </body>
  </worldbody>
  <tendon>
    <spatial name="rope"><site site="anchor"/><site site="top"/></spatial>
  </tendon>
  <equality>
    <connect name="pin" body1="arm" body2="world" anchor="0 0 0"/>
  </equality>
</mujoco>)";

class SoftwareModelTest : public testing::CompiledModelTest {
 protected:
  const char* Xml() const override { return kModel; }
};

TEST_F(SoftwareModelTest, GravityCompensationCancelsGravityExactlyAndOnlyWhileRegistered) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  physics::SoftwareModelSpec spec;
  spec.gravcomp = {{"ball", 1.0}, {"arm", 0.5}};
  {
    physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareModel(m, spec);
    mj_forward(m, d);
    EXPECT_NEAR(d->qfrc_passive[0], 2 * 10, 1e-12);  // m g on the slide
    // half the arm's weight at its centre (0.25 m from the hinge): 0.5 * 1 * 10 * 0.25
    EXPECT_NEAR(d->qfrc_passive[1], -0.5 * 10 * 0.25, 1e-9);
    for (int i = 0; i < 200; ++i) mj_step(m, d);
    EXPECT_NEAR(d->qpos[0], 0, 1e-12);  // the fully compensated ball stays
  }
  mj_forward(m, d);
  EXPECT_EQ(d->qfrc_passive[0], 0);
}

TEST_F(SoftwareModelTest, DeadbandSpringIsSilentInsideTheBandAndPullsToTheBound) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  physics::SoftwareModelSpec spec;
  spec.deadband_springs = {{"rope", 100, 0.8, 0.95}};  // rope length at qpos0: 0.9
  physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareModel(m, spec);
  mj_forward(m, d);
  EXPECT_EQ(d->qfrc_passive[0], 0);
  d->qpos[0] = -0.1;  // length 1.0: 0.05 beyond the upper bound, the ball is pulled up
  mj_forward(m, d);
  EXPECT_NEAR(d->qfrc_passive[0], 100 * 0.05, 1e-9);
  d->qpos[0] = 0.2;  // length 0.7: 0.1 short of the lower bound, pushed down
  mj_forward(m, d);
  EXPECT_NEAR(d->qfrc_passive[0], -100 * 0.1, 1e-9);
}

TEST_F(SoftwareModelTest, BadNamesAreErrors) {
  physics::SoftwareModelSpec body;
  body.gravcomp = {{"nope", 1}};
  EXPECT_THROW(physics::RegisterSoftwareModel(model_.get(), body), Error);
  physics::SoftwareModelSpec tendon;
  tendon.deadband_springs = {{"nope", 1, 0, 1}};
  EXPECT_THROW(physics::RegisterSoftwareModel(model_.get(), tendon), Error);
  physics::SoftwareModelSpec eq;
  eq.site_equalities = {{"pin", "top", "anchor"}};  // 'top' is not on the equality's body1
  EXPECT_THROW(physics::ApplySiteEqualities(model_.get(), eq), Error);
}

TEST_F(SoftwareModelTest, SiteConnectTakesItsAnchorsFromTheSites) {
  physics::SoftwareModelSpec eq;
  eq.site_equalities = {{"pin", "end", "anchor"}};
  physics::ApplySiteEqualities(model_.get(), eq);
  const mjtNum* data = model_->eq_data;
  EXPECT_EQ(data[0], 0.5);  // 'end' in the arm's frame
  EXPECT_EQ(data[5], 2);    // 'anchor' in the world's
}

}  // namespace
}  // namespace urlab
