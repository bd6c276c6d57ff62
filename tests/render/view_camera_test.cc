// `--camera track:BODY` frames the tracked body's subtree (a robot), not the whole scene: the
// chase distance follows the subtree's size (it used to be 0.6 of the scene's extent, which put a
// Go2 filling the frame from a few centimetres).
#include "render/view_camera.h"

#include <gtest/gtest.h>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab::render {
namespace {

class ViewCameraTest : public testing::MujocoTest {};

TEST_F(ViewCameraTest, TrackingFramesTheSubtree) {
  const physics::ModelPtr model = physics::CompileXmlString(R"(<mujoco>
  <worldbody>
    <geom type="plane" size="50 50 .1"/>
    <body name="robot" pos="0 0 .5">
      <freejoint/>
      <geom type="box" size=".3 .1 .1"/>
      <body name="leg" pos=".3 0 -.2"><geom type="capsule" size=".02" fromto="0 0 0 0 0 -.2"/></body>
    </body>
  </worldbody>
</mujoco>)");
  const ViewCamera small = ParseViewCamera(model.get(), "track:robot", "--camera");
  EXPECT_EQ(small.view.type, mjCAMERA_TRACKING);
  // The leg's tip reaches about 0.6 m from the base: a few times that, whatever the floor's size.
  EXPECT_GT(small.view.distance, 1.0);
  EXPECT_LT(small.view.distance, 4.0);
  EXPECT_THROW(ParseViewCamera(model.get(), "track:nobody", "--camera"), Error);
}

}  // namespace
}  // namespace urlab::render
