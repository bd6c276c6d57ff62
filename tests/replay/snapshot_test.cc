// Snapshots: one state in a recording-format file, restored bit for bit on its own model only.
#include "urlab/replay/snapshot.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {
namespace {

namespace fs = std::filesystem;

class SnapshotTest : public urlab::testing::MujocoTest {
 protected:
  void SetUp() override {
    model_ = physics::CompileXmlString(urlab::testing::kArmXml);
    data_ = physics::MakeData(model_.get());
    DescribeModel(model_, &info_);
    info_.tables = ModelTables::Of(model_.get(), {"arm"});
    // A state worth saving: moving, actuated, with a mocap body moved and forces applied.
    mjData* d = data_.get();
    mj_resetDataKeyframe(model_.get(), d, 1);
    for (int i = 0; i < model_->nu; ++i) d->ctrl[i] = 0.3 * (i + 1);
    d->mocap_pos[0] = 0.25;
    d->qfrc_applied[0] = 0.1;
    for (int i = 0; i < 200; ++i) mj_step(model_.get(), d);
  }
  // Steps `d` n times and returns its state.
  physics::PhysicsState Continue(mjData* d, int n) {
    for (int i = 0; i < n; ++i) mj_step(model_.get(), d);
    return physics::CaptureState(model_.get(), d);
  }

  std::string dir_ = urlab::testing::MakeTempDir("snapshot");
  physics::Model model_;
  physics::DataPtr data_;
  RecordingInfo info_;
};

TEST_F(SnapshotTest, RoundTripIsBitForBitAndContinuesLikeTheOriginal) {
  const std::string path = dir_ + "/state.urrec";
  const physics::PhysicsState saved = physics::CaptureState(model_.get(), data_.get());
  SaveSnapshot(path, info_, saved);
  EXPECT_FALSE(fs::exists(path + ".part"));
  const RecordingReader reader = RecordingReader::Open(path);
  EXPECT_EQ(reader.info().kind, "snapshot");
  EXPECT_TRUE(reader.finished());

  const physics::PhysicsState loaded = LoadSnapshot(path, model_);
  EXPECT_TRUE(loaded.BitwiseEquals(saved));

  physics::DataPtr other = physics::MakeData(model_.get());
  physics::RestoreState(model_.get(), other.get(), loaded);
  const physics::PhysicsState original = Continue(data_.get(), 300);
  const physics::PhysicsState resumed = Continue(other.get(), 300);
  EXPECT_TRUE(resumed.BitwiseEquals(original));
  EXPECT_GT(resumed.time, saved.time);
}

TEST_F(SnapshotTest, AnotherModelIsRefusedNamingBothHashes) {
  const std::string path = dir_ + "/state.urrec";
  SaveSnapshot(path, info_, physics::CaptureState(model_.get(), data_.get()));
  std::string xml = urlab::testing::kArmXml;
  xml.replace(xml.find("timestep=\"0.002\""), 16, "timestep=\"0.001\"");
  const physics::Model other = physics::CompileXmlString(xml);
  try {
    LoadSnapshot(path, other);
    FAIL() << "loaded on another model";
  } catch (const RecordingError& e) {
    EXPECT_EQ(e.reason(), RecordingError::Reason::kWrongModel);
    const std::string what = e.what();
    EXPECT_NE(what.find(HashText(info_.model_hash)), std::string::npos) << what;
    EXPECT_NE(what.find(HashText(other.Hash())), std::string::npos) << what;
  }
}

TEST_F(SnapshotTest, ARecordingIsNotASnapshot) {
  const std::string path = dir_ + "/run.urrec";
  WriteRecording(path, info_,
                 {{Record{StateRecord{0, physics::CaptureState(model_.get(), data_.get())}}}});
  try {
    LoadSnapshot(path, model_);
    FAIL() << "a recording loaded as a snapshot";
  } catch (const RecordingError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not a snapshot"), std::string::npos) << what;
    EXPECT_NE(what.find(path), std::string::npos) << what;
  }
}

TEST_F(SnapshotTest, ATruncatedFileIsRefused) {
  const std::string path = dir_ + "/state.urrec";
  SaveSnapshot(path, info_, physics::CaptureState(model_.get(), data_.get()));
  fs::resize_file(path, fs::file_size(path) - 40);
  EXPECT_THROW(LoadSnapshot(path, model_), RecordingError);
  fs::resize_file(path, 10);
  EXPECT_THROW(LoadSnapshot(path, model_), RecordingError);
  EXPECT_THROW(LoadSnapshot(dir_ + "/missing.urrec", model_), Error);
}

}  // namespace
}  // namespace urlab::replay
