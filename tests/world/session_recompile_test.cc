// Session::EditModel and Session::ReloadKeepingState: new values in the running model through
// the scene's spec, with the state kept exactly; structural changes refused with nothing touched.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/state.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

// A pendulum swinging under gravity from horizontal (its damping is what the tests change).
std::string ArmXml(const std::string& damping, const std::string& extra_body = "") {
  return R"(<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping=")" +
         damping + R"("/>
      <geom name="rod" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>)" +
         extra_body + R"(
  </worldbody>
</mujoco>)";
}

struct Kept {
  std::vector<mjtNum> qpos, qvel;
  double time = 0;
};

Kept StateOf(world::Session& s) {
  Kept k;
  s.engine().WithLockedData([&](mjModel* m, mjData* d) {
    k.qpos.assign(d->qpos, d->qpos + m->nq);
    k.qvel.assign(d->qvel, d->qvel + m->nv);
    k.time = d->time;
  });
  return k;
}

// Bit for bit, not approximately.
void ExpectSameBits(const Kept& a, const Kept& b) {
  ASSERT_EQ(a.qpos.size(), b.qpos.size());
  ASSERT_EQ(a.qvel.size(), b.qvel.size());
  EXPECT_EQ(0, std::memcmp(a.qpos.data(), b.qpos.data(), a.qpos.size() * sizeof(mjtNum)));
  EXPECT_EQ(0, std::memcmp(a.qvel.data(), b.qvel.data(), a.qvel.size() * sizeof(mjtNum)));
  EXPECT_EQ(0, std::memcmp(&a.time, &b.time, sizeof(double)));
}

double Damping(world::Session& s) {
  double v = 0;
  s.engine().WithLockedData([&](mjModel* m, mjData*) { v = m->dof_damping[0]; });
  return v;
}

void SetJointDamping(mjSpec* spec, double damping) {
  mjsElement* e = mjs_findElement(spec, mjOBJ_JOINT, "arm_hinge");
  ASSERT_NE(e, nullptr);
  mjsJoint* j = mjs_asJoint(e);
  j->damping[0] = damping;
}

class SessionRecompileTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("session_recompile");
    testing::WriteTextFile(dir_, "arm.xml", ArmXml("0.01"));
    scene_path_ = testing::WriteTextFile(dir_, "scene.yaml",
                                         "articulations:\n  - name: arm\n    mjcf: arm.xml\n");
  }
  std::shared_ptr<world::Session> Create() {
    return world::Session::Create(world::LoadSceneOrModel(scene_path_));
  }
  std::string dir_, scene_path_;
};

TEST_F(SessionRecompileTest, EditThroughTheSpecTakesEffectAndKeepsTheState) {
  auto s = Create();
  s->engine().StepSync(150);
  const Kept before = StateOf(*s);
  const mjSpec* spec_before = s->scene().spec.get();
  const std::uint64_t generation = s->engine().model_generation();
  ASSERT_DOUBLE_EQ(Damping(*s), 0.01);

  const std::uint64_t seq = s->EditModel([](mjSpec* spec) { SetJointDamping(spec, 4.0); });
  EXPECT_TRUE(s->engine().WaitForCommand(seq, std::chrono::seconds(5)).ok());

  EXPECT_DOUBLE_EQ(Damping(*s), 4.0);
  ExpectSameBits(StateOf(*s), before);
  EXPECT_EQ(s->engine().model_generation(), generation + 1);
  // The edited copy is the scene's spec now: MuJoCo writes the scene with the new value.
  EXPECT_NE(s->scene().spec.get(), spec_before);
  const mjsElement* j = mjs_findElement(s->scene().spec.get(), mjOBJ_JOINT, "arm_hinge");
  ASSERT_NE(j, nullptr);
  EXPECT_DOUBLE_EQ(mjs_asJoint(const_cast<mjsElement*>(j))->damping[0], 4.0);
  EXPECT_EQ(s->spec().get(), s->scene().spec.get());
  const std::string xml = world::SceneXml(s->spec().get());
  EXPECT_NE(xml.find("damping=\"4\""), std::string::npos) << xml;
}

// The same through the physics thread: the command is applied there, between iterations.
TEST_F(SessionRecompileTest, AnEditReachesARunningEngineThroughItsCommandQueue) {
  auto s = Create();
  s->engine().StepSync(100);
  s->engine().SetPaused(true);
  s->Start();
  const Kept before = StateOf(*s);
  const std::uint64_t seq = s->EditModel([](mjSpec* spec) { SetJointDamping(spec, 4.0); });
  EXPECT_TRUE(s->engine().WaitForCommand(seq, std::chrono::seconds(10)).ok());
  EXPECT_DOUBLE_EQ(Damping(*s), 4.0);
  ExpectSameBits(StateOf(*s), before);  // paused: the time and the state stay where they were
  s->engine().SetPaused(false);
  s->engine().WaitForCommand(s->engine().Submit(physics::cmd::Step{10}), std::chrono::seconds(10));
  EXPECT_GT(StateOf(*s).time, before.time);
  s->Stop();
}

TEST_F(SessionRecompileTest, SteppingAfterTheEditIsThePhysicsOfTheNewValue) {
  auto edited = Create();
  auto unedited = Create();
  edited->engine().StepSync(100);
  unedited->engine().StepSync(100);
  ExpectSameBits(StateOf(*edited), StateOf(*unedited));
  const physics::PhysicsState at_edit = edited->engine().Snapshot();

  edited->EditModel([](mjSpec* spec) { SetJointDamping(spec, 4.0); });
  edited->engine().StepSync(100);
  unedited->engine().StepSync(100);
  const Kept e = StateOf(*edited), u = StateOf(*unedited);
  // Damping slows the swing.
  EXPECT_LT(std::abs(e.qvel[0]), std::abs(u.qvel[0]));
  EXPECT_NE(e.qpos[0], u.qpos[0]);

  // The same as a scene compiled from the edited file, started from the same state.
  testing::WriteTextFile(dir_, "arm.xml", ArmXml("4"));
  auto fresh = Create();
  fresh->engine().Restore(at_edit);
  fresh->engine().StepSync(100);
  ExpectSameBits(StateOf(*fresh), e);
}

TEST_F(SessionRecompileTest, AnEditAddingABodyIsRefusedAndNothingChanges) {
  auto s = Create();
  s->engine().StepSync(80);
  const Kept before = StateOf(*s);
  const mjSpec* spec_before = s->scene().spec.get();
  const int nbody = s->engine().model()->nbody;
  try {
    s->EditModel([](mjSpec* spec) {
      mjsBody* b = mjs_addBody(mjs_findBody(spec, "world"), nullptr);
      mjs_setName(b->element, "extra");
      mjsGeom* g = mjs_addGeom(b, nullptr);
      g->size[0] = 0.05;
    });
    FAIL() << "an edit adding a body was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nbody " + std::to_string(nbody) + " -> " + std::to_string(nbody + 1)),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("unchanged"), std::string::npos) << what;
  }
  EXPECT_EQ(s->engine().model()->nbody, nbody);
  EXPECT_EQ(s->scene().spec.get(), spec_before);
  EXPECT_EQ(mjs_findBody(s->scene().spec.get(), "extra"), nullptr);
  ExpectSameBits(StateOf(*s), before);
}

TEST_F(SessionRecompileTest, AnEditThatDoesNotCompileNamesMujocosError) {
  auto s = Create();
  try {
    s->EditModel([](mjSpec* spec) {
      mjsElement* e = mjs_findElement(spec, mjOBJ_GEOM, "arm_rod");
      mjs_setString(mjs_asGeom(e)->material, "no_such_material");
    });
    FAIL() << "an edit that cannot compile was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does not compile"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no_such_material"), std::string::npos) << e.what();
  }
}

TEST_F(SessionRecompileTest, ReloadWithTheSameStructureKeepsTheStateAndTakesTheNewValue) {
  auto s = Create();
  s->engine().StepSync(120);
  const Kept before = StateOf(*s);
  testing::WriteTextFile(dir_, "arm.xml", ArmXml("2.5"));

  const world::Session::Reload r = s->ReloadKeepingState();
  ASSERT_TRUE(r.kept) << r.reason;
  EXPECT_TRUE(s->engine().WaitForCommand(r.seq, std::chrono::seconds(5)).ok());
  EXPECT_DOUBLE_EQ(Damping(*s), 2.5);
  ExpectSameBits(StateOf(*s), before);
}

TEST_F(SessionRecompileTest, ReloadWithAChangedStructureFallsBackSayingWhy) {
  auto s = Create();
  s->engine().StepSync(60);
  const Kept before = StateOf(*s);
  testing::WriteTextFile(dir_, "arm.xml",
                         ArmXml("2.5", R"(<body name="ball" pos="1 0 1"><freejoint/>
      <geom type="sphere" size="0.05"/></body>)"));
  const world::Session::Reload r = s->ReloadKeepingState();
  EXPECT_FALSE(r.kept);
  EXPECT_NE(r.reason.find("nq 1 -> 8"), std::string::npos) << r.reason;
  EXPECT_DOUBLE_EQ(Damping(*s), 0.01);
  ExpectSameBits(StateOf(*s), before);
}

TEST_F(SessionRecompileTest, ReloadOfAFileThatNoLongerLoadsFallsBack) {
  auto s = Create();
  testing::WriteTextFile(dir_, "arm.xml", "<mujoco><worldbody><body></mujoco>");
  const world::Session::Reload r = s->ReloadKeepingState();
  EXPECT_FALSE(r.kept);
  EXPECT_NE(r.reason.find("arm.xml"), std::string::npos) << r.reason;
  EXPECT_DOUBLE_EQ(Damping(*s), 0.01);
}

TEST_F(SessionRecompileTest, ReloadAfterTheSceneFileChangedFallsBack) {
  auto s = Create();
  testing::WriteTextFile(dir_, "scene.yaml",
                         "articulations:\n  - name: arm\n    mjcf: arm.xml\n    pos: [0, 0, 1]\n");
  const world::Session::Reload r = s->ReloadKeepingState();
  EXPECT_FALSE(r.kept);
  EXPECT_NE(r.reason.find("scene.yaml changed"), std::string::npos) << r.reason;
}

// The gait controller took the robot's masses and feet when it bound: a mass edit is refused, a
// value it never read (a leg joint's damping) is taken.
TEST_F(SessionRecompileTest, AGaitControlledRobotRefusesAMassEditButTakesADampingEdit) {
  auto s = world::Session::Create(
      world::LoadSceneFile(std::string(URLAB_SOURCE_DIR) + "/examples/scenes/quadruped_walk.yaml"));
  s->engine().StepSync(50);
  const Kept before = StateOf(*s);
  const mjModel* m = s->engine().model();
  try {
    s->EditModel([&](mjSpec* spec) {
      mjsElement* torso = mjs_findElement(spec, mjOBJ_GEOM, "dog_torso");
      ASSERT_NE(torso, nullptr);
      mjs_asGeom(torso)->mass = 12;
    });
    FAIL() << "a mass edit of a walking robot was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gait controller"), std::string::npos) << e.what();
  }
  ExpectSameBits(StateOf(*s), before);

  const int dof = m->jnt_dofadr[1];
  const std::string joint = mj_id2name(m, mjOBJ_JOINT, 1);
  const std::uint64_t seq = s->EditModel([&](mjSpec* spec) {
    mjsJoint* j = mjs_asJoint(mjs_findElement(spec, mjOBJ_JOINT, joint.c_str()));
    ASSERT_NE(j, nullptr);
    j->damping[0] = 0.75;
  });
  EXPECT_TRUE(s->engine().WaitForCommand(seq, std::chrono::seconds(5)).ok());
  s->engine().WithLockedData(
      [&](mjModel* model, mjData*) { EXPECT_EQ(model->dof_damping[dof], 0.75); });
  ExpectSameBits(StateOf(*s), before);
}

}  // namespace
}  // namespace urlab
