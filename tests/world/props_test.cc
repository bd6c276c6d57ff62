// Quick Convert props in scenes: a converted mug keeps its opening (a ball dropped into it stays
// inside, where a single convex hull holds it on top), modes (static, dynamic, mocap driven by
// the host), part geoms in group 3 and the scene-file errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "convert/test_meshes.h"
#include "mujoco_test.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/physics/model.h"
#include "urlab/world/manager.h"
#include "urlab/world/scene.h"
#include "urlab/world/session.h"
#include "wait.h"

namespace urlab {
namespace {

// A table top and a ball 25 cm above the mug's centre.
constexpr const char* kTable = R"(<mujoco model="table">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="top" type="box" size="0.4 0.4 0.02" pos="0 0 0.7"/>
    <body name="ball" pos="0 0 0.97">
      <freejoint/>
      <geom type="sphere" size="0.015" density="500"/>
    </body>
  </worldbody>
</mujoco>)";

class PropsTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("props");
    setenv("URLAB_CACHE_DIR", (dir_ + "/cache").c_str(), 1);
    testing::WriteTextFile(dir_, "table.xml", kTable);
    const std::string obj = convert::ObjBytes(convert::testing::Cup());
    std::ofstream(dir_ + "/mug.obj", std::ios::binary) << obj;
  }
  void TearDown() override {
    unsetenv("URLAB_CACHE_DIR");
    testing::MujocoTest::TearDown();
  }
  world::SceneConfig Scene(const std::string& prop_extra) {
    return world::ParseScene(R"(articulations:
  - name: table
    mjcf: table.xml
props:
  - name: mug
    mesh: mug.obj
    pos: [0, 0, 0.72]
)" + prop_extra,
                             dir_ + "/scene.yaml");
  }
  // Drops the ball and returns its final position relative to the mug's base.
  std::array<double, 3> DropBall(const world::CompiledScene& s) {
    const mjModel* m = s.model.get();
    physics::DataPtr d = physics::MakeData(m);
    for (int i = 0; i < 1000; ++i) mj_step(m, d.get());  // 2 s
    const int ball = mj_name2id(m, mjOBJ_BODY, "table_ball");
    return {d->xpos[3 * ball], d->xpos[3 * ball + 1], d->xpos[3 * ball + 2] - 0.72};
  }
  std::string dir_;
};

TEST_F(PropsTest, ConvertedMugKeepsTheBallInside_SingleHullDoesNot) {
  const world::CompiledScene s = world::BuildScene(Scene(""));
  ASSERT_EQ(s.props.size(), 1u);
  const world::PropLayout& mug = s.props[0];
  EXPECT_GE(mug.part_geoms.size(), 4u);
  for (int g : mug.part_geoms) {
    EXPECT_EQ(s.model->geom_group[g], convert::kPartGroup);
    EXPECT_TRUE(world::IsConvertedPropPart(s, g));
  }
  EXPECT_EQ(s.model->geom_group[mug.visual_geom], convert::kVisualGroup);
  EXPECT_EQ(s.model->geom_contype[mug.visual_geom], 0);
  EXPECT_FALSE(world::IsConvertedPropPart(s, mug.visual_geom));
  const auto inside = DropBall(s);
  EXPECT_LT(std::hypot(inside[0], inside[1]), 0.044) << "the ball left the mug";
  EXPECT_LT(inside[2], 0.1) << "the ball is not inside the mug (z above the base " << inside[2]
                            << ")";
  EXPECT_GT(inside[2], 0.0);

  const world::CompiledScene hull = world::BuildScene(Scene("    max_parts: 1\n"));
  ASSERT_EQ(hull.props[0].part_geoms.size(), 1u);
  const auto on_top = DropBall(hull);
  EXPECT_GT(on_top[2], 0.1) << "a single hull should hold the ball above the rim";
}

TEST_F(PropsTest, SecondBuildReadsTheCachedDecomposition) {
  EXPECT_EQ(world::BuildScene(Scene("")).props[0].parts_from_cache, 0);
  EXPECT_EQ(world::BuildScene(Scene("")).props[0].parts_from_cache, 1);
}

TEST_F(PropsTest, DynamicPropFallsAndReportsItsPose_MocapPropFollowsTheHost) {
  world::SceneConfig scene = Scene("    mode: dynamic\n    mass: 0.3\n");
  scene.props[0].pos = {0.2, 0, 1.0};
  {
    world::Manager manager;
    manager.BeginPlay(scene);
    const world::PropLayout* p = manager.session().FindProp("mug");
    ASSERT_NE(p, nullptr);
    EXPECT_NEAR(manager.session().engine().model()->body_subtreemass[p->body], 0.3, 1e-9);
    manager.session().SetPaused(false);
    // A dynamic prop falls: ticked until its reported pose is a centimetre lower (bounded).
    EXPECT_TRUE(urlab::testing::WaitFor([&] {
      manager.Tick();
      const auto now = manager.BodyPose("mug", "body");
      return now && now->pos[2] < 0.99;
    })) << "a dynamic prop falls";
    const auto pose = manager.BodyPose("mug", "body");
    ASSERT_TRUE(pose);
    EXPECT_THROW(manager.session().SetHostDrivenPose("mug", "body", {}), Error);
    manager.EndPlay();
  }
  world::SceneConfig mocap = Scene("    mode: mocap\n");
  world::Manager manager;
  manager.BeginPlay(mocap);
  world::Pose target;
  target.pos = {0.3, -0.2, 0.9};
  manager.session().SetHostDrivenPose("mug", "body", target);
  // Ticked until the mocap body left where the scene put it (bounded): then it is at the target.
  EXPECT_TRUE(urlab::testing::WaitFor([&] {
    manager.Tick();
    const auto now = manager.BodyPose("mug", "body");
    return now && now->pos[2] != 0.72;
  }));
  const auto pose = manager.BodyPose("mug", "body");
  ASSERT_TRUE(pose);
  EXPECT_NEAR(pose->pos[0], 0.3, 1e-9);
  EXPECT_NEAR(pose->pos[2], 0.9, 1e-9);
  manager.EndPlay();
}

TEST_F(PropsTest, BadPropEntriesNameTheLine) {
  auto error_of = [&](const std::string& extra) {
    try {
      Scene(extra);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("    mode: floating\n").find("scene.yaml:8: mug.mode must be static, dynamic"),
            std::string::npos)
      << error_of("    mode: floating\n");
  EXPECT_NE(error_of("    mass: -1\n").find("mug.mass must be > 0"), std::string::npos);
  EXPECT_NE(error_of("    mass: 1\n    density: 2\n").find("mass or density"), std::string::npos);
  EXPECT_NE(error_of("    threshold: 0\n").find("threshold"), std::string::npos);
  EXPECT_NE(error_of("    max_parts: 2.5\n").find("integer"), std::string::npos);
  EXPECT_NE(error_of("    colour: red\n").find("unknown key 'colour'"), std::string::npos);
  const std::string missing = [&] {
    try {
      world::ParseScene(
          "articulations:\n  - name: table\n    mjcf: table.xml\nprops:\n  - name: x\n"
          "    mesh: nowhere.stl\n",
          dir_ + "/scene.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  EXPECT_NE(missing.find("scene.yaml:6: x: mesh file"), std::string::npos) << missing;
  EXPECT_NE(missing.find("nowhere.stl"), std::string::npos) << missing;
}

TEST_F(PropsTest, ErrorsBuildingAPropNameItsSceneLineThenItsFile) {
  // They used to name only the mesh file (line 0) or the generated model.
  testing::WriteTextFile(dir_, "flat.obj",
                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  std::ofstream(dir_ + "/empty.stl", std::ios::binary) << std::string(84, '\0');
  for (const auto& [mesh, what] : {std::pair{"flat.obj", "cannot use this mesh as the visual mesh"},
                                   {"empty.stl", "the mesh has no triangles"}}) {
    const world::SceneConfig scene = world::ParseScene(
        std::string("articulations:\n  - {name: table, mjcf: table.xml}\nprops:\n  - name: p\n"
                    "    mesh: ") +
            mesh + "\n",
        dir_ + "/scene.yaml");
    try {
      world::BuildScene(scene);
      ADD_FAILURE() << mesh << " built";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().str(), dir_ + "/scene.yaml:4") << e.what();
      EXPECT_NE(e.message().find("p: " + dir_ + "/" + mesh + ": "), std::string::npos) << e.what();
      EXPECT_NE(e.message().find(what), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace urlab
