// Software sensors: <user> sensors filled in by the runtime through mjcb_sensor, dispatched by
// model; the values are MuJoCo's own actuator results.
#include "urlab/physics/software_sensors.h"

#include <atomic>
#include <thread>

#include "compiled_model_test.h"
#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

using physics::SoftwareSensorKind;
using physics::SoftwareSensorSpec;

constexpr const char* kSensorsModel = R"(<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body>
      <joint name="j" axis="0 0 1"/>
      <geom type="box" size="0.1 0.2 0.3"/>
      <body pos="1 0 0">
        <joint name="k" type="slide" axis="1 0 0"/>
        <geom type="box" size="0.1 0.1 0.1"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="t"><joint joint="j" coef="1"/><joint joint="k" coef="2"/></fixed>
  </tendon>
  <actuator>
    <motor name="mj" joint="j" gear="2"/>
    <motor name="mt1" tendon="t" gear="3"/>
    <motor name="mt2" tendon="t"/>
  </actuator>
  <sensor>
    <user name="jf" objtype="joint" objname="j" datatype="real" needstage="acc" dim="1"/>
    <user name="tf" objtype="tendon" objname="t" datatype="real" needstage="acc" dim="1"/>
    <user name="cut" objtype="joint" objname="j" datatype="real" needstage="acc" dim="1"
          cutoff="1"/>
    <user name="wide" objtype="joint" objname="j" datatype="real" needstage="acc" dim="2"/>
  </sensor>
</mujoco>)";

const SoftwareSensorSpec kSpecs[] = {{"jf", SoftwareSensorKind::kJointActuatorForce},
                                     {"tf", SoftwareSensorKind::kTendonActuatorForce},
                                     {"cut", SoftwareSensorKind::kJointActuatorForce}};

class SoftwareSensorsTest : public testing::CompiledModelTest {
 protected:
  const char* Xml() const override { return kSensorsModel; }
};

TEST_F(SoftwareSensorsTest, ComputesJointAndTendonActuatorForces) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareSensors(m, kSpecs);
  d->ctrl[0] = 0.25;
  d->ctrl[1] = 0.5;
  d->ctrl[2] = -2;
  mj_step(m, d);
  // joint j: 2 * 0.25 from its motor + tendon moment 1 * (3 * 0.5 + 1 * -2)
  EXPECT_NEAR(d->qfrc_actuator[0], 0.5 + (1.5 - 2), 1e-12);
  EXPECT_NEAR(d->sensordata[0], d->qfrc_actuator[0], 1e-12);
  // tendon: sum of its actuators' forces (gear not applied)
  EXPECT_NEAR(d->sensordata[1], 0.5 - 2, 1e-12);
  // cutoff
  d->ctrl[0] = 5;
  mj_step(m, d);
  EXPECT_NEAR(d->sensordata[2], 1, 1e-12);
}

TEST_F(SoftwareSensorsTest, UnregisteredModelsAreLeftAlone) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  {
    physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareSensors(m, kSpecs);
    EXPECT_GE(physics::RegisteredSoftwareSensorModels(), 1);
  }
  d->ctrl[0] = 1;
  mj_step(m, d);
  EXPECT_EQ(d->sensordata[0], 0);
  // A replaced registration does not remove the newer one.
  physics::SoftwareSensorRegistration a = physics::RegisterSoftwareSensors(m, kSpecs);
  physics::SoftwareSensorRegistration b = physics::RegisterSoftwareSensors(m, kSpecs);
  a = physics::SoftwareSensorRegistration();
  mj_step(m, d);
  EXPECT_NEAR(d->sensordata[0], 2, 1e-12);
}

TEST_F(SoftwareSensorsTest, BadSpecsAreErrors) {
  const mjModel* m = model_.get();
  const SoftwareSensorSpec missing{"nope", SoftwareSensorKind::kJointActuatorForce};
  EXPECT_THROW(physics::RegisterSoftwareSensors(m, {&missing, 1}), Error);
  const SoftwareSensorSpec wide{"wide", SoftwareSensorKind::kJointActuatorForce};
  EXPECT_THROW(physics::RegisterSoftwareSensors(m, {&wide, 1}), Error);
  const SoftwareSensorSpec wrong{"tf", SoftwareSensorKind::kJointActuatorForce};
  EXPECT_THROW(physics::RegisterSoftwareSensors(m, {&wrong, 1}), Error);
}

TEST_F(SoftwareSensorsTest, ModelsOnSeveralThreadsAreDispatchedByModel) {
  physics::ModelPtr other = physics::CompileXmlString(kSensorsModel);
  physics::SoftwareSensorRegistration r1 = physics::RegisterSoftwareSensors(model_.get(), kSpecs);
  physics::SoftwareSensorRegistration r2 = physics::RegisterSoftwareSensors(other.get(), kSpecs);
  std::atomic<int> bad = 0;
  auto run = [&](const mjModel* m, double ctrl) {
    physics::DataPtr d = physics::MakeData(m);
    for (int i = 0; i < 2000; ++i) {
      d->ctrl[0] = ctrl;
      mj_step(m, d.get());
      if (d->sensordata[0] != d->qfrc_actuator[0]) ++bad;
    }
  };
  std::thread t1(run, model_.get(), 0.1), t2(run, other.get(), -0.2);
  t1.join();
  t2.join();
  EXPECT_EQ(bad.load(), 0);
}

}  // namespace
}  // namespace urlab
