// The camera renderer with no window: a camera 2 m above a box of known size sees its top face
// at the known distance, the box's geom in segmentation, its colour in RGB; a camera on a
// sliding body sees the box move.
#include "render/camera_renderer.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include "mujoco_test.h"
#include "render/gl_context.h"

namespace urlab::render {
namespace {

// The box's top face is at z = 0.1; the fixed camera is at z = 2 looking down (-z), so the
// centre pixel is 1.9 m away. The rig camera rides a slide joint along x.
constexpr char kScene[] = R"(
<mujoco>
  <visual><headlight ambient="0.4 0.4 0.4" diffuse="0.6 0.6 0.6" specular="0 0 0"/></visual>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1" rgba="0.2 0.2 0.2 1" pos="0 0 -0.5"/>
    <body name="box" pos="0 0 0">
      <geom name="box" type="box" size="0.1 0.1 0.1" rgba="1 0 0 1"/>
    </body>
    <camera name="top" pos="0 0 2" fovy="45"/>
    <body name="rig" pos="0 0 1">
      <joint name="slide" type="slide" axis="1 0 0"/>
      <geom name="rig" type="sphere" size="0.01" contype="0" conaffinity="0" rgba="0 0 1 0"/>
      <camera name="rig" pos="0 0 0" fovy="45"/>
    </body>
  </worldbody>
</mujoco>)";

class CameraRendererTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    model_ = physics::CompileXmlString(kScene);
    gl_ = OffscreenGl::Create();
    renderer_ = std::make_unique<CameraRenderer>(model_.get(), 64, 48, RenderSettings{});
    renderer_->MakeContext();
    frame_ = physics::StateFrame::SizedFor(model_.get());
    auto data = physics::MakeData(model_.get());
    mj_forward(model_.get(), data.get());
    frame_.CopyFrom(model_.get(), data.get());
  }

  std::size_t Centre(const CameraImages& im) const {
    return static_cast<std::size_t>(im.height / 2) * im.width + im.width / 2;
  }

  physics::ModelPtr model_;
  std::unique_ptr<OffscreenGl> gl_;
  std::unique_ptr<CameraRenderer> renderer_;
  physics::StateFrame frame_;
};

TEST_F(CameraRendererTest, CentrePixelSeesTheBoxAtItsDistanceWithItsIdAndColour) {
  renderer_->SetGeomGroups({-1, 7, -1});  // the box's group: 7 (an articulation index)
  renderer_->Update(frame_);
  CameraImages im;
  renderer_->Render(mj_name2id(model_.get(), mjOBJ_CAMERA, "top"), 64, 48,
                    {.rgb = true, .depth = true, .segmentation = true}, im);
  ASSERT_EQ(im.rgb.size(), 64u * 48u * 3u);
  ASSERT_EQ(im.depth.size(), 64u * 48u);
  const std::size_t c = Centre(im);
  EXPECT_NEAR(im.depth[c], 1.9, 1e-3) << "(backend " << gl_->Describe() << ")";
  EXPECT_EQ(im.geom_ids[c], mj_name2id(model_.get(), mjOBJ_GEOM, "box"));
  EXPECT_EQ(im.group_ids[c], 7);
  // Red box under a white headlight: red dominates, green and blue stay dark.
  EXPECT_GT(im.rgb[3 * c], 150);
  EXPECT_LT(im.rgb[3 * c + 1], 40);
  EXPECT_LT(im.rgb[3 * c + 2], 40);
  // A corner sees the floor, 2.5 m away along the optical axis (depth is not the ray's length),
  // its geom and no group.
  EXPECT_NEAR(im.depth[0], 2.5, 1e-3);
  EXPECT_EQ(im.geom_ids[0], mj_name2id(model_.get(), mjOBJ_GEOM, "floor"));
  EXPECT_EQ(im.group_ids[0], -1);
}

TEST_F(CameraRendererTest, ImagesAreTopDown) {
  // Move the box towards +y: in the image of a camera looking down -z with +y up in the image,
  // the box's pixels move to the top rows.
  const int box_body = mj_name2id(model_.get(), mjOBJ_BODY, "box");
  model_->body_pos[3 * box_body + 1] = 0.5;
  renderer_ = std::make_unique<CameraRenderer>(model_.get(), 64, 48, RenderSettings{});
  renderer_->MakeContext();
  renderer_->Update(frame_);
  CameraImages im;
  renderer_->Render(mj_name2id(model_.get(), mjOBJ_CAMERA, "top"), 64, 48, {.segmentation = true},
                    im);
  const int box = mj_name2id(model_.get(), mjOBJ_GEOM, "box");
  int top = 0, bottom = 0;
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      if (im.geom_ids[static_cast<std::size_t>(y) * 64 + x] == box) (y < 24 ? top : bottom)++;
    }
  }
  EXPECT_GT(top, 20);
  EXPECT_EQ(bottom, 0);
}

TEST_F(CameraRendererTest, ACameraOnAMovingBodySeesTheSceneMove) {
  const int cam = mj_name2id(model_.get(), mjOBJ_CAMERA, "rig");
  const int box = mj_name2id(model_.get(), mjOBJ_GEOM, "box");
  CameraImages before, after;
  renderer_->Update(frame_);
  renderer_->Render(cam, 64, 48, {.depth = true, .segmentation = true}, before);
  EXPECT_EQ(before.geom_ids[Centre(before)], box);
  EXPECT_NEAR(before.depth[Centre(before)], 0.9, 1e-3);
  frame_.qpos[0] = 0.5;  // the rig slides 0.5 m along +x: the box leaves the centre
  renderer_->Update(frame_);
  renderer_->Render(cam, 64, 48, {.depth = true, .segmentation = true}, after);
  EXPECT_NE(after.geom_ids[Centre(after)], box);
  EXPECT_GT(after.depth[Centre(after)], 1.4);
  // The box is now to the left of the image (smaller x).
  int left = 0, right = 0;
  for (std::size_t i = 0; i < after.geom_ids.size(); ++i) {
    if (after.geom_ids[i] == box) (static_cast<int>(i % 64) < 32 ? left : right)++;
  }
  EXPECT_GT(left, 0);
  EXPECT_EQ(right, 0);
}

TEST_F(CameraRendererTest, BadCameraOrSizeIsAnError) {
  CameraImages im;
  EXPECT_THROW(renderer_->Render(99, 64, 48, {.rgb = true}, im), Error);
  EXPECT_THROW(renderer_->Render(0, 65, 48, {.rgb = true}, im), Error);
  EXPECT_THROW(renderer_->Render(0, 0, 48, {.rgb = true}, im), Error);
}

TEST(IdColor, RoundTripsAndBackgroundIsBlack) {
  for (std::int32_t id : {-1, 0, 1, 255, 256, 70000}) {
    std::uint8_t c[4];
    IdColor(id, c);
    EXPECT_EQ(DecodeIdColor(c), id);
    EXPECT_EQ(c[3], 255);
  }
  std::uint8_t black[4];
  IdColor(-1, black);
  EXPECT_EQ(black[0] | black[1] | black[2], 0);
}

TEST(OffscreenGl, BackendsAreChosenAtRunTime) {
  EXPECT_EQ(ParseGlBackend("egl", "x"), GlBackend::kEgl);
  EXPECT_THROW(ParseGlBackend("glx", "URLAB_GL"), Error);
  // OSMesa, the fallback, works alone on this machine too. (ctest runs each test in a process of
  // its own: MuJoCo's GL loader takes its entry points from the first GL library it finds loaded,
  // so a process that made an EGL context renders through EGL afterwards.)
  auto model = physics::CompileXmlString(kScene);
  auto gl = OffscreenGl::Create(GlBackend::kOsMesa);
  EXPECT_EQ(gl->Describe(), "osmesa");
  CameraRenderer renderer(model.get(), 32, 24, RenderSettings{});
  renderer.MakeContext();
  auto frame = physics::StateFrame::SizedFor(model.get());
  auto data = physics::MakeData(model.get());
  mj_forward(model.get(), data.get());
  frame.CopyFrom(model.get(), data.get());
  renderer.Update(frame);
  CameraImages im;
  renderer.Render(0, 32, 24, {.depth = true}, im);
  EXPECT_NEAR(im.depth[12 * 32 + 16], 1.9, 1e-3);
}

}  // namespace
}  // namespace urlab::render
