// A scene of the bundled robots (the Go2- and H1-style Unitree models and the Menagerie-style
// arm) plus a second Go2, composed through mjSpec: every name carries its articulation's prefix,
// no articulation's defaults reach another's elements (every joint, geom and actuator has the
// parameters of the same file compiled alone), each articulation starts in its own keyframe at
// its placement, and the MJB of the composed model steps bit for bit like the model itself.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <string>
#include <vector>

#include "mujoco_test.h"
#include "urlab/physics/model.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

struct BundledRobot {
  const char* name;
  const char* file;  // under tests/data/mjcf/robots
  double x;          // placement
};
constexpr BundledRobot kRobots[] = {{"dog", "go2/scene.xml", 0},
                                    {"h1", "h1/h1.xml", 2},
                                    {"arm", "arm/arm.xml", 4},
                                    {"dog2", "go2/go2.xml", -2}};

class RobotSceneTest : public testing::MujocoTest {
 protected:
  static world::SceneConfig Scene() {
    std::string yaml = "articulations:\n";
    for (const BundledRobot& r : kRobots) {
      yaml += std::string("  - {name: ") + r.name + ", mjcf: " URLAB_TEST_DATA_DIR "/mjcf/robots/" +
              r.file + ", pos: [" + std::to_string(r.x) + ", 0, 0], keyframe: home" +
              (std::string(r.name) == "dog" ? "" : ", include_world: false") + "}\n";
    }
    return world::ParseScene(yaml, testing::MakeTempDir("robot_scene") + "/scene.yaml");
  }
};

std::string ElementNameOf(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "";
}

TEST_F(RobotSceneTest, NamesPrefixedDefaultsKeptApartKeyframesApplied) {
  const world::CompiledScene scene = world::BuildScene(Scene());
  const mjModel* m = scene.model.get();
  for (const BundledRobot& r : kRobots) {
    SCOPED_TRACE(r.name);
    const std::string prefix = std::string(r.name) + "_";
    const world::CompiledScene alone =
        world::BuildModel(std::string(URLAB_TEST_DATA_DIR "/mjcf/robots/") + r.file);
    const mjModel* a = alone.model.get();
    // Every named joint, geom and actuator is there under the prefix, with its own parameters.
    for (int j = 0; j < a->njnt; ++j) {
      const std::string n = ElementNameOf(a, mjOBJ_JOINT, j);
      if (n.empty()) continue;
      const int c = mj_name2id(m, mjOBJ_JOINT, (prefix + n).c_str());
      ASSERT_GE(c, 0) << n;
      EXPECT_EQ(m->jnt_type[c], a->jnt_type[j]) << n;
      EXPECT_EQ(m->jnt_range[2 * c + 1], a->jnt_range[2 * j + 1]) << n;
      EXPECT_EQ(m->dof_armature[m->jnt_dofadr[c]], a->dof_armature[a->jnt_dofadr[j]]) << n;
      EXPECT_EQ(m->dof_damping[m->jnt_dofadr[c]], a->dof_damping[a->jnt_dofadr[j]]) << n;
      EXPECT_EQ(m->dof_frictionloss[m->jnt_dofadr[c]], a->dof_frictionloss[a->jnt_dofadr[j]]) << n;
    }
    for (int g = 0; g < a->ngeom; ++g) {
      const std::string n = ElementNameOf(a, mjOBJ_GEOM, g);
      if (n.empty()) continue;
      const int c = mj_name2id(m, mjOBJ_GEOM, (prefix + n).c_str());
      ASSERT_GE(c, 0) << n;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(m->geom_size[3 * c + k], a->geom_size[3 * g + k]) << n;
        EXPECT_EQ(m->geom_friction[3 * c + k], a->geom_friction[3 * g + k]) << n;
      }
      EXPECT_EQ(m->geom_contype[c], a->geom_contype[g]) << n;
      EXPECT_EQ(m->geom_group[c], a->geom_group[g]) << n;
    }
    ASSERT_EQ(static_cast<int>(scene.articulations.size()), 4);
    int actuators = 0;
    for (int u = 0; u < a->nu; ++u) {
      const std::string n = ElementNameOf(a, mjOBJ_ACTUATOR, u);
      const int c = mj_name2id(m, mjOBJ_ACTUATOR, (prefix + n).c_str());
      ASSERT_GE(c, 0) << n;
      ++actuators;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(m->actuator_gainprm[mjNGAIN * c + k], a->actuator_gainprm[mjNGAIN * u + k]) << n;
        EXPECT_EQ(m->actuator_biasprm[mjNBIAS * c + k], a->actuator_biasprm[mjNBIAS * u + k]) << n;
      }
      EXPECT_EQ(m->actuator_ctrlrange[2 * c + 1], a->actuator_ctrlrange[2 * u + 1]) << n;
      EXPECT_EQ(m->actuator_forcerange[2 * c + 1], a->actuator_forcerange[2 * u + 1]) << n;
    }
    EXPECT_EQ(actuators, a->nu);
    // Its keyframe, under its prefix, at its placement.
    const int ka = mj_name2id(a, mjOBJ_KEY, "home");
    const int kc = mj_name2id(m, mjOBJ_KEY, (prefix + "home").c_str());
    ASSERT_GE(ka, 0);
    ASSERT_GE(kc, 0);
    for (int j = 0; j < a->njnt; ++j) {
      const std::string n = ElementNameOf(a, mjOBJ_JOINT, j);
      if (n.empty()) continue;
      const int c = mj_name2id(m, mjOBJ_JOINT, (prefix + n).c_str());
      const int width = a->jnt_type[j] == mjJNT_FREE ? 7 : a->jnt_type[j] == mjJNT_BALL ? 4 : 1;
      for (int k = 0; k < width; ++k) {
        const double want =
            a->key_qpos[ka * a->nq + a->jnt_qposadr[j] + k] + (width == 7 && k == 0 ? r.x : 0.0);
        EXPECT_NEAR(m->key_qpos[kc * m->nq + m->jnt_qposadr[c] + k], want, 1e-12) << n << " " << k;
      }
    }
  }
  // The floor comes from the first Go2's scene.xml only (include_world: false elsewhere).
  int planes = 0;
  for (int g = 0; g < m->ngeom; ++g) planes += m->geom_type[g] == mjGEOM_PLANE;
  EXPECT_EQ(planes, 1);
}

TEST_F(RobotSceneTest, EveryArticulationStartsInItsKeyframeAndTheMjbStepsTheSame) {
  const std::shared_ptr<world::Session> session = world::Session::Create(Scene());
  physics::Model model = session->engine().CopyModel();
  physics::DataPtr live = physics::MakeData(model.get());
  session->engine().WithLockedData([&](mjModel* m, mjData* d) {
    mj_copyData(live.get(), m, d);
    int free_bases = 0;
    for (const BundledRobot& r : kRobots) {
      const std::string prefix = std::string(r.name) + "_";
      for (int j = 0; j < m->njnt; ++j) {
        if (m->jnt_type[j] != mjJNT_FREE || ElementNameOf(m, mjOBJ_JOINT, j).rfind(prefix, 0) != 0)
          continue;
        EXPECT_NEAR(d->qpos[m->jnt_qposadr[j]], r.x, 1e-12) << r.name;
        ++free_bases;
      }
    }
    EXPECT_EQ(free_bases, 3);  // the two Go2s and the H1 (the arm is fixed)
  });
  // The MJB of the composed model, loaded back, steps exactly like the model from that state.
  const physics::ModelPtr from_mjb = physics::LoadMjbBytes(model.Mjb());
  physics::DataPtr copy = physics::MakeData(from_mjb.get());
  mj_copyData(copy.get(), from_mjb.get(), live.get());
  for (int i = 0; i < 200; ++i) {
    mj_step(model.get(), live.get());
    mj_step(from_mjb.get(), copy.get());
  }
  for (int i = 0; i < model->nq; ++i) ASSERT_EQ(live->qpos[i], copy->qpos[i]) << i;
  for (int i = 0; i < model->nv; ++i) ASSERT_EQ(live->qvel[i], copy->qvel[i]) << i;
  for (int i = 0; i < model->nq; ++i) ASSERT_TRUE(std::isfinite(live->qpos[i])) << i;
}

}  // namespace
}  // namespace urlab
