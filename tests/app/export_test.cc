// `urlab record --sensordata` then `urlab replay --export-npz/--export-csv` end to end: both
// exports carry names and the recorded sensor values, numpy and Python's csv module read them back,
// the values match the recorded state, and the counts agree with the run's summary.
#include <filesystem>
#include <regex>
#include <string>

#include "mujoco_test.h"
#include "urlab/replay/csv.h"
#include "urlab/replay/recording.h"

namespace urlab {
namespace {

using testing::RunCommand;
using testing::UrlabBinary;

constexpr char kArm[] = R"(<mujoco model="arm">
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" range="-1.5 1.5" limited="true" damping="1"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <body name="lower" pos="0.5 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="1"/>
        <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
        <site name="tip" pos="0.4 0 0"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="shoulder_motor" joint="shoulder" gear="40" ctrlrange="-1 1" ctrllimited="true"/>
    <motor name="elbow_motor" joint="elbow" gear="20" ctrlrange="-1 1" ctrllimited="true"/>
  </actuator>
  <sensor>
    <jointpos name="shoulder_pos" joint="shoulder"/>
    <framepos name="tip_pos" objtype="site" objname="tip"/>
  </sensor>
  <keyframe>
    <key name="raised" qpos="0.8 -0.4"/>
  </keyframe>
</mujoco>
)";

constexpr char kScene[] = R"(articulations:
  - name: arm
    mjcf: arm.xml
    controller: {type: pd, kp: 300, kv: 10}
    keyframe: raised
)";

// Reads the exports with numpy and csv, checks names and sensor values against the state, and
// prints "rows N".
constexpr char kReadBack[] = R"(import csv, sys
import numpy as np
npz, csv_path = sys.argv[1], sys.argv[2]
z = np.load(npz, allow_pickle=False)
for k in ["time", "qpos", "qvel", "ctrl", "targets", "sensordata", "qpos_names", "qvel_names",
          "ctrl_names", "target_names", "sensor_names", "joint_names", "articulations"]:
    assert k in z.files, (k, z.files)
assert list(z["qpos_names"]) == ["arm/shoulder", "arm/elbow"], z["qpos_names"]
assert list(z["ctrl_names"]) == ["arm/shoulder_motor", "arm/elbow_motor"], z["ctrl_names"]
assert list(z["target_names"]) == list(z["ctrl_names"]), z["target_names"]
assert list(z["sensor_names"]) == ["arm/shoulder_pos", "arm/tip_pos[0]", "arm/tip_pos[1]",
                                   "arm/tip_pos[2]"], z["sensor_names"]
assert list(z["articulations"]) == ["arm"] and list(z["joint_names"]) == ["shoulder", "elbow"]
rows = z["time"].shape[0]
assert rows > 100 and z["sensordata"].shape == (rows, 4), z["sensordata"].shape
# mj_step computes sensors before it integrates: a row's jointpos is the previous row's qpos.
assert np.array_equal(z["sensordata"][1:, 0], z["qpos"][:-1, 0]), "sensor != qpos"
with open(csv_path, newline="") as f:
    table = list(csv.reader(f))
header, body = table[0], table[1:]
assert len(body) == rows, (len(body), rows)
for name in ["arm_shoulder", "sensor:arm_shoulder_pos", "sensor:arm_tip_pos[2]"]:
    assert name in header, (name, header)
sensor = np.array([float(r[header.index("sensor:arm_shoulder_pos")]) for r in body])
assert np.array_equal(sensor, z["sensordata"][:, 0]), "CSV sensor column != NPZ sensordata"
tip_z = np.array([float(r[header.index("sensor:arm_tip_pos[2]")]) for r in body])
assert np.array_equal(tip_z, z["sensordata"][:, 3])
print("rows", rows)
)";

TEST(ExportTest, NpzAndCsvCarryNamesAndSensorDataAndCountsMatchTheRun) {
  const std::string dir = testing::MakeTempDir("export");
  testing::WriteTextFile(dir, "arm.xml", kArm);
  const std::string scene = testing::WriteTextFile(dir, "scene.yaml", kScene);
  const std::string file = dir + "/arm.urrec";
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " record --ports auto " + scene + " -o " + file +
                           " --duration 1 --no-network --sensordata",
                       &out),
            0)
      << out;
  // The run's summary and the recording agree on the steps.
  std::smatch rec, sum;
  ASSERT_TRUE(std::regex_search(
      out, rec, std::regex(R"(recording: \S+ steps=(\d+) .*bytes=(\d+) \(([0-9.]+) )")))
      << out;
  ASSERT_TRUE(std::regex_search(out, sum, std::regex(R"(summary: \S+ s steps=(\d+))"))) << out;
  EXPECT_EQ(rec[1], sum[1]) << out;
  const std::string steps = rec[1];
  const double per_step = std::stod(rec[3]);
  const double file_bytes = std::stod(rec[2]);  // `out` is reused below: copy the matches
  // --info agrees on the steps and on the bytes per step of the data chunks (the run's figure
  // leaves the embedded model out, as --info does).
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --info", &out), 0) << out;
  EXPECT_NE(out.find("content:     " + steps + " steps"), std::string::npos) << out;
  std::smatch info;
  ASSERT_TRUE(std::regex_search(out, info, std::regex(R"(size:\s+([0-9.]+) bytes per step)")))
      << out;
  // (the run's figure counts each chunk's header too: within 2 %); the old figure, the file's
  // bytes per step, is larger by the model.
  EXPECT_NEAR(per_step, std::stod(info[1]), 0.02 * std::stod(info[1])) << out;
  EXPECT_GT(file_bytes / std::stod(steps), per_step + 1) << out;

  const std::string npz = dir + "/arm.npz", csv = dir + "/arm.csv";
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --export-npz " + npz, &out), 0) << out;
  EXPECT_NE(out.find("wrote " + npz + ": " + steps + " rows"), std::string::npos) << out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --export-csv " + csv, &out), 0) << out;
  const std::string script = testing::WriteTextFile(dir, "read_back.py", kReadBack);
  ASSERT_EQ(RunCommand("/usr/bin/python3 " + script + " " + npz + " " + csv, &out), 0) << out;
  EXPECT_NE(out.find("rows " + steps), std::string::npos) << out;

  // Our own CSV reader takes the file back: sensor columns are not state, and are skipped.
  const replay::RecordingReader reader = replay::RecordingReader::Open(file);
  replay::CsvImportReport report;
  const replay::Trajectory t = replay::ImportCsv(
      csv, reader.info().tables,
      std::vector<double>(static_cast<std::size_t>(reader.info().tables.nq), 0), &report);
  EXPECT_TRUE(report.unmatched_columns.empty());
  EXPECT_EQ(t.rows(), reader.frame_count());
}

}  // namespace
}  // namespace urlab
