// The recorder against a real physics thread: every step captured, jumps marked with their
// states, re-simulation bit for bit, a perturbed recording reported at its step, kinematic
// playback through the engine's custom step handler, and every kind of bad file.
#include "urlab/replay/recorder.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "physics/test_models.h"
#include "support/controlled_articulation.h"
#include "support/mujoco_test.h"
#include "support/step_recording.h"
#include "support/wait.h"
#include "urlab/physics/engine.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {
namespace {

namespace fs = std::filesystem;
using testing::FramesOf;
using namespace std::chrono_literals;
using physics::PhysicsEngine;
namespace cmd = physics::cmd;
using urlab::testing::WaitFor;

// The engines here run as fast as possible (100k steps/s for the arm) on a machine that ctest
// loads: a ring of about a second keeps a starved writer from dropping frames, which would end
// bit-exact re-simulation at a gap.
constexpr std::size_t kDeepRing = 1 << 17;

class RecorderTest : public urlab::testing::MujocoTest {
 protected:
  std::string dir_ = urlab::testing::MakeTempDir("recorder");
};

// Runs `engine` as fast as possible with controls that change every step (like a policy's
// commands arriving), one-shot forces, a mocap move, a reset and an options change, recording
// it all. Returns the finished file's path.
std::string RecordBusyRun(PhysicsEngine& engine, Recorder& recorder, const std::string& path,
                          RecorderOptions options = {}) {
  options.path = path;
  const mjModel* m = engine.model();
  engine.AddPreStepCallback([](const mjModel* model, mjData* d) {
    for (int i = 0; i < model->nu; ++i) d->ctrl[i] = 0.3 * std::sin(40 * d->time + i);
  });
  engine.SetAsFastAsPossible(true);
  engine.Start();
  recorder.Start(options);
  // Each phase lasts until the recorder's writer has taken at least `kPhaseSteps` more frames:
  // the tests need a few hundred frames in each phase, and chunks, which the writer starts with
  // keyframes it asks of the running engine. (Waiting on the engine's steps alone let a starved
  // writer ask only after the engine had stopped: one chunk.)
  constexpr std::uint64_t kPhaseSteps = 300;
  const auto phase = [&] {
    const std::uint64_t from = recorder.status().frames;
    EXPECT_TRUE(WaitFor([&] { return recorder.status().frames >= from + kPhaseSteps; }));
  };
  phase();
  const int box = mj_name2id(m, mjOBJ_BODY, "box");
  if (box >= 0) engine.Submit(cmd::ApplyForce{box, {0.5, 0, 0}, {0, 0, 0}, 3});
  if (m->nmocap > 0) engine.Submit(cmd::SetMocap{0, {0.2, 0.1, 0.6}, {1, 0, 0, 0}});
  phase();
  engine.Reset();
  phase();
  engine.Submit(cmd::SetOptions{[](mjOption& o) { o.gravity[2] = -5; }, "low gravity"});
  phase();
  recorder.Stop();
  engine.Stop();
  return path;
}

TEST_F(RecorderTest, RecordsEveryStepAndReSimulatesBitForBit) {
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  Recorder recorder(engine, {{"arm"}, "<mujoco/>", "arm.xml"}, kDeepRing);
  const std::uint64_t hash = engine.owned_model().Hash();  // the run changes the options
  const std::string path = RecordBusyRun(engine, recorder, dir_ + "/arm.urrec");
  ASSERT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".part"));
  const RecorderStatus st = recorder.status();
  EXPECT_FALSE(st.active);
  EXPECT_EQ(st.dropped, 0u);
  EXPECT_GE(st.markers, 2u);  // the reset and the options change

  const RecordingReader reader = RecordingReader::Open(path);
  EXPECT_TRUE(reader.finished());
  EXPECT_EQ(reader.info().tables.joints[0].short_name, "shoulder");
  EXPECT_EQ(reader.info().model_hash, hash);
  const std::vector<Record> records = ReadAllRecords(reader);
  const std::vector<Frame> frames = FramesOf(records);
  ASSERT_GT(frames.size(), 100u);
  EXPECT_EQ(frames.size(), st.frames);
  EXPECT_EQ(frames.size(), reader.frame_count());
  // Consecutive steps, no gap.
  for (std::size_t i = 1; i < frames.size(); ++i) ASSERT_EQ(frames[i].step, frames[i - 1].step + 1);
  int resets = 0, options = 0;
  for (const Record& r : records) {
    if (const auto* mk = std::get_if<Marker>(&r)) {
      resets += (mk->flags & physics::kDiscontinuityReset) != 0;
      options += (mk->flags & physics::kDiscontinuityOptions) != 0;
    }
  }
  EXPECT_EQ(resets, 1);
  EXPECT_EQ(options, 1);
  // The one-shot force is in the frames of the three steps it acted on.
  const int box = mj_name2id(engine.model(), mjOBJ_BODY, "box");
  int pushed = 0;
  for (const Frame& f : frames) pushed += f.xfrc_applied[6 * box] == 0.5;
  EXPECT_EQ(pushed, 3);

  const ResimReport r = Resimulate(reader);
  EXPECT_TRUE(r.identical) << r.str();
  EXPECT_EQ(r.steps_checked, frames.size());
}

TEST_F(RecorderTest, HumanoidReSimulatesAndAPerturbedRecordingIsReportedAtItsStep) {
  PhysicsEngine engine(physics::LoadXmlFile(urlab::testing::kHumanoidPath));
  Recorder recorder(engine, {{}, "", ""}, kDeepRing);
  const std::string path = RecordBusyRun(engine, recorder, dir_ + "/humanoid.urrec");
  const RecordingReader reader = RecordingReader::Open(path);
  ResimReport r = Resimulate(reader);
  ASSERT_TRUE(r.identical) << r.str() << " of " << reader.frame_count();

  // Change one control of one step, keep everything else: the step after it diverges.
  std::vector<std::vector<Record>> chunks;
  for (std::size_t c = 0; c < reader.chunks().size(); ++c) chunks.push_back(reader.ReadChunk(c));
  std::uint64_t target_step = 0;
  std::size_t seen = 0;
  for (auto& chunk : chunks) {
    for (Record& rec : chunk) {
      if (auto* f = std::get_if<Frame>(&rec); f && ++seen == 500) {
        f->ctrl[3] += 1e-9;
        target_step = f->step;
      }
    }
  }
  ASSERT_GT(target_step, 0u);
  const std::string perturbed = dir_ + "/perturbed.urrec";
  WriteRecording(perturbed, reader.info(), chunks);
  r = Resimulate(RecordingReader::Open(perturbed));
  EXPECT_FALSE(r.identical);
  ASSERT_TRUE(r.diverged) << r.str();
  EXPECT_EQ(r.divergent_step, target_step) << r.str();
  EXPECT_EQ(r.divergent_index, 499u);
  EXPECT_TRUE(r.field == "qpos" || r.field == "qvel") << r.field;
  EXPECT_NE(r.str().find("DIVERGED at step " + std::to_string(target_step)), std::string::npos);
}

TEST_F(RecorderTest, KinematicPlaybackShowsEveryRecordedFrameBitIdentical) {
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  Recorder recorder(engine, {{"arm"}, "", ""}, kDeepRing);
  const std::string path = RecordBusyRun(engine, recorder, dir_ + "/kin.urrec");
  const RecordingReader reader = RecordingReader::Open(path);
  const std::vector<Frame> frames = FramesOf(ReadAllRecords(reader));

  for (PlayMode mode : {PlayMode::kKinematic, PlayMode::kResimulate}) {
    PhysicsEngine player_engine(LoadRecordedModel(reader));
    const auto ring = player_engine.SubscribeEveryStep("check", frames.size() + 16);
    PlayerOptions options;
    options.mode = mode;
    Player player(player_engine, reader, options);
    // One recorded frame per iteration, plus one iteration that waits for the recorded options
    // change to apply (re-simulation).
    for (int k = 0; k < 10 && !player.status().finished; ++k) {
      player_engine.StepSync(k == 0 ? static_cast<int>(frames.size()) : 1);
    }
    EXPECT_TRUE(player.status().finished);
    physics::StateFrame f;
    std::size_t i = 0;
    double last_time = -1;
    while (ring->TryPop(&f)) {
      if (!f.stepped || f.time == last_time) continue;  // an iteration that showed nothing new
      last_time = f.time;
      ASSERT_LT(i, frames.size());
      ASSERT_EQ(f.qpos, frames[i].qpos)
          << (mode == PlayMode::kKinematic ? "kinematic" : "resim") << " frame " << i << " t "
          << f.time << " rec " << frames[i].time << " prev " << frames[i - 1].time;
      ASSERT_EQ(f.time, frames[i].time) << "frame " << i;
      ++i;
    }
    EXPECT_EQ(i, frames.size());
    if (mode == PlayMode::kResimulate) {
      EXPECT_FALSE(player.status().resim.diverged) << player.status().resim.str();
    }
  }
}

// The command frames behind every step are recorded beside the state: a policy's targets (and
// gain overrides) as the controllers applied them, with their publication numbers and source.
TEST_F(RecorderTest, RecordsTheAppliedCommandFrames) {
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  urlab::testing::ControlledArticulation arm(engine);
  urlab::testing::StepRecording recording(engine, {{"arm"}, "", ""}, kDeepRing);
  RecorderOptions o;
  o.path = dir_ + "/commands.urrec";
  o.keyframe_interval = 0.05;  // several chunks: each must carry the frames again
  recording.Start(o);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::uint64_t> published;
  for (int k = 1; k <= 3; ++k) {
    for (int i = 0; i < 3; ++i) recording.Step(10);
    ASSERT_TRUE(arm->PublishFrame(control::ControlSource::kNetwork,
                                  std::vector<double>{0.1 * k, 0.2 * k, 0.3 * k},
                                  std::vector<double>{k == 2 ? 7.0 : nan, nan, nan}));
    published.push_back(arm->channel(control::ControlSource::kNetwork).last_seq());
  }
  for (int i = 0; i < 3; ++i) recording.Step(10);
  recording.Finish();

  const RecordingReader reader = RecordingReader::Open(o.path);
  ASSERT_EQ(reader.info().tables.command_groups, engine.command_layout());
  ASSERT_GT(reader.chunks().size(), 2u);
  const std::vector<Frame> frames = FramesOf(ReadAllRecords(reader));
  std::vector<std::uint64_t> seen;
  for (const Frame& f : frames) {
    ASSERT_EQ(f.commands.targets.size(), 3u);
    ASSERT_EQ(f.commands.seq.size(), 1u);
    EXPECT_EQ(f.commands.source[0], static_cast<std::uint8_t>(control::ControlSource::kNetwork));
    // Passthrough controller: the ctrl of a step is exactly the targets it applied.
    EXPECT_EQ(f.ctrl, f.commands.targets);
    if (seen.empty() || seen.back() != f.commands.seq[0]) seen.push_back(f.commands.seq[0]);
    for (std::size_t k = 0; k < published.size(); ++k) {
      if (f.commands.seq[0] != published[k]) continue;
      const double scale = static_cast<double>(k + 1);
      EXPECT_EQ(f.commands.targets, (std::vector<double>{0.1 * scale, 0.2 * scale, 0.3 * scale}));
      EXPECT_EQ(f.commands.kp[0] == 7.0, k >= 1);  // NaN: the gain stays
    }
  }
  ASSERT_GE(seen.size(), 3u);
  EXPECT_TRUE(std::equal(published.begin(), published.end(), seen.end() - 3));
  EXPECT_TRUE(Resimulate(reader).identical);
}

TEST_F(RecorderTest, SeekingLandsOnTheFrameAtThatTime) {
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  Recorder recorder(engine, {{"arm"}, "", ""}, kDeepRing);
  RecorderOptions o;
  o.keyframe_interval = 0.05;  // many chunks
  const std::string path = RecordBusyRun(engine, recorder, dir_ + "/seek.urrec", o);
  const RecordingReader reader = RecordingReader::Open(path);
  ASSERT_GT(reader.chunks().size(), 3u);
  const std::vector<Frame> frames = FramesOf(ReadAllRecords(reader));
  // The middle frame, and the last one (after the run's options change: a re-simulating seek
  // must start from a keyframe with the options in effect there).
  for (const Frame* target : {&frames[frames.size() / 2], &frames.back()}) {
    for (PlayMode mode : {PlayMode::kKinematic, PlayMode::kResimulate}) {
      const char* what = mode == PlayMode::kKinematic ? "kinematic" : "resimulate";
      PhysicsEngine player_engine(LoadRecordedModel(reader));
      Player player(player_engine, reader, {mode, 1.0, false, /*start_paused=*/true});
      player.SeekStep(target->step);
      // One iteration, or a few when the seek passes a recorded options change (each waits for
      // the engine to apply it).
      for (int k = 0; k < 5 && player.status().step != target->step; ++k) {
        player_engine.StepSync(1);
      }
      EXPECT_EQ(player.status().step, target->step) << what;
      player_engine.WithLockedData([&](mjModel* m, mjData* d) {
        EXPECT_EQ(std::vector<double>(d->qpos, d->qpos + m->nq), target->qpos) << what;
        EXPECT_EQ(std::vector<double>(d->qvel, d->qvel + m->nv), target->qvel) << what;
      });
      if (mode == PlayMode::kResimulate) {
        EXPECT_FALSE(player.status().resim.diverged) << player.status().resim.str();
      }
    }
  }
}

TEST_F(RecorderTest, KilledRecordingKeepsEveryFlushedChunk) {
  // A crash is simulated by copying the .part file while the recorder runs (what a kill -9
  // leaves): it opens as partial, with everything but the unflushed tail.
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  Recorder recorder(engine, {{"arm"}, "", ""}, kDeepRing);
  engine.SetAsFastAsPossible(true);
  engine.SetSpeedPercent(100);
  engine.Start();
  RecorderOptions o;
  o.path = dir_ + "/killed.urrec";
  o.chunk_seconds = 0.1;
  recorder.Start(o);
  ASSERT_TRUE(WaitFor([&] { return recorder.status().chunks >= 3; }));
  fs::copy_file(o.path + ".part", dir_ + "/crash.urrec");
  const RecorderStatus at_copy = recorder.status();
  recorder.Stop();
  engine.Stop();
  EXPECT_THROW(RecordingReader::Open(dir_ + "/crash.urrec"), RecordingError);
  const RecordingReader r = RecordingReader::Open(dir_ + "/crash.urrec", {true});
  EXPECT_FALSE(r.finished());
  EXPECT_FALSE(r.problem().empty());
  EXPECT_GE(r.chunks().size(), 3u);
  EXPECT_NO_THROW(r.Verify());
  EXPECT_GT(r.frame_count(), 0u);
  (void)at_copy;
  EXPECT_TRUE(Resimulate(r).identical);
}

// ---- bad files ----

class BadFileTest : public RecorderTest {
 protected:
  void SetUp() override {
    PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
    Recorder recorder(engine, {{"arm"}, "", ""}, kDeepRing);
    RecorderOptions o;
    o.keyframe_interval = 0.02;
    good_ = RecordBusyRun(engine, recorder, dir_ + "/good.urrec", o);
    std::ifstream in(good_, std::ios::binary);
    bytes_.assign(std::istreambuf_iterator<char>(in), {});
    const RecordingReader r = RecordingReader::Open(good_);
    ASSERT_GE(r.chunks().size(), 4u);
    chunk2_ = r.chunks()[2];
  }
  std::string Write(const std::string& name, const std::string& bytes) {
    const std::string p = dir_ + "/" + name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  static RecordingError::Reason ReasonOf(const std::function<void()>& fn, std::string* what) {
    try {
      fn();
    } catch (const RecordingError& e) {
      *what = e.what();
      return e.reason();
    }
    ADD_FAILURE() << "no RecordingError";
    return RecordingError::Reason::kNotARecording;
  }
  std::string good_, bytes_;
  ChunkInfo chunk2_;
};

TEST_F(BadFileTest, TruncatedFileNamesTheChunkAndKeepsItsPrefix) {
  const std::string p =
      Write("truncated.urrec", bytes_.substr(0, chunk2_.offset + 80 + chunk2_.stored_size / 2));
  std::string what;
  EXPECT_EQ(ReasonOf([&] { RecordingReader::Open(p); }, &what), RecordingError::Reason::kTruncated);
  EXPECT_NE(what.find("truncated.urrec"), std::string::npos) << what;
  EXPECT_NE(what.find("chunk 3"), std::string::npos) << what;  // data chunk 2 is file chunk 3
  const RecordingReader r = RecordingReader::Open(p, {true});
  EXPECT_EQ(r.chunks().size(), 2u);
  EXPECT_NO_THROW(r.Verify());
}

TEST_F(BadFileTest, CorruptedChunkNamesTheChunkAndTheOthersStayReadable) {
  std::string bytes = bytes_;
  bytes[chunk2_.offset + 80 + chunk2_.stored_size / 2] ^= 0x10;
  const std::string p = Write("corrupt.urrec", bytes);
  const RecordingReader r = RecordingReader::Open(p);  // the structure is intact
  EXPECT_NO_THROW(r.ReadChunk(0));
  EXPECT_NO_THROW(r.ReadChunk(1));
  std::string what;
  EXPECT_EQ(ReasonOf([&] { r.ReadChunk(2); }, &what), RecordingError::Reason::kCorrupt);
  EXPECT_NE(what.find("chunk 3"), std::string::npos) << what;
  EXPECT_NE(what.find("checksum"), std::string::npos) << what;
  EXPECT_NO_THROW(r.ReadChunk(3));
  EXPECT_THROW(r.Verify(), RecordingError);
  EXPECT_THROW(Resimulate(r), RecordingError);
}

TEST_F(BadFileTest, WrongVersionAndNotARecording) {
  std::string bytes = bytes_;
  bytes[8] = 7;
  std::string what;
  EXPECT_EQ(ReasonOf([&] { RecordingReader::Open(Write("v7.urrec", bytes)); }, &what),
            RecordingError::Reason::kVersion);
  EXPECT_NE(what.find("version 7"), std::string::npos) << what;
  EXPECT_EQ(
      ReasonOf([&] { RecordingReader::Open(Write("text.urrec", "hello world, not ours")); }, &what),
      RecordingError::Reason::kNotARecording);
  EXPECT_EQ(ReasonOf([&] { RecordingReader::Open(dir_ + "/missing.urrec"); }, &what),
            RecordingError::Reason::kNotARecording);
  EXPECT_NE(what.find("no such file"), std::string::npos) << what;
}

TEST_F(BadFileTest, WrongModelIsRefusedWithBothHashes) {
  const RecordingReader r = RecordingReader::Open(good_);
  PhysicsEngine other(physics::LoadXmlFile(urlab::testing::kHumanoidPath));
  std::string what;
  EXPECT_EQ(ReasonOf([&] { Player p(other, r, {}); }, &what), RecordingError::Reason::kWrongModel);
  EXPECT_NE(what.find(HashText(r.info().model_hash)), std::string::npos) << what;
  const physics::Model other_model = other.CopyModel();
  EXPECT_EQ(ReasonOf([&] { Resimulate(r, &other_model); }, &what),
            RecordingError::Reason::kWrongModel);
}

TEST_F(RecorderTest, RefusesWhatItCannotDo) {
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  Recorder recorder(engine, {{"arm"}, "", ""}, kDeepRing);
  EXPECT_THROW(recorder.Stop(), RecorderError);
  RecorderOptions o;
  o.path = "/proc/urlab-cannot-write-here/x.urrec";
  try {
    recorder.Start(o);
    ADD_FAILURE();
  } catch (const RecorderError& e) {
    EXPECT_EQ(e.code(), "path_not_writable");
  }
  o.path = dir_ + "/a.urrec";
  o.keyframe_interval = NAN;
  try {
    recorder.Start(o);
    ADD_FAILURE();
  } catch (const RecorderError& e) {
    EXPECT_EQ(e.code(), "bad_value");
  }
  o.keyframe_interval = 1;
  engine.Start();
  recorder.Start(o);
  try {
    recorder.Start(o);
    ADD_FAILURE();
  } catch (const RecorderError& e) {
    EXPECT_EQ(e.code(), "recording_already_active");
  }
  recorder.Stop();
  engine.Stop();
}

TEST_F(RecorderTest, NeverDestroysACrashedRecordingOrItsOwnFile) {
  PhysicsEngine engine(physics::CompileXmlString(urlab::testing::kArmXml));
  Recorder recorder(engine, {{"arm"}, "<mujoco/>", "arm.xml"}, kDeepRing);
  const std::string path = dir_ + "/run.urrec";
  std::ofstream(path + ".part") << "a crashed recording";
  RecorderOptions o;
  o.path = path;
  try {
    recorder.Start(o);
    FAIL() << "started over an existing .part";
  } catch (const RecorderError& e) {
    EXPECT_EQ(e.code(), "path_not_writable");
    EXPECT_NE(std::string(e.what()).find("urlab replay " + path + ".part --info"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(urlab::testing::ReadTextFile(path + ".part"), "a crashed recording");
  fs::remove(path + ".part");
  engine.SetAsFastAsPossible(true);
  engine.Start();
  recorder.Start(o);
  WaitFor([&] { return recorder.status().frames > 100; }, 60000ms);
  // A copy may not be saved over the recording being written, under any of its names.
  fs::create_symlink(path + ".part", dir_ + "/link.urrec");
  for (const std::string& self : {path, path + ".part", dir_ + "/link.urrec"}) {
    try {
      recorder.Save(self);
      ADD_FAILURE() << "saved over " << self;
    } catch (const RecorderError& e) {
      EXPECT_NE(std::string(e.what()).find("is the recording being written"), std::string::npos);
    }
  }
  EXPECT_NO_THROW(recorder.Save(dir_ + "/copy.urrec"));
  recorder.Stop();
  engine.Stop();
  EXPECT_TRUE(RecordingReader::Open(path).finished());
  EXPECT_TRUE(RecordingReader::Open(dir_ + "/copy.urrec").finished());
}

}  // namespace
}  // namespace urlab::replay
