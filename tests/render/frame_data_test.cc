// CopyFrameToData fills what drawing reads: a flex's vertices follow the published state (a flag
// drawn from them used to stay in its rest pose in the viewer and the cameras).
#include "render/frame_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "mujoco_test.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state_frame.h"

namespace urlab::render {
namespace {

class FrameDataTest : public testing::MujocoTest {};

TEST_F(FrameDataTest, FlexVerticesFollowTheFrame) {
  const physics::ModelPtr model = physics::CompileXmlString(R"(<mujoco>
  <option wind="5 5 0" density="10"/>
  <worldbody>
    <body name="pole" pos="0 0 1">
      <flexcomp name="flag" type="grid" count="5 9 1" spacing=".05 .05 .05" mass="1" dim="2">
        <pin id="0 1 2 3 4"/>
        <edge equality="true"/>
      </flexcomp>
    </body>
  </worldbody>
</mujoco>)");
  const mjModel* m = model.get();
  ASSERT_EQ(m->nflex, 1);
  physics::DataPtr sim = physics::MakeData(m);
  for (int i = 0; i < 300; ++i) mj_step(m, sim.get());
  mj_forward(m, sim.get());
  physics::StateFrame frame;
  frame.time = sim->time;
  frame.qpos.assign(sim->qpos, sim->qpos + m->nq);
  frame.qvel.assign(sim->qvel, sim->qvel + m->nv);
  physics::DataPtr drawn = physics::MakeData(m);
  CopyFrameToData(m, drawn.get(), frame);
  physics::DataPtr rest = physics::MakeData(m);
  mj_forward(m, rest.get());
  double moved = 0;
  for (int i = 0; i < 3 * m->nflexvert; ++i) {
    EXPECT_EQ(drawn->flexvert_xpos[i], sim->flexvert_xpos[i]) << i;
    moved = std::max(moved, std::abs(sim->flexvert_xpos[i] - rest->flexvert_xpos[i]));
  }
  EXPECT_GT(moved, 0.01);  // the flag is not in its rest pose
}

}  // namespace
}  // namespace urlab::render
