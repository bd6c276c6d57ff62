// The scene export: MuJoCo writes the composed scene from its spec with the physics options
// changed at run time, and nothing else changes.
#include "urlab/ops/scene_export.h"

#include <mujoco/mujoco.h>

#include "ops/ops_fixture.h"
#include "urlab/mjcf/spec.h"
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
  EXPECT_EQ(xml, mjcf::SaveXml(session().scene().spec.get()));
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
  EXPECT_EQ(changed, (std::vector<std::string>{"gravity", "integrator", "iterations", "timestep"}));
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
  // The scene's own spec is not touched by the export.
  EXPECT_EQ(session().scene().spec->option.timestep, 0.002);
}

TEST_F(SceneExportTest, FlagsAreNamedByTheirMjcfNames) {
  mjOption compiled;
  mj_defaultOption(&compiled);
  mjOption now = compiled;
  now.disableflags |= mjDSBL_CONTACT | mjDSBL_GRAVITY;
  now.enableflags |= mjENBL_ENERGY;
  now.cone = mjCONE_ELLIPTIC;
  now.solver = mjSOL_CG;
  EXPECT_EQ(
      ChangedOptions(compiled, now),
      (std::vector<std::string>{"cone", "flag.contact", "flag.energy", "flag.gravity", "solver"}));
  // The same names set them back.
  mjOption again = compiled;
  for (const auto& [k, v] : mjcf::OptionText(now)) mjcf::SetOption(&again, k, v);
  EXPECT_EQ(again.disableflags, now.disableflags);
  EXPECT_EQ(again.enableflags, now.enableflags);
  EXPECT_EQ(again.cone, mjCONE_ELLIPTIC);
  EXPECT_EQ(again.solver, mjSOL_CG);
}

}  // namespace
}  // namespace urlab::ops::test
