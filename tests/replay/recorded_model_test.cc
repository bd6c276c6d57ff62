// Recordings carry the compiled model (MuJoCo 3's MJB, the MuJoCo version named) and its hash: a
// recording of a model using gravity compensation, a dead-band spring and a joint actuator force
// sensor (which MuJoCo computes itself) re-simulates bit for bit from the file alone; a model
// that differs only in gravcomp is "another model"; a recording started after the physics options
// changed at run time is accepted by the engine that made it and replays those options; formats
// 1 to 3 (MuJoCo 2.2.2 models) are refused saying so, newer versions by number.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>

#include "physics/test_models.h"
#include "replay/format.h"
#include "support/mujoco_test.h"
#include "support/step_recording.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/model.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {
namespace {

namespace fs = std::filesystem;
using physics::PhysicsEngine;

physics::Model Compile(double gravcomp = 1.0) {
  return physics::Model(physics::CompileXmlString(urlab::testing::CompensatedArmXml(gravcomp)));
}

class RecordedModelTest : public urlab::testing::MujocoTest {
 protected:
  // Records `steps` steps of `engine` (driven with changing controls) to `name`.
  // `before_start` runs between the recorder's construction (in begin-play) and its Start.
  std::string RecordRun(PhysicsEngine& engine, const std::string& name, int steps,
                        bool sensordata = true, const std::function<void()>& before_start = {}) {
    urlab::testing::StepRecording recording(engine);
    if (before_start) before_start();
    engine.AddPreStepCallback(
        [](const mjModel*, mjData* d) { d->ctrl[0] = std::sin(5 * d->time); });
    RecorderOptions o;
    o.path = dir_ + "/" + name;
    o.sensordata = sensordata;
    recording.Start(o);
    recording.Step(steps);
    return recording.Finish();
  }
  std::string dir_ = urlab::testing::MakeTempDir("recorded_model");
};

TEST_F(RecordedModelTest, ARecordingReSimulatesFromTheFileAlone) {
  PhysicsEngine engine(Compile());
  engine.SetPaused(true);
  const std::string path = RecordRun(engine, "ext.urrec", 400);
  const RecordingReader reader = RecordingReader::Open(path);
  EXPECT_EQ(reader.info().format_version, kRecordingFormatVersion);
  EXPECT_EQ(reader.info().mujoco_version, physics::MujocoVersion());
  EXPECT_EQ(reader.info().model_hash, engine.owned_model().Hash());
  EXPECT_EQ(reader.frame_count(), 400u);
  // MuJoCo computed the sensor while recording (not left at 0).
  bool sensor_moved = false;
  for (const Record& r : ReadAllRecords(reader)) {
    if (const auto* f = std::get_if<Frame>(&r))
      sensor_moved = sensor_moved || f->sensordata[0] != 0;
  }
  EXPECT_TRUE(sensor_moved);

  const ResimReport from_file = Resimulate(reader);
  EXPECT_TRUE(from_file.identical) << from_file.str();
  EXPECT_EQ(from_file.steps_checked, 400u);
  const physics::Model same = Compile();
  const ResimReport on_scene = Resimulate(reader, &same);
  EXPECT_TRUE(on_scene.identical) << on_scene.str();
  const physics::Model loaded = LoadRecordedModel(reader);
  EXPECT_EQ(loaded->body_gravcomp[mj_name2id(loaded.get(), mjOBJ_BODY, "arm")], 1.0);
  EXPECT_EQ(loaded.Hash(), reader.info().model_hash);
}

TEST_F(RecordedModelTest, AnotherGravityCompensationIsAnotherModel) {
  PhysicsEngine engine(Compile(1.0));
  engine.SetPaused(true);
  const RecordingReader reader = RecordingReader::Open(RecordRun(engine, "a.urrec", 50));
  const physics::Model half = Compile(0.5);
  try {
    Resimulate(reader, &half);
    FAIL() << "re-simulated on another model";
  } catch (const RecordingError& e) {
    EXPECT_EQ(e.reason(), RecordingError::Reason::kWrongModel);
    EXPECT_NE(std::string(e.what()).find(HashText(half.Hash())), std::string::npos) << e.what();
  }
}

TEST_F(RecordedModelTest, OptionsChangedAtRunTimeAreRecordedAndReplayed) {
  PhysicsEngine engine(Compile());
  engine.SetPaused(true);
  // As the step server's set_sim_options does while the simulation plays, before the recording
  // starts.
  const std::string path = RecordRun(engine, "options.urrec", 300, true, [&engine] {
    engine.Submit(physics::cmd::SetOptions{[](mjOption& o) { o.gravity[2] = -3; }, "low gravity"});
  });
  const RecordingReader reader = RecordingReader::Open(path);
  // The engine that made it accepts it (replay_load's check), as does a player on it.
  EXPECT_NO_THROW(CheckSameModel(reader, engine.CopyModel()));
  EXPECT_NO_THROW({ Player player(engine, reader, {}); });
  // The recorded model has the options in effect at the start.
  EXPECT_EQ(LoadRecordedModel(reader)->opt.gravity[2], -3);
  const ResimReport r = Resimulate(reader);
  EXPECT_TRUE(r.identical) << r.str();
  // A fresh model (default gravity) is the same model: the recording re-applies the options.
  const physics::Model fresh = Compile();
  const ResimReport on_fresh = Resimulate(reader, &fresh);
  EXPECT_TRUE(on_fresh.identical) << on_fresh.str();
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST_F(RecordedModelTest, FormatsOfMujoco222AndNewerOnesAreRefusedSayingWhy) {
  PhysicsEngine engine(Compile());
  engine.SetPaused(true);
  const std::string bytes = Slurp(RecordRun(engine, "now.urrec", 100, false));
  const auto refused = [&](std::uint32_t version, const std::string& expected) {
    std::string copy = bytes;
    copy[8] = static_cast<char>(version);  // the file header's version (u32, little-endian)
    const std::string path = dir_ + "/v" + std::to_string(version) + ".urrec";
    std::ofstream(path, std::ios::binary) << copy;
    try {
      RecordingReader::Open(path);
      ADD_FAILURE() << "read format " << version;
    } catch (const RecordingError& e) {
      EXPECT_EQ(e.reason(), RecordingError::Reason::kVersion);
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  };
  for (std::uint32_t v : {1u, 2u, 3u}) {
    refused(v, "recording format version " + std::to_string(v) +
                   " was written by a URLab on MuJoCo 2.2.2");
  }
  refused(kRecordingFormatVersion + 1,
          "format version " + std::to_string(kRecordingFormatVersion + 1) + " is not supported");
}

}  // namespace
}  // namespace urlab::replay
