// FrameSampler: the recording's state at k/fps on its time axis (the start state at 0, each step
// by its time difference, a reset by one timestep), as `urlab render` draws it.
#include "urlab/replay/frame_sampler.h"

#include <gtest/gtest.h>

#include <cmath>

#include "mujoco_test.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state.h"

namespace urlab::replay {
namespace {

constexpr const char* kXml = R"(<mujoco model="slider">
  <option timestep="0.0033333333333333335" gravity="0 0 0"/>
  <worldbody>
    <body name="b"><joint name="x" type="slide" axis="1 0 0"/>
      <geom type="sphere" size="0.1" mass="1"/></body>
  </worldbody>
</mujoco>
)";

// `steps` steps at constant velocity, a keyframe every 300 steps, and a reset back to t = 0
// before step `reset_at` (none when 0).
std::string Write(const std::string& dir, int steps, int reset_at) {
  const physics::Model model(physics::CompileXmlString(kXml));
  const mjModel* m = model.get();
  RecordingInfo info;
  info.tables = ModelTables::Of(m);
  DescribeModel(model, &info);
  physics::DataPtr data = physics::MakeData(m);
  mjData* d = data.get();
  d->qvel[0] = 1;
  std::vector<std::vector<Record>> chunks;
  for (int n = 0; n < steps; ++n) {
    if (n % 300 == 0) {
      chunks.emplace_back();
      chunks.back().push_back(StateRecord{0, physics::CaptureState(m, d)});
    }
    if (reset_at && n == reset_at) {
      mj_resetData(m, d);
      d->qvel[0] = 1;
      chunks.back().push_back(Marker{physics::kDiscontinuityReset, 0, 0, "reset"});
      chunks.back().push_back(
          StateRecord{physics::kDiscontinuityReset, physics::CaptureState(m, d)});
    }
    mj_step(m, d);
    Frame f;
    f.time = d->time;
    f.step = static_cast<std::uint64_t>(n + 1);
    f.qpos = {d->qpos[0]};
    f.qvel = {d->qvel[0]};
    f.qfrc_applied = {0};
    f.xfrc_applied.assign(static_cast<std::size_t>(6 * m->nbody), 0);
    chunks.back().push_back(std::move(f));
  }
  const std::string path = dir + "/slide.urrec";
  WriteRecording(path, info, chunks);
  return path;
}

TEST(FrameSampler, FrameKShowsTheStepAtKOverFps) {
  const std::string dir = testing::MakeTempDir("sampler");
  const RecordingReader reader = RecordingReader::Open(Write(dir, 1200, 0));
  FrameSampler sampler(reader);
  EXPECT_NEAR(sampler.duration(), 4.0, 1e-9);
  EXPECT_EQ(sampler.FrameCount(30), 120u);
  EXPECT_EQ(sampler.FrameCount(25), 100u);
  for (int k = 0; k < 120; ++k) {
    const physics::StateFrame& f = sampler.At(k / 30.0);
    EXPECT_EQ(f.step, static_cast<std::uint64_t>(10 * k)) << k;
    EXPECT_NEAR(f.time, k / 30.0, 1e-9) << k;
    EXPECT_NEAR(f.qpos[0], k / 30.0, 1e-9) << k;  // 1 m/s from 0
  }
}

TEST(FrameSampler, AResetCountsOneTimestepOnTheAxis) {
  const std::string dir = testing::MakeTempDir("sampler_reset");
  const RecordingReader reader = RecordingReader::Open(Write(dir, 600, 300));
  FrameSampler sampler(reader);
  // 300 steps, then the reset's step (time back to 1/300), then 299 more: 600 timesteps.
  EXPECT_NEAR(sampler.duration(), 2.0, 1e-9);
  EXPECT_EQ(sampler.FrameCount(30), 60u);
  EXPECT_NEAR(sampler.At(0.5).time, 0.5, 1e-9);
  const physics::StateFrame& after = sampler.At(1.5);  // half a second after the reset
  EXPECT_EQ(after.step, 450u);
  EXPECT_NEAR(after.time, 0.5, 1e-9);
}

}  // namespace
}  // namespace urlab::replay
