// physics::Model, the compiled model that owns its extensions: a copy, an MJB saved and loaded
// back with its extensions' text, and the original step identically (sensor data and
// trajectories bit for bit), also on several threads at once; the content hash covers the
// extensions; the registration ends with the model.
#include <cmath>
#include <cstring>
#include <thread>
#include <vector>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"
#include "urlab/physics/software_sensors.h"

namespace urlab {
namespace {

using physics::Model;

// A motor-driven arm whose link is gravity-compensated, a ball on a rope with a dead-band
// spring, a joint actuator force sensor (a <user> sensor the runtime fills), and a weld between
// two sites whose data comes from the sites' frames.
constexpr const char* kXml = R"(<mujoco>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <site name="anchor" pos="0 0 2"/>
    <body name="arm" pos="1 0 1">
      <joint name="h" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05" mass="1"/>
    </body>
    <body name="ball" pos="0 0 1">
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom size="0.1" mass="2"/>
      <site name="top" pos="0 0 0.1"/>
    </body>
    <body name="box" pos="-1 0 1">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" mass="0.5"/>
      <site name="box_site" pos="0.1 0 0"/>
    </body>
    <site name="hook" pos="-0.85 0 1.05"/>
  </worldbody>
  <tendon>
    <spatial name="rope"><site site="anchor"/><site site="top"/></spatial>
  </tendon>
  <equality>
    <weld name="hold" body1="box" body2="world"/>
  </equality>
  <actuator>
    <motor name="m" joint="h" gear="2"/>
  </actuator>
  <sensor>
    <user name="h_force" objtype="joint" objname="h" datatype="real" needstage="acc" dim="1"/>
    <jointpos name="h_pos" joint="h"/>
    <jointpos name="z_pos" joint="z"/>
  </sensor>
</mujoco>)";

physics::SoftwareModelSpec Extensions(double gravcomp = 1.0) {
  physics::SoftwareModelSpec e;
  e.sensors = {{"h_force", physics::SoftwareSensorKind::kJointActuatorForce, {}}};
  e.gravcomp = {{"arm", gravcomp}};
  e.deadband_springs = {{"rope", 200, 0.8, 0.95}};
  e.site_equalities = {{"hold", "box_site", "hook"}};
  return e;
}

struct Trace {
  std::vector<double> qpos, qvel, sensordata;  // every step, one after the other
};

Trace Simulate(const mjModel* m, int steps) {
  physics::DataPtr data = physics::MakeData(m);
  mjData* d = data.get();
  d->qpos[1] = -0.2;  // the rope longer than its band: the spring pulls
  Trace r;
  for (int i = 0; i < steps; ++i) {
    d->ctrl[0] = 0.5 * std::sin(0.01 * i);
    mj_step(m, d);
    r.qpos.insert(r.qpos.end(), d->qpos, d->qpos + m->nq);
    r.qvel.insert(r.qvel.end(), d->qvel, d->qvel + m->nv);
    r.sensordata.insert(r.sensordata.end(), d->sensordata, d->sensordata + m->nsensordata);
  }
  return r;
}

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

bool SameRun(const Trace& a, const Trace& b) {
  return SameBits(a.qpos, b.qpos) && SameBits(a.qvel, b.qvel) &&
         SameBits(a.sensordata, b.sensordata);
}

class OwnedModelTest : public testing::MujocoTest {
 protected:
  Model Compile(double gravcomp = 1.0) {
    return Model(physics::CompileXmlString(kXml), Extensions(gravcomp));
  }
  static constexpr int kSteps = 500;
};

TEST_F(OwnedModelTest, CopyAndMjbReloadStepLikeTheOriginal) {
  const Model original = Compile();
  const Trace reference = Simulate(original.get(), kSteps);
  // The extensions act: the sensor reads the motor's joint force, the arm does not fall (its
  // gravity is compensated), and the plain MuJoCo model (what a copy used to be) runs otherwise.
  const int h_force = mj_name2id(original.get(), mjOBJ_SENSOR, "h_force");
  const std::size_t last_step = static_cast<std::size_t>((kSteps - 1) * original->nsensordata);
  EXPECT_NE(
      reference.sensordata[last_step + static_cast<std::size_t>(original->sensor_adr[h_force])], 0);
  physics::ModelPtr plain(mj_copyModel(nullptr, original.get()));
  EXPECT_FALSE(SameRun(Simulate(plain.get(), kSteps), reference));

  const Model copy = original.Copy();
  EXPECT_NE(copy.get(), original.get());
  EXPECT_TRUE(SameRun(Simulate(copy.get(), kSteps), reference));

  const Model loaded = Model::FromMjb(original.Mjb(), original.extension_text());
  EXPECT_TRUE(SameRun(Simulate(loaded.get(), kSteps), reference));
  EXPECT_EQ(loaded.Hash(), original.Hash());
  EXPECT_EQ(copy.Hash(), original.Hash());
  // A copy of the reloaded model, after the original is gone, still carries them.
  EXPECT_TRUE(SameRun(Simulate(loaded.Copy().get(), kSteps), reference));
}

TEST_F(OwnedModelTest, SiteEqualityDataTravelsWithTheModel) {
  const Model original = Compile();
  const int hold = mj_name2id(original.get(), mjOBJ_EQUALITY, "hold");
  const mjtNum* data = original->eq_data + hold * mjNEQDATA;
  EXPECT_EQ(data[3], 0.1);  // box_site in the box's frame
  const Model loaded = Model::FromMjb(original.Mjb(), original.extension_text());
  EXPECT_EQ(std::memcmp(loaded->eq_data, original->eq_data,
                        sizeof(mjtNum) * mjNEQDATA * static_cast<std::size_t>(original->neq)),
            0);
}

TEST_F(OwnedModelTest, TheHashCoversTheExtensions) {
  const Model full = Compile(1.0);
  const Model half = Compile(0.5);
  EXPECT_EQ(full.Mjb(), half.Mjb());  // MuJoCo's model alone cannot tell them apart
  EXPECT_NE(full.Hash(), half.Hash());
  const Model bare(physics::CompileXmlString(kXml));
  EXPECT_EQ(bare.extension_text(), "");
  EXPECT_EQ(bare.Hash(), physics::ContentHash(bare.Mjb(), ""));  // as recording format 1 did
  // The text reads back to the same extensions.
  EXPECT_EQ(physics::SerializeExtensions(physics::ParseExtensions(full.extension_text())),
            full.extension_text());
  EXPECT_THROW(physics::ParseExtensions("{\"version\": 99}"), Error);
  EXPECT_THROW(physics::ParseExtensions("not json"), Error);
}

TEST_F(OwnedModelTest, ExtensionNamesThatAreNotUtf8AreAnErrorNotACrash) {
  // (Found by fuzz_scene: a site name with a stray byte made the JSON dump throw past every
  // handler and end the process.)
  physics::SoftwareModelSpec spec;
  spec.site_equalities.push_back({"weld", "grip\xA4", "target"});
  try {
    (void)physics::SerializeExtensions(spec);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not UTF-8"), std::string::npos) << e.what();
  }
}

TEST_F(OwnedModelTest, RegistrationEndsWithTheModelAndSurvivesMoves) {
  const int before = physics::RegisteredSoftwareSensorModels();
  {
    Model a = Compile();
    EXPECT_EQ(physics::RegisteredSoftwareSensorModels(), before + 1);
    Model b = std::move(a);
    EXPECT_EQ(physics::RegisteredSoftwareSensorModels(), before + 1);
    Model c = b.Copy();
    EXPECT_EQ(physics::RegisteredSoftwareSensorModels(), before + 2);
    c = Compile();  // the old copy is unregistered, the new model registered
    EXPECT_EQ(physics::RegisteredSoftwareSensorModels(), before + 2);
    const Trace moved = Simulate(b.get(), 50);
    EXPECT_TRUE(SameRun(moved, Simulate(c.get(), 50)));
  }
  EXPECT_EQ(physics::RegisteredSoftwareSensorModels(), before);
}

TEST_F(OwnedModelTest, CopiesStepOnSeveralThreadsAtOnce) {
  const Model original = Compile();
  const Trace reference = Simulate(original.get(), kSteps);
  constexpr int kThreads = 4;
  std::vector<Trace> runs(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    // Each thread copies (registers), steps and drops (unregisters) its own models while the
    // others step theirs through the same process-global callbacks.
    threads.emplace_back([&, t] {
      for (int k = 0; k < 3; ++k)
        runs[static_cast<std::size_t>(t)] = Simulate(original.Copy().get(), kSteps);
    });
  }
  for (std::thread& th : threads) th.join();
  for (const Trace& r : runs) EXPECT_TRUE(SameRun(r, reference));
}

}  // namespace
}  // namespace urlab
