#include "urlab/physics/state.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "urlab/physics/model.h"

namespace urlab::physics {
namespace {

using testing::kArmXml;
using testing::kHumanoidPath;

class StateTest : public urlab::testing::MujocoTest {};

// Puts a data into an "interesting" state: moving, in contact, with inputs set everywhere.
void Excite(const mjModel* m, mjData* d, int steps) {
  for (int i = 0; i < steps; ++i) {
    for (int u = 0; u < m->nu; ++u) d->ctrl[u] = 0.5 * std::sin(0.01 * i + u);
    if (m->nbody > 1) d->xfrc_applied[6 * 1 + 2] = 2.0 * std::cos(0.02 * i);
    if (m->nv > 0) d->qfrc_applied[0] = 0.1 * std::sin(0.03 * i);
    for (int k = 0; k < m->nuserdata; ++k) d->userdata[k] = i + k;
    for (int k = 0; k < m->nmocap; ++k) d->mocap_pos[3 * k] += 1e-4;
    mj_step(m, d);
  }
}

bool StateBitsEqual(const mjtNum* a, const mjtNum* b, int n) {
  return n == 0 || std::memcmp(a, b, sizeof(mjtNum) * static_cast<std::size_t>(n)) == 0;
}

// Runs `steps` of a fixed, input-free continuation and returns the final state.
PhysicsState Continue(const mjModel* m, mjData* d, int steps) {
  for (int i = 0; i < steps; ++i) mj_step(m, d);
  return CaptureState(m, d);
}

TEST_F(StateTest, CaptureApplyRoundTrip) {
  ModelPtr m = CompileXmlString(kArmXml);
  DataPtr d = MakeData(m.get());
  Excite(m.get(), d.get(), 200);
  const PhysicsState s = CaptureState(m.get(), d.get());
  EXPECT_TRUE(s.IsConsistent());
  EXPECT_EQ(s.act.size(), 1u);
  EXPECT_EQ(s.mocap_quat.size(), 4u);
  EXPECT_EQ(s.userdata.size(), 3u);
  DataPtr d2 = MakeData(m.get());
  ApplyState(m.get(), d2.get(), s);
  EXPECT_TRUE(CaptureState(m.get(), d2.get()).BitwiseEquals(s));
}

// The central property: restore + continue reproduces the continuation bit for bit, for
// every derived quantity too (sensors, contacts, energy).
TEST_F(StateTest, RestoreReproducesContinuationBitForBit) {
  ModelPtr m = LoadXmlFile(kHumanoidPath);
  m->opt.enableflags |= mjENBL_ENERGY;
  DataPtr d = MakeData(m.get());
  Excite(m.get(), d.get(), 1000);  // humanoid has fallen and is in contact by now
  const PhysicsState snap = CaptureState(m.get(), d.get());
  const PhysicsState a = Continue(m.get(), d.get(), 1000);
  std::vector<mjtNum> a_xpos(d->xpos, d->xpos + 3 * m->nbody);
  std::vector<mjtNum> a_sensor(d->sensordata, d->sensordata + m->nsensordata);
  const double a_energy[2] = {d->energy[0], d->energy[1]};
  const int a_ncon = d->ncon;

  // Restore into a fresh mjData as well as into the used one.
  for (int fresh = 0; fresh < 2; ++fresh) {
    DataPtr fresh_data = MakeData(m.get());
    mjData* target = fresh ? fresh_data.get() : d.get();
    RestoreState(m.get(), target, snap);
    const PhysicsState b = Continue(m.get(), target, 1000);
    EXPECT_TRUE(a.BitwiseEquals(b)) << "fresh=" << fresh;
    EXPECT_TRUE(StateBitsEqual(a_xpos.data(), target->xpos, 3 * m->nbody));
    EXPECT_TRUE(StateBitsEqual(a_sensor.data(), target->sensordata, m->nsensordata));
    EXPECT_TRUE(StateBitsEqual(a_energy, target->energy, 2));
    EXPECT_EQ(a_ncon, target->ncon);
  }
  EXPECT_GT(a_ncon, 0) << "the test should exercise contacts";
}

// Shows that the warm start is part of the state: dropping it changes the continuation.
// MuJoCo 3's state beyond 2.2.2's: the history buffers of delayed actuators and sensors, and
// equality constraints switched off at run time, travel with the state (mj_getState's
// components): a restore continues bit for bit, and without them it would not.
TEST_F(StateTest, HistoryAndEqActiveAreState) {
  ModelPtr m = CompileXmlString(R"(<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <body name="a"><joint name="h" axis="0 1 0"/><geom size=".1" pos=".2 0 0"/></body>
    <body name="b" pos="0 0 1"><freejoint/><geom size=".1"/></body>
  </worldbody>
  <equality><weld name="hold" body1="b"/></equality>
  <actuator><motor joint="h" nsample="4" delay="0.006"/></actuator>
  <sensor><jointpos joint="h" nsample="3" delay="0.004"/></sensor>
</mujoco>)");
  DataPtr d = MakeData(m.get());
  for (int i = 0; i < 50; ++i) {
    d->ctrl[0] = std::sin(0.3 * i);
    mj_step(m.get(), d.get());
  }
  d->eq_active[0] = 0;  // the box falls from here on
  const PhysicsState s = CaptureState(m.get(), d.get());
  EXPECT_GT(s.layout.nhistory, 0);
  EXPECT_EQ(s.history.size(), static_cast<std::size_t>(s.layout.nhistory));
  ASSERT_EQ(s.eq_active.size(), 1u);
  EXPECT_EQ(s.eq_active[0], 0.0);
  const auto run = [&](mjData* data) {
    for (int i = 0; i < 20; ++i) {
      data->ctrl[0] = 0;
      mj_step(m.get(), data);
    }
    return CaptureState(m.get(), data);
  };
  const PhysicsState reference = run(d.get());
  DataPtr restored = MakeData(m.get());
  RestoreState(m.get(), restored.get(), s);
  // (A fresh mjData's history holds no controls: without it the delayed motor acts otherwise.)
  EXPECT_TRUE(run(restored.get()).BitwiseEquals(reference));
  // The serialised form carries them.
  EXPECT_TRUE(DeserializeState(SerializeState(s)).BitwiseEquals(s));
}

TEST_F(StateTest, WarmstartIsNecessary) {
  ModelPtr m = LoadXmlFile(kHumanoidPath);
  DataPtr d = MakeData(m.get());
  Excite(m.get(), d.get(), 1000);
  PhysicsState snap = CaptureState(m.get(), d.get());
  const PhysicsState a = Continue(m.get(), d.get(), 200);
  std::fill(snap.qacc_warmstart.begin(), snap.qacc_warmstart.end(), 0.0);
  RestoreState(m.get(), d.get(), snap);
  const PhysicsState b = Continue(m.get(), d.get(), 200);
  EXPECT_FALSE(a.BitwiseEquals(b));
}

TEST_F(StateTest, DeterminismAcrossReset) {
  ModelPtr m = CompileXmlString(kArmXml);
  DataPtr d = MakeData(m.get());
  Excite(m.get(), d.get(), 300);
  const PhysicsState snap = CaptureState(m.get(), d.get());
  auto run = [&] {
    Excite(m.get(), d.get(), 300);
    mj_resetData(m.get(), d.get());
    mj_forward(m.get(), d.get());
    Excite(m.get(), d.get(), 300);
    return CaptureState(m.get(), d.get());
  };
  const PhysicsState a = run();
  RestoreState(m.get(), d.get(), snap);
  const PhysicsState b = run();
  EXPECT_TRUE(a.BitwiseEquals(b));
}

TEST_F(StateTest, ApplyRejectsOtherModel) {
  ModelPtr arm = CompileXmlString(kArmXml);
  ModelPtr hum = LoadXmlFile(kHumanoidPath);
  DataPtr d = MakeData(hum.get());
  DataPtr da = MakeData(arm.get());
  const PhysicsState s = CaptureState(arm.get(), da.get());
  try {
    ApplyState(hum.get(), d.get(), s);
    FAIL() << "expected StateError";
  } catch (const StateError& e) {
    EXPECT_NE(std::string(e.what()).find("does not match the model"), std::string::npos);
  }
  PhysicsState broken = s;
  broken.qpos.pop_back();
  EXPECT_THROW(ApplyState(arm.get(), da.get(), broken), StateError);
}

TEST_F(StateTest, SerializeRoundTrip) {
  ModelPtr m = CompileXmlString(kArmXml);
  DataPtr d = MakeData(m.get());
  Excite(m.get(), d.get(), 100);
  d->qvel[0] = std::nan("");  // NaN payloads survive too
  const PhysicsState s = CaptureState(m.get(), d.get());
  const std::vector<std::uint8_t> bytes = SerializeState(s);
  const PhysicsState t = DeserializeState(bytes);
  EXPECT_TRUE(s.BitwiseEquals(t));
  EXPECT_EQ(t.layout, StateLayout::Of(m.get()));
}

std::string ErrorOf(const std::vector<std::uint8_t>& bytes) {
  try {
    DeserializeState(bytes);
  } catch (const StateError& e) {
    return e.what();
  }
  return "";
}

TEST_F(StateTest, DeserializeRejectsCorruptInput) {
  ModelPtr m = CompileXmlString(kArmXml);
  DataPtr d = MakeData(m.get());
  const std::vector<std::uint8_t> good = SerializeState(CaptureState(m.get(), d.get()));

  EXPECT_NE(ErrorOf({}).find("bad magic"), std::string::npos);
  auto bad_magic = good;
  bad_magic[0] = 'X';
  EXPECT_NE(ErrorOf(bad_magic).find("bad magic"), std::string::npos);

  auto bad_version = good;
  bad_version[4] = 99;
  EXPECT_NE(ErrorOf(bad_version).find("unsupported state format version 99"), std::string::npos);

  auto truncated = good;
  truncated.resize(good.size() - 9);
  EXPECT_NE(ErrorOf(truncated).find("truncated"), std::string::npos);
  auto header_only = good;
  header_only.resize(20);
  EXPECT_NE(ErrorOf(header_only).find("truncated"), std::string::npos);

  auto too_long = good;
  too_long.push_back(0);
  EXPECT_NE(ErrorOf(too_long).find("expected"), std::string::npos);

  auto flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  EXPECT_NE(ErrorOf(flipped).find("checksum"), std::string::npos);

  auto bad_layout = good;
  const std::int32_t huge = -5;
  std::memcpy(bad_layout.data() + 12, &huge, 4);  // nq
  EXPECT_NE(ErrorOf(bad_layout).find("bad length for qpos"), std::string::npos);

  auto inconsistent = good;
  const std::int32_t nq = 3;
  std::memcpy(inconsistent.data() + 12, &nq, 4);
  EXPECT_NE(ErrorOf(inconsistent).find("payload"), std::string::npos);
}

}  // namespace
}  // namespace urlab::physics
