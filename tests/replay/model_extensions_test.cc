// Recordings carry the model with its extensions (physics/model.h) and hash both: a recording of
// a model with software sensors and passive forces re-simulates bit for bit from the file alone;
// a model whose extensions differ is "another model"; a recording started after the physics
// options changed at run time is accepted by the engine that made it and replays those options;
// format 1 files (no extensions section) are still read; other versions are refused by number.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

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

// An arm held up by gravity compensation, a ball hanging from a dead-band rope spring, and a
// joint actuator force sensor (3.x constructs the runtime computes for 2.2.2).
constexpr const char* kExtensionsXml = R"(<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <site name="anchor" pos="0 0 2"/>
    <body name="arm" pos="1 0 1">
      <joint name="h" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05" mass="1"/>
    </body>
    <body name="ball" pos="0 0 1">
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom size="0.1" mass="2"/>
      <site name="top" pos="0 0 0.1"/>
    </body>
  </worldbody>
  <tendon>
    <spatial name="rope"><site site="anchor"/><site site="top"/></spatial>
  </tendon>
  <actuator>
    <motor name="m" joint="h" gear="2"/>
  </actuator>
  <sensor>
    <user name="h_force" objtype="joint" objname="h" datatype="real" needstage="acc" dim="1"/>
  </sensor>
</mujoco>)";

physics::Model Compile(double gravcomp = 1.0) {
  physics::SoftwareModelSpec e;
  e.sensors = {{"h_force", physics::SoftwareSensorKind::kJointActuatorForce, {}}};
  e.gravcomp = {{"arm", gravcomp}};
  e.deadband_springs = {{"rope", 200, 0.8, 0.95}};
  return physics::Model(physics::CompileXmlString(kExtensionsXml), std::move(e));
}

class ModelExtensionsTest : public urlab::testing::MujocoTest {
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
  std::string dir_ = urlab::testing::MakeTempDir("model_extensions");
};

TEST_F(ModelExtensionsTest, ARecordingReSimulatesWithItsExtensionsFromTheFileAlone) {
  PhysicsEngine engine(Compile());
  engine.SetPaused(true);
  const std::string path = RecordRun(engine, "ext.urrec", 400);
  const RecordingReader reader = RecordingReader::Open(path);
  EXPECT_EQ(reader.info().format_version, kRecordingFormatVersion);
  EXPECT_EQ(reader.info().extensions, engine.owned_model().extension_text());
  EXPECT_EQ(reader.info().model_hash, engine.owned_model().Hash());
  EXPECT_EQ(reader.frame_count(), 400u);
  // The software sensor was computed while recording (not left at 0).
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
  // The loaded model carries them.
  const physics::Model loaded = LoadRecordedModel(reader);
  EXPECT_EQ(loaded.extensions().gravcomp.size(), 1u);
  EXPECT_EQ(loaded.Hash(), reader.info().model_hash);
}

TEST_F(ModelExtensionsTest, OtherExtensionsAreAnotherModel) {
  PhysicsEngine engine(Compile(1.0));
  engine.SetPaused(true);
  const RecordingReader reader = RecordingReader::Open(RecordRun(engine, "a.urrec", 50));
  const physics::Model half = Compile(0.5);  // the same MJB, other gravity compensation
  try {
    Resimulate(reader, &half);
    FAIL() << "re-simulated on another model";
  } catch (const RecordingError& e) {
    EXPECT_EQ(e.reason(), RecordingError::Reason::kWrongModel);
    EXPECT_NE(std::string(e.what()).find(HashText(half.Hash())), std::string::npos) << e.what();
  }
}

TEST_F(ModelExtensionsTest, OptionsChangedAtRunTimeAreRecordedAndReplayed) {
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

// Rewrites a recording of a model without extensions as format 1 wrote it: file header version
// 1, the header chunk without the extensions section, the data and end chunks as they are.
std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string AsFormat1(const std::string& path, const std::string& out) {
  const std::string bytes = Slurp(path);
  format::ChunkHeader h;
  EXPECT_TRUE(format::DecodeChunkHeader(
      std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()) + format::kFileHeaderSize,
                format::kChunkHeaderSize),
      &h));
  const std::size_t rest = format::kFileHeaderSize + format::kChunkHeaderSize + h.stored_size;
  const RecordingInfo info = RecordingReader::Open(path).info();
  EXPECT_TRUE(info.extensions.empty());
  std::string payload = format::EncodeInfo(info);
  payload.resize(payload.size() - 8);  // the empty extensions section: its length only
  const std::string key = "\"format_version\":" + std::to_string(kRecordingFormatVersion);
  const std::size_t at = payload.find(key);
  EXPECT_NE(at, std::string::npos);
  payload.replace(at, key.size(), "\"format_version\":1");
  std::string file = format::FileHeader();
  file[8] = 1;  // version 1 (u32, little-endian)
  format::ChunkHeader header;
  header.kind = format::ChunkKind::kHeader;
  header.raw_size = payload.size();
  file += format::EncodeChunk(header, payload) + bytes.substr(rest);
  std::ofstream(out, std::ios::binary) << file;
  return out;
}

TEST_F(ModelExtensionsTest, Format1RecordingsAreStillReadAndOthersRefusedByVersion) {
  PhysicsEngine engine(
      physics::CompileXmlString(kExtensionsXml));  // no extensions, as format 1 knew
  engine.SetPaused(true);
  const std::string now = RecordRun(engine, "now.urrec", 100, false);
  const std::string v1 = AsFormat1(now, dir_ + "/v1.urrec");
  const RecordingReader reader = RecordingReader::Open(v1);
  EXPECT_EQ(reader.info().format_version, 1u);
  EXPECT_EQ(reader.info().model_hash, RecordingReader::Open(now).info().model_hash);
  const ResimReport r = Resimulate(reader);
  EXPECT_TRUE(r.identical) << r.str();

  std::string bytes = Slurp(now);
  const std::uint32_t next = kRecordingFormatVersion + 1;
  bytes[8] = static_cast<char>(next);
  const std::string newer = dir_ + "/newer.urrec";
  std::ofstream(newer, std::ios::binary) << bytes;
  try {
    RecordingReader::Open(newer);
    FAIL() << "read a format this build does not know";
  } catch (const RecordingError& e) {
    EXPECT_EQ(e.reason(), RecordingError::Reason::kVersion);
    EXPECT_NE(std::string(e.what()).find("format version " + std::to_string(next)),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace urlab::replay
