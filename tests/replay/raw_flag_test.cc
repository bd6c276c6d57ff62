// Recording format 3: each command frame's raw flag (control_mode raw: the targets were the
// actuators' controls, the controller did not run) is recorded with the frame, in every chunk;
// a run with raw steps re-simulates bit for bit; format 2 files (no raw flags) are still read,
// every frame as not raw, and a format 2 file carrying raw flags is refused as damaged.
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

// The file as format 2 wrote it: the same chunks under version 2 in the file header and the
// header chunk's JSON (format 3 changed only the data records of raw frames).
std::string AsFormat2(const std::string& path, const std::string& out) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes(std::istreambuf_iterator<char>(in), {});
  format::ChunkHeader h;
  EXPECT_TRUE(format::DecodeChunkHeader(
      std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()) + format::kFileHeaderSize,
                format::kChunkHeaderSize),
      &h));
  const std::size_t rest = format::kFileHeaderSize + format::kChunkHeaderSize + h.stored_size;
  std::string payload = format::EncodeInfo(RecordingReader::Open(path).info());
  const std::string key = "\"format_version\":" + std::to_string(kRecordingFormatVersion);
  const std::size_t at = payload.find(key);
  EXPECT_NE(at, std::string::npos);
  payload.replace(at, key.size(), "\"format_version\":2");
  std::string file = format::FileHeader();
  file[8] = 2;  // version 2 (u32, little-endian)
  format::ChunkHeader header;
  header.kind = format::ChunkKind::kHeader;
  header.raw_size = payload.size();
  file += format::EncodeChunk(header, payload) + bytes.substr(rest);
  std::ofstream(out, std::ios::binary) << file;
  return out;
}

TEST_F(RawFlagTest, EachFramesRawFlagIsRecordedInEveryChunkAndReplaysBitForBit) {
  const Run run = RecordRun("raw.urrec", true);
  const RecordingReader reader = RecordingReader::Open(run.path);
  EXPECT_EQ(reader.info().format_version, 3u);
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

  // Relabelled as format 2, whose records had no raw flags: refused as damaged, naming why.
  const RecordingReader v2 = RecordingReader::Open(AsFormat2(run.path, dir_ + "/raw_v2.urrec"));
  bool refused = false;
  for (std::size_t c = 0; c < v2.chunks().size(); ++c) {
    try {
      v2.ReadChunk(c);
    } catch (const RecordingError& e) {
      refused = true;
      EXPECT_EQ(e.reason(), RecordingError::Reason::kCorrupt);
      EXPECT_NE(std::string(e.what()).find("raw flags in a format 2 recording"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(refused);
}

TEST_F(RawFlagTest, Format2RecordingsAreStillReadEveryFrameNotRaw) {
  const Run run = RecordRun("plain.urrec", false);
  const RecordingReader reader =
      RecordingReader::Open(AsFormat2(run.path, dir_ + "/plain_v2.urrec"));
  EXPECT_EQ(reader.info().format_version, 2u);
  const std::vector<Frame> frames = FramesOf(ReadAllRecords(reader));
  ASSERT_FALSE(frames.empty());
  for (const Frame& f : frames) {
    ASSERT_EQ(f.commands.raw, (std::vector<std::uint8_t>{0}));
  }
  const ResimReport r = Resimulate(reader);
  EXPECT_TRUE(r.identical) << r.str();
}

}  // namespace
}  // namespace urlab::replay
