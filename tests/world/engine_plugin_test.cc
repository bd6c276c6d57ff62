// Models that use MuJoCo's engine plugins (here the elasticity library's cable) compose and run:
// the plugins shipped with the release are registered at start (urlab::LoadEnginePlugins).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <string>

#include "mujoco_test.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/physics/model.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"

namespace urlab {
namespace {

class EnginePluginTest : public testing::MujocoTest {};

TEST_F(EnginePluginTest, ACableOfTheElasticityPluginComposesAndRuns) {
  EXPECT_FALSE(EnginePluginDir().empty());
  EXPECT_GE(mjp_pluginCount(), 1);
  const std::string dir = testing::MakeTempDir("engine_plugin");
  testing::WriteTextFile(dir, "cable.xml", R"(<mujoco model="cable">
  <extension><plugin plugin="mujoco.elasticity.cable"/></extension>
  <worldbody>
    <geom type="plane" size="2 2 .1"/>
    <composite type="cable" curve="s" count="20 1 1" size="1" offset="-.5 0 .8" initial="none">
      <plugin plugin="mujoco.elasticity.cable">
        <config key="twist" value="1e6"/>
        <config key="bend" value="1e6"/>
      </plugin>
      <joint kind="main" damping=".015"/>
      <geom type="capsule" size=".005"/>
    </composite>
  </worldbody>
</mujoco>
)");
  const world::CompiledScene scene = world::BuildScene(world::ParseScene(
      "articulations:\n  - {name: c, mjcf: cable.xml, pos: [0, 0, 0.2]}\n", dir + "/s.yaml"));
  const mjModel* m = scene.model.get();
  EXPECT_EQ(m->nplugin, 1);
  physics::DataPtr d = physics::MakeData(m);
  const double z0 = d->qpos[2];
  for (int i = 0; i < 200; ++i) mj_step(m, d.get());
  for (int i = 0; i < m->nq; ++i) ASSERT_TRUE(std::isfinite(d->qpos[i])) << i;
  EXPECT_NE(d->qpos[2], z0);  // it moved (falls under gravity)
}

}  // namespace
}  // namespace urlab
