// Each command frame's raw flag (control_mode raw: the targets were the actuators' controls, the
// controller did not run) is recorded with the frame, in every chunk; a run with raw steps
// re-simulates bit for bit.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "physics/test_models.h"
#include "replay/format.h"
#include "support/controlled_articulation.h"
#include "support/mujoco_test.h"
#include "support/step_recording.h"
#include "urlab/physics/engine.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {
namespace {

using testing::FramesOf;

using control::ControlSource;
using physics::PhysicsEngine;

class RawFlagTest : public urlab::testing::MujocoTest {
 protected:
  // Records the arm under a passthrough controller, the network source publishing targets, with
  // a raw window when `raw` (a frame patched raw, then one patched back). Returns the path and
  // the publication numbers of the raw frame and of the frame after it (0 without a window).
  struct Run {
    std::string path;
    std::uint64_t raw_seq = 0, back_seq = 0;
  };
  Run RecordRun(const std::string& name, bool raw) {
    PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
    urlab::testing::ControlledArticulation arm(engine);
    urlab::testing::StepRecording recording(engine);
    RecorderOptions o;
    o.path = dir_ + "/" + name;
    o.keyframe_interval = 0.05;  // several chunks: each carries the frames (and flags) again
    recording.Start(o);
    control::FrameChannel& channel = arm->channel(ControlSource::kNetwork);
    const std::vector<std::pair<int, double>> first{{0, 0.2}, {1, -0.1}};
    EXPECT_TRUE(channel.Patch(first));
    for (int i = 0; i < 8; ++i) recording.Step(10);  // 0.16 s: chunks of 0.05 s
    Run run{o.path};
    if (raw) {
      const std::vector<std::pair<int, double>> controls_now{{0, 0.5}, {1, 0.25}};
      EXPECT_TRUE(channel.Patch(controls_now, true));
      run.raw_seq = channel.last_seq();
      for (int i = 0; i < 4; ++i) recording.Step(10);
      EXPECT_TRUE(channel.Patch(first, false));
      run.back_seq = channel.last_seq();
      for (int i = 0; i < 4; ++i) recording.Step(10);
    }
    recording.Finish();
    return run;
  }

  std::string dir_ = urlab::testing::MakeTempDir("raw_flag");
};

TEST_F(RawFlagTest, EachFramesRawFlagIsRecordedInEveryChunkAndReplaysBitForBit) {
  const Run run = RecordRun("raw.urrec", true);
  const RecordingReader reader = RecordingReader::Open(run.path);
  EXPECT_EQ(reader.info().format_version, kRecordingFormatVersion);
  ASSERT_GT(reader.chunks().size(), 2u);
  std::size_t raw_frames = 0, after = 0, chunks_with_raw = 0;
  for (std::size_t c = 0; c < reader.chunks().size(); ++c) {
    bool any = false;
    for (const Frame& f : FramesOf(reader.ReadChunk(c))) {
      ASSERT_EQ(f.commands.raw.size(), 1u);
      const bool raw = f.commands.seq[0] == run.raw_seq;
      EXPECT_EQ(f.commands.raw[0], raw ? 1 : 0) << "seq " << f.commands.seq[0];
      if (raw) {
        EXPECT_EQ(f.commands.targets, (std::vector<double>{0.5, 0.25, 0.0}));  // 3 actuators
      }
      raw_frames += raw;
      after += f.commands.seq[0] == run.back_seq;
      any = any || raw;
    }
    chunks_with_raw += any;
  }
  EXPECT_GT(raw_frames, 0u);
  EXPECT_GT(after, 0u) << "the frame patched back is not raw";
  EXPECT_GE(chunks_with_raw, 1u);
  const ResimReport r = Resimulate(reader);
  EXPECT_TRUE(r.identical) << r.str();
}

}  // namespace
}  // namespace urlab::replay
