// `urlab record --video CAM OUT`: a camera's frames written through ffmpeg, checked with ffprobe;
// a bad camera name or extension is a clear error. `urlab render`: a recording to a video, frame
// k showing the state at k/fps (checked against an independent render of that state), and
// `view --screenshot --at T` showing the state at T.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <vector>

#include "mujoco_test.h"
#include "render/camera_renderer.h"
#include "render/gl_context.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state.h"
#include "urlab/replay/recording.h"
#include "viewer/framing.h"
#include "viewer/layout.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

TEST(RecordVideo, WritesTheCameraToAnMp4) {
  const std::string dir = testing::MakeTempDir("video");
  const std::string out = dir + "/wrist.mp4";
  std::string log;
  ASSERT_EQ(testing::RunCommand(testing::UrlabBinary() + " record --ports auto " +
                                    testing::TestData("cameras/two_cameras.yaml") +
                                    " --no-network --duration 1 --video rig/wrist " + out,
                                &log),
            0)
      << log;
  EXPECT_NE(log.find("video: " + out + " frames="), std::string::npos) << log;
  std::string probe;
  ASSERT_EQ(testing::RunCommand("ffprobe -v error -count_frames -show_entries "
                                "stream=codec_name,width,height,nb_read_frames -of compact " +
                                    out,
                                &probe),
            0)
      << probe;
  EXPECT_NE(probe.find("codec_name=h264|width=64|height=48"), std::string::npos) << probe;
  EXPECT_EQ(probe.find("nb_read_frames=0"), std::string::npos) << probe;
  fs::remove_all(dir);
}

// Frame-exact however fast the run: 1 s at the camera's rate is that many frames, at full
// speed too (the simulation waits for each frame's render; it used to keep a frame or two).
TEST(RecordVideo, EveryFrameIsWrittenAtFullSpeed) {
  const std::string dir = testing::MakeTempDir("video");
  for (const char* speed : {"", " --max-speed"}) {
    const std::string out = dir + "/wrist.mp4";
    fs::remove(out);
    std::string log;
    ASSERT_EQ(testing::RunCommand(testing::UrlabBinary() + " record --ports auto " +
                                      testing::TestData("cameras/two_cameras.yaml") +
                                      " --no-network --duration 1 --video rig/wrist " + out + speed,
                                  &log),
              0)
        << log;
    EXPECT_NE(log.find("video: " + out + " frames=30\n"), std::string::npos) << speed << log;
    std::string probe;
    ASSERT_EQ(
        testing::RunCommand(
            "ffprobe -v error -count_frames -show_entries stream=nb_read_frames -of compact " + out,
            &probe),
        0)
        << probe;
    EXPECT_NE(probe.find("nb_read_frames=30"), std::string::npos) << speed << probe;
  }
  fs::remove_all(dir);
}

TEST(RecordVideo, BadCameraOrExtensionIsAClearError) {
  const std::string dir = testing::MakeTempDir("video_bad");
  std::string log;
  EXPECT_NE(testing::RunCommand(testing::UrlabBinary() + " record --ports auto " +
                                    testing::TestData("cameras/two_cameras.yaml") +
                                    " --no-network --duration 1 --video rig/nose " + dir + "/a.mp4",
                                &log),
            0);
  EXPECT_NE(log.find("no camera 'nose'"), std::string::npos) << log;
  EXPECT_NE(testing::RunCommand(testing::UrlabBinary() + " record --ports auto " +
                                    testing::TestData("cameras/two_cameras.yaml") +
                                    " --no-network --duration 1 --video rig/top " + dir + "/a.avi",
                                &log),
            0);
  EXPECT_NE(log.find(".mp4 (H.264) or .webm"), std::string::npos) << log;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace urlab

// ---- Frame-exact rendering: `urlab render` and `view --screenshot --at` ----

namespace urlab {
namespace {

namespace fs = std::filesystem;

// A rod falling from horizontal about a hinge (gravity only): where it is shows the time. The
// timestep is 1/300 s, so a 30 frames/s video shows every tenth step.
constexpr const char* kPendulumXml = R"(<mujoco model="pendulum">
  <option timestep="0.0033333333333333335"/>
  <visual><global offwidth="320" offheight="240"/></visual>
  <worldbody>
    <light pos="0 -2 3" dir="0 0.5 -1"/>
    <camera name="side" pos="0 -3 0" xyaxes="1 0 0 0 0 1" fovy="60"/>
    <body name="arm" pos="0 0 0.5">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 1 0 0" size="0.1" rgba="0.9 0.1 0.1 1" mass="1"/>
    </body>
  </worldbody>
</mujoco>
)";
constexpr int kStepsPerFrame = 10;  // 30 frames/s at 1/300 s
constexpr int kWidth = 160, kHeight = 120;

// Simulates the pendulum for `steps` steps from rest and writes a recording of it (a keyframe
// every 300 steps, as the recorder makes them); qpos of every step in *qpos (index = step).
void WritePendulumRecording(const mjModel* m, const std::string& path, int steps,
                            std::vector<std::vector<double>>* qpos) {
  replay::RecordingInfo info;
  info.tables = replay::ModelTables::Of(m);
  info.mjcf = kPendulumXml;
  replay::DescribeModel(physics::Model(physics::ModelPtr(mj_copyModel(nullptr, m))), &info);
  physics::DataPtr data = physics::MakeData(m);
  mjData* d = data.get();
  mj_forward(m, d);
  auto take = [&](const double* v, int n) { return std::vector<double>(v, v + n); };
  qpos->assign(1, take(d->qpos, m->nq));
  std::vector<std::vector<replay::Record>> chunks;
  for (int n = 0; n < steps; ++n) {
    if (n % 300 == 0) {
      chunks.emplace_back();
      chunks.back().push_back(replay::StateRecord{0, physics::CaptureState(m, d)});
    }
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
    qpos->push_back(take(d->qpos, m->nq));
  }
  replay::WriteRecording(path, info, chunks);
}

// Decodes a video or image into RGB frames of width x height with ffmpeg.
std::vector<std::uint8_t> Decode(const std::string& file, const std::string& raw) {
  std::string log;
  EXPECT_EQ(testing::RunCommand(
                "ffmpeg -v error -y -i " + file + " -f rawvideo -pix_fmt rgb24 " + raw, &log),
            0)
      << log;
  const std::string bytes = testing::ReadTextFile(raw);
  return {bytes.begin(), bytes.end()};
}

// Pixels of two RGB images (`n` bytes) that differ clearly: by more than 150 summed over the
// channels, far above what the video's compression changes (the red rod on black).
double Difference(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  int count = 0;
  for (std::size_t i = 0; i + 2 < n; i += 3) {
    int sum = 0;
    for (std::size_t c = 0; c < 3; ++c) sum += std::abs(int{a[i + c]} - int{b[i + c]});
    if (sum > 150) ++count;
  }
  return count;
}

// The viewer's default camera: the whole scene framed at its first state (qpos0) for a viewport
// of `aspect` (viewer/framing.h).
mjvCamera ViewerCamera(const mjModel* m, double aspect) {
  physics::DataPtr d = physics::MakeData(m);
  mj_forward(m, d.get());
  mjvCamera cam;
  mjv_defaultFreeCamera(m, &cam);
  viewer::internal::FrameScene(m, d.get(), aspect, &cam);
  return cam;
}

// Renders the pendulum at `qpos` through `camera` (an MJCF camera id, or -1 for the free camera
// framing the scene), as an independent reference.
class Reference {
 public:
  Reference(const mjModel* m, int width, int height)
      : model_(m),
        gl_(render::OffscreenGl::Create()),
        renderer_(m, width, height, {}),
        width_(width),
        height_(height),
        data_(physics::MakeData(m)) {
    renderer_.MakeContext();
  }
  // `free_camera`: the free camera to look through (null: MuJoCo's default free camera).
  std::vector<std::uint8_t> At(const std::vector<double>& qpos, int camera,
                               const mjvCamera* free_camera = nullptr) {
    std::copy(qpos.begin(), qpos.end(), data_->qpos);
    mj_forward(model_, data_.get());
    physics::StateFrame f = physics::StateFrame::SizedFor(model_);
    f.CopyFrom(model_, data_.get());
    renderer_.Update(f);
    render::ImageRequest rgb;
    rgb.rgb = true;
    if (camera >= 0) {
      renderer_.Render(camera, width_, height_, rgb, image_);
    } else {
      mjvCamera free;
      mjv_defaultFreeCamera(model_, &free);
      if (free_camera) free = *free_camera;
      renderer_.RenderView(free, width_, height_, rgb, image_);
    }
    return image_.rgb;
  }

 private:
  const mjModel* model_;
  std::unique_ptr<render::OffscreenGl> gl_;
  render::CameraRenderer renderer_;
  int width_, height_;
  physics::DataPtr data_;
  render::CameraImages image_;
};

TEST(RenderRecording, FourSecondsAt30FpsAre120FramesEachShowingItsTime) {
  const std::string dir = testing::MakeTempDir("render");
  const physics::ModelPtr model = physics::CompileXmlString(kPendulumXml);
  const mjModel* m = model.get();
  std::vector<std::vector<double>> qpos;
  WritePendulumRecording(m, dir + "/fall.urrec", 1200, &qpos);  // 4 s
  const std::string out = dir + "/fall.mp4";
  std::string log;
  ASSERT_EQ(testing::RunCommand(testing::UrlabBinary() + " render " + dir + "/fall.urrec --video " +
                                    out + " --fps 30 --camera side --width 160 --height 120",
                                &log),
            0)
      << log;
  EXPECT_NE(log.find("wrote " + out + ": 120 frames at 30 frames/s"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir + "/.fall.urlab-tmp.mp4")) << "the temporary video stayed";
  std::string probe;
  ASSERT_EQ(testing::RunCommand("ffprobe -v error -count_frames -show_entries "
                                "stream=width,height,nb_read_frames,r_frame_rate -of compact " +
                                    out,
                                &probe),
            0)
      << probe;
  EXPECT_NE(probe.find("width=160|height=120"), std::string::npos) << probe;
  EXPECT_NE(probe.find("r_frame_rate=30/1"), std::string::npos) << probe;
  EXPECT_NE(probe.find("nb_read_frames=120"), std::string::npos) << probe;

  const std::vector<std::uint8_t> video = Decode(out, dir + "/fall.rgb");
  const std::size_t frame_bytes = 3 * kWidth * kHeight;
  ASSERT_EQ(video.size(), 120 * frame_bytes);
  Reference reference(m, kWidth, kHeight);
  const int side = mj_name2id(m, mjOBJ_CAMERA, "side");
  // Frame k against the state at k/30 s (step 10k) and against its neighbours' states: the
  // decoded frame is (near) the right one, and clearly nearer to it than to 1/30 s off.
  int discriminating = 0;
  // The rod turns around at about 0, 1, 2 and 3 s and is fastest half-way between.
  for (int k : {0, 1, 8, 15, 22, 30, 45, 52, 60, 75, 90, 105, 119}) {
    const std::uint8_t* frame = video.data() + static_cast<std::size_t>(k) * frame_bytes;
    const auto right = reference.At(qpos[static_cast<std::size_t>(k * kStepsPerFrame)], side);
    const double d_right = Difference(frame, right.data(), frame_bytes);
    EXPECT_LT(d_right, 40) << "frame " << k;
    double d_off = 1e9;
    for (int off : {-1, 1}) {
      const int j = k + off;
      if (j < 0 || j >= 120) continue;
      const auto other = reference.At(qpos[static_cast<std::size_t>(j * kStepsPerFrame)], side);
      d_off = std::min(d_off, Difference(frame, other.data(), frame_bytes));
    }
    // Where the rod moves (all but the turning points) a frame 1/30 s off looks clearly
    // different; nothing is nearer than the right state anywhere.
    EXPECT_LE(d_right, d_off) << "frame " << k;
    if (d_off > 2 * d_right + 20) ++discriminating;
  }
  EXPECT_GE(discriminating, 7) << "the rod hardly moves between frames: the check is too weak";
  fs::remove_all(dir);
}

// Issue 38, case 4: `render --video` follows the one output rule of core/files.h (it renamed
// its temporary over the name, replacing a symbolic link, or a device node, with a file): a
// link is written through and stays a link, a device is written in place, a folder is refused.
TEST(RenderRecording, TheVideoFollowsTheOutputRule) {
  const std::string dir = testing::MakeTempDir("render_rule");
  const physics::ModelPtr model = physics::CompileXmlString(kPendulumXml);
  std::vector<std::vector<double>> qpos;
  WritePendulumRecording(model.get(), dir + "/fall.urrec", 30, &qpos);
  const auto render = [&](const std::string& out, std::string* log) {
    return testing::RunCommand(testing::UrlabBinary() + " render " + dir + "/fall.urrec --video " +
                                   out + " --fps 30 --camera side --width 64 --height 48",
                               log);
  };
  std::string log;
  // A symbolic link: its target gets the video, the link stays.
  fs::create_directories(dir + "/videos");
  fs::create_symlink(dir + "/videos/real.mp4", dir + "/link.mp4");
  ASSERT_EQ(render(dir + "/link.mp4", &log), 0) << log;
  EXPECT_TRUE(fs::is_symlink(dir + "/link.mp4")) << "the link was replaced by a file";
  EXPECT_TRUE(fs::is_regular_file(dir + "/videos/real.mp4"));
  EXPECT_GT(fs::file_size(dir + "/videos/real.mp4"), 0u);
  EXPECT_FALSE(fs::exists(dir + "/.link.urlab-tmp.mp4"));
  EXPECT_FALSE(fs::exists(dir + "/videos/.real.urlab-tmp.mp4"));
  // A device (through a link named *.mp4): written in place, never replaced.
  fs::create_symlink("/dev/null", dir + "/null.mp4");
  ASSERT_EQ(render(dir + "/null.mp4", &log), 0) << log;
  EXPECT_TRUE(fs::is_symlink(dir + "/null.mp4")) << "the link to /dev/null was replaced";
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  // A folder named *.mp4: refused, nothing written.
  fs::create_directories(dir + "/folder.mp4");
  EXPECT_EQ(render(dir + "/folder.mp4", &log), 1) << log;
  EXPECT_NE(log.find("folder"), std::string::npos) << log;
  EXPECT_TRUE(fs::is_empty(dir + "/folder.mp4"));
  fs::remove_all(dir);
}

TEST(RenderRecording, UnknownCameraIsAClearErrorAndWritesNothing) {
  const std::string dir = testing::MakeTempDir("render_bad");
  const physics::ModelPtr model = physics::CompileXmlString(kPendulumXml);
  std::vector<std::vector<double>> qpos;
  WritePendulumRecording(model.get(), dir + "/fall.urrec", 30, &qpos);
  std::string log;
  EXPECT_EQ(testing::RunCommand(testing::UrlabBinary() + " render " + dir + "/fall.urrec --video " +
                                    dir + "/a.mp4 --camera top",
                                &log),
            1);
  EXPECT_NE(log.find("--camera top: no camera 'top'"), std::string::npos) << log;
  EXPECT_NE(log.find("side"), std::string::npos) << "the error lists the cameras: " << log;
  EXPECT_FALSE(fs::exists(dir + "/a.mp4"));
  fs::remove_all(dir);
}

TEST(ViewScreenshot, AtTimeShowsTheStateAtThatTime) {
  if (testing::RunCommand("command -v Xvfb >/dev/null") != 0) {
    GTEST_SKIP() << "Xvfb is not installed";
  }
  const std::string dir = testing::MakeTempDir("shot_at");
  const std::string xml = testing::WriteTextFile(dir, "pendulum.xml", kPendulumXml);
  const std::string shot = dir + "/shot.png";
  std::string log;
  ASSERT_EQ(
      testing::RunCommand(testing::XvfbRun("640x480x24") + testing::UrlabBinary() + " view " + xml +
                              " --no-network --no-cameras --no-panel --width 320 "
                              "--height 240 --no-shadows --no-reflections --no-skybox "
                              "--screenshot " +
                              shot + " --at 0.3",
                          &log),
      0)
      << log;
  const std::vector<std::uint8_t> image = Decode(shot, dir + "/shot.rgb");
  constexpr int w = 320, h = 240;
  ASSERT_EQ(image.size(), static_cast<std::size_t>(3 * w * h)) << log;
  const physics::ModelPtr model = physics::CompileXmlString(kPendulumXml);
  const mjModel* m = model.get();
  physics::DataPtr data = physics::MakeData(m);
  std::vector<std::vector<double>> qpos(1, {0.0});
  for (int n = 0; n < 200; ++n) {
    mj_step(m, data.get());
    qpos.push_back({data->qpos[0]});
  }
  // The shot against the viewer's default camera (framing the scene at its first state) on the
  // states 0.3 s +- 1/30 s and +- 1/15 s: the state at 0.3 s (step 90) is the nearest.
  Reference reference(m, w, h);
  const mjvCamera framed = ViewerCamera(m, static_cast<double>(w) / h);
  std::vector<std::pair<double, int>> diffs;
  for (int step : {70, 80, 90, 100, 110}) {
    const auto expected = reference.At(qpos[static_cast<std::size_t>(step)], -1, &framed);
    diffs.emplace_back(Difference(image.data(), expected.data(), image.size()), step);
  }
  std::sort(diffs.begin(), diffs.end());
  std::string table;
  for (const auto& [diff, step] : diffs) table += fmt::format(" step {}: {} pixels;", step, diff);
  EXPECT_EQ(diffs[0].second, 90) << table << "\n" << log;
  EXPECT_LT(diffs[0].first, 0.6 * diffs[1].first) << table;
  fs::remove_all(dir);
}

TEST(ReplayView, WatchesARecordingWithTheTimelineAtAnExactTime) {
  if (testing::RunCommand("command -v Xvfb >/dev/null") != 0) {
    GTEST_SKIP() << "Xvfb is not installed";
  }
  const std::string dir = testing::MakeTempDir("replay_view");
  const std::string xml = testing::WriteTextFile(dir, "pendulum.xml", kPendulumXml);
  const std::string rec = dir + "/fall.urrec";
  std::string log;
  ASSERT_EQ(testing::RunCommand(testing::UrlabBinary() + " record --ports auto " + xml + " -o " +
                                    rec + " --no-network --no-cameras --max-speed --duration 0.6",
                                &log),
            0)
      << log;
  // A shot past the recording's end is refused at once (it used to wait for ever).
  ASSERT_EQ(
      testing::RunCommand(testing::XvfbRun("1024x768x24") + testing::UrlabBinary() + " replay " +
                              rec + " --view --screenshot " + dir + "/late.png --at 0.7",
                          &log),
      1)
      << log;
  EXPECT_NE(log.find("--at 0.7: past the recording's last frame"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir + "/late.png"));
  const std::string shot = dir + "/timeline.png";
  ASSERT_EQ(testing::RunCommand(
                testing::XvfbRun("1024x768x24") + testing::UrlabBinary() + " replay " + rec +
                    " --view --width 1200 --height 500 --no-shadows --no-reflections "
                    "--no-skybox --screenshot " +
                    shot + " --at 0.5",
                &log),
            0)
      << log;
  EXPECT_NE(log.find("viewing on " + xml), std::string::npos) << log;  // the recorded scene
  EXPECT_NE(log.find("keyframes"), std::string::npos) << log;
  const std::vector<std::uint8_t> image = Decode(shot, dir + "/timeline.rgb");
  constexpr int w = 1200, h = 500;
  ASSERT_EQ(image.size(), static_cast<std::size_t>(3 * w * h)) << log;
  // The scene region (right of the panel, above the timeline) shows the recorded state at 0.5 s
  // (step 150 of 1/300 s): nearer to it than to 1/30 s before or after.
  const physics::ModelPtr model = physics::CompileXmlString(kPendulumXml);
  const mjModel* m = model.get();
  physics::DataPtr data = physics::MakeData(m);
  std::vector<std::vector<double>> qpos(1, {0.0});
  for (int n = 0; n < 200; ++n) {
    mj_step(m, data.get());
    qpos.push_back({data->qpos[0]});
  }
  // The 3D viewport right of the docked panel (its default width and the splitter).
  const int vx = static_cast<int>(viewer::internal::Layout::kDefaultWidth +
                                  viewer::internal::Layout::kSplitter);
  const int vw = w - vx;
  Reference reference(m, vw, h);
  const mjvCamera framed = ViewerCamera(m, static_cast<double>(vw) / h);
  auto region_difference = [&](const std::vector<std::uint8_t>& expected) {
    double count = 0;
    for (int y = 0; y < h - 110; ++y) {
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * w + static_cast<std::size_t>(vx));
      const std::size_t e = 3 * (static_cast<std::size_t>(y) * vw);
      count += Difference(image.data() + i, expected.data() + e, 3 * static_cast<std::size_t>(vw));
    }
    return count;
  };
  std::vector<std::pair<double, int>> diffs;
  for (int step : {140, 150, 160}) {
    diffs.emplace_back(
        region_difference(reference.At(qpos[static_cast<std::size_t>(step)], -1, &framed)), step);
  }
  std::sort(diffs.begin(), diffs.end());
  std::string table;
  for (const auto& [diff, step] : diffs) table += fmt::format(" step {}: {} pixels;", step, diff);
  EXPECT_EQ(diffs[0].second, 150) << table;
  // The timeline strip along the bottom is drawn (not the scene's black background).
  int lit = 0;
  for (int y = h - 100; y < h - 4; ++y) {
    for (int x = 380; x < w - 10; ++x) {
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x));
      if (image[i] + image[i + 1] + image[i + 2] > 150) ++lit;
    }
  }
  EXPECT_GT(lit, 300) << "no timeline at the bottom of the window";
  // `urlab view` opens a recording the same way (as it does one dropped on its window).
  const std::string via_view = dir + "/via_view.png";
  ASSERT_EQ(testing::RunCommand(testing::XvfbRun("1024x768x24") + testing::UrlabBinary() +
                                    " view " + rec +
                                    " --width 1200 --height 500 --no-shadows --no-reflections "
                                    "--no-skybox --screenshot " +
                                    via_view + " --at 0.5",
                                &log),
            0)
      << log;
  EXPECT_NE(log.find("viewing on " + xml), std::string::npos) << log;
  const std::vector<std::uint8_t> viewed = Decode(via_view, dir + "/via_view.rgb");
  ASSERT_EQ(viewed.size(), image.size()) << log;
  EXPECT_LT(Difference(viewed.data(), image.data(), image.size()), 0.01 * w * h)
      << "`view RECORDING` shows another picture than `replay RECORDING --view`";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace urlab
