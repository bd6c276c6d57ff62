// physics::Model: a copy, an MJB saved and loaded back, and the original step identically
// (sensor data and trajectories bit for bit), also on several threads at once, for a model using
// what MuJoCo 2.2.2 lacked and URLab once computed beside it (body gravity compensation, a
// dead-band tendon spring, a joint actuator force sensor, a weld between two sites): MuJoCo 3
// computes them itself, so the MJB alone holds the whole physics.
#include <cmath>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "mujoco_test.h"
#include "physics/test_models.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

using physics::Model;

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
  static Model Compile(double gravcomp = 1.0) {
    return Model(physics::CompileXmlString(testing::CompensatedArmXml(gravcomp)));
  }
  static constexpr int kSteps = 500;
};

TEST_F(OwnedModelTest, CopyAndMjbReloadStepLikeTheOriginal) {
  const Model original = Compile();
  const Trace reference = Simulate(original.get(), kSteps);
  // MuJoCo computes them: the sensor reads the motor's joint force, and the arm falls otherwise
  // without its gravity compensation.
  const int h_force = mj_name2id(original.get(), mjOBJ_SENSOR, "h_force");
  const std::size_t last_step = static_cast<std::size_t>((kSteps - 1) * original->nsensordata);
  EXPECT_NE(
      reference.sensordata[last_step + static_cast<std::size_t>(original->sensor_adr[h_force])], 0);
  EXPECT_FALSE(SameRun(Simulate(Compile(0.0).get(), kSteps), reference));

  const Model copy = original.Copy();
  EXPECT_NE(copy.get(), original.get());
  EXPECT_TRUE(SameRun(Simulate(copy.get(), kSteps), reference));

  const Model loaded = Model::FromMjb(original.Mjb());
  EXPECT_TRUE(SameRun(Simulate(loaded.get(), kSteps), reference));
  EXPECT_EQ(loaded.Hash(), original.Hash());
  EXPECT_EQ(copy.Hash(), original.Hash());
  // A copy of the reloaded model steps the same.
  EXPECT_TRUE(SameRun(Simulate(loaded.Copy().get(), kSteps), reference));
}

TEST_F(OwnedModelTest, SiteEqualityTravelsWithTheModel) {
  const Model original = Compile();
  const int hold = mj_name2id(original.get(), mjOBJ_EQUALITY, "hold");
  // MuJoCo's own weld between two sites (2.2.2 had only bodies: URLab wrote the anchors).
  EXPECT_EQ(original->eq_objtype[hold], mjOBJ_SITE);
  EXPECT_EQ(original->eq_obj1id[hold], mj_name2id(original.get(), mjOBJ_SITE, "box_site"));
  const Model loaded = Model::FromMjb(original.Mjb());
  EXPECT_EQ(loaded->eq_objtype[hold], mjOBJ_SITE);
  EXPECT_EQ(std::memcmp(loaded->eq_data, original->eq_data,
                        sizeof(mjtNum) * mjNEQDATA * static_cast<std::size_t>(original->neq)),
            0);
}

TEST_F(OwnedModelTest, TheHashIsTheMjbs) {
  const Model full = Compile(1.0);
  const Model half = Compile(0.5);
  EXPECT_NE(full.Mjb(), half.Mjb());  // the gravity compensation is in MuJoCo's model
  EXPECT_NE(full.Hash(), half.Hash());
  EXPECT_EQ(full.Hash(), physics::ContentHash(full.Mjb()));
  EXPECT_EQ(full.Copy().Hash(), full.Hash());
}

TEST_F(OwnedModelTest, CopiesStepOnSeveralThreadsAtOnce) {
  const Model original = Compile();
  const Trace reference = Simulate(original.get(), kSteps);
  constexpr int kThreads = 4;
  std::vector<Trace> runs(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    // Each thread copies, steps and drops its own models while the others step theirs.
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
