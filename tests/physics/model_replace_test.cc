// InPlaceDifference, CopyModelValuesInPlace and the ReplaceModel command: a new compile's values
// in a running model of the same structure, every address and the whole state kept.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "support/mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/model.h"

namespace urlab::physics {
namespace {

class ModelReplaceTest : public urlab::testing::MujocoTest {};

// A hinged rod and a free ball; `body`, `joint` and `range` are what the cases change.
std::string Xml(const std::string& damping = "0.1", const std::string& joint = "hinge",
                const std::string& range = "-1 1", const std::string& extra = "",
                const std::string& timestep = "0.002") {
  return R"(<mujoco>
  <option timestep=")" +
         timestep + R"("/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name=")" +
         joint + R"(" axis="0 1 0" range=")" + range + R"(" damping=")" + damping + R"("/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
    <body name="ball" pos="0.5 0 1"><freejoint/><geom size="0.05" mass="0.2"/></body>)" +
         extra + R"(
  </worldbody>
</mujoco>)";
}

TEST_F(ModelReplaceTest, SameStructureIsNamedEmptyAndTheCopyKeepsEveryAddress) {
  ModelPtr running = CompileXmlString(Xml("0.1"));
  ModelPtr fresh = CompileXmlString(Xml("3"));
  EXPECT_EQ(InPlaceDifference(running.get(), fresh.get()), "");
  void* buffer = running->buffer;
  mjtNum* damping = running->dof_damping;
  mjtNum* mass = running->body_mass;
  CopyModelValuesInPlace(running.get(), fresh.get());
  EXPECT_EQ(running->buffer, buffer);
  EXPECT_EQ(running->dof_damping, damping);
  EXPECT_EQ(running->body_mass, mass);
  EXPECT_EQ(running->dof_damping[0], 3.0);
  EXPECT_EQ(std::string(MjbBytes(running.get())), std::string(MjbBytes(fresh.get())));
}

TEST_F(ModelReplaceTest, DifferencesAreNamed) {
  ModelPtr running = CompileXmlString(Xml());
  EXPECT_EQ(
      InPlaceDifference(running.get(),
                        CompileXmlString(Xml("0.1", "hinge", "-1 1",
                                             R"(<body name="extra"><geom size="0.1"/></body>)"))
                            .get()),
      "nbody 3 -> 4");
  EXPECT_EQ(InPlaceDifference(running.get(), CompileXmlString(Xml("0.1", "knee")).get()),
            "joint 0 'hinge' is now 'knee'");
  EXPECT_EQ(InPlaceDifference(running.get(), CompileXmlString(Xml("0.1", "hinge", "-2 2")).get()),
            "joint 'hinge' range");
}

TEST_F(ModelReplaceTest, ReplaceModelKeepsTheStateExactlyAndFollowsTheTimestep) {
  PhysicsEngine engine(CompileXmlString(Xml()));
  engine.StepSync(200);
  const PhysicsState before = engine.Snapshot();
  const std::uint64_t generation = engine.model_generation();

  cmd::ReplaceModel c;
  c.model = std::make_shared<const Model>(CompileXmlString(Xml("3", "hinge", "-1 1", "", "0.001")));
  const std::uint64_t seq = engine.Submit(std::move(c));
  EXPECT_TRUE(engine.WaitForCommand(seq, std::chrono::seconds(5)).ok());

  // The whole integration state (time, qpos, qvel, act, warm start, ctrl, applied forces, mocap,
  // ...), bit for bit.
  EXPECT_TRUE(engine.Snapshot().BitwiseEquals(before));
  EXPECT_EQ(engine.timestep(), 0.001);
  EXPECT_EQ(engine.model_generation(), generation + 1);
  engine.WithLockedData([](mjModel* m, mjData*) { EXPECT_EQ(m->dof_damping[0], 3.0); });
}

TEST_F(ModelReplaceTest, KeepOptionsKeepsTheOptionsInEffect) {
  PhysicsEngine engine(CompileXmlString(Xml()));
  engine.Submit(cmd::SetOptions{[](mjOption& o) { o.gravity[2] = -1; }, "gravity"});
  cmd::ReplaceModel c;
  c.model = std::make_shared<const Model>(CompileXmlString(Xml("3", "hinge", "-1 1", "", "0.001")));
  c.keep_options = true;
  engine.Submit(std::move(c));
  engine.WithLockedData([](mjModel* m, mjData*) {
    EXPECT_EQ(m->opt.gravity[2], -1);
    EXPECT_EQ(m->opt.timestep, 0.002);
    EXPECT_EQ(m->dof_damping[0], 3.0);
  });
  EXPECT_EQ(engine.timestep(), 0.002);
}

TEST_F(ModelReplaceTest, AnotherStructureIsRefusedAtSubmission) {
  PhysicsEngine engine(CompileXmlString(Xml()));
  engine.StepSync(10);
  const PhysicsState before = engine.Snapshot();
  cmd::ReplaceModel c;
  c.model = std::make_shared<const Model>(CompileXmlString(
      Xml("0.1", "hinge", "-1 1", R"(<body name="extra"><geom size="0.1"/></body>)")));
  try {
    engine.Submit(std::move(c));
    FAIL() << "a model of another structure was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nbody 3 -> 4"), std::string::npos) << e.what();
  }
  EXPECT_EQ(engine.model()->nbody, 3);
  EXPECT_TRUE(engine.Snapshot().BitwiseEquals(before));
}

}  // namespace
}  // namespace urlab::physics
