// The scene export: the composed MJCF carries the physics options changed at run time (MuJoCo
// 2.2.2 saves the XML as loaded), and nothing else changes.
#include "urlab/ops/scene_export.h"

#include <mujoco/mujoco.h>

#include "ops/ops_fixture.h"
#include "urlab/mjcf/reader.h"
#include "urlab/ops/state.h"

namespace urlab::ops::test {
namespace {

class SceneExportTest : public OpsTest {};

// Compiles MJCF text written into the test's folder.
mjModel* Compile(const std::string& dir, const std::string& xml) {
  const std::string path = urlab::testing::WriteTextFile(dir, "exported.xml", xml);
  char error[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
  EXPECT_NE(m, nullptr) << error;
  return m;
}

TEST_F(SceneExportTest, UnchangedOptionsWriteTheComposedSceneAsIs) {
  Play();
  std::vector<std::string> changed = {"sentinel"};
  const std::string xml = SceneXml(session(), {}, &changed);
  EXPECT_TRUE(changed.empty());
  EXPECT_EQ(xml, mjcf::WriteString(session().scene().doc, {}));
}

TEST_F(SceneExportTest, OptionsChangedAtRunTimeAreWrittenAndCompileBack) {
  Play();
  OptionsChange change;
  change.timestep = 0.001;
  change.gravity = std::array<double, 3>{0.5, 0, -3.25};
  change.integrator = mjINT_RK4;
  change.iterations = 17;
  Wait(SetOptions(session(), change).seq);
  std::vector<std::string> changed;
  const std::string xml = SceneXml(session(), {}, &changed);
  EXPECT_EQ(changed, (std::vector<std::string>{"timestep", "gravity", "integrator", "iterations"}));
  mjModel* m = Compile(dir_, xml);
  ASSERT_NE(m, nullptr);
  const physics::Model now = session().engine().CopyModel();
  EXPECT_EQ(m->opt.timestep, 0.001);
  EXPECT_EQ(m->opt.gravity[0], 0.5);
  EXPECT_EQ(m->opt.gravity[2], -3.25);
  EXPECT_EQ(m->opt.integrator, mjINT_RK4);
  EXPECT_EQ(m->opt.iterations, 17);
  // Every other option as in effect.
  EXPECT_EQ(m->opt.tolerance, now->opt.tolerance);
  EXPECT_EQ(m->opt.cone, now->opt.cone);
  EXPECT_EQ(m->opt.disableflags, now->opt.disableflags);
  EXPECT_EQ(m->nbody, now->nbody);
  mj_deleteModel(m);
  // The scene's own document is not touched by the export.
  EXPECT_EQ(session().scene().doc.FindSection("option")->GetOr("timestep", ""), "0.002");
}

TEST_F(SceneExportTest, FlagsAreWrittenByTheirMjcfNames) {
  document::Document doc = mjcf::ReadString(kArmXml, "arm.xml");
  mjOption compiled;
  mj_defaultOption(&compiled);
  mjOption now = compiled;
  now.disableflags |= mjDSBL_CONTACT | mjDSBL_GRAVITY;
  now.enableflags |= mjENBL_ENERGY;
  now.cone = mjCONE_ELLIPTIC;
  now.solver = mjSOL_CG;
  const auto written = WriteOptionChanges(compiled, now, doc);
  EXPECT_EQ(written, (std::vector<std::string>{"cone", "solver", "flag.contact", "flag.gravity",
                                               "flag.energy"}));
  const document::Element* option = doc.FindSection("option");
  ASSERT_NE(option, nullptr);
  EXPECT_EQ(option->GetOr("cone", ""), "elliptic");
  EXPECT_EQ(option->GetOr("solver", ""), "CG");
  const document::Element* flag = option->FirstChild("flag");
  ASSERT_NE(flag, nullptr);
  EXPECT_EQ(flag->GetOr("contact", ""), "disable");
  EXPECT_EQ(flag->GetOr("gravity", ""), "disable");
  EXPECT_EQ(flag->GetOr("energy", ""), "enable");
  mjModel* m = Compile(urlab::testing::MakeTempDir("export"), mjcf::WriteString(doc, {}));
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->opt.disableflags, now.disableflags);
  EXPECT_EQ(m->opt.enableflags, now.enableflags);
  EXPECT_EQ(m->opt.cone, mjCONE_ELLIPTIC);
  EXPECT_EQ(m->opt.solver, mjSOL_CG);
  mj_deleteModel(m);
}

}  // namespace
}  // namespace urlab::ops::test
