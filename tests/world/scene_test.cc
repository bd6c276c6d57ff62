// Scene files and composition: many articulations in one model with prefixes and placements,
// colliding names, per-articulation keyframes, option resolution, and errors that name the
// articulation and element.
#include "urlab/world/scene.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "mujoco_test.h"
#include "urlab/core/files.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

class SceneTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("scene"); }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  world::CompiledScene Build(const std::string& yaml) {
    return world::BuildScene(world::ParseScene(yaml, dir_ + "/scene.yaml"));
  }
  std::string dir_;
};

int Id(const mjModel* m, mjtObj type, const std::string& name) {
  return mj_name2id(m, type, name.c_str());
}

TEST_F(SceneTest, TwoHumanoidsWithPrefixesAndPlacement) {
  world::CompiledScene s = Build(R"(articulations:
  - name: h0
    mjcf: )" URLAB_SOURCE_DIR R"(/examples/models/humanoid.xml
    pos: [0, 0, 0]
  - name: h1
    mjcf: )" URLAB_SOURCE_DIR R"(/examples/models/humanoid.xml
    pos: [2, 0, 0]
    euler: [0, 0, 90]   # degrees
)");
  const mjModel* m = s.model.get();
  EXPECT_EQ(m->nq, 56);
  EXPECT_EQ(m->nu, 42);
  const int t0 = Id(m, mjOBJ_BODY, "h0_torso"), t1 = Id(m, mjOBJ_BODY, "h1_torso");
  ASSERT_GE(t0, 0);
  ASSERT_GE(t1, 0);
  physics::DataPtr d = physics::MakeData(m);
  mj_forward(m, d.get());
  EXPECT_NEAR(d->xpos[3 * t1 + 0] - d->xpos[3 * t0 + 0], 2.0, 1e-12);
  EXPECT_NEAR(d->xpos[3 * t1 + 1] - d->xpos[3 * t0 + 1], 0.0, 1e-12);
  // h1 is yawed by 90 degrees: its torso's x axis points along world y.
  EXPECT_NEAR(d->xmat[9 * t1 + 3], 1.0, 1e-9);
  // Actuators reference their own articulation's joints.
  const int a = Id(m, mjOBJ_ACTUATOR, "h1_abdomen_y");
  ASSERT_GE(a, 0);
  EXPECT_EQ(m->actuator_trnid[2 * a], Id(m, mjOBJ_JOINT, "h1_abdomen_y"));
}

TEST_F(SceneTest, TwentyTwoHumanoidsCompileAndSimulate) {
  std::string yaml = "size: {nconmax: 1000, njmax: 3000}\narticulations:\n";
  for (int i = 0; i < 22; ++i) {
    yaml += "  - name: h" + std::to_string(i) +
            "\n    mjcf: " URLAB_SOURCE_DIR "/examples/models/humanoid.xml\n    pos: [" +
            std::to_string(2 * (i % 5)) + ", " + std::to_string(2 * (i / 5)) + ", 0]\n" +
            (i ? "    include_world: false\n" : "");
  }
  world::CompiledScene s = Build(yaml);
  const mjModel* m = s.model.get();
  EXPECT_EQ(m->nq, 616);
  EXPECT_EQ(m->nu, 462);
  physics::DataPtr d = physics::MakeData(m);
  for (int i = 0; i < 1000; ++i) mj_step(m, d.get());
  for (int i = 0; i < m->nq; ++i) ASSERT_TRUE(std::isfinite(d->qpos[i])) << i;
  for (int i = 0; i < m->nv; ++i) ASSERT_LT(std::abs(d->qvel[i]), 1e3) << i;
  EXPECT_EQ(d->warning[mjWARN_BADQACC].number, 0);
}

// Two different robots whose element, class and asset names all collide.
constexpr const char* kRobotTemplate = R"(<mujoco model="robot">
  <default>
    <default class="link"><geom rgba="RGBA" type="capsule" size="0.05"/></default>
  </default>
  <asset>
    <material name="paint" rgba="RGBA"/>
    <mesh name="part" vertex="0 0 0  1 0 0  0 1 0  0 0 1" scale="SCALE SCALE SCALE"/>
  </asset>
  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="j1" axis="0 1 0"/>
      <geom name="g" class="link" fromto="0 0 0 0.3 0 0"/>
      <geom name="m" type="mesh" mesh="part" material="paint"/>
      <site name="s" pos="0.3 0 0"/>
      <body name="tip" pos="0.3 0 0">
        <joint name="j2" axis="0 1 0"/>
        <geom name="g2" class="link" fromto="0 0 0 0.2 0 0"/>
        <site name="s2" pos="0.2 0 0"/>
      </body>
    </body>
  </worldbody>
  <tendon><spatial name="t"><site site="s"/><site site="s2"/></spatial></tendon>
  <equality><joint name="eq" joint1="j1" joint2="j2" active="false"/></equality>
  <contact><exclude body1="base" body2="tip"/></contact>
  <actuator><motor name="a1" joint="j1" gear="GEAR"/><motor name="a2" tendon="t"/></actuator>
  <sensor><jointpos name="p1" joint="j1"/><framepos name="f" objtype="site" objname="s2"/></sensor>
</mujoco>)";

std::string Robot(const std::string& rgba, const std::string& scale, const std::string& gear) {
  std::string s = kRobotTemplate;
  for (auto [k, v] :
       {std::pair<std::string, std::string>{"RGBA", rgba}, {"SCALE", scale}, {"GEAR", gear}}) {
    for (size_t p; (p = s.find(k)) != std::string::npos;) s.replace(p, k.size(), v);
  }
  return s;
}

TEST_F(SceneTest, CollidingNamesResolveToTheirOwnArticulation) {
  Write("a.xml", Robot("1 0 0 1", "1", "2"));
  Write("b.xml", Robot("0 0 1 1", "2", "3"));
  world::CompiledScene s = Build(R"(articulations:
  - {name: A, mjcf: a.xml}
  - {name: B, mjcf: b.xml, pos: [0, 2, 0]}
)");
  const mjModel* m = s.model.get();
  for (const std::string p : {"A_", "B_"}) {
    const float want_blue = p == "B_" ? 1.0f : 0.0f;
    // Default class "link" of each robot applies to its own geoms.
    const int g = Id(m, mjOBJ_GEOM, p + "g");
    ASSERT_GE(g, 0) << p;
    EXPECT_EQ(m->geom_rgba[4 * g + 2], want_blue) << p;
    // Material and mesh references.
    const int mg = Id(m, mjOBJ_GEOM, p + "m");
    EXPECT_EQ(m->geom_matid[mg], Id(m, mjOBJ_MATERIAL, p + "paint")) << p;
    EXPECT_EQ(m->geom_dataid[mg], Id(m, mjOBJ_MESH, p + "part")) << p;
    EXPECT_EQ(m->mat_rgba[4 * m->geom_matid[mg] + 2], want_blue) << p;
    // Actuators, tendons, sensors, equalities, excludes.
    const int a1 = Id(m, mjOBJ_ACTUATOR, p + "a1"), a2 = Id(m, mjOBJ_ACTUATOR, p + "a2");
    EXPECT_EQ(m->actuator_trnid[2 * a1], Id(m, mjOBJ_JOINT, p + "j1")) << p;
    EXPECT_EQ(m->actuator_gear[6 * a1], p == "B_" ? 3.0 : 2.0) << p;
    EXPECT_EQ(m->actuator_trnid[2 * a2], Id(m, mjOBJ_TENDON, p + "t")) << p;
    const int t = Id(m, mjOBJ_TENDON, p + "t");
    EXPECT_EQ(m->wrap_objid[m->tendon_adr[t]], Id(m, mjOBJ_SITE, p + "s")) << p;
    const int f = Id(m, mjOBJ_SENSOR, p + "f");
    EXPECT_EQ(m->sensor_objid[f], Id(m, mjOBJ_SITE, p + "s2")) << p;
    const int eq = Id(m, mjOBJ_EQUALITY, p + "eq");
    EXPECT_EQ(m->eq_obj1id[eq], Id(m, mjOBJ_JOINT, p + "j1")) << p;
  }
  ASSERT_EQ(m->nexclude, 2);
  // Each exclude pairs its own articulation's bodies (signatures encode body ids + 1).
  for (int i = 0; i < 2; ++i) {
    const int sig = m->exclude_signature[i];
    const std::string p = i == 0 ? "A_" : "B_";
    const std::set<int> pair = {sig >> 16, sig & 0xFFFF};
    EXPECT_EQ(pair, (std::set<int>{Id(m, mjOBJ_BODY, p + "base"), Id(m, mjOBJ_BODY, p + "tip")}));
  }
}

TEST_F(SceneTest, KeyframesStayPerArticulation) {
  world::CompiledScene s = Build(
      "articulations:\n"
      "  - {name: a0, mjcf: " URLAB_SOURCE_DIR
      "/examples/models/pendulum_arm.xml}\n"
      "  - {name: a1, mjcf: " URLAB_SOURCE_DIR
      "/examples/models/pendulum_arm.xml,"
      " pos: [1, 0, 0], keyframe: raised}\n");
  const mjModel* m = s.model.get();
  ASSERT_EQ(m->nkey, 2);
  const int k1 = Id(m, mjOBJ_KEY, "a1_raised");
  ASSERT_GE(k1, 0);
  physics::DataPtr d = physics::MakeData(m);
  mj_resetDataKeyframe(m, d.get(), k1);
  const int s0 = m->jnt_qposadr[Id(m, mjOBJ_JOINT, "a0_shoulder")];
  const int s1 = m->jnt_qposadr[Id(m, mjOBJ_JOINT, "a1_shoulder")];
  const int e1 = m->jnt_qposadr[Id(m, mjOBJ_JOINT, "a1_elbow")];
  EXPECT_EQ(d->qpos[s0], m->qpos0[s0]);  // a0 keeps its reference pose
  EXPECT_EQ(d->qpos[s1], 0.5);
  EXPECT_EQ(d->qpos[e1], -1.0);
  EXPECT_EQ(d->ctrl[Id(m, mjOBJ_ACTUATOR, "a1_elbow_servo")], -1.0);
  EXPECT_EQ(d->ctrl[Id(m, mjOBJ_ACTUATOR, "a0_elbow_servo")], 0.0);
  // The saved scene holds full-length keys and loads on its own with the same keyframes.
  const std::string saved = dir_ + "/out/scene_compiled.xml";
  urlab::WriteFileAtomic(saved, world::SceneXml(s, nullptr, dir_ + "/out"));
  physics::ModelPtr again = physics::LoadXmlFile(saved);
  ASSERT_EQ(again->nkey, m->nkey);
  for (int i = 0; i < m->nkey * m->nq; ++i) EXPECT_EQ(again->key_qpos[i], m->key_qpos[i]) << i;
  for (int i = 0; i < m->nkey * m->nu; ++i) EXPECT_EQ(again->key_ctrl[i], m->key_ctrl[i]) << i;
}

TEST_F(SceneTest, PlacedKeyframesMoveFreeAndMocapBodies) {
  Write("free.xml", R"(<mujoco><worldbody>
    <body name="box" pos="0 0 1"><freejoint name="f"/><geom type="box" size="0.1 0.1 0.1"/></body>
    <body name="target" mocap="true" pos="1 0 0"><geom size="0.05" contype="0" conaffinity="0"/></body>
  </worldbody><keyframe><key name="k" qpos="0.5 0 1 1 0 0 0" mpos="2 0 0" mquat="1 0 0 0"/>
  </keyframe></mujoco>)");
  world::CompiledScene s =
      Build("articulations:\n  - {name: a, mjcf: free.xml, pos: [10, 0, 0], euler: [0, 0, 90]}\n");
  const mjModel* m = s.model.get();
  const int k = Id(m, mjOBJ_KEY, "a_k");
  ASSERT_GE(k, 0);
  // (0.5, 0, 1) yawed by 90 degrees and moved by (10, 0, 0).
  EXPECT_NEAR(m->key_qpos[m->nq * k + 0], 10.0, 1e-12);
  EXPECT_NEAR(m->key_qpos[m->nq * k + 1], 0.5, 1e-12);
  EXPECT_NEAR(m->key_qpos[m->nq * k + 2], 1.0, 1e-12);
  EXPECT_NEAR(m->key_qpos[m->nq * k + 3], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(m->key_qpos[m->nq * k + 6], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(m->key_mpos[3 * m->nmocap * k + 0], 10.0, 1e-12);
  EXPECT_NEAR(m->key_mpos[3 * m->nmocap * k + 1], 2.0, 1e-12);
  // The reference configuration is placed too.
  const int box = Id(m, mjOBJ_BODY, "a_box");
  EXPECT_NEAR(m->qpos0[m->jnt_qposadr[m->body_jntadr[box]]], 10.0, 1e-12);
}

TEST_F(SceneTest, OptionResolutionAndDisagreement) {
  const std::string arm = URLAB_SOURCE_DIR "/examples/models/pendulum_arm.xml";
  world::CompiledScene s = Build("articulations:\n  - {name: a, mjcf: " + arm +
                                 ", options: {timestep: 0.001}}\n  - {name: b, mjcf: " + arm +
                                 ", options: {timestep: 0.005}}\n");
  EXPECT_EQ(s.model->opt.timestep, 0.001);  // first articulation's options win
  bool warned = false;
  for (const auto& d : s.diagnostics) {
    warned =
        warned || (d.message.find("timestep") != std::string::npos && d.message.find("b:") == 0);
  }
  EXPECT_TRUE(warned);
  world::CompiledScene o = Build(
      "options: {timestep: 0.004, gravity: [0, 0, -1]}\n"
      "articulations:\n  - {name: a, mjcf: " +
      arm + ", options: {timestep: 0.001}}\n");
  EXPECT_EQ(o.model->opt.timestep, 0.004);  // the scene's overrides win
  EXPECT_EQ(o.model->opt.gravity[2], -1.0);
  EXPECT_EQ(o.model->opt.integrator, mjINT_IMPLICIT);  // from the MJCF, untouched
}

TEST_F(SceneTest, ErrorsNameArticulationAndElement) {
  Write("bad.xml", R"(<mujoco>
  <worldbody>
    <body name="leg">
      <joint name="left_knee" type="hinge" range="0 1" limited="true" stiffness="-1"/>
      <geom size="0.1"/>
    </body>
  </worldbody>
  <actuator><motor joint="left_kne"/></actuator>
</mujoco>)");
  try {
    Build("articulations:\n  - {name: g1, mjcf: bad.xml}\n");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("g1: "), std::string::npos) << what;
    EXPECT_NE(what.find("left_kne"), std::string::npos) << what;
    EXPECT_EQ(e.where().line, 8) << what;
  }
}

TEST_F(SceneTest, MixedAngleUnitsAreNormalised) {
  // The first articulation is in radians, the second in degrees (MJCF's default) with euler
  // orientations and hinge ranges coming partly from a default class.
  Write("rad.xml", R"(<mujoco><compiler angle="radian"/><worldbody>
    <body name="b" euler="0 0 1.5707963267948966"><joint name="j" range="-1 1" limited="true"/>
      <geom size="0.1"/></body></worldbody></mujoco>)");
  Write("deg.xml", R"(<mujoco><default><joint range="-90 45" limited="true"/></default>
    <worldbody><body name="b" euler="0 0 90"><joint name="j"/><joint name="s" type="slide"/>
      <geom size="0.1"/></body></worldbody></mujoco>)");
  world::CompiledScene s = Build(
      "articulations:\n  - {name: r, mjcf: rad.xml}\n"
      "  - {name: d, mjcf: deg.xml}\n");
  const mjModel* m = s.model.get();
  const int rj = Id(m, mjOBJ_JOINT, "r_j"), dj = Id(m, mjOBJ_JOINT, "d_j");
  const int ds = Id(m, mjOBJ_JOINT, "d_s");
  EXPECT_DOUBLE_EQ(m->jnt_range[2 * rj + 1], 1.0);
  EXPECT_NEAR(m->jnt_range[2 * dj], -M_PI / 2, 1e-12);
  EXPECT_NEAR(m->jnt_range[2 * dj + 1], M_PI / 4, 1e-12);
  // A slide joint's range is a length: not converted.
  EXPECT_DOUBLE_EQ(m->jnt_range[2 * ds], -90.0);
  const int rb = Id(m, mjOBJ_BODY, "r_b"), db = Id(m, mjOBJ_BODY, "d_b");
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(m->body_quat[4 * rb + k], m->body_quat[4 * db + k], 1e-12);
}

TEST_F(SceneTest, SceneWideCompilerSettingsAreGuarded) {
  ExpectWarning("'settotalmass' is deprecated");  // MuJoCo's, when it parses mass.xml
  Write("mass.xml", R"(<mujoco><compiler settotalmass="5"/><worldbody><body name="b">
    <joint/><geom size="0.1"/></body></worldbody></mujoco>)");
  Write("plain.xml", R"(<mujoco><compiler boundmass="0.01"/><worldbody><body name="b">
    <joint/><geom size="0.1"/></body></worldbody></mujoco>)");
  try {
    Build("articulations:\n  - {name: p, mjcf: plain.xml}\n  - {name: m, mjcf: mass.xml}\n");
    FAIL() << "settotalmass was composed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("settotalmass"), std::string::npos) << e.what();
    EXPECT_EQ(e.where().line, 1);
  }
  Build("articulations:\n  - {name: m, mjcf: mass.xml}\n");  // alone it is fine
  Write("other.xml", R"(<mujoco><worldbody><body name="b">
    <joint/><geom size="0.1"/></body></worldbody></mujoco>)");
  world::CompiledScene s =
      Build("articulations:\n  - {name: p, mjcf: plain.xml}\n  - {name: o, mjcf: other.xml}\n");
  bool warned = false;
  for (const auto& d : s.diagnostics) warned = warned || d.message.find("o: its <compiler>") == 0;
  EXPECT_TRUE(warned);
}

TEST_F(SceneTest, SceneFileErrorsHaveFileAndLine) {
  const std::string arm = URLAB_SOURCE_DIR "/examples/models/pendulum_arm.xml";
  struct Case {
    std::string yaml;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {"articulations:\n  - name: a\n    mjcf: " + arm + "\n    poss: [0, 0, 0]\n", 4,
       "unknown key 'poss'"},
      {"articulations:\n  - name: a\n    mjcf: " + arm + "\n    pos: [0, x, 0]\n", 4, "number"},
      {"articulations:\n  - name: a\n    mjcf: missing.xml\n", 3, "not found"},
      {"articulations: []\n", 1, "non-empty"},
      {"articulations:\n  - {name: a, mjcf: " + arm + "}\n  - {name: a, mjcf: " + arm + "}\n", 3,
       "two articulations"},
      {"articulations:\n  - name: a\n    mjcf: " + arm + "\n    controller: {type: pdd}\n", 4,
       "controller type"},
      {"articulations: [\n", 2, "malformed YAML"},
  };
  for (const Case& c : cases) {
    try {
      world::ParseScene(c.yaml, dir_ + "/s.yaml");
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().file, dir_ + "/s.yaml");
      EXPECT_EQ(e.where().line, c.line) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace urlab
