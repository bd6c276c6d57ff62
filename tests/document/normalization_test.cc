// Import normalization checked against MuJoCo itself: orientation forms, fromto resolution and
// its export rule, default-class resolution and inherited visual offsets; and the C++ builder.
#include <cmath>

#include "mujoco_test.h"
#include "urlab/document/builder.h"
#include "urlab/document/orientation.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

using document::Quat;

class NormalizationTest : public testing::MujocoTest {
 protected:
  document::Document Read(const std::string& xml) {
    return mjcf::ReadString(xml, testing::MakeTempDir("norm") + "/m.xml");
  }
};

void ExpectSameRotation(const Quat& a, const mjtNum* b, const std::string& what) {
  // q and -q are the same rotation.
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  EXPECT_NEAR(std::abs(dot), 1.0, 1e-9) << what;
}

TEST_F(NormalizationTest, EveryOrientationFormMatchesMujoco) {
  for (const std::string compiler :
       {"angle=\"degree\"", "angle=\"radian\"", "angle=\"degree\" eulerseq=\"ZYX\"",
        "angle=\"radian\" eulerseq=\"zXz\""}) {
    const bool degree = compiler.find("degree") != std::string::npos;
    const std::string a = degree ? "40" : "0.7";
    const std::string xml = "<mujoco><compiler " + compiler + R"(/><worldbody>
      <body name="q" quat="0.9 0.1 -0.3 0.2"><geom size="1"/></body>
      <body name="aa" axisangle="1 2 3 )" +
                            a + R"("><geom size="1"/></body>
      <body name="eu" euler=")" +
                            a + " -" + a + " " + a + R"("><geom size="1"/></body>
      <body name="xy" xyaxes="1 1 0 -1 2 0.5"><geom size="1"/></body>
      <body name="z" zaxis="0.3 -1 0.2"><geom size="1"/></body>
      <body name="zdown" zaxis="0 0 -1"><geom size="1"/></body>
    </worldbody></mujoco>)";
    document::Document doc = Read(xml);
    physics::ModelPtr m = physics::CompileXmlString(mjcf::WriteString(doc));
    for (const char* name : {"q", "aa", "eu", "xy", "z", "zdown"}) {
      const document::Element* e = doc.FindNamed(document::Namespace::kBody, name);
      ASSERT_NE(e, nullptr);
      const auto q = document::OwnOrientation(*e, doc.Compiler());
      ASSERT_TRUE(q.has_value()) << name;
      const int id = mj_name2id(m.get(), mjOBJ_BODY, name);
      ExpectSameRotation(*q, m->body_quat + 4 * id, compiler + " " + name);
    }
  }
}

TEST_F(NormalizationTest, FromtoResolvesLikeMujocoAndExportRuleKeepsThePhysics) {
  const std::string xml = R"(<mujoco><default><default class="thin">
      <geom type="capsule" size="0.03"/></default>
      <default class="boxy"><geom type="box" size="0.05 0.05 0.05"/></default></default>
    <worldbody><body name="b" pos="0 0 1"><joint/>
      <geom name="cap" class="thin" fromto="0 0 0 0.3 0.1 -0.2"/>
      <geom name="box" class="boxy" fromto="0 0 0 0 0.4 0"/>
      <geom name="own" type="cylinder" size="0.02 9" fromto="0.1 0 0 0.1 0 0.5"/>
    </body></worldbody></mujoco>)";
  document::Document doc = Read(xml);
  physics::ModelPtr before = physics::CompileXmlString(mjcf::WriteString(doc));
  for (const char* name : {"cap", "box", "own"}) {
    document::Element* g = doc.FindNamed(document::Namespace::kGeom, name);
    const auto f = document::ResolveFromTo(doc, *g);
    ASSERT_TRUE(f.has_value());
    const int id = mj_name2id(before.get(), mjOBJ_GEOM, name);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f->pos[i], before->geom_pos[3 * id + i], 1e-12);
    ExpectSameRotation(f->quat, before->geom_quat + 4 * id, name);
    EXPECT_NEAR(f->half_length, before->geom_size[3 * id + f->slot], 1e-12) << name;
    EXPECT_TRUE(document::NormalizeFromTo(doc, *g));
    EXPECT_FALSE(g->Has("fromto"));
  }
  // Rewritten as pos/quat/size, the model is the same.
  physics::ModelPtr after = physics::CompileXmlString(mjcf::WriteString(doc));
  for (int i = 0; i < before->ngeom; ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(before->geom_size[3 * i + k], after->geom_size[3 * i + k], 1e-12) << i;
      EXPECT_NEAR(before->geom_pos[3 * i + k], after->geom_pos[3 * i + k], 1e-12) << i;
    }
    ExpectSameRotation({after->geom_quat[4 * i], after->geom_quat[4 * i + 1],
                        after->geom_quat[4 * i + 2], after->geom_quat[4 * i + 3]},
                       before->geom_quat + 4 * i, "geom " + std::to_string(i));
  }
}

TEST_F(NormalizationTest, DefaultChainAndInheritedVisualOffset) {
  document::Document doc = Read(R"(<mujoco><default>
      <geom rgba="1 0 0 1" group="1"/>
      <default class="visual"><geom group="2" contype="0" conaffinity="0"/>
        <default class="visual_zflip"><geom quat="0 0 0 1" pos="0 0 0.1"/></default>
      </default></default>
    <worldbody><body name="b" childclass="visual"><geom name="g1" size="1"/>
      <geom name="g2" class="visual_zflip" size="1"/>
      <geom name="g3" class="main" size="1" group="5"/></body></worldbody></mujoco>)");
  auto geom = [&](const char* n) { return doc.FindNamed(document::Namespace::kGeom, n); };
  EXPECT_EQ(document::EffectiveClass(*geom("g1")), "visual");
  EXPECT_EQ(*document::ResolveAttribute(doc, *geom("g1"), "group"), "2");
  EXPECT_EQ(*document::ResolveAttribute(doc, *geom("g1"), "rgba"), "1 0 0 1");
  EXPECT_EQ(*document::ResolveAttribute(doc, *geom("g2"), "group"), "2");
  EXPECT_EQ(*document::ResolveAttribute(doc, *geom("g3"), "group"), "5");
  EXPECT_EQ(document::ResolveAttribute(doc, *geom("g3"), "contype"), nullptr);
  const document::InheritedPose pose = document::InheritedDefaultPose(doc, *geom("g2"));
  EXPECT_TRUE(pose.any);
  EXPECT_EQ(pose.quat, (Quat{0, 0, 0, 1}));
  EXPECT_EQ(pose.pos[2], 0.1);
  EXPECT_FALSE(document::InheritedDefaultPose(doc, *geom("g1")).any);
}

TEST_F(NormalizationTest, EditedValuesRoundTripExactly) {
  document::Document doc =
      Read("<mujoco><worldbody><geom name=\"g\" size=\"1\"/></worldbody></mujoco>");
  document::Element* g = doc.FindNamed(document::Namespace::kGeom, "g");
  const double v = 0.1 + 0.2;  // not representable in short decimal
  g->SetReals("pos", std::vector<double>{v, -1e-300, 3.0});
  EXPECT_TRUE(g->edited());
  EXPECT_EQ((*g->GetReals("pos"))[0], v);
  EXPECT_THROW(g->Set("type", "sphere2"), InputError);
  EXPECT_THROW(g->Set("pos", "1 2 3 4"), InputError);
  physics::ModelPtr m = physics::CompileXmlString(mjcf::WriteString(doc));
  EXPECT_EQ(m->geom_pos[0], v);
}

TEST_F(NormalizationTest, BuilderMakesUniqueNamesAndCompiles) {
  document::ArticulationBuilder b("arm");
  b.Template("main", "joint").Set("damping", "0.5");
  auto& base = b.Body(nullptr, "link", {0, 0, 1});
  b.Joint(base, "j", "hinge", {0, 1, 0});
  b.Geom(&base, "capsule", {0.05}, "seg").Set("fromto", "0 0 0 0.3 0 0");
  auto& tip = b.Body(&base, "link", {0.3, 0, 0});
  b.Joint(tip, "j", "hinge", {0, 1, 0});
  b.Geom(&tip, "sphere", {0.05}, "seg");
  EXPECT_EQ(tip.Name(), "link_1");
  b.Actuator("motor", "m", "j");
  b.Actuator("position", "m", "j_1").Set("kp", "10");
  b.Sensor("jointpos", "s", "joint", "j_1");
  b.Keyframe("home", {0.1, 0.2}, {0, 0.2});
  document::Document doc = b.Build();
  physics::ModelPtr m = physics::CompileXmlString(mjcf::WriteString(doc));
  EXPECT_EQ(m->nbody, 3);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_JOINT, "j_1"), 0);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_GEOM, "seg_1"), 0);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_ACTUATOR, "m_1"), 0);
  EXPECT_EQ(m->dof_damping[1], 0.5);
  EXPECT_EQ(m->nkey, 1);
  EXPECT_EQ(m->key_qpos[1], 0.2);
}

}  // namespace
}  // namespace urlab
