// The dialect bridge: MJCF written for MuJoCo 3.x, rewritten for MuJoCo 2.2.2. Every translation
// is checked by what it does in simulation (or in the compiled model), not by the text written.
#include "urlab/mjcf/bridge.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "mjcf/bridge_pass.h"
#include "mjcf/bridge_rules.h"
#include "mujoco_test.h"
#include "urlab/document/grammar.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"
#include "urlab/physics/software_sensors.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using mjcf::BridgeChange;
using Kind = BridgeChange::Kind;

constexpr double kPi = 3.14159265358979323846;

struct Bridged {
  document::Document doc;
  mjcf::BridgeReport report;
  physics::ModelPtr model;
  physics::DataPtr data;
};

class BridgeTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("bridge"); }

  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }

  // Reads, bridges, writes and compiles `path`.
  Bridged LoadFile(const std::string& path) {
    Bridged b{mjcf::ReadFile(path), {}, nullptr, nullptr};
    b.report = mjcf::ApplyBridge(b.doc);
    mjcf::LineMap lines;
    const std::string xml = mjcf::WriteString(b.doc, {}, &lines);
    try {
      b.model = physics::CompileXmlString(xml);
    } catch (const physics::CompileError& e) {
      ADD_FAILURE() << mjcf::ExplainCompileMessage(e.what(), lines) << "\n" << xml;
      throw;
    }
    b.data = physics::MakeData(b.model.get());
    return b;
  }
  Bridged Load(const std::string& xml) { return LoadFile(Write("m.xml", xml)); }

  // The report of a document whose bridge refuses something (refusals not thrown).
  mjcf::BridgeReport ReportOf(const std::string& xml) {
    document::Document doc = mjcf::ReadFile(Write("r.xml", xml));
    mjcf::BridgeOptions o;
    o.throw_on_refusal = false;
    return mjcf::ApplyBridge(doc, o);
  }

  static int Count(const mjcf::BridgeReport& r, Kind k) {
    int n = 0;
    for (const BridgeChange& c : r.changes) n += c.kind == k;
    return n;
  }
  static bool Mentions(const mjcf::BridgeReport& r, Kind k, const std::string& text) {
    for (const BridgeChange& c : r.changes) {
      if (c.kind == k && c.what.find(text) != std::string::npos) return true;
    }
    return false;
  }

  static int Id(const mjModel* m, mjtObj type, const char* name) {
    const int id = mj_name2id(m, type, name);
    EXPECT_GE(id, 0) << name;
    return id;
  }

  std::string dir_;
};

// ---------------------------------------------------------------------------------------------
// Grammar: the dialect table extends rows that exist (Grammar throws otherwise).

TEST(BridgeGrammarTest, DialectRowsExtendExistingRows) {
  const document::Grammar& g = document::Grammar::Get();
  for (const document::GrammarRow& r : document::DialectGrammarTable()) {
    if (r.id[0] == '+') {
      EXPECT_NE(g.Find(r.id + 1), nullptr) << r.id;
    }
  }
  const document::ElementSpec* joint = g.Find("joint");
  ASSERT_NE(joint, nullptr);
  const document::AttributeSpec* a = joint->FindAttribute("actuatorfrcrange");
  ASSERT_NE(a, nullptr);
  EXPECT_TRUE(a->dialect);
  ASSERT_NE(joint->FindAttribute("range"), nullptr);
  EXPECT_FALSE(joint->FindAttribute("range")->dialect);
}

// ---------------------------------------------------------------------------------------------
// No-op on 2.2.2 documents.

TEST_F(BridgeTest, PlainMujoco222DocumentsAreUntouched) {
  int checked = 0;
  for (const char* dir : {"/usr/share/mujoco/model", URLAB_TEST_DATA_DIR "/mjcf/corpus"}) {
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.path().extension() != ".xml") continue;
      document::Document doc;
      try {
        doc = mjcf::ReadFile(e.path().string());
      } catch (const InputError&) {
        continue;  // included fragments
      }
      const std::string before = mjcf::WriteString(doc);
      const mjcf::BridgeReport report = mjcf::ApplyBridge(doc);
      EXPECT_FALSE(report.dialect) << e.path() << "\n" << report.Format();
      EXPECT_TRUE(report.changes.empty()) << e.path();
      EXPECT_EQ(mjcf::WriteString(doc), before) << e.path();
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

TEST_F(BridgeTest, UnknownAttributesStayVerbatimWithDiagnostic) {
  document::Document doc = mjcf::ReadFile(Write("u.xml", R"(<mujoco>
  <worldbody>
    <body><joint name="j" notanattribute="1"/><geom size="1"/></body>
  </worldbody>
</mujoco>)"));
  ASSERT_EQ(doc.diagnostics().size(), 1u);
  const mjcf::BridgeReport report = mjcf::ApplyBridge(doc);
  EXPECT_FALSE(report.dialect);
  EXPECT_NE(mjcf::WriteString(doc).find("notanattribute=\"1\""), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// autolimits

TEST_F(BridgeTest, RangeWithoutLimitedGetsThe3xAutolimitsDefault) {
  Bridged b = Load(R"(<mujoco>
  <worldbody>
    <body pos="0 0 1">
      <joint name="j" axis="0 1 0" range="-10 10"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02"/>
    </body>
  </worldbody>
</mujoco>)");
  EXPECT_TRUE(b.report.dialect);
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "autolimits"));
  const mjModel* m = b.model.get();
  EXPECT_EQ(m->jnt_limited[0], 1);
  // The pendulum falls under gravity; the limit holds it near 10 degrees.
  for (int i = 0; i < 2000; ++i) mj_step(m, b.data.get());
  EXPECT_LT(std::abs(b.data->qpos[0]), 10 * kPi / 180 + 0.02);
  EXPECT_GT(std::abs(b.data->qpos[0]), 10 * kPi / 180 - 0.05);
}

TEST_F(BridgeTest, ExplicitAutolimitsIsKept) {
  Bridged b = Load(R"(<mujoco>
  <compiler autolimits="false"/>
  <worldbody>
    <body><joint name="j" limited="true" range="-1 1" actuatorfrclimited="false"/><geom size="1"/></body>
  </worldbody>
</mujoco>)");
  EXPECT_FALSE(Mentions(b.report, Kind::kTranslated, "autolimits"));
  EXPECT_TRUE(Mentions(b.report, Kind::kDropped, "actuator force clamp disabled"));
}

// ---------------------------------------------------------------------------------------------
// actuatorfrcrange

constexpr const char* kClampModel = R"(<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body>
      <joint name="j" axis="0 0 1" actuatorfrcrange="-3 4"/>
      <geom type="box" size="0.1 0.2 0.3"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="m" joint="j" gear="GEAR" ctrlrange="-100 100"/>
  </actuator>
</mujoco>)";

std::string WithGear(const char* gear) {
  std::string s = kClampModel;
  s.replace(s.find("GEAR"), 4, gear);
  return s;
}

TEST_F(BridgeTest, JointActuatorForceIsClampedInSimulation) {
  for (const char* gear : {"2", "-0.5"}) {
    SCOPED_TRACE(gear);
    Bridged b = Load(WithGear(gear));
    EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "actuatorfrcrange"));
    const mjModel* m = b.model.get();
    mjData* d = b.data.get();
    for (double ctrl : {100.0, -100.0, 1.0}) {
      d->ctrl[0] = ctrl;
      mj_step(m, d);
      const double g = m->actuator_gear[0];
      const double expected = std::clamp(g * ctrl, -3.0, 4.0);
      EXPECT_NEAR(d->qfrc_actuator[0], expected, 1e-12) << ctrl;
    }
  }
}

TEST_F(BridgeTest, ActuatorForceRangeFromDefaultClassIntersectsOwnForceRange) {
  Bridged b = Load(R"(<mujoco>
  <option gravity="0 0 0"/>
  <default>
    <default class="leg">
      <joint actuatorfrcrange="-5 5"/>
      <motor forcerange="-2 8" ctrlrange="-50 50"/>
    </default>
  </default>
  <worldbody>
    <body childclass="leg">
      <joint name="a" axis="0 0 1"/>
      <geom type="box" size="0.1 0.2 0.3"/>
      <body pos="1 0 0">
        <joint name="b" axis="0 0 1" class="leg"/>
        <geom type="box" size="0.1 0.2 0.3"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor class="leg" name="ma" joint="a"/>
    <motor class="leg" name="mb" joint="b" gear="2"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  d->ctrl[0] = 50;
  d->ctrl[1] = -50;
  mj_forward(m, d);
  EXPECT_NEAR(d->qfrc_actuator[m->jnt_dofadr[Id(m, mjOBJ_JOINT, "a")]], 5, 1e-12);
  // gear 2: own range [-2, 8] gives [-4, 16] at the joint, joint range [-5, 5]: -4.
  EXPECT_NEAR(d->qfrc_actuator[m->jnt_dofadr[Id(m, mjOBJ_JOINT, "b")]], -4, 1e-12);
}

TEST_F(BridgeTest, SharedJointClampIsRefusedUnlessNeverActive) {
  const std::string shared = R"(<mujoco>
  <worldbody>
    <body><joint name="j" actuatorfrcrange="-1 1"/><geom size="1"/></body>
  </worldbody>
  <actuator>
    <motor joint="j" FR1/>
    <motor joint="j" FR2/>
  </actuator>
</mujoco>)";
  auto with = [&](const char* a, const char* c) {
    std::string s = shared;
    s.replace(s.find("FR1"), 3, a);
    s.replace(s.find("FR2"), 3, c);
    return s;
  };
  const mjcf::BridgeReport refused = ReportOf(with("", ""));
  EXPECT_TRUE(refused.HasRefusals());
  ASSERT_EQ(refused.Refusals().size(), 1u);
  EXPECT_EQ(refused.Refusals()[0].where().line, 3);
  EXPECT_NE(refused.Refusals()[0].message().find("2 actuators"), std::string::npos);
  // Both clamped to 0.4: the sum never leaves [-1, 1], so the clamp is dropped.
  Bridged ok = Load(with(R"(forcerange="-0.4 0.4")", R"(forcerange="-0.4 0.4")"));
  EXPECT_TRUE(Mentions(ok.report, Kind::kDropped, "never active"));
  // Throwing form names file and line.
  try {
    document::Document doc = mjcf::ReadFile(Write("t.xml", with("", "")));
    mjcf::ApplyBridge(doc);
    ADD_FAILURE() << "no refusal";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 3);
    EXPECT_NE(std::string(e.what()).find("t.xml:3"), std::string::npos) << e.what();
  }
}

TEST_F(BridgeTest, TendonActuatorForceIsClampedAndSensed) {
  Bridged b = Load(R"(<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body><joint name="a" type="slide" axis="1 0 0"/><geom size="0.1"/></body>
    <body pos="0 1 0"><joint name="b" type="slide" axis="1 0 0"/><geom size="0.1"/></body>
  </worldbody>
  <tendon>
    <fixed name="t" actuatorfrcrange="-2 3">
      <joint joint="a" coef="1"/>
      <joint joint="b" coef="-1"/>
    </fixed>
  </tendon>
  <actuator>
    <motor name="m" tendon="t" ctrlrange="-10 10"/>
  </actuator>
  <sensor>
    <tendonactuatorfrc name="tf" tendon="t"/>
  </sensor>
</mujoco>)");
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  ASSERT_EQ(b.report.software_sensors.size(), 1u);
  EXPECT_EQ(b.report.software_sensors[0].name, "tf");
  const physics::SoftwareSensorSpec spec{"tf", physics::SoftwareSensorKind::kTendonActuatorForce};
  physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareSensors(m, {&spec, 1});
  for (double ctrl : {10.0, -10.0, 1.5}) {
    d->ctrl[0] = ctrl;
    mj_step(m, d);
    const double expected = std::clamp(ctrl, -2.0, 3.0);
    EXPECT_NEAR(d->actuator_force[0], expected, 1e-12);
    EXPECT_NEAR(d->qfrc_actuator[0], expected, 1e-12);
    EXPECT_NEAR(d->qfrc_actuator[1], -expected, 1e-12);
    EXPECT_NEAR(d->sensordata[m->sensor_adr[Id(m, mjOBJ_SENSOR, "tf")]], expected, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// jointactuatorfrc

TEST_F(BridgeTest, JointActuatorForceSensorReadsTheJointsTotalActuatorForce) {
  Bridged b = Load(R"(<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body><joint name="j" axis="0 0 1"/><geom type="box" size="0.1 0.2 0.3"/></body>
  </worldbody>
  <actuator>
    <motor name="m1" joint="j" gear="2" ctrlrange="-1 1"/>
    <motor name="m2" joint="j" gear="-3" ctrlrange="-1 1"/>
  </actuator>
  <sensor>
    <jointactuatorfrc name="torque" joint="j" cutoff="4"/>
    <jointactuatorfrc joint="j"/>
  </sensor>
</mujoco>)");
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  ASSERT_EQ(b.report.software_sensors.size(), 2u);
  EXPECT_EQ(b.report.software_sensors[1].name, "jointactuatorfrc_j");
  std::vector<physics::SoftwareSensorSpec> specs;
  for (const mjcf::BridgedSensor& s : b.report.software_sensors) {
    specs.push_back({s.name, physics::SoftwareSensorKind::kJointActuatorForce});
  }
  EXPECT_EQ(m->sensor_type[0], mjSENS_USER);
  physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareSensors(m, specs);
  d->ctrl[0] = 1;
  d->ctrl[1] = 0.5;
  mj_step(m, d);
  EXPECT_NEAR(d->qfrc_actuator[0], 2 - 1.5, 1e-12);
  EXPECT_NEAR(d->sensordata[0], 0.5, 1e-12);
  EXPECT_NEAR(d->sensordata[1], 0.5, 1e-12);
  d->ctrl[1] = -1;  // 2 + 3 = 5, cut off at 4 for the first sensor
  mj_step(m, d);
  EXPECT_NEAR(d->sensordata[0], 4, 1e-12);
  EXPECT_NEAR(d->sensordata[1], 5, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// <frame>

// The example of the 3.x XML reference (frame section), with its stated result.
TEST_F(BridgeTest, FrameFollowsTheReferenceExample) {
  Bridged b = Load(R"(<mujoco>
  <worldbody>
    <frame quat="0 0 1 0">
       <geom name="Alice" quat="0 1 0 0" size="1"/>
    </frame>
    <frame pos="0 1 0">
      <geom name="Bob" pos="0 1 0" size="1"/>
      <body name="Carl" pos="1 0 0">
        <geom size="1"/>
      </body>
    </frame>
  </worldbody>
</mujoco>)");
  const mjModel* m = b.model.get();
  const int alice = Id(m, mjOBJ_GEOM, "Alice"), bob = Id(m, mjOBJ_GEOM, "Bob");
  const int carl = Id(m, mjOBJ_BODY, "Carl");
  // quat 0 0 0 1 (up to sign)
  EXPECT_NEAR(std::abs(m->geom_quat[4 * alice + 3]), 1, 1e-12);
  EXPECT_NEAR(m->geom_pos[3 * bob + 1], 2, 1e-12);
  EXPECT_NEAR(m->body_pos[3 * carl + 0], 1, 1e-12);
  EXPECT_NEAR(m->body_pos[3 * carl + 1], 1, 1e-12);
  EXPECT_EQ(Count(b.report, Kind::kTranslated), 3);  // two frames + autolimits
}

// World poses of everything in frames.xml equal those of the same model written by hand
// without frames (poses computed with MuJoCo's own quaternion functions).
TEST_F(BridgeTest, FramesComposePosesClassesFromtoJointsCamerasAndLights) {
  Bridged b = LoadFile(testing::TestData("mjcf/dialect3x/frames.xml"));
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  mj_forward(m, d);
  // stage frame: pos (0.5 0 0), euler 90 0 0 with eulerseq zyx => 90 degrees about z.
  const double s = std::sqrt(0.5);
  const double qstage[4] = {s, 0, 0, s};
  auto stage = [&](const double local[3], double out[3]) {
    mju_rotVecQuat(out, local, qstage);
    out[0] += 0.5;
  };
  // light: pos (0 0 2) -> (0.5 0 2); dir (1 0 -1) -> (0 1 -1) (normalised by MuJoCo)
  const int lamp = Id(m, mjOBJ_LIGHT, "lamp");
  EXPECT_NEAR(m->light_pos[3 * lamp + 0], 0.5, 1e-12);
  EXPECT_NEAR(m->light_pos[3 * lamp + 2], 2, 1e-12);
  EXPECT_NEAR(m->light_dir[3 * lamp + 0], 0, 1e-12);
  EXPECT_NEAR(m->light_dir[3 * lamp + 1], s, 1e-12);
  EXPECT_NEAR(m->light_dir[3 * lamp + 2], -s, 1e-12);
  // camera pos (1 0 1) -> (0.5 1 1)
  const int cam = Id(m, mjOBJ_CAMERA, "cam");
  EXPECT_NEAR(m->cam_pos[3 * cam + 0], 0.5, 1e-12);
  EXPECT_NEAR(m->cam_pos[3 * cam + 1], 1, 1e-12);
  // camera x axis (0 1 0) in the frame -> (-1 0 0) in the world
  EXPECT_NEAR(d->cam_xmat[9 * cam + 0], -1, 1e-9);
  // fromto geom: from (0 0 0) to (0.3 0 0.3) -> midpoint (0.15 0 0.15) rotated and shifted
  const int post = Id(m, mjOBJ_GEOM, "post");
  double mid[3] = {0.15, 0, 0.15}, want[3];
  stage(mid, want);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(d->geom_xpos[3 * post + i], want[i], 1e-12);
  // pendulum body: inner frame pos (0 .2 0) euler (0 0 30) zyx (30 deg about x); body pos (0 0 1)
  const double c30 = std::cos(kPi / 12), s30 = std::sin(kPi / 12);
  const double qinner[4] = {c30, s30, 0, 0};
  double local[3] = {0, 0, 1}, inner[3], world[3];
  mju_rotVecQuat(inner, local, qinner);
  inner[1] += 0.2;
  stage(inner, world);
  const int pend = Id(m, mjOBJ_BODY, "pendulum");
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(d->xpos[3 * pend + i], world[i], 1e-12);
  double qworld[4];
  mju_mulQuat(qworld, qstage, qinner);
  double dot = 0;
  for (int i = 0; i < 4; ++i) dot += qworld[i] * d->xquat[4 * pend + i];
  EXPECT_NEAR(std::abs(dot), 1, 1e-12);
  // childclass: the bob is red (class of the inner frame), the tip geom and tail geom blue.
  const int bob = Id(m, mjOBJ_GEOM, "bob"), tip = Id(m, mjOBJ_GEOM, "tip_geom");
  const int tail = Id(m, mjOBJ_GEOM, "tail_geom");
  EXPECT_EQ(m->geom_rgba[4 * bob + 0], 1.0f);
  EXPECT_EQ(m->geom_rgba[4 * tip + 2], 1.0f);
  EXPECT_EQ(m->geom_rgba[4 * tail + 2], 1.0f);
  EXPECT_NEAR(m->geom_size[3 * tail], 0.04, 1e-12);
  EXPECT_NEAR(m->dof_damping[m->jnt_dofadr[Id(m, mjOBJ_JOINT, "swing")]], 0.2, 1e-12);
  EXPECT_NEAR(m->site_size[3 * Id(m, mjOBJ_SITE, "tip")], 0.02, 1e-12);
  // tip site: at the bob (0 0 -0.3 in the pendulum), frame rotated 90 degrees about x
  const int tipsite = Id(m, mjOBJ_SITE, "tip");
  EXPECT_NEAR(m->site_pos[3 * tipsite + 2], -0.3, 1e-12);
  EXPECT_NEAR(std::abs(m->site_quat[4 * tipsite + 1]), s, 1e-12);
  // joint in a frame inside a body: axis (0 0 1) turned by 90 degrees about y -> (1 0 0)
  const int hinge = Id(m, mjOBJ_JOINT, "cart_hinge");
  EXPECT_NEAR(m->jnt_axis[3 * hinge + 0], 1, 1e-6);
  EXPECT_NEAR(m->jnt_pos[3 * hinge + 0], 0.1 + 0.05, 1e-6);
}

// ---------------------------------------------------------------------------------------------
// position / intvelocity: kv, dampratio, timeconst, inheritrange

TEST_F(BridgeTest, PositionKvDampsLikeThe3xBias) {
  Bridged b = Load(R"(<mujoco>
  <option gravity="0 0 0"/>
  <default><default class="servo"><position kp="10" kv="2"/></default></default>
  <worldbody>
    <body><joint name="j" type="slide" axis="1 0 0"/><geom type="box" size="0.1 0.1 0.1"/></body>
    <body pos="0 1 0"><joint name="k" type="slide" axis="1 0 0"/><geom type="box" size="0.1 0.1 0.1"/></body>
  </worldbody>
  <actuator>
    <position name="p" class="servo" joint="j"/>
    <position name="q" class="servo" joint="k" kv="0.5"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  d->qpos[0] = 0.3;
  d->qvel[0] = 1.5;
  d->qvel[1] = -2;
  d->ctrl[0] = 0.1;
  mj_forward(m, d);
  EXPECT_NEAR(d->actuator_force[0], 10 * (0.1 - 0.3) - 2 * 1.5, 1e-12);
  EXPECT_NEAR(d->actuator_force[1], -0.5 * -2, 1e-12);
}

TEST_F(BridgeTest, DampRatioGivesCriticalDampingFromTheInertiaAtQpos0) {
  Bridged b = Load(R"(<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body>
      <joint name="j" type="slide" axis="1 0 0" armature="0.5"/>
      <geom type="box" size="0.1 0.1 0.1" mass="1.5"/>
    </body>
  </worldbody>
  <actuator>
    <position name="p" joint="j" kp="50" dampratio="1" gear="2"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  // mass at the actuator: (1.5 + 0.5) / gear^2 = 0.5; kv = 2 sqrt(50 * 0.5) = 10
  EXPECT_NEAR(m->actuator_biasprm[2], -10, 1e-9);
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "dampratio=1 -> kv=10"));
  // Critically damped: released from an offset, it never overshoots the setpoint.
  mjData* d = b.data.get();
  d->qpos[0] = 0.2;
  double min_q = 1;
  for (int i = 0; i < 3000; ++i) {
    mj_step(m, d);
    min_q = std::min(min_q, d->qpos[0]);
  }
  EXPECT_GT(min_q, -1e-4);
  EXPECT_LT(std::abs(d->qpos[0]), 1e-3);
}

TEST_F(BridgeTest, TimeconstFiltersExactlyLikeFilterexact) {
  Bridged b = Load(R"(<mujoco>
  <option gravity="0 0 0" timestep="0.005"/>
  <worldbody>
    <body><joint name="j" type="slide" axis="1 0 0"/><geom type="box" size="0.1 0.1 0.1"/></body>
  </worldbody>
  <actuator>
    <position name="p" joint="j" kp="3" timeconst="0.02"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  ASSERT_EQ(m->na, 1);
  d->ctrl[0] = 1;
  double act = 0;
  for (int i = 0; i < 10; ++i) {
    mj_step(m, d);
    act += (1 - act) * (1 - std::exp(-0.005 / 0.02));  // MuJoCo 3.x filterexact
    EXPECT_NEAR(d->act[0], act, 1e-12) << i;
  }
}

TEST_F(BridgeTest, InheritRangeCopiesTheTargetRange) {
  Bridged b = Load(R"(<mujoco>
  <compiler angle="degree"/>
  <worldbody>
    <body>
      <joint name="h" axis="0 0 1" range="-90 30"/>
      <geom type="box" size="0.1 0.1 0.1"/>
      <body pos="1 0 0">
        <joint name="s" type="slide" axis="1 0 0" range="0 1"/>
        <geom type="box" size="0.1 0.1 0.1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="p" joint="h" kp="5" inheritrange="1"/>
    <position name="q" joint="s" kp="5" inheritrange="0.8"/>
    <intvelocity name="v" joint="s" kp="5" inheritrange="1.2"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  EXPECT_EQ(m->actuator_ctrllimited[0], 1);
  EXPECT_NEAR(m->actuator_ctrlrange[0], -kPi / 2, 1e-12);
  EXPECT_NEAR(m->actuator_ctrlrange[1], kPi / 6, 1e-12);
  EXPECT_NEAR(m->actuator_ctrlrange[2], 0.1, 1e-12);
  EXPECT_NEAR(m->actuator_ctrlrange[3], 0.9, 1e-12);
  EXPECT_EQ(m->actuator_actlimited[2], 1);
  EXPECT_NEAR(m->actuator_actrange[4], -0.1, 1e-12);
  EXPECT_NEAR(m->actuator_actrange[5], 1.1, 1e-12);
}

// Found by tests/mjcf/reference3x_test.cc: the most specific kv/dampratio wins whatever its value
// (kv="0" overrides a class's dampratio); both on one element is a 3.x error.
TEST_F(BridgeTest, KvAndDampratioFollowTheMostSpecificSetterAndAreExclusive) {
  Bridged b = Load(R"(<mujoco>
  <default><default class="servo"><position kp="10" dampratio="1"/></default></default>
  <worldbody>
    <body><joint name="j" type="slide" axis="1 0 0"/><geom type="box" size="0.1 0.1 0.1"/></body>
  </worldbody>
  <actuator><position name="p" class="servo" joint="j" kv="0"/></actuator>
</mujoco>)");
  EXPECT_EQ(b.model->actuator_biasprm[2], 0);
  const mjcf::BridgeReport both = ReportOf(R"(<mujoco>
  <worldbody>
    <body><joint name="j" type="slide" axis="1 0 0"/><geom type="box" size="0.1 0.1 0.1"/></body>
  </worldbody>
  <actuator><position joint="j" kp="10" kv="2" dampratio="0"/></actuator>
</mujoco>)");
  EXPECT_TRUE(Mentions(both, Kind::kRefused, "kv and dampratio set together"));
}

// 3.x (since 3.0.1) weighs a mesh by its volume; 2.2.2's default by its inertia box.
TEST_F(BridgeTest, MeshMassIsTheMeshVolumeAs3xComputesIt) {
  Bridged b = Load(R"(<mujoco>
  <asset>
    <mesh name="wedge" inertia="legacy"
          vertex="0 0 0  0.06 0 0  0 0.06 0  0 0 0.06  0.06 0.06 0  0.06 0 0.06"/>
  </asset>
  <worldbody><body name="b"><freejoint/><geom type="mesh" mesh="wedge"/></body></worldbody>
</mujoco>)");
  // a triangular prism: 0.5 * 0.06^3 m^3 at 1000 kg/m^3 (2.2.2's default gives 2/sqrt(3) of it)
  EXPECT_NEAR(b.model->body_mass[1], 0.108, 1e-8);
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "exactmeshinertia"));
}

// actuatorgroupdisable lists group numbers: "0" disables every actuator of the default group.
TEST_F(BridgeTest, ActuatorGroupDisableIsAListOfGroups) {
  const std::string model = R"(<mujoco>
  <option actuatorgroupdisable="GROUPS"/>
  <worldbody><body><joint name="j"/><geom size="0.1"/></body></worldbody>
  <actuator><motor name="m" joint="j"/></actuator>
</mujoco>)";
  auto with = [&](const std::string& groups) {
    std::string xml = model;
    xml.replace(xml.find("GROUPS"), 6, groups);
    return ReportOf(xml);
  };
  EXPECT_TRUE(Mentions(with("0"), Kind::kRefused, "actuatorgroupdisable=\"0\" disables"));
  EXPECT_TRUE(Mentions(with("2 3"), Kind::kDropped, "no actuator is in these groups"));
}

// A fromto box in a rotated frame keeps the roll 3.x gives it (the frame's), not 2.2.2's choice.
TEST_F(BridgeTest, FromtoInARotatedFrameKeepsTheFramesRoll) {
  Bridged b = Load(R"(<mujoco>
  <worldbody>
    <frame euler="0 0 90">
      <geom name="g" type="box" fromto="0 0 0 1 0 0" size="0.1 0.2"/>
    </frame>
  </worldbody>
</mujoco>)");
  const mjModel* m = b.model.get();
  // 3.x: quat = frame (90 deg about z) * z2quat(-x), pos at the rotated midpoint, half-length 0.5
  double local[4], expected[4];
  const double dir[3] = {-1, 0, 0};
  mju_quatZ2Vec(local, dir);
  const double frame[4] = {std::cos(kPi / 4), 0, 0, std::sin(kPi / 4)};
  mju_mulQuat(expected, frame, local);
  const int g = Id(m, mjOBJ_GEOM, "g");
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m->geom_quat[4 * g + i], expected[i], 1e-9) << i;
  EXPECT_NEAR(m->geom_pos[3 * g + 1], 0.5, 1e-12);
  EXPECT_NEAR(m->geom_size[3 * g + 2], 0.5, 1e-12);
}

TEST_F(BridgeTest, ActuatorArmatureAndDampingMoveToTheJoint) {
  Bridged b = Load(R"(<mujoco>
  <worldbody>
    <body>
      <joint name="j" axis="0 0 1" armature="0.1" damping="1"/>
      <geom type="box" size="0.1 0.1 0.1"/>
    </body>
  </worldbody>
  <actuator>
    <motor joint="j" gear="3" armature="0.01" damping="0.2"/>
    <motor joint="j" armature="0.05"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  EXPECT_NEAR(m->dof_armature[0], 0.1 + 0.01 * 9 + 0.05, 1e-12);
  EXPECT_NEAR(m->dof_damping[0], 1 + 0.2 * 9, 1e-12);
}

TEST_F(BridgeTest, StatefulActuatorsAreMovedAfterStatelessOnes) {
  Bridged b = Load(R"(<mujoco>
  <worldbody>
    <body><joint name="j" type="slide" axis="1 0 0" range="-1 1"/><geom size="0.1"/></body>
  </worldbody>
  <actuator>
    <intvelocity name="iv" joint="j" actrange="-1 1"/>
    <motor name="m" joint="j"/>
  </actuator>
</mujoco>)");
  const mjModel* m = b.model.get();
  EXPECT_EQ(mj_name2id(m, mjOBJ_ACTUATOR, "m"), 0);
  EXPECT_EQ(mj_name2id(m, mjOBJ_ACTUATOR, "iv"), 1);
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "ctrl/act indices"));
}

// ---------------------------------------------------------------------------------------------
// option, compiler, rendering attributes

TEST_F(BridgeTest, SpringDamperFlagsBecomePassive) {
  Bridged b = Load(R"(<mujoco>
  <option><flag spring="disable" damper="disable"/></option>
  <worldbody>
    <body><joint name="j" axis="0 1 0" stiffness="10" damping="3"/><geom size="0.1" pos="0 0 -1"/></body>
  </worldbody>
</mujoco>)");
  EXPECT_TRUE(b.model->opt.disableflags & mjDSBL_PASSIVE);
  b.data->qvel[0] = 1;
  b.data->qpos[0] = 0.5;
  mj_forward(b.model.get(), b.data.get());
  EXPECT_EQ(b.data->qfrc_passive[0], 0);
  // One of the two: passive stays on, the disabled forces are zeroed in the model.
  for (const char* which : {"spring", "damper"}) {
    Bridged one = Load(std::string(R"(<mujoco>
  <option><flag )") + which +
                       R"(="disable"/></option>
  <default><joint stiffness="10"/></default>
  <worldbody>
    <body><joint name="j" axis="0 1 0" damping="3"/><geom size="0.1" pos="0 0 -1"/></body>
  </worldbody>
</mujoco>)");
    EXPECT_FALSE(one.model->opt.disableflags & mjDSBL_PASSIVE) << which;
    one.data->qvel[0] = 1;
    one.data->qpos[0] = 0.5;
    mj_forward(one.model.get(), one.data.get());
    const double expected = std::string(which) == "spring" ? -3.0 : -5.0;  // -d*v or -k*q
    EXPECT_DOUBLE_EQ(one.data->qfrc_passive[0], expected) << which;
    EXPECT_TRUE(Mentions(one.report, Kind::kTranslated, "passive stays enabled")) << which;
  }
}

TEST_F(BridgeTest, OptionsMiscLoadsAndTranslatesWhatIsExact) {
  Bridged b = LoadFile(testing::TestData("mjcf/dialect3x/options_misc.xml"));
  const mjModel* m = b.model.get();
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_PASSIVE);
  // focalpixel 800 px with 600 px over 3 mm: focal 4 mm; fovy = 2 atan(1.5 / 4)
  const int eye = Id(m, mjOBJ_CAMERA, "eye");
  EXPECT_NEAR(m->cam_fovy[eye], 2 * std::atan(1.5 / 4) * 180 / kPi, 1e-9);
  EXPECT_EQ(m->light_directional[Id(m, mjOBJ_LIGHT, "top")], 1);
  EXPECT_EQ(m->light_directional[Id(m, mjOBJ_LIGHT, "bulb")], 0);
  EXPECT_TRUE(Mentions(b.report, Kind::kApproximated, "type=\"point\""));
  EXPECT_TRUE(Mentions(b.report, Kind::kDropped, "metallic"));
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "inteval"));
  EXPECT_FALSE(b.report.HasRefusals());
}

// A memory sized for 3.x's arena (which also holds contacts and constraints, for a sparse
// solver) used to become a 2.2.2 stack too small for 2.2.2's dense solver: 64 resting spheres
// overflowed it on the first step. 2.2.2's own estimate applies when it is larger.
TEST_F(BridgeTest, MemorySizedFor3xLeaves222EnoughStack) {
  Bridged b = LoadFile(testing::TestData("mjcf/bridge3x/memory_contacts.xml"));
  const mjModel* m = b.model.get();
  EXPECT_GT(m->nstack, 2 * 1024 * 1024 / 8);  // 2.2.2's estimate, not memory / 8
  for (int i = 0; i < 200; ++i) mj_step(m, b.data.get());
  EXPECT_EQ(b.data->ncon, 64);
  EXPECT_TRUE(Mentions(b.report, Kind::kApproximated, "size memory=\"2M\""));
  // A memory larger than 2.2.2's estimate is kept as the stack (in mjtNums).
  Bridged big = Load(R"(<mujoco>
  <size memory="64M"/>
  <worldbody><body><freejoint/><geom size="0.1"/></body></worldbody>
</mujoco>)");
  EXPECT_EQ(big.model->nstack, 64 * 1024 * 1024 / 8);
}

TEST_F(BridgeTest, RefusalsAreAllListedWithLines) {
  const mjcf::BridgeReport r = ReportOf(R"(<mujoco>
  <worldbody>
    <body gravcomp="1">
      <joint name="j"/>
      <geom size="0.1" surfacevel="1 0 0"/>
    </body>
  </worldbody>
  <actuator>
    <motor joint="j" delay="0.01"/>
  </actuator>
  <sensor>
    <e_kinetic name="ke"/>
  </sensor>
</mujoco>)");
  std::vector<int> lines;
  for (const InputError& e : r.Refusals()) lines.push_back(e.where().line);
  EXPECT_EQ(lines, (std::vector<int>{5, 9})) << r.Format();
  EXPECT_NE(r.Format().find("r.xml:5: refused [attr.refused]: <geom> surfacevel"),
            std::string::npos)
      << r.Format();
}

// The reference manual's own <replicate> example (MuJoCo 3.3.8 fails on its sensor, so it is not
// in the 3.x-checked corpus): names, poses and the replicated sensor as the manual prints them.
TEST_F(BridgeTest, ReplicateFollowsTheReferenceExample) {
  Bridged b = Load(R"(<mujoco>
  <worldbody>
    <replicate count="2" offset="0 1 0" euler="90 0 0">
      <replicate count="2" sep="-" offset="1 0 0" euler="0 90 0">
        <site name="Alice" size=".1"/>
      </replicate>
    </replicate>
  </worldbody>
  <sensor>
    <accelerometer name="Bob" site="Alice"/>
  </sensor>
</mujoco>)");
  const mjModel* m = b.model.get();
  ASSERT_EQ(m->nsite, 4);
  ASSERT_EQ(m->nsensor, 4);
  const char* sites[] = {"Alice-00", "Alice-10", "Alice-01", "Alice-11"};
  const double pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const double quat[4][4] = {{1, 0, 0, 0},
                             {M_SQRT1_2, 0, M_SQRT1_2, 0},
                             {M_SQRT1_2, M_SQRT1_2, 0, 0},
                             {0.5, 0.5, 0.5, 0.5}};
  for (int i = 0; i < 4; ++i) {
    const int s = Id(m, mjOBJ_SITE, sites[i]);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(m->site_pos[3 * s + k], pos[i][k], 1e-12) << sites[i];
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(m->site_quat[4 * s + k], quat[i][k], 1e-12) << sites[i];
    const std::string bob = std::string("Bob") + (sites[i] + 5);
    EXPECT_EQ(m->sensor_objid[Id(m, mjOBJ_SENSOR, bob.c_str())], s) << bob;
  }
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "<replicate count=2>"));
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "refers into a <replicate>"));
}

// A model attached many times brings, each time, the assets and referring elements of every
// section of its kind (finger.xml keeps its pad material in a second <asset> and a sensor in a
// second <sensor>): they used to stop at the first section, leaving every copy's pad material
// dangling. MuJoCo 3.3.8 loads many.xml with 8 materials, 4 textures and 8 sensors.
TEST_F(BridgeTest, ModelAttachedManyTimesKeepsEverySectionsAssets) {
  const Bridged b = LoadFile(testing::TestData("mjcf/bridge3x/attach/many.xml"));
  EXPECT_FALSE(b.report.HasRefusals()) << b.report.Format();
  const mjModel* m = b.model.get();
  EXPECT_EQ(m->nmat, 8);
  EXPECT_EQ(m->ntex, 4);
  EXPECT_EQ(m->nsensor, 8);
  EXPECT_EQ(m->nu, 4);
  for (const std::string f : {"f1_", "f2_", "f3_", "f4_"}) {
    const int pad = Id(m, mjOBJ_MATERIAL, (f + "pad").c_str());
    const int body = Id(m, mjOBJ_BODY, (f + "knuckle").c_str());
    int pads = 0;
    for (int g = 0; g < m->ngeom; ++g) pads += m->geom_bodyid[g] == body && m->geom_matid[g] == pad;
    EXPECT_EQ(pads, 1) << f;
    EXPECT_EQ(m->mat_texid[pad], Id(m, mjOBJ_TEXTURE, (f + "ridges").c_str())) << f;
    EXPECT_GE(Id(m, mjOBJ_SENSOR, (f + "tip_pos").c_str()), 0) << f;
  }
}

// Keyframes of an attached model join the parent's as "{prefix}{name}": the attached joints',
// actuators' (activations included) values from the child's key, everything else (a joint and
// a mocap body of the child outside the attached subtree, the parent's own) as qpos0 / zero /
// the body's pose (reference3x_test compares parent.xml's merged keys with MuJoCo 3.3.8).
TEST_F(BridgeTest, AttachedModelsKeyframesAreMergedByName) {
  Write("child.xml", R"(<mujoco model="child">
  <worldbody>
    <body name="outside"><joint name="out" type="slide"/><geom size="0.1"/></body>
    <body name="target" mocap="true" pos="1 0 0"><geom size="0.05" contype="0" conaffinity="0"/></body>
    <body name="arm" pos="0 0 1"><joint name="j" axis="0 1 0"/><geom size="0.1"/></body>
  </worldbody>
  <actuator><general name="filt" joint="j" dyntype="filter" dynprm="0.1"/></actuator>
  <keyframe>
    <key name="k" time="2" qpos="0.7 0.4" qvel="0.1 0.2" act="0.25" ctrl="0.5" mpos="1 2 3" mquat="0 1 0 0"/>
  </keyframe>
</mujoco>)");
  const Bridged b = Load(R"(<mujoco>
  <asset><model name="c" file="child.xml"/></asset>
  <worldbody>
    <body name="m" mocap="true" pos="0 1 0"/>
    <body name="p"><joint name="pj" type="slide" ref="0.05"/><geom size="0.1"/>
      <attach model="c" body="arm" prefix="c_"/>
    </body>
  </worldbody>
</mujoco>)");
  EXPECT_FALSE(b.report.HasRefusals()) << b.report.Format();
  const mjModel* m = b.model.get();
  ASSERT_EQ(m->nkey, 1);
  EXPECT_STREQ(mj_id2name(m, mjOBJ_KEY, 0), "c_k");
  EXPECT_EQ(m->key_time[0], 2);
  const int pj = Id(m, mjOBJ_JOINT, "pj"), j = Id(m, mjOBJ_JOINT, "c_j");
  EXPECT_EQ(m->key_qpos[m->jnt_qposadr[pj]], 0.05);  // the parent's joint at qpos0
  EXPECT_EQ(m->key_qpos[m->jnt_qposadr[j]], 0.4);
  EXPECT_EQ(m->key_qvel[m->jnt_dofadr[pj]], 0);
  EXPECT_EQ(m->key_qvel[m->jnt_dofadr[j]], 0.2);
  ASSERT_EQ(m->nu, 1);
  EXPECT_EQ(m->key_ctrl[0], 0.5);
  EXPECT_EQ(m->key_act[0], 0.25);
  ASSERT_EQ(m->nmocap, 1);  // the parent's; the child's target stayed behind
  EXPECT_EQ(m->key_mpos[1], 1);
  EXPECT_EQ(m->key_mquat[0], 1);
  EXPECT_TRUE(Mentions(b.report, Kind::kTranslated, "keyframe(s) added after the parent's keys"));
}

// freejoint align moves the body frame; a body-frame equality anchor on that body would then
// mean another point, so that alignment is refused with the nearest 2.2.2 construct.
TEST_F(BridgeTest, FreeJointAlignWithBodyAnchoredEqualityIsRefused) {
  const mjcf::BridgeReport r = ReportOf(R"(<mujoco>
  <worldbody>
    <body name="b" pos="0 0 1"><freejoint align="true"/><geom size="0.1" pos="0.1 0 0"/></body>
  </worldbody>
  <equality><connect body1="b" anchor="0 0 0.1"/></equality>
</mujoco>)");
  ASSERT_TRUE(r.HasRefusals());
  EXPECT_TRUE(Mentions(r, Kind::kRefused, "nearest 2.2.2 construct: align=\"false\""));
  EXPECT_EQ(r.Refusals()[0].where().line, 3);
}

// A weld in a 3.x document is kept but reported as approximated (2.2.2's weld rows differ from
// 3.x's: reference3x_test SiteWeldDiffersOnlyByTwoWeldChangesOfMujoco3); a 2.2.2 document's is
// not touched.
TEST_F(BridgeTest, WeldsOf3xDocumentsAreApproximated) {
  const std::string model = R"(<mujoco>
  <worldbody>
    <body name="a" pos="0 0 1" GRAVCOMP><freejoint/><geom size="0.1"/></body>
  </worldbody>
  <equality><weld body1="a" torquescale="0.5"/></equality>
</mujoco>)";
  std::string x3 = model;
  x3.replace(x3.find("GRAVCOMP"), 8, R"(gravcomp="0.5")");
  const Bridged b = Load(x3);
  EXPECT_TRUE(Mentions(b.report, Kind::kApproximated, "efc_diagApprox"));
  for (const BridgeChange& c : b.report.changes) {
    if (c.rule == "equality.weld") {
      EXPECT_EQ(c.where.line, 5);
    }
  }
  std::string x2 = model;
  x2.replace(x2.find("GRAVCOMP"), 8, "");
  EXPECT_TRUE(Load(x2).report.changes.empty());
}

// What cannot be expressed in 2.2.2 is refused with where, why and the nearest 2.2.2 construct
// (reference3x_test checks that MuJoCo 3.x loads these models).
TEST_F(BridgeTest, InexpressibleConstructsAreRefusedWithReasonAndNearestConstruct) {
  int files = 0;
  for (const auto& e : fs::directory_iterator(URLAB_TEST_DATA_DIR "/mjcf/bridge3x_refused")) {
    if (e.path().extension() != ".xml") continue;
    ++files;
    document::Document doc = mjcf::ReadFile(e.path().string());
    mjcf::BridgeOptions o;
    o.throw_on_refusal = false;
    const mjcf::BridgeReport r = mjcf::ApplyBridge(doc, o);
    ASSERT_TRUE(r.HasRefusals()) << e.path();
    for (const InputError& err : r.Refusals()) {
      EXPECT_GT(err.where().line, 0) << err.what();
      EXPECT_NE(err.message().find("nearest 2.2.2 construct"), std::string::npos) << err.what();
    }
    document::Document again = mjcf::ReadFile(e.path().string());
    EXPECT_THROW(mjcf::ApplyBridge(again), InputError) << e.path();
  }
  EXPECT_EQ(files, 3);
}

TEST(BridgeRulesTest, RuleIdsAreUniqueAndPoliciesNameRules) {
  std::set<std::string> ids;
  for (const mjcf::BridgeRule& r : mjcf::BridgeRules()) {
    EXPECT_TRUE(ids.insert(r.id).second) << "duplicate rule " << r.id;
    EXPECT_FALSE(mjcf::BridgeRuleFunction(r).empty()) << r.id;
    // Every pass a rule names runs: it is a row of the pass table (names and files come from it).
    const auto passes = mjcf::bridge::Passes();
    for (mjcf::BridgePassFn fn : r.passes) {
      if (!fn) continue;
      EXPECT_TRUE(std::any_of(passes.begin(), passes.end(), [&](const mjcf::bridge::PassEntry& p) {
        return p.run == fn;
      })) << r.id;
    }
    EXPECT_TRUE(r.passes[0] || r.elsewhere) << r.id;
    EXPECT_FALSE(std::string(r.construct).empty()) << r.id;
  }
  for (const mjcf::AttributePolicy& p : mjcf::AttributePolicies()) {
    EXPECT_TRUE(ids.count(p.rule_if)) << p.elements << " " << p.attributes;
    if (p.condition != mjcf::AttributeCondition::kAlways) {
      ASSERT_NE(p.rule_else, nullptr) << p.elements << " " << p.attributes;
      EXPECT_TRUE(ids.count(p.rule_else)) << p.elements << " " << p.attributes;
    }
  }
}

TEST_F(BridgeTest, EveryChangeNamesItsRuleAndTheRuleGivesItsKind) {
  std::set<std::string> used;
  for (const char* dir : {URLAB_TEST_DATA_DIR "/mjcf/dialect3x", URLAB_TEST_DATA_DIR "/mjcf/robots",
                          URLAB_TEST_DATA_DIR "/mjcf/bridge3x"}) {
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.path().extension() != ".xml") continue;
      document::Document doc = mjcf::ReadFile(e.path().string());
      mjcf::BridgeOptions o;
      o.throw_on_refusal = false;
      const mjcf::BridgeReport r = mjcf::ApplyBridge(doc, o);
      for (const BridgeChange& c : r.changes) {
        const mjcf::BridgeRule& rule = mjcf::FindBridgeRule(c.rule);
        EXPECT_EQ(rule.kind, c.kind) << c.rule << ": " << c.what;
        used.insert(c.rule);
      }
    }
  }
  EXPECT_GE(used.size(), 20u);
}

// ---------------------------------------------------------------------------------------------
// Corpus: every hand-written 3.x model loads, compiles without warnings and simulates.

class DialectCorpusTest : public BridgeTest, public ::testing::WithParamInterface<std::string> {};

TEST_P(DialectCorpusTest, LoadsCompilesAndSimulates) {
  Bridged b = LoadFile(GetParam());
  EXPECT_TRUE(b.report.dialect);
  EXPECT_FALSE(b.report.HasRefusals()) << b.report.Format();
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  std::vector<physics::SoftwareSensorSpec> specs;
  for (const mjcf::BridgedSensor& s : b.report.software_sensors) {
    specs.push_back({s.name, s.kind == mjcf::BridgedSensor::Kind::kJointActuatorForce
                                 ? physics::SoftwareSensorKind::kJointActuatorForce
                                 : physics::SoftwareSensorKind::kTendonActuatorForce});
  }
  physics::SoftwareSensorRegistration reg = physics::RegisterSoftwareSensors(m, specs);
  if (m->nkey > 0) mj_resetDataKeyframe(m, d, 0);
  for (int i = 0; i < 500; ++i) {
    for (int u = 0; u < m->nu; ++u) d->ctrl[u] = 0.3 * std::sin(0.01 * i + u);
    mj_step(m, d);
  }
  for (int i = 0; i < m->nq; ++i) ASSERT_TRUE(std::isfinite(d->qpos[i])) << i;
  for (int i = 0; i < m->nsensordata; ++i) ASSERT_TRUE(std::isfinite(d->sensordata[i])) << i;
  // Software sensors read the engine's own numbers.
  for (const physics::SoftwareSensorSpec& s : specs) {
    if (s.kind != physics::SoftwareSensorKind::kJointActuatorForce) continue;
    const int id = Id(m, mjOBJ_SENSOR, s.sensor_name.c_str());
    const int dof = m->jnt_dofadr[m->sensor_objid[id]];
    double expected = d->qfrc_actuator[dof];
    if (m->sensor_cutoff[id] > 0) {
      expected = std::clamp(expected, -m->sensor_cutoff[id], m->sensor_cutoff[id]);
    }
    EXPECT_NEAR(d->sensordata[m->sensor_adr[id]], expected, 1e-9) << s.sensor_name;
  }
}

// The 3.x dialect corpus and the robot-style corpus (models with their asset folders).
std::vector<std::string> CorpusFiles() {
  std::vector<std::string> out;
  for (const char* dir :
       {URLAB_TEST_DATA_DIR "/mjcf/dialect3x", URLAB_TEST_DATA_DIR "/mjcf/robots"}) {
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.path().extension() == ".xml") out.push_back(e.path().string());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string CorpusName(const ::testing::TestParamInfo<std::string>& p) {
  std::string n =
      fs::path(p.param).parent_path().filename().string() + "_" + fs::path(p.param).stem().string();
  for (char& c : n) {
    if (!isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return n;
}

INSTANTIATE_TEST_SUITE_P(Dialect3x, DialectCorpusTest, ::testing::ValuesIn(CorpusFiles()),
                         CorpusName);

// The quadruped's knees: motor ctrlrange 60, joint actuatorfrcrange 45.43 from the default class.
TEST_F(BridgeTest, QuadrupedKneeTorqueIsClampedAtTheClassRange) {
  Bridged b = LoadFile(testing::TestData("mjcf/dialect3x/go2_like.xml"));
  const mjModel* m = b.model.get();
  mjData* d = b.data.get();
  for (int u = 0; u < m->nu; ++u) d->ctrl[u] = 60;
  mj_forward(m, d);
  const int knee = Id(m, mjOBJ_JOINT, "FL_calf_joint"), hip = Id(m, mjOBJ_JOINT, "FL_hip_joint");
  EXPECT_NEAR(d->qfrc_actuator[m->jnt_dofadr[knee]], 45.43, 1e-12);
  EXPECT_NEAR(d->qfrc_actuator[m->jnt_dofadr[hip]], 23.7, 1e-12);
}

}  // namespace
}  // namespace urlab
