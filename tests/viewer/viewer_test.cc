// The viewer on a real display (CI runs these under xvfb-run with Mesa's software renderer):
// a Manager with the ViewerSubsystem plays a scene, the test reads the window's pixels and checks
// where things are drawn, injects key and mouse events through the window's input handler, and
// checks what they did to the simulation.
#include "urlab/viewer/viewer.h"

#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include "mujoco_test.h"
#include "urlab/world/manager.h"
#include "viewer/image_io.h"
#include "viewer/panel.h"
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
// scene's camera as mjr_render sets up its frustum.
Pixel Project(ViewerCore& core, const mjtNum p[3]) {
  const mjvScene& scn = core.view().scene();
  const mjvGLCamera cam = mjv_averageCamera(&scn.camera[0], &scn.camera[1]);
  int w = 0, h = 0;
  core.window().FramebufferSize(&w, &h);
  const double aspect = static_cast<double>(w) / h;
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
  px.x = (xn - (cam.frustum_center - half_w)) / (2 * half_w) * w;
  px.y = (1 - (yn - cam.frustum_bottom) / (cam.frustum_top - cam.frustum_bottom)) * h;
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

class ViewerTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("viewer"); }
  void TearDown() override {
    manager_.reset();
    testing::MujocoTest::TearDown();
  }

  // Plays `xml` as articulation "bot" with a viewer window of 640x480; `extra` is appended to
  // the scene file.
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
    vo.width = 640;
    vo.height = 480;
    auto v = std::make_unique<viewer::ViewerSubsystem>(vo);
    v->SetManager(manager_.get());
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

TEST_F(ViewerTest, DrawsThePanel) {
  Play(kBotXml);
  const Image with = viewer_->ReadPixels();
  viewer::ViewerOptions vo;
  // The panel's region (the left kWidth pixels) against the same frame with the panel off: a
  // second play in the same process.
  manager_.reset();
  vo.panel = false;
  Play(kBotXml, vo);
  const Image without = viewer_->ReadPixels();
  const int panel_w = static_cast<int>(viewer::internal::Panel::kWidth);
  int changed = 0, total = 0;
  for (int y = 0; y < with.height; y += 2) {
    for (int x = 0; x < panel_w; x += 2) {
      ++total;
      int sum = 0;
      for (int c = 0; c < 3; ++c) sum += std::abs(int(with.at(x, y)[c]) - int(without.at(x, y)[c]));
      if (sum > 30) ++changed;
    }
  }
  EXPECT_GT(changed, total / 2) << "the panel covers the left " << panel_w << " pixels";
  // Right of the panel the frames agree.
  int right_changed = 0;
  for (int y = 0; y < with.height; y += 2) {
    for (int x = panel_w + 20; x < with.width; x += 2) {
      int sum = 0;
      for (int c = 0; c < 3; ++c) sum += std::abs(int(with.at(x, y)[c]) - int(without.at(x, y)[c]));
      if (sum > 30) ++right_changed;
    }
  }
  EXPECT_LT(right_changed, total / 50);
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

}  // namespace
}  // namespace urlab
