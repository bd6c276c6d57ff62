// The viewer on a real display (CI runs these under xvfb-run with Mesa's software renderer):
// a Manager with the ViewerSubsystem plays a scene, the test reads the window's pixels and checks
// where things are drawn, injects key and mouse events through the window's input handler, and
// checks what they did to the simulation.
#include "urlab/viewer/viewer.h"

#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <thread>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "mujoco_test.h"
#include "net/step_test_client.h"
#include "urlab/net/network.h"
#include "urlab/replay/playback.h"
#include "urlab/replay/recording.h"
#include "urlab/viewer/scene_settings.h"
#include "urlab/world/manager.h"
#include "viewer/image_io.h"
#include "viewer/panel.h"
#include "viewer/timeline.h"
#include "viewer/viewer_core.h"
#include "wait.h"

namespace urlab {
namespace {

using testing::WaitFor;
using viewer::Image;
using viewer::internal::ViewerCore;

// A red ball resting on a floor, carrying a blue stick on a limited hinge with a position servo.
constexpr const char* kBotXml = R"(<mujoco model="bot">
  <visual><headlight ambient="0.5 0.5 0.5" diffuse="0.5 0.5 0.5"/></visual>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1" rgba="0.25 0.25 0.25 1"/>
    <body name="base" pos="0.5 0.4 0.1">
      <freejoint name="root"/>
      <geom name="ball" type="sphere" size="0.1" rgba="1 0 0 1"/>
      <body name="arm" pos="0 0 0.1">
        <joint name="hinge" type="hinge" axis="0 1 0" range="-1 1" damping="1"/>
        <geom name="stick" type="capsule" fromto="0 0 0 0 0 0.3" size="0.02" rgba="0 0 1 1"
              contype="0" conaffinity="0" mass="0.05"/>
      </body>
    </body>
  </worldbody>
  <actuator><position name="servo" joint="hinge" kp="20" ctrlrange="-1 1"/></actuator>
</mujoco>
)";

// A floating box without gravity, for perturbation.
constexpr const char* kFloatXml = R"(<mujoco model="float">
  <option gravity="0 0 0"/>
  <worldbody>
    <body name="box" pos="0 0 1">
      <freejoint name="root"/>
      <geom name="box" type="box" size="0.1 0.1 0.1" rgba="0 1 0 1"/>
    </body>
  </worldbody>
</mujoco>
)";

struct Pixel {
  double x = 0, y = 0;
};

// Where a world point lands in the window's framebuffer (pixels, origin top-left), from the
// scene's camera as mjr_render sets up its frustum in the 3D viewport last drawn.
Pixel Project(ViewerCore& core, const mjtNum p[3]) {
  const mjvScene& scn = core.view().scene();
  const mjvGLCamera cam = mjv_averageCamera(&scn.camera[0], &scn.camera[1]);
  int w = 0, h = 0;
  core.window().FramebufferSize(&w, &h);
  mjrRect vp = core.last_viewport();
  if (vp.width <= 0) vp = {0, 0, w, h};  // nothing drawn yet: the whole window
  const double aspect = static_cast<double>(vp.width) / vp.height;
  const double half_w = 0.5 * aspect * (cam.frustum_top - cam.frustum_bottom);
  mjtNum v[3], right[3], fwd[3], up[3];
  mju_f2n(fwd, cam.forward, 3);
  mju_f2n(up, cam.up, 3);
  mjtNum pos[3];
  mju_f2n(pos, cam.pos, 3);
  mju_sub3(v, p, pos);
  mju_cross(right, fwd, up);
  const double z = mju_dot3(v, fwd);
  const double xn = mju_dot3(v, right) * cam.frustum_near / z;
  const double yn = mju_dot3(v, up) * cam.frustum_near / z;
  Pixel px;
  px.x = vp.left + (xn - (cam.frustum_center - half_w)) / (2 * half_w) * vp.width;
  px.y = (h - vp.bottom - vp.height) +
         (1 - (yn - cam.frustum_bottom) / (cam.frustum_top - cam.frustum_bottom)) * vp.height;
  return px;
}

// Pixels that differ by more than a little, inside and outside a circle.
struct Diff {
  int inside = 0, outside = 0;
};
Diff Compare(const Image& a, const Image& b, Pixel centre, double radius) {
  Diff d;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      int sum = 0;
      for (int c = 0; c < 3; ++c) sum += std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c]));
      if (sum < 60) continue;
      const double dx = x - centre.x, dy = y - centre.y;
      (dx * dx + dy * dy <= radius * radius ? d.inside : d.outside)++;
    }
  }
  return d;
}

// Distance in pixels from p to the segment a-b.
double DistToSegment(Pixel p, Pixel a, Pixel b) {
  const double vx = b.x - a.x, vy = b.y - a.y;
  const double len2 = vx * vx + vy * vy;
  const double t =
      len2 > 0 ? std::clamp(((p.x - a.x) * vx + (p.y - a.y) * vy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - (a.x + t * vx), p.y - (a.y + t * vy));
}

class ViewerTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("viewer");
    viewer::RegisterSceneSections();  // scenes here have viewer: and cinematic: sections
  }
  void TearDown() override {
    manager_.reset();
    testing::MujocoTest::TearDown();
  }

  // Plays `xml` as articulation "bot" with a viewer window of 640x480. `extra` is appended to the
  // scene file: indented lines add to the articulation's entry, others are top-level sections;
  // subsystems in more_ play before the viewer.
  void Play(const char* xml, viewer::ViewerOptions vo = {}, bool paused = true,
            const std::string& extra = "") {
    testing::WriteTextFile(dir_, "bot.xml", xml);
    const world::SceneConfig scene = world::ParseScene(
        "control_source: ui\narticulations:\n  - name: bot\n    mjcf: bot.xml\n"
        "    controller: {type: passthrough}\n" +
            extra,
        dir_ + "/scene.yaml");
    world::ManagerOptions mo;
    mo.start_paused = paused;
    manager_ = std::make_unique<world::Manager>(mo);
    for (auto& sub : more_) manager_->AddSubsystem(std::move(sub));
    more_.clear();
    vo.width = 640;
    vo.height = 480;
    auto v = std::make_unique<viewer::ViewerSubsystem>(vo);
    v->SetManager(manager_.get());
    if (playback_) v->SetPlayback(playback_);
    viewer_ = v.get();
    manager_->AddSubsystem(std::move(v));
    manager_->BeginPlay(scene);
    ASSERT_TRUE(WaitFor([&] {
      manager_->Tick();
      return manager_->frame() != nullptr && core().frame() != nullptr;
    }));
  }
  ViewerCore& core() { return viewer_->core(); }
  physics::PhysicsEngine& engine() { return manager_->session().engine(); }
  int Body(const char* name) {
    return mj_name2id(core().view().model(), mjOBJ_BODY, (std::string("bot_") + name).c_str());
  }
  const mjtNum* BodyPos(const char* name) { return core().view().data()->xpos + 3 * Body(name); }
  void Press(int key) { core().OnKey(key, GLFW_PRESS, 0); }
  void Release(int key) { core().OnKey(key, GLFW_RELEASE, 0); }
  void Key(int key, int mods = 0) {
    core().OnKey(key, GLFW_PRESS, mods);
    core().OnKey(key, GLFW_RELEASE, mods);
  }
  // Ticks until the viewer's copy of the state shows `pred`.
  bool TickUntil(const std::function<bool()>& pred) {
    return WaitFor([&] {
      manager_->Tick();
      return pred();
    });
  }

  std::string dir_;
  std::vector<std::unique_ptr<world::Subsystem>> more_;
  std::shared_ptr<replay::PlaybackSlot> playback_;  // given to the viewer when set
  std::unique_ptr<world::Manager> manager_;
  viewer::ViewerSubsystem* viewer_ = nullptr;
};

TEST_F(ViewerTest, DrawsTheRobotWhereItsProjectionSays) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo);
  const Image img = viewer_->ReadPixels();
  ASSERT_EQ(img.width, 640);
  ASSERT_EQ(img.height, 480);
  const Pixel ball = Project(core(), BodyPos("base"));
  ASSERT_GT(ball.x, 0);
  ASSERT_LT(ball.x, img.width);
  ASSERT_GT(ball.y, 0);
  ASSERT_LT(ball.y, img.height);
  const std::uint8_t* c = img.at(static_cast<int>(ball.x), static_cast<int>(ball.y));
  EXPECT_GT(c[0], 120) << "red ball expected at " << ball.x << "," << ball.y;
  EXPECT_LT(c[1], 80);
  EXPECT_LT(c[2], 80);
  // A point of the floor well away from the ball is not red.
  const mjtNum far[3] = {-1.5, -1.5, 0};
  const Pixel f = Project(core(), far);
  if (f.x >= 0 && f.x < img.width && f.y >= 0 && f.y < img.height) {
    const std::uint8_t* g = img.at(static_cast<int>(f.x), static_cast<int>(f.y));
    EXPECT_FALSE(g[0] > 120 && g[1] < 80 && g[2] < 80);
  }
}

TEST_F(ViewerTest, DrawsThePanelDockedBesideTheViewport) {
  Play(kBotXml);
  const Image with = viewer_->ReadPixels();
  // The 3D viewport is the window right of the panel and its splitter: the camera is centred
  // there, and the robot is drawn there (not behind the panel).
  const viewer::internal::WindowRect vp = core().ViewportRect();
  const float panel_w = core().layout().Panel(640, 480).w;
  EXPECT_EQ(panel_w, viewer::internal::Layout::kDefaultWidth);
  EXPECT_EQ(vp.x, panel_w + viewer::internal::Layout::kSplitter);
  EXPECT_EQ(vp.w, 640 - vp.x);
  EXPECT_EQ(core().last_viewport().left, static_cast<int>(vp.x));
  EXPECT_EQ(core().last_viewport().width, static_cast<int>(vp.w));
  const Pixel ball = Project(core(), BodyPos("base"));
  EXPECT_GT(ball.x, vp.x + 10) << "the robot stands right of the panel";
  EXPECT_LT(ball.x, 630);
  const std::uint8_t* c = with.at(static_cast<int>(ball.x), static_cast<int>(ball.y));
  EXPECT_GT(c[0], 120) << "red ball expected at " << ball.x << "," << ball.y;
  EXPECT_LT(c[2], 80);
  // The panel is opaque: against the same frame without a panel, its region changed.
  manager_.reset();
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo);
  const Image without = viewer_->ReadPixels();
  int changed = 0, total = 0;
  for (int y = 0; y < with.height; y += 2) {
    for (int x = 0; x < static_cast<int>(panel_w); x += 2) {
      ++total;
      int sum = 0;
      for (int k = 0; k < 3; ++k) sum += std::abs(int(with.at(x, y)[k]) - int(without.at(x, y)[k]));
      if (sum > 30) ++changed;
    }
  }
  EXPECT_GT(changed, total / 2) << "the panel covers the left " << panel_w << " pixels";
  EXPECT_EQ(core().ViewportRect().x, 0) << "without a panel the viewport is the whole window";
}

TEST_F(ViewerTest, SplitterResizesAndHCollapsesThePanel) {
  Play(kBotXml);
  using Mouse = viewer::internal::Window::InjectedMouse;
  viewer::internal::Layout& layout = core().layout();
  const viewer::internal::WindowRect s = layout.Splitter(640, 480);
  ASSERT_GT(s.w, 0);
  const float x0 = s.x + s.w / 2, y = 200;
  const float vp0 = core().ViewportRect().x;
  // Drag the splitter 80 pixels to the right through ImGui's own input.
  core().window().InjectImGuiMouse(Mouse{x0, y, false});
  manager_->Tick();
  core().window().InjectImGuiMouse(Mouse{x0, y, true});
  manager_->Tick();
  for (int dx = 20; dx <= 80; dx += 20) {
    core().window().InjectImGuiMouse(Mouse{x0 + dx, y, true});
    manager_->Tick();
  }
  core().window().InjectImGuiMouse(Mouse{x0 + 80, y, false});
  manager_->Tick();
  core().window().InjectImGuiMouse(std::nullopt);
  EXPECT_NEAR(core().ViewportRect().x, vp0 + 80, 1.5);
  viewer_->ReadPixels();
  EXPECT_NEAR(core().last_viewport().left, vp0 + 80, 1.5) << "MuJoCo renders into the new rect";
  EXPECT_NEAR(core().last_viewport().width, 640 - (vp0 + 80), 1.5);
  // H collapses the panel to a strip and opens it again at the same width.
  Key(GLFW_KEY_H);
  viewer_->ReadPixels();
  EXPECT_EQ(core().last_viewport().left,
            static_cast<int>(viewer::internal::Layout::kCollapsedWidth));
  Key(GLFW_KEY_H);
  viewer_->ReadPixels();
  EXPECT_NEAR(core().last_viewport().left, vp0 + 80, 1.5);
}

TEST_F(ViewerTest, DefaultCameraFramesEveryRobotOfTheScene) {
  // Two robots 6 m apart (and a third far above): every body of each is in the view frustum,
  // inside the viewport right of the panel.
  Play(kBotXml, {}, true,
       "    pos: [0, -3, 0]\n  - name: other\n    mjcf: bot.xml\n    pos: [0, 3, 0]\n"
       "    controller: {type: passthrough}\n  - name: high\n    mjcf: bot.xml\n"
       "    pos: [1, 0, 2]\n    controller: {type: passthrough}\n");
  viewer_->ReadPixels();
  const viewer::internal::WindowRect vp = core().ViewportRect();
  const mjModel* m = core().view().model();
  const mjData* d = core().view().data();
  ASSERT_EQ(manager_->session().articulations().size(), 3u);
  int checked = 0;
  double min_x = 1e9, max_x = -1e9;
  for (int b = 1; b < m->nbody; ++b) {
    const Pixel p = Project(core(), d->xpos + 3 * b);
    EXPECT_GT(p.x, vp.x) << mj_id2name(m, mjOBJ_BODY, b);
    EXPECT_LT(p.x, vp.x + vp.w) << mj_id2name(m, mjOBJ_BODY, b);
    EXPECT_GT(p.y, 0) << mj_id2name(m, mjOBJ_BODY, b);
    EXPECT_LT(p.y, 480) << mj_id2name(m, mjOBJ_BODY, b);
    min_x = std::min(min_x, p.x);
    max_x = std::max(max_x, p.x);
    ++checked;
  }
  EXPECT_EQ(checked, 6);
  EXPECT_GT(max_x - min_x, vp.w / 4) << "the scene fills the view, not a corner of it";
  // Ctrl+A frames it again after the camera moved away.
  core().view().camera().distance *= 10;
  core().view().camera().lookat[0] += 20;
  Key(GLFW_KEY_A, GLFW_MOD_CONTROL);
  viewer_->ReadPixels();
  for (int b = 1; b < m->nbody; ++b) {
    const Pixel p = Project(core(), d->xpos + 3 * b);
    EXPECT_GT(p.x, vp.x);
    EXPECT_LT(p.x, vp.x + vp.w);
  }
}

TEST_F(ViewerTest, RenderQualityFromTheSceneAndTheCommandLine) {
  // Defaults: shadows, reflections and the sky on; a gradient sky where nothing is drawn.
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo);
  const mjvScene& scn = core().view().scene();
  EXPECT_TRUE(scn.flags[mjRND_SHADOW]);
  EXPECT_TRUE(scn.flags[mjRND_REFLECTION]);
  EXPECT_TRUE(scn.flags[mjRND_SKYBOX]);
  core().view().camera().elevation = 10;  // looking a little up: sky in the top rows
  const Image sky = viewer_->ReadPixels();
  const std::uint8_t* top = sky.at(320, 3);
  EXPECT_GT(top[2], 120) << "a blue sky at the top";
  EXPECT_GT(top[2], top[0]);
  // The scene's viewer: section, and the command line winning over it.
  manager_.reset();
  vo.shadows = false;
  vo.skybox = false;
  Play(kBotXml, vo, true, "viewer: {shadows: true, reflections: false, render_scale: 0.5}\n");
  const mjvScene& scn2 = core().view().scene();
  EXPECT_FALSE(scn2.flags[mjRND_SHADOW]) << "--no-shadows wins over the scene";
  EXPECT_FALSE(scn2.flags[mjRND_REFLECTION]) << "the scene's reflections: false";
  EXPECT_FALSE(scn2.flags[mjRND_SKYBOX]);
  EXPECT_EQ(core().quality().scale, 0.5);
  core().view().camera().elevation = 10;
  const Image half = viewer_->ReadPixels();
  const std::uint8_t* dark = half.at(320, 3);
  EXPECT_LT(dark[0] + dark[1] + dark[2], 40) << "no sky: the background stays dark";
  // At half resolution the robot is still drawn where it is.
  core().view().camera().elevation = -30;
  const Image img = viewer_->ReadPixels();
  const Pixel ball = Project(core(), BodyPos("base"));
  const std::uint8_t* c = img.at(static_cast<int>(ball.x), static_cast<int>(ball.y));
  EXPECT_GT(c[0], 120);
  EXPECT_LT(c[2], 80);
}

TEST_F(ViewerTest, DebugTogglesChangeTheExpectedRegion) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo);
  // Contacts come from the physics thread's capture: wait until one arrived.
  core().debug().Global(viewer::internal::DebugLayer::kContacts) = true;
  ASSERT_TRUE(TickUntil([&] { return !core().contacts().empty(); }));
  core().debug().Global(viewer::internal::DebugLayer::kContacts) = false;
  const Image plain = viewer_->ReadPixels();
  const mjtNum* ball = BodyPos("base");
  const Pixel centre = Project(core(), ball);
  mjtNum top[3] = {ball[0], ball[1], ball[2] + 0.1};
  const Pixel t = Project(core(), top);
  const double ball_px = std::hypot(t.x - centre.x, t.y - centre.y);
  ASSERT_GT(ball_px, 3);

  // 1: contact point and force arrow at the ball's bottom.
  Key(GLFW_KEY_1);
  const std::uint64_t captures = core().capture().captures();
  ASSERT_TRUE(TickUntil([&] { return core().capture().captures() > captures; }));
  const Image contacts = viewer_->ReadPixels();
  const mjtNum bottom[3] = {ball[0], ball[1], 0};
  Diff d = Compare(plain, contacts, Project(core(), bottom), 3 * ball_px);
  EXPECT_GT(d.inside, 10);
  EXPECT_GT(d.inside, 2 * d.outside) << "contacts drawn away from the contact point";
  Key(GLFW_KEY_1);

  // 3 toggles every collision wireframe (the floor's too); the articulation's own toggle only
  // its ball.
  Key(GLFW_KEY_3);
  EXPECT_TRUE(core().debug().Global(viewer::internal::DebugLayer::kCollision));
  const Image all_wire = viewer_->ReadPixels();
  EXPECT_GT(Compare(plain, all_wire, centre, 1.5 * ball_px).inside, 10);
  Key(GLFW_KEY_3);
  core()
      .debug()
      .articulation[0][static_cast<std::size_t>(viewer::internal::DebugLayer::kCollision)] = true;
  const Image ball_wire = viewer_->ReadPixels();
  d = Compare(plain, ball_wire, centre, 1.5 * ball_px);
  EXPECT_GT(d.inside, 10);
  EXPECT_GT(d.inside, 4 * d.outside) << "the ball's wireframe drawn elsewhere";
  core()
      .debug()
      .articulation[0][static_cast<std::size_t>(viewer::internal::DebugLayer::kCollision)] = false;

  // 4: the hinge's axis and range arc at its anchor.
  Key(GLFW_KEY_4);
  const Image joints = viewer_->ReadPixels();
  const mjtNum* anchor = core().view().data()->xanchor;  // joint 1 (0 is the free joint)
  d = Compare(plain, joints, Project(core(), anchor + 3), 4 * ball_px);
  EXPECT_GT(d.inside, 10);
  EXPECT_GT(d.inside, 2 * d.outside);
  Key(GLFW_KEY_4);
  // All off again: the frame is the plain one.
  const Image again = viewer_->ReadPixels();
  d = Compare(plain, again, centre, 1);
  EXPECT_EQ(d.inside + d.outside, 0);
}

// An L-shaped block as a Wavefront OBJ: concave, so Quick Convert splits it into parts.
std::string LBlockObj() {
  std::string obj;
  const double x[2][2] = {{0, 0.3}, {0, 0.1}};  // [box][min,max] in x; box 0 is the long leg
  const double y[2][2] = {{0, 0.1}, {0.1, 0.3}};
  for (int b = 0; b < 2; ++b) {
    for (int i = 0; i < 8; ++i) {
      obj += fmt::format("v {} {} {}\n", x[b][i & 1], y[b][(i >> 1) & 1], 0.1 * ((i >> 2) & 1));
    }
  }
  const int faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                            {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (int b = 0; b < 2; ++b) {
    for (const auto& f : faces) {
      obj += fmt::format("f {} {} {}\n", 8 * b + f[0] + 1, 8 * b + f[1] + 1, 8 * b + f[2] + 1);
    }
  }
  return obj;
}

TEST_F(ViewerTest, HotkeyFiveDrawsTheConvertedPropsParts) {
  setenv("URLAB_CACHE_DIR", (dir_ + "/cache").c_str(), 1);
  testing::WriteTextFile(dir_, "block.obj", LBlockObj());
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, true,
       "props:\n  - name: block\n    mesh: block.obj\n    pos: [-0.4, -0.3, 0]\n");
  unsetenv("URLAB_CACHE_DIR");
  const auto& props = manager_->session().props();
  ASSERT_EQ(props.size(), 1u);
  ASSERT_GE(props[0].part_geoms.size(), 1u);
  const Image plain = viewer_->ReadPixels();
  const mjtNum corner[3] = {-0.4, -0.3, 0.05}, mid[3] = {-0.25, -0.15, 0.05};
  const Pixel c = Project(core(), mid);
  const Pixel k = Project(core(), corner);
  const double radius = 2 * std::hypot(c.x - k.x, c.y - k.y);
  ASSERT_GT(radius, 5);
  // 3 (articulation collision wireframes) leaves the prop alone; 5 draws its parts there.
  Key(GLFW_KEY_3);
  const Image art_wire = viewer_->ReadPixels();
  Key(GLFW_KEY_3);
  Key(GLFW_KEY_5);
  EXPECT_TRUE(core().debug().Global(viewer::internal::DebugLayer::kPropCollision));
  const Image prop_wire = viewer_->ReadPixels();
  Key(GLFW_KEY_5);
  const Diff d = Compare(art_wire, prop_wire, c, radius);
  EXPECT_GT(d.inside, 10);
  const Diff only_prop = Compare(plain, prop_wire, c, radius);
  EXPECT_GT(only_prop.inside, 10);
  EXPECT_GT(only_prop.inside, 4 * only_prop.outside) << "the prop's wireframe drawn elsewhere";
}

TEST_F(ViewerTest, ContactForceArrowsPointAlongTheForce) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, /*paused=*/false);
  core().debug().Global(viewer::internal::DebugLayer::kContacts) = true;
  // Forces exist once the physics stepped; paused after, the captured contact stays the same.
  ASSERT_TRUE(TickUntil([&] { return core().frame()->time > 0.2; }));
  Key(GLFW_KEY_P);
  ASSERT_TRUE(TickUntil([&] { return core().frame()->paused; }));
  const std::uint64_t captures = core().capture().captures();
  ASSERT_TRUE(TickUntil([&] { return core().capture().captures() > captures; }));
  manager_->Tick();
  ASSERT_EQ(core().contacts().size(), 1u) << "the ball touches the floor at one point";
  const viewer::internal::CapturedContact c = core().contacts()[0];
  mjtNum force[3];
  mju_mulMatTVec(force, c.frame, c.force, 3, 3);
  const mjtNum magnitude = mju_norm3(force);
  ASSERT_GT(force[2], 0.9 * magnitude) << "the floor pushes the ball up";
  // The arrow's scale is MuJoCo's (vis.map.force per mean body mass): a scale too small for an
  // arrow leaves the contact point alone; one that makes it 0.8 m long draws it above the ball.
  mjModel* m = core().view().model();
  core().view().camera().distance *= 1.6;  // room above the ball
  m->vis.map.force = 1e-9f;
  const Image points = viewer_->ReadPixels();
  const mjtNum length = 0.8;
  m->vis.map.force = static_cast<float>(length * m->stat.meanmass / magnitude);
  const Image arrows = viewer_->ReadPixels();
  mjtNum tip[3];
  mju_addScl3(tip, c.pos, force, length / magnitude);
  const Pixel a = Project(core(), c.pos), b = Project(core(), tip);
  ASSERT_GT(std::hypot(b.x - a.x, b.y - a.y), 30) << "the arrow is long on screen";
  int near = 0, far = 0;
  for (int y = 0; y < arrows.height; ++y) {
    for (int x = 0; x < arrows.width; ++x) {
      int sum = 0;
      for (int k = 0; k < 3; ++k)
        sum += std::abs(int(points.at(x, y)[k]) - int(arrows.at(x, y)[k]));
      if (sum < 60) continue;
      (DistToSegment({double(x), double(y)}, a, b) < 12 ? near : far)++;
    }
  }
  EXPECT_GT(near, 50);
  EXPECT_GT(near, 4 * far) << "the arrow drawn away from the force's line";
  // Above the ball, along the force's line, the arrow's own colour (orange-red; the ball is
  // pure red and the stick blue): looked for in a few pixels around each point of the line.
  int orange = 0;
  for (mjtNum z = 0.22; z <= length; z += 0.02) {
    const mjtNum p[3] = {c.pos[0], c.pos[1], c.pos[2] + z};
    const Pixel u = Project(core(), p);
    bool found = false;
    for (int y = static_cast<int>(u.y) - 3; y <= static_cast<int>(u.y) + 3 && !found; ++y) {
      for (int x = static_cast<int>(u.x) - 3; x <= static_cast<int>(u.x) + 3 && !found; ++x) {
        if (x < 0 || y < 0 || x >= arrows.width || y >= arrows.height) continue;
        const std::uint8_t* px = arrows.at(x, y);
        const std::uint8_t* before = points.at(x, y);
        found = px[0] > 150 && px[1] > 30 && px[0] > px[1] + 60 && px[0] > px[2] + 60 &&
                (px[0] != before[0] || px[1] != before[1] || px[2] != before[2]);
      }
    }
    orange += found;
  }
  EXPECT_GE(orange, 2) << "no arrow colour above the ball";
}

TEST_F(ViewerTest, PanelSliderMovesTheActuator) {
  Play(kBotXml, {}, /*paused=*/false);
  manager_->Tick();
  viewer::internal::Panel* panel = core().panel();
  ASSERT_NE(panel, nullptr);
  ASSERT_EQ(panel->sliders().size(), 1u) << "one slider for the servo";
  const viewer::internal::Panel::SliderRect s = panel->sliders()[0];
  // Press on the slider at 90 % of its width, through ImGui's own input: the slider publishes
  // the value on the UI control source, and the servo carries the hinge there.
  const float x = s.x0 + 0.9f * (s.x1 - s.x0);
  using Mouse = viewer::internal::Window::InjectedMouse;
  core().window().InjectImGuiMouse(Mouse{x, s.y, false});
  manager_->Tick();
  core().window().InjectImGuiMouse(Mouse{x, s.y, true});
  manager_->Tick();
  manager_->Tick();
  core().window().InjectImGuiMouse(Mouse{x, s.y, false});
  manager_->Tick();
  core().window().InjectImGuiMouse(std::nullopt);
  control::ArticulationControl& ctl = *manager_->session().articulations()[0].control;
  const double target = ctl.GetTarget(control::ControlSource::kUi, 0);
  EXPECT_GT(target, 0.5);
  EXPECT_LE(target, 1.0);
  const int hinge = mj_name2id(core().view().model(), mjOBJ_JOINT, "bot_hinge");
  ASSERT_GE(hinge, 0);
  const int adr = core().view().model()->jnt_qposadr[hinge];
  // (The hinge's range is +-1 degree, a soft limit the servo presses into: it moves toward the
  // target, not to it.)
  EXPECT_TRUE(TickUntil([&] { return core().view().data()->qpos[adr] > 0.1; }))
      << "the hinge did not follow the slider: q=" << core().view().data()->qpos[adr];
  EXPECT_TRUE(TickUntil([&] { return std::abs(core().frame()->ctrl[0] - target) < 1e-9; }));
}

// The twist a `{art}/twist` message carries.
control::Twist DecodeTwist(const std::string& payload) {
  float v[3] = {0, 0, 0};
  if (payload.size() == sizeof v) std::memcpy(v, payload.data(), sizeof v);
  return {v[0], v[1], v[2]};
}

TEST_F(ViewerTest, PossessDrivesTheTwistTopicFromKeys) {
  net::NetworkOptions no;
  no.state = no.control = no.info = no.rpc = "tcp://127.0.0.1:*";
  auto network = std::make_unique<net::NetworkSubsystem>(no);
  net::NetworkSubsystem* net = network.get();
  more_.push_back(std::move(network));
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, /*paused=*/false,
       "    twist: {mode: hover, max_vx: 0.8, max_vy: 0.4, max_yaw_rate: 1.0}\n");
  zmq::context_t ctx;
  zmq::socket_t sub(ctx, zmq::socket_type::sub);
  sub.set(zmq::sockopt::subscribe, "bot/twist");
  sub.set(zmq::sockopt::subscribe, "bot/actions");
  sub.set(zmq::sockopt::rcvtimeo, 100);
  sub.connect(net->endpoints().state);
  // Receives until a message on `topic` satisfies `pred`, ticking the viewer meanwhile. The topics
  // come every physics step, far faster than a (software-rendered) tick: each tick drains all
  // that is queued, so the wait never falls behind a backlog of old messages.
  const auto receive = [&](const std::string& topic, const std::function<bool(std::string)>& pred) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < end) {
      manager_->Tick();
      for (bool first = true;; first = false) {
        std::vector<zmq::message_t> parts;
        const auto flags = first ? zmq::recv_flags::none : zmq::recv_flags::dontwait;
        if (!zmq::recv_multipart(sub, std::back_inserter(parts), flags)) break;
        if (parts.size() == 2 && parts[0].to_string() == topic && pred(parts[1].to_string())) {
          return true;
        }
      }
    }
    return false;
  };
  control::TwistController* twist = manager_->session().articulations()[0].control->twist();
  ASSERT_NE(twist, nullptr) << "a free base gets a twist controller";
  EXPECT_FALSE(twist->attached());
  EXPECT_EQ(twist->settings().max_vx, 0.8);

  Key(GLFW_KEY_TAB);
  ASSERT_TRUE(core().possession().active());
  EXPECT_TRUE(twist->attached());
  manager_->Tick();
  EXPECT_EQ(core().view().camera().type, mjCAMERA_TRACKING) << "the chase camera";
  EXPECT_EQ(core().view().camera().trackbodyid, Body("base"));
  const mjtNum start[3] = {BodyPos("base")[0], BodyPos("base")[1], BodyPos("base")[2]};

  // W forward, Q turn left, D right at once: clamped to the scene's maxima; digit 3 is action 3.
  Press(GLFW_KEY_W);
  Press(GLFW_KEY_Q);
  Press(GLFW_KEY_D);
  Press(GLFW_KEY_3);
  EXPECT_FALSE(core().debug().Global(viewer::internal::DebugLayer::kJoints))
      << "while possessed, digits are action keys";
  const control::Twist want{0.8, -0.4, 1.0};
  EXPECT_TRUE(receive("bot/twist", [&](const std::string& p) {
    const control::Twist t = DecodeTwist(p);
    return std::abs(t.vx - want.vx) < 1e-6 && std::abs(t.vy - want.vy) < 1e-6 &&
           std::abs(t.yaw_rate - want.yaw_rate) < 1e-6;
  })) << "the twist topic never carried the keys' twist";
  EXPECT_TRUE(receive("bot/actions", [](const std::string& p) {
    std::int32_t mask = 0;
    if (p.size() == sizeof mask) std::memcpy(&mask, p.data(), sizeof mask);
    return mask == (1 << 3);
  }));
  // The twist controller pushes the base.
  EXPECT_TRUE(TickUntil([&] {
    return std::hypot(BodyPos("base")[0] - start[0], BodyPos("base")[1] - start[1]) > 0.05;
  })) << "the base did not move";

  // Keys up: a zero twist; Tab releases (no more twist messages are published).
  for (int k : {GLFW_KEY_W, GLFW_KEY_Q, GLFW_KEY_D, GLFW_KEY_3}) Release(k);
  EXPECT_TRUE(receive("bot/twist",
                      [](const std::string& p) { return DecodeTwist(p) == control::Twist{}; }));
  Key(GLFW_KEY_TAB);
  EXPECT_FALSE(core().possession().active());
  EXPECT_FALSE(twist->attached());
  Key(GLFW_KEY_4);
  EXPECT_TRUE(core().debug().Global(viewer::internal::DebugLayer::kJoints)) << "hotkeys again";
}

TEST_F(ViewerTest, InputMappingDrivesTheActuatorFromKeys) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, /*paused=*/false,
       "    control_source: input\n    input:\n"
       "      - {actuator: servo, key: J, scale: 0.6}\n"
       "      - {actuator: servo, key: k, scale: -0.6}\n");
  control::ArticulationControl& ctl = *manager_->session().articulations()[0].control;
  const int hinge = mj_name2id(core().view().model(), mjOBJ_JOINT, "bot_hinge");
  const int adr = core().view().model()->jnt_qposadr[hinge];
  // The servo presses the hinge into its soft +-1 degree range, toward the target's side.
  const auto hinge_toward = [&](double q) {
    return TickUntil([&] { return core().view().data()->qpos[adr] * q > 0.1 * std::abs(q); });
  };
  Press(GLFW_KEY_J);
  manager_->Tick();
  EXPECT_DOUBLE_EQ(ctl.GetTarget(control::ControlSource::kInput, 0), 0.6);
  EXPECT_TRUE(hinge_toward(0.6)) << "J drives the servo toward 0.6";
  Press(GLFW_KEY_K);  // both held: they cancel
  manager_->Tick();
  EXPECT_DOUBLE_EQ(ctl.GetTarget(control::ControlSource::kInput, 0), 0.0);
  Release(GLFW_KEY_J);
  manager_->Tick();
  EXPECT_DOUBLE_EQ(ctl.GetTarget(control::ControlSource::kInput, 0), -0.6);
  EXPECT_TRUE(hinge_toward(-0.6));
  Release(GLFW_KEY_K);
  manager_->Tick();
  EXPECT_DOUBLE_EQ(ctl.GetTarget(control::ControlSource::kInput, 0), 0.0);
  // A mapped key is consumed: mapping R would not reset; here unmapped hotkeys still work.
  Key(GLFW_KEY_4);
  EXPECT_TRUE(core().debug().Global(viewer::internal::DebugLayer::kJoints));
}

TEST_F(ViewerTest, InputMappingErrorsNameTheBinding) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  testing::WriteTextFile(dir_, "bot.xml", kBotXml);
  for (const auto& [binding, message] :
       {std::pair<std::string, std::string>{"{actuator: servo, key: Hyper}", "unknown key 'Hyper'"},
        {"{actuator: nope, key: J}", "no actuator 'nope'"}}) {
    world::Manager manager;
    auto v = std::make_unique<viewer::ViewerSubsystem>(vo);
    manager.AddSubsystem(std::move(v));
    try {  // an unknown key is refused when the scene is read, a wrong actuator when it is built
      const world::SceneConfig scene = world::ParseScene(
          "articulations:\n  - name: bot\n    mjcf: bot.xml\n    input:\n      - " + binding + "\n",
          dir_ + "/scene.yaml");
      manager.BeginPlay(scene);
      ADD_FAILURE() << "accepted " << binding;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().line, 5) << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST_F(ViewerTest, OCyclesOrbitAndKeyframeCameras) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  // The path looks at the ball from two sides (the ball rests at 0.5 0.4 0.1).
  Play(kBotXml, vo, true,
       "cinematic:\n  orbit_period: 8\n  path:\n"
       "    - {t: 0, pos: [2.5, 0.4, 1.0], look_at: [0.5, 0.4, 0.1]}\n"
       "    - {t: 10, pos: [0.5, 2.4, 1.0], look_at: [0.5, 0.4, 0.1]}\n");
  using viewer::internal::CinematicMode;
  const mjtNum* ball = BodyPos("base");
  int w = 0, h = 0;
  core().window().FramebufferSize(&w, &h);
  // O: the orbit camera looks at the robot's root body.
  Key(GLFW_KEY_O);
  EXPECT_EQ(core().cinematic().mode(), CinematicMode::kOrbit);
  viewer_->ReadPixels();  // draws a frame
  const mjvCamera& cam = core().view().camera();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(cam.lookat[c], ball[c], 1e-9);
  // O again: the keyframe path; at t=0 the camera is at the first key, the ball in the middle
  // of the image and drawn there (red).
  Key(GLFW_KEY_O);
  EXPECT_EQ(core().cinematic().mode(), CinematicMode::kPath);
  const Image path = viewer_->ReadPixels();
  EXPECT_NEAR(cam.distance, std::sqrt(2.0 * 2.0 + 0.9 * 0.9), 1e-6);
  EXPECT_NEAR(std::abs(cam.azimuth), 180, 1e-6);  // looking from +x along -x at the ball
  EXPECT_LT(cam.elevation, 0);                    // and down
  const Pixel p = Project(core(), ball);
  EXPECT_NEAR(p.x, w / 2.0, 3);
  EXPECT_NEAR(p.y, h / 2.0, 3);
  const auto* centre = path.at(w / 2, h / 2);
  EXPECT_GT(centre[0], 2 * centre[2]) << "the red ball at the image centre";
  // O again: off, the free camera keeps the last shot.
  Key(GLFW_KEY_O);
  EXPECT_EQ(core().cinematic().mode(), CinematicMode::kOff);
  EXPECT_EQ(cam.type, mjCAMERA_FREE);
}

TEST_F(ViewerTest, KeysPauseResetAndScreenshot) {
  Play(kBotXml, {}, /*paused=*/false);
  ASSERT_TRUE(TickUntil([&] { return core().frame()->time > 0.1; }));
  Key(GLFW_KEY_P);
  EXPECT_TRUE(engine().paused());
  ASSERT_TRUE(TickUntil([&] { return core().frame()->paused; }));
  const double t = core().frame()->time;
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  manager_->Tick();
  EXPECT_EQ(core().frame()->time, t) << "paused";
  Key(GLFW_KEY_R);
  EXPECT_TRUE(TickUntil([&] { return core().frame()->time < t; })) << "reset to the start";
  Key(GLFW_KEY_P);
  EXPECT_FALSE(engine().paused());
  // F12 writes a PNG of the window (here with the name the test asks for).
  const std::string shot = dir_ + "/shot.png";
  core().RequestScreenshot(shot);
  manager_->Tick();
  ASSERT_TRUE(std::filesystem::exists(shot));
  const Image png = viewer::internal::ReadImage(shot);
  EXPECT_EQ(png.width, 640);
  EXPECT_EQ(png.height, 480);
}

TEST_F(ViewerTest, HotkeyFFiresTheLaunchers) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, /*paused=*/false,
       "launchers:\n  - name: gun\n    pos: [-0.5, -0.5, 0.5]\n    speed: 3\n    pool: 2\n");
  ASSERT_EQ(manager_->session().launchers().size(), 1u);
  const world::LauncherLayout& l = manager_->session().launchers()[0];
  const int first = l.bodies[0], second = l.bodies[1];
  const mjtNum* xpos = core().view().data()->xpos;
  ASSERT_TRUE(TickUntil([&] { return core().frame()->time > 0.05; }));
  const double parked_y = xpos[3 * first + 1];
  EXPECT_LT(xpos[3 * first], l.muzzle[0]) << "parked on the tray, behind the muzzle";
  Key(GLFW_KEY_F);
  // The viewer's copy shows the first projectile leave the tray along +x; the second stays.
  EXPECT_TRUE(TickUntil([&] { return xpos[3 * first] > l.muzzle[0] + 0.3; }))
      << "x " << xpos[3 * first];
  EXPECT_NEAR(xpos[3 * first + 1], -0.5, 0.02) << "along the launcher's +x only";
  EXPECT_NE(xpos[3 * first + 1], parked_y);
  EXPECT_LT(xpos[3 * second], l.muzzle[0]);
  Key(GLFW_KEY_F);
  EXPECT_TRUE(TickUntil([&] { return xpos[3 * second] > l.muzzle[0] + 0.3; }));
}

TEST_F(ViewerTest, PanelFireButtonLaunches) {
  Play(kBotXml, {}, /*paused=*/false,
       "launchers:\n  - name: gun\n    pos: [-0.5, -0.5, 0.5]\n    speed: 3\n    pool: 1\n");
  manager_->Tick();
  viewer::internal::Panel* panel = core().panel();
  ASSERT_NE(panel, nullptr);
  ASSERT_EQ(panel->fire_buttons().size(), 1u);
  const viewer::internal::Panel::Point b = panel->fire_buttons()[0];
  const world::LauncherLayout& l = manager_->session().launchers()[0];
  const mjtNum* xpos = core().view().data()->xpos;
  EXPECT_LT(xpos[3 * l.bodies[0]], l.muzzle[0]);
  // A click through ImGui's own input: press, then release on the button.
  using Mouse = viewer::internal::Window::InjectedMouse;
  core().window().InjectImGuiMouse(Mouse{b.x, b.y, false});
  manager_->Tick();
  core().window().InjectImGuiMouse(Mouse{b.x, b.y, true});
  manager_->Tick();
  core().window().InjectImGuiMouse(Mouse{b.x, b.y, false});
  manager_->Tick();
  core().window().InjectImGuiMouse(std::nullopt);
  EXPECT_TRUE(TickUntil([&] { return xpos[3 * l.bodies[0]] > l.muzzle[0] + 0.3; }))
      << "x " << xpos[3 * l.bodies[0]];
}

TEST_F(ViewerTest, MouseRotatesSelectsAndPerturbs) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kFloatXml, vo, /*paused=*/false);
  manager_->Tick();
  // Left drag rotates the camera.
  const double azimuth = core().view().camera().azimuth;
  core().OnCursor(300, 200);
  core().OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, GLFW_PRESS, 0);
  core().OnCursor(400, 200);
  core().OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, GLFW_RELEASE, 0);
  EXPECT_NE(core().view().camera().azimuth, azimuth);
  manager_->Tick();
  // Double-click on the box selects it.
  const mjtNum start[3] = {BodyPos("box")[0], BodyPos("box")[1], BodyPos("box")[2]};
  const Pixel p = Project(core(), start);
  int ww = 0, wh = 0, fw = 0, fh = 0;
  core().WindowSize(&ww, &wh);
  core().window().FramebufferSize(&fw, &fh);
  const double sx = p.x * ww / fw, sy = p.y * wh / fh;  // window coordinates
  core().OnCursor(sx, sy);
  for (int i = 0; i < 2; ++i) {
    core().OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, GLFW_PRESS, 0);
    core().OnMouseButton(GLFW_MOUSE_BUTTON_LEFT, GLFW_RELEASE, 0);
  }
  ASSERT_EQ(core().view().perturb().select, Body("box"));
  // Ctrl + right drag pulls it: the physics thread moves the body.
  core().OnMouseButton(GLFW_MOUSE_BUTTON_RIGHT, GLFW_PRESS, GLFW_MOD_CONTROL);
  EXPECT_EQ(core().view().perturb().active, mjPERT_TRANSLATE);
  core().OnCursor(sx + 120, sy);
  EXPECT_TRUE(TickUntil([&] { return mju_dist3(BodyPos("box"), start) > 0.05; }))
      << "the perturbation force did not move the box";
  core().OnMouseButton(GLFW_MOUSE_BUTTON_RIGHT, GLFW_RELEASE, GLFW_MOD_CONTROL);
  EXPECT_EQ(core().view().perturb().active, 0);
}

// ---- What MuJoCo's simulate offers ----

// The bot with a model camera looking down at it and a keyframe.
std::string BotWithCameraAndKey() {
  std::string xml = kBotXml;
  xml.replace(xml.find("  <worldbody>\n"), 14,
              "  <worldbody>\n    <camera name=\"top\" pos=\"0.5 0.4 4\"/>\n");
  xml.replace(
      xml.find("</mujoco>"), 9,
      "<keyframe><key name=\"up\" qpos=\"0.5 0.4 0.5 1 0 0 0 0.3\"/></keyframe>\n</mujoco>");
  return xml;
}

TEST_F(ViewerTest, PossessIsNotOfferedForAPropWithoutActuators) {
  // A free box without actuators: it has a twist controller (a free base) but nothing drives
  // it unless hover pushes the base.
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kFloatXml, vo);
  ASSERT_NE(manager_->session().articulations()[0].control->twist(), nullptr);
  Key(GLFW_KEY_TAB);
  EXPECT_FALSE(core().possession().active());
  EXPECT_NE(core().status().find("nothing to possess"), std::string::npos) << core().status();
  manager_.reset();
  Play(kFloatXml, vo, true, "    twist: {mode: hover}\n");
  Key(GLFW_KEY_TAB);
  EXPECT_TRUE(core().possession().active()) << core().status();
  Key(GLFW_KEY_TAB);
}

TEST_F(ViewerTest, RightStepsExactlyOneStepWhilePaused) {
  Play(kBotXml);
  ASSERT_TRUE(engine().paused());
  const std::uint64_t s0 = engine().step_count();
  Key(GLFW_KEY_RIGHT);
  ASSERT_TRUE(TickUntil([&] { return core().frame()->step == s0 + 1; }));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  manager_->Tick();
  EXPECT_EQ(engine().step_count(), s0 + 1) << "exactly one step";
  Key(GLFW_KEY_RIGHT);
  Key(GLFW_KEY_RIGHT);
  ASSERT_TRUE(TickUntil([&] { return core().frame()->step == s0 + 3; }));
  EXPECT_EQ(engine().step_count(), s0 + 3);
  // While running, Right does not step (and says so).
  Key(GLFW_KEY_P);
  ASSERT_FALSE(engine().paused());
  Key(GLFW_KEY_RIGHT);
  EXPECT_NE(core().status().find("while paused"), std::string::npos) << core().status();
}

TEST_F(ViewerTest, CameraListSwitchesToTheModelsCameras) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  const std::string xml = BotWithCameraAndKey();
  Play(xml.c_str(), vo);
  EXPECT_EQ(core().camera(), -1);
  const Image free_view = viewer_->ReadPixels();
  Key(GLFW_KEY_RIGHT_BRACKET);
  EXPECT_EQ(core().camera(), 0);
  EXPECT_EQ(core().view().camera().type, mjCAMERA_FIXED);
  EXPECT_EQ(core().view().camera().fixedcamid, 0);
  const Image top = viewer_->ReadPixels();
  // Looking straight down on the bot: the ball (or its stick, pointing up) at the centre.
  const std::uint8_t* c = top.at(top.width / 2, top.height / 2);
  const bool red_ball = c[0] > 120 && c[2]<80, blue_stick = c[2]> 120 && c[0] < 80;
  EXPECT_TRUE(red_ball || blue_stick)
      << "the bot at the image centre: " << int(c[0]) << " " << int(c[1]) << " " << int(c[2]);
  EXPECT_GT(Compare(free_view, top, {0, 0}, 0).outside, 1000) << "a different view";
  Key(GLFW_KEY_RIGHT_BRACKET);  // past the last camera: the free camera again
  EXPECT_EQ(core().camera(), -1);
  EXPECT_EQ(core().view().camera().type, mjCAMERA_FREE);
  Key(GLFW_KEY_LEFT_BRACKET);  // backwards: the last camera
  EXPECT_EQ(core().camera(), 0);
  Key(GLFW_KEY_ESCAPE);
  EXPECT_EQ(core().camera(), -1);
}

TEST_F(ViewerTest, FlagsAndGroupsReachTheModelAndTheRenderOptions) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, /*paused=*/false);
  // Physics flags: a SetOptions command reaches the engine's model (and the viewer's copy).
  const mjtNum* ball = BodyPos("base");
  // (MuJoCo's flag enums are masks; the panel's items are bit indices.)
  const auto bit = [](int mask) { return __builtin_ctz(static_cast<unsigned>(mask)); };
  core().SetDisableFlag(bit(mjDSBL_GRAVITY), true);
  core().SetDisableFlag(bit(mjDSBL_CONTACT), true);
  int flags = 0;
  ASSERT_TRUE(TickUntil([&] {
    engine().WithLockedData([&](mjModel* m, mjData*) { flags = m->opt.disableflags; });
    return flags == (mjDSBL_GRAVITY | mjDSBL_CONTACT);
  })) << flags;
  EXPECT_EQ(core().view().model()->opt.disableflags, mjDSBL_GRAVITY | mjDSBL_CONTACT);
  // Without gravity and contacts the ball floats where it is.
  const double z = ball[2];
  ASSERT_TRUE(TickUntil([&] { return core().frame()->time > 0.3; }));
  EXPECT_NEAR(ball[2], z, 0.02);
  core().SetDisableFlag(bit(mjDSBL_GRAVITY), false);
  core().SetDisableFlag(bit(mjDSBL_CONTACT), false);
  core().SetEnableFlag(bit(mjENBL_ENERGY), true);
  ASSERT_TRUE(TickUntil([&] {
    engine().WithLockedData([&](mjModel* m, mjData*) { flags = m->opt.enableflags; });
    return flags == mjENBL_ENERGY;
  }));
  // Options (tolerance, gravity, wind) the panel sets go the same way.
  core().SetOptions(
      [](mjOption& o) {
        o.tolerance = 1e-6;
        o.wind[0] = 2;
        o.gravity[2] = -5;
      },
      "test");
  mjOption opt{};
  ASSERT_TRUE(TickUntil([&] {
    engine().WithLockedData([&](mjModel* m, mjData*) { opt = m->opt; });
    return opt.wind[0] == 2;
  }));
  EXPECT_EQ(opt.tolerance, 1e-6);
  EXPECT_EQ(opt.gravity[2], -5);
  // Visualisation flags by their simulate letters (Shift+I: inertia boxes), drawn.
  const Image plain = viewer_->ReadPixels();
  EXPECT_FALSE(core().view().option().flags[mjVIS_INERTIA]);
  Key(GLFW_KEY_I, GLFW_MOD_SHIFT);
  EXPECT_TRUE(core().view().option().flags[mjVIS_INERTIA]);
  Key(GLFW_KEY_P);
  ASSERT_TRUE(TickUntil([&] { return core().frame()->paused; }));
  const Image still = viewer_->ReadPixels();
  Key(GLFW_KEY_I, GLFW_MOD_SHIFT);
  const Image without = viewer_->ReadPixels();
  EXPECT_GT(Compare(without, still, {0, 0}, 0).outside, 50) << "inertia boxes drawn";
  (void)plain;
  // Geom groups: Alt+0 hides group 0 (every geom of the bot): the ball is gone.
  Key(GLFW_KEY_0, GLFW_MOD_ALT);
  EXPECT_FALSE(core().view().option().geomgroup[0]);
  const Image hidden = viewer_->ReadPixels();
  const Pixel p = Project(core(), ball);
  const std::uint8_t* c = hidden.at(static_cast<int>(p.x), static_cast<int>(p.y));
  EXPECT_FALSE(c[0] > 120 && c[1] < 80 && c[2] < 80) << "the ball still drawn";
  Key(GLFW_KEY_0, GLFW_MOD_ALT);
  EXPECT_TRUE(core().view().option().geomgroup[0]);
  Key(GLFW_KEY_0, GLFW_MOD_ALT | GLFW_MOD_SHIFT);
  EXPECT_FALSE(core().view().option().sitegroup[0]);
}

TEST_F(ViewerTest, PlotsAccumulateSamplesOfChosenSignals) {
  Play(kBotXml, {}, /*paused=*/false);
  viewer::internal::Plots& plots = core().plots();
  int hinge = -1, force = -1, sensor = -1;
  for (int i = 0; i < static_cast<int>(plots.available().size()); ++i) {
    const auto& sig = plots.available()[static_cast<std::size_t>(i)];
    if (sig.name == "bot_hinge") hinge = i;
    if (sig.name == "bot_servo force") force = i;
    if (sig.kind == viewer::internal::SignalKind::kSensor) sensor = i;
  }
  ASSERT_GE(hinge, 0);
  ASSERT_GE(force, 0);
  EXPECT_EQ(sensor, -1) << "the bot has no sensors";
  EXPECT_TRUE(plots.Choose(hinge, true));
  EXPECT_TRUE(plots.Choose(force, true));
  Key(GLFW_KEY_F4);
  EXPECT_TRUE(core().overlays().plots);
  ASSERT_TRUE(TickUntil([&] { return plots.points() >= 10; })) << plots.points();
  // The newest sample is the newest frame's value.
  const int adr = core().view().model()->jnt_qposadr[mj_name2id(core().view().model(), mjOBJ_JOINT,
                                                                "bot_hinge")];
  EXPECT_FLOAT_EQ(plots.last(0), static_cast<float>(core().frame()->qpos[adr]));
  EXPECT_FLOAT_EQ(plots.last(1), static_cast<float>(core().frame()->actuator_force[0]));
  // Drawn: the plot's corner of the viewport changes.
  const Image with = viewer_->ReadPixels();
  Key(GLFW_KEY_F4);
  const Image without = viewer_->ReadPixels();
  EXPECT_GT(Compare(with, without, {620, 460}, 100).inside, 500);
  // A reset starts the plot again.
  const int before = plots.points();
  Key(GLFW_KEY_R);
  EXPECT_TRUE(TickUntil([&] { return plots.points() < before; }));
}

TEST_F(ViewerTest, SavesMjbXmlAndPrintsModelAndData) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  vo.files_dir = dir_;
  Play(kBotXml, vo);
  Key(GLFW_KEY_S, GLFW_MOD_CONTROL | GLFW_MOD_SHIFT);
  const std::string mjb = dir_ + "/urlab_scene.mjb";
  ASSERT_TRUE(std::filesystem::exists(mjb)) << core().status();
  const physics::Model running = engine().CopyModel();
  const std::string bytes = testing::ReadTextFile(mjb);
  const physics::ModelPtr loaded = physics::LoadMjbBytes(bytes);
  ASSERT_TRUE(loaded);
  EXPECT_EQ(physics::ContentHash(physics::MjbBytes(loaded.get())), running.Hash())
      << "the saved MJB loads as the same model";
  // An option changed at run time (gravity off, as the panel's physics flags do) is saved too.
  core().SetDisableFlag(std::countr_zero(static_cast<unsigned>(mjDSBL_GRAVITY)), true);
  ASSERT_TRUE(TickUntil([&] { return engine().CopyModel()->opt.disableflags & mjDSBL_GRAVITY; }));
  Key(GLFW_KEY_S, GLFW_MOD_CONTROL);
  const std::string xml = dir_ + "/urlab_scene.xml";
  ASSERT_TRUE(std::filesystem::exists(xml));
  EXPECT_NE(core().status().find("flag.gravity"), std::string::npos) << core().status();
  char error[500] = "";
  mjModel* m = mj_loadXML(xml.c_str(), nullptr, error, sizeof error);
  ASSERT_NE(m, nullptr) << error;
  EXPECT_EQ(m->nq, running->nq);
  EXPECT_EQ(m->nbody, running->nbody);
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_GRAVITY);
  mj_deleteModel(m);
  Key(GLFW_KEY_M, GLFW_MOD_CONTROL);
  Key(GLFW_KEY_D, GLFW_MOD_CONTROL);
  const std::string model_txt = testing::ReadTextFile(dir_ + "/urlab_model.txt");
  const std::string data_txt = testing::ReadTextFile(dir_ + "/urlab_data.txt");
  EXPECT_NE(model_txt.find("nq"), std::string::npos);
  EXPECT_NE(data_txt.find("QPOS"), std::string::npos);
  EXPECT_NE(core().status().find("urlab_data.txt"), std::string::npos) << core().status();
}

TEST_F(ViewerTest, KeysCopyPoseAndReload) {
  viewer::ViewerOptions vo;
  vo.panel = false;
  const std::string xml = BotWithCameraAndKey();
  Play(xml.c_str(), vo);
  const mjModel* m = core().view().model();
  ASSERT_EQ(m->nkey, 1);
  // Load key: the keyframe's pose reaches the simulation (the stick at 0.3 rad).
  const int hinge = m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "bot_hinge")];
  Key(GLFW_KEY_K, GLFW_MOD_CONTROL);
  ASSERT_TRUE(TickUntil([&] { return std::abs(core().frame()->qpos[hinge] - 0.3) < 1e-12; }));
  EXPECT_NEAR(core().frame()->qpos[2], 0.5, 1e-12);
  // Save key stores the current state; after a reset Load key brings it back.
  Key(GLFW_KEY_K, GLFW_MOD_CONTROL | GLFW_MOD_SHIFT);
  Key(GLFW_KEY_R);
  ASSERT_TRUE(TickUntil([&] { return std::abs(core().frame()->qpos[hinge] - 0.3) > 0.1; }));
  Key(GLFW_KEY_K, GLFW_MOD_CONTROL);
  EXPECT_TRUE(TickUntil([&] { return std::abs(core().frame()->qpos[hinge] - 0.3) < 1e-12; }));
  // Copy pose: a <key> with every qpos value, on the clipboard.
  Key(GLFW_KEY_C, GLFW_MOD_CONTROL);
  const std::string clip = core().window().Clipboard();
  EXPECT_EQ(clip.rfind("<key time=", 0), 0u) << clip;
  EXPECT_NE(clip.find("qpos=\"0.5 0.4 0.5 1 0 0 0 0.3\""), std::string::npos) << clip;
  // Reload (Ctrl+L) ends play for the host to open the scene again; a dropped file likewise.
  EXPECT_FALSE(core().stop_requested());
  core().OnDrop({dir_ + "/notes.txt"});
  EXPECT_FALSE(core().stop_requested());
  EXPECT_NE(core().status().find("cannot open"), std::string::npos);
  Key(GLFW_KEY_L, GLFW_MOD_CONTROL);
  EXPECT_EQ(core().reload_request(), dir_ + "/scene.yaml");
  EXPECT_TRUE(core().stop_requested());
  EXPECT_TRUE(manager_->StopRequested());
  // A dropped recording is opened too (the host plays it with the replay timeline).
  core().OnDrop({dir_ + "/run.urrec"});
  EXPECT_EQ(core().reload_request(), dir_ + "/run.urrec");
}

TEST_F(ViewerTest, HelpInfoAndProfilerOverlays) {
  Play(kBotXml, {}, /*paused=*/false);
  const Image plain = viewer_->ReadPixels();
  Key(GLFW_KEY_F1);
  EXPECT_TRUE(core().overlays().help);
  const Image help = viewer_->ReadPixels();
  const viewer::internal::WindowRect vp = core().ViewportRect();
  // The help's key column at the viewport's top left.
  EXPECT_GT(Compare(plain, help, {vp.x + 60, 60}, 60).inside, 300);
  Key(GLFW_KEY_F1);
  EXPECT_FALSE(core().overlays().help);
  // F2 and F3: the physics thread's timings and sizes arrive (Inspect commands).
  Key(GLFW_KEY_F2);
  Key(GLFW_KEY_F3);
  EXPECT_TRUE(TickUntil([&] { return core().profiler().samples() >= 3; }));
  const std::optional<viewer::internal::ProfileSample> p = core().profiler().Latest();
  ASSERT_TRUE(p.has_value());
  EXPECT_GE(p->ncon, 1) << "the ball rests on the floor";
  EXPECT_TRUE(TickUntil([&] {
    const auto q = core().profiler().Latest();
    return q && q->step_ms > 0;
  })) << "MuJoCo's timers run";
}

}  // namespace
}  // namespace urlab

// ---- Replay mode: the timeline ----

namespace urlab {
namespace {

// A recording of the bot on the session's own model: 900 steps, a keyframe every 300, and a
// reset back to the initial state after step 450 (as the recorder writes one).
std::string WriteBotRecording(physics::PhysicsEngine& engine, const std::string& path) {
  const physics::Model model = engine.CopyModel();
  const mjModel* m = model.get();
  replay::RecordingInfo info;
  info.tables = replay::ModelTables::Of(m, {"bot"});
  replay::DescribeModel(model, &info);
  physics::DataPtr data = physics::MakeData(m);
  mjData* d = data.get();
  mj_forward(m, d);
  auto take = [](const double* v, int n) { return std::vector<double>(v, v + n); };
  std::vector<std::vector<replay::Record>> chunks;
  for (int n = 0; n < 900; ++n) {
    if (n % 300 == 0) {
      chunks.emplace_back();
      chunks.back().push_back(replay::StateRecord{0, physics::CaptureState(m, d)});
    }
    if (n == 450) {
      mj_resetData(m, d);
      mj_forward(m, d);
      chunks.back().push_back(replay::Marker{physics::kDiscontinuityReset, d->time, 450, "reset"});
      chunks.back().push_back(
          replay::StateRecord{physics::kDiscontinuityReset, physics::CaptureState(m, d)});
    }
    d->ctrl[0] = 0.5;
    mj_step(m, d);
    replay::Frame f;
    f.time = d->time;
    f.step = static_cast<std::uint64_t>(n + 1);
    f.qpos = take(d->qpos, m->nq);
    f.qvel = take(d->qvel, m->nv);
    f.act = take(d->act, m->na);
    f.ctrl = take(d->ctrl, m->nu);
    f.mocap_pos = take(d->mocap_pos, 3 * m->nmocap);
    f.mocap_quat = take(d->mocap_quat, 4 * m->nmocap);
    f.qfrc_applied = take(d->qfrc_applied, m->nv);
    f.xfrc_applied = take(d->xfrc_applied, 6 * m->nbody);
    chunks.back().push_back(std::move(f));
  }
  replay::WriteRecording(path, info, chunks);
  return path;
}

TEST_F(ViewerTest, ReplayTimelineDrivesThePlayerAndShowsItsFrames) {
  const auto slot = std::make_shared<replay::PlaybackSlot>();
  viewer::ViewerOptions vo;
  // The slot goes to the viewer the way the app hands it over, before play.
  {
    testing::WriteTextFile(dir_, "bot.xml", kBotXml);
    const world::SceneConfig scene = world::ParseScene(
        "control_source: ui\narticulations:\n  - name: bot\n    mjcf: bot.xml\n"
        "    controller: {type: passthrough}\n",
        dir_ + "/scene.yaml");
    manager_ = std::make_unique<world::Manager>();
    vo.width = 640;
    vo.height = 480;
    auto v = std::make_unique<viewer::ViewerSubsystem>(vo);
    v->SetManager(manager_.get());
    v->SetPlayback(slot);
    viewer_ = v.get();
    manager_->AddSubsystem(std::move(v));
    manager_->BeginPlay(scene);
  }
  EXPECT_FALSE(core().replay_mode());
  EXPECT_FALSE(core().PerformTimeline(viewer::internal::TimelineAction::kPlayPause));
  const replay::RecordingReader reader =
      replay::RecordingReader::Open(WriteBotRecording(engine(), dir_ + "/bot.urrec"));
  const std::vector<replay::Record> all = replay::ReadAllRecords(reader);
  std::vector<const replay::Frame*> frames;
  for (const replay::Record& r : all) {
    if (const auto* f = std::get_if<replay::Frame>(&r)) frames.push_back(f);
  }
  ASSERT_EQ(frames.size(), 900u);
  replay::PlayerOptions po;
  po.start_paused = true;
  replay::Player player(engine(), reader, po);
  replay::Playback shown;
  shown.player = &player;
  shown.reader = &reader;
  shown.marks = replay::ScanTimeline(reader);
  shown.label = "bot.urrec";
  shown.mode = "kinematic";
  ASSERT_EQ(shown.marks.keyframes.size(), 3u);
  ASSERT_EQ(shown.marks.jumps.size(), 1u);
  EXPECT_EQ(shown.marks.jumps[0].frame, 450u);
  EXPECT_EQ(core().HelpText().first.find("PgUp"), std::string::npos);
  slot->Set(&shown);
  ASSERT_TRUE(core().replay_mode());
  // The help overlay (F1) lists the timeline's keys while a replay plays.
  EXPECT_EQ(core().HelpText().first.rfind("Space\nLeft\nRight\n", 0), 0u)
      << core().HelpText().first;
  EXPECT_NE(core().HelpText().first.find("PgUp"), std::string::npos);

  using viewer::internal::TimelineAction;
  // The viewer shows the frame the player shows: its qpos, bit for bit (kinematic playback).
  auto shows = [&](std::size_t index) {
    return TickUntil([&] {
      const replay::PlayerStatus st = player.status();
      const physics::StateFrame* f = core().frame();
      return st.frame == index && !st.playing && f && f->qpos == frames[index]->qpos;
    });
  };
  Key(GLFW_KEY_RIGHT);  // one step on, paused
  EXPECT_TRUE(shows(1)) << player.status().frame;
  Key(GLFW_KEY_RIGHT);
  EXPECT_TRUE(shows(2));
  Key(GLFW_KEY_LEFT);
  EXPECT_TRUE(shows(1));
  Key(GLFW_KEY_PAGE_DOWN);  // next keyframe: the second chunk starts at frame 300
  EXPECT_TRUE(TickUntil([&] { return player.status().frame == 300; })) << player.status().frame;
  Key(GLFW_KEY_RIGHT_BRACKET);  // next reset: frame 450, time back near 0
  EXPECT_TRUE(shows(450)) << player.status().frame;
  EXPECT_LT(player.status().time, 0.01);
  Key(GLFW_KEY_PAGE_UP);  // previous keyframe
  EXPECT_TRUE(TickUntil([&] { return player.status().frame == 300; }));
  Key(GLFW_KEY_END);
  EXPECT_TRUE(shows(899));
  Key(GLFW_KEY_HOME);
  EXPECT_TRUE(TickUntil([&] { return player.status().frame == 0; }));
  Key(GLFW_KEY_UP);
  EXPECT_EQ(player.status().speed, 2.0);
  Key(GLFW_KEY_DOWN);
  Key(GLFW_KEY_DOWN);
  EXPECT_EQ(player.status().speed, 0.5);
  Key(GLFW_KEY_L);
  EXPECT_TRUE(player.status().loop);
  Key(GLFW_KEY_SPACE);  // play: frames advance
  EXPECT_TRUE(TickUntil([&] { return player.status().playing && player.status().frame > 5; }));
  Key(GLFW_KEY_P);  // P pauses the replay, not the engine
  EXPECT_TRUE(TickUntil([&] { return !player.status().playing; }));
  EXPECT_FALSE(engine().paused());
  // The timeline is drawn at the bottom of the window (right of the panel).
  const Image with = viewer_->ReadPixels();
  slot->Set(nullptr);
  EXPECT_FALSE(core().replay_mode());
  const Image without = viewer_->ReadPixels();
  const int panel_w = static_cast<int>(core().ViewportRect().x);
  const int strip = static_cast<int>(viewer::internal::Timeline::kHeight);
  int changed = 0;
  for (int y = with.height - strip + 4; y < with.height - 4; ++y) {
    for (int x = panel_w + 4; x < with.width - 4; ++x) {
      int sum = 0;
      for (int c = 0; c < 3; ++c) sum += std::abs(int(with.at(x, y)[c]) - int(without.at(x, y)[c]));
      if (sum > 60) ++changed;
    }
  }
  EXPECT_GT(changed, 500) << "no timeline drawn";
}

TEST_F(ViewerTest, StepServerReplayShowsOnTheTimelineAndTheTimelineDrivesIt) {
  playback_ = std::make_shared<replay::PlaybackSlot>();
  net::NetworkOptions no;
  no.state = no.control = no.info = no.rpc = "tcp://127.0.0.1:*";
  no.files_dir = dir_;  // clients name files in the test's folder
  auto network = std::make_unique<net::NetworkSubsystem>(no);
  net::NetworkSubsystem* net = network.get();
  network->SetPlayback(playback_);
  more_.push_back(std::move(network));
  viewer::ViewerOptions vo;
  vo.panel = false;
  Play(kBotXml, vo, /*paused=*/false);
  const std::string path = WriteBotRecording(engine(), dir_ + "/bot.urrec");
  const replay::RecordingReader reader = replay::RecordingReader::Open(path);
  const std::vector<replay::Record> all = replay::ReadAllRecords(reader);
  std::vector<const replay::Frame*> frames;
  for (const replay::Record& r : all) {
    if (const auto* f = std::get_if<replay::Frame>(&r)) frames.push_back(f);
  }
  zmq::context_t ctx;
  net::test_client::Client client(ctx, net->endpoints().rpc);
  client.Hello();
  ASSERT_EQ(client.Op("replay_load", {{"path", "bot.urrec"}})["op"], "replay_load_ok");
  EXPECT_FALSE(core().replay_mode());
  ASSERT_EQ(client.Op("replay_start", {{"mode", "kinematic"}})["op"], "replay_start_ok");
  ASSERT_TRUE(TickUntil([&] { return core().replay_mode(); }));
  // The viewer's keys act on the step server's player; replay_status reports it.
  Key(GLFW_KEY_SPACE);
  net::test_client::Json st = client.Op("replay_status");
  EXPECT_EQ(st["playing"], false) << st.dump();
  Key(GLFW_KEY_HOME);
  Key(GLFW_KEY_PAGE_DOWN);  // the second keyframe: frame 300
  ASSERT_TRUE(TickUntil([&] {
    st = client.Op("replay_status");
    const physics::StateFrame* f = core().frame();
    return st["frame"] == 300 && f && f->qpos == frames[300]->qpos;
  })) << st.dump();
  EXPECT_EQ(st["playing"], false);
  Key(GLFW_KEY_RIGHT);
  ASSERT_TRUE(TickUntil([&] { return client.Op("replay_status")["frame"] == 301; }));
  ASSERT_EQ(client.Op("replay_stop")["op"], "replay_stop_ok");
  EXPECT_TRUE(TickUntil([&] { return !core().replay_mode(); }));
  EXPECT_FALSE(core().PerformTimeline(viewer::internal::TimelineAction::kPlayPause));
}

}  // namespace
}  // namespace urlab
