// `urlab record` and `urlab replay` end to end: the real binary records a humanoid under PD
// control, the recording re-simulates bit for bit, exports to CSV and imports back (shuffled
// columns, short names) bit for bit, and a recorder killed with SIGKILL leaves a file that opens
// with all but the last second.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "mujoco_test.h"
#include "step_recording.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/model.h"
#include "urlab/replay/csv.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"

extern char** environ;

namespace urlab {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using testing::RunCommand;
using testing::SourcePath;
using testing::UrlabBinary;

// Writes `in` with its columns in a shuffled order.
void ShuffleColumns(const std::string& in, const std::string& out) {
  std::ifstream f(in);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(f, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    rows.push_back(cells);
  }
  std::vector<std::size_t> order(rows.front().size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  std::ofstream o(out);
  for (const auto& r : rows) {
    for (std::size_t i = 0; i < order.size(); ++i) o << (i ? "," : "") << r[order[i]];
    o << "\n";
  }
}

TEST(RecordReplayTest, RecordsReSimulatesAndRoundTripsThroughCsv) {
  const std::string dir = testing::MakeTempDir("record_replay");
  const std::string file = dir + "/h.urrec";
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " record --ports auto " +
                           SourcePath("examples/scenes/humanoid_pd.yaml") + " -o " + file +
                           " --duration 1.5 --no-network",
                       &out),
            0)
      << out;
  EXPECT_NE(out.find("recording: " + file + " steps="), std::string::npos) << out;
  ASSERT_TRUE(fs::exists(file));
  EXPECT_FALSE(fs::exists(file + ".part"));

  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --check", &out), 0) << out;
  EXPECT_NE(out.find("re-simulation identical"), std::string::npos) << out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --info", &out), 0) << out;
  EXPECT_NE(out.find("finished:    yes"), std::string::npos) << out;
  EXPECT_NE(out.find("commands:    h: "), std::string::npos) << out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --resimulate --fast", &out), 0) << out;
  EXPECT_NE(out.find("re-simulation identical"), std::string::npos) << out;
  // The .npz holds ctrl and the applied command targets beside qpos/qvel, one row per step.
  const std::string npz = dir + "/h.npz";
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --export-npz " + npz, &out), 0) << out;
  ASSERT_EQ(RunCommand("/usr/bin/python3 -c \"import numpy as n; z = n.load('" + npz +
                           "'); print(sorted(z.keys()), z['ctrl'].shape[0] == z['qpos'].shape[0] "
                           "== z['targets'].shape[0], z['targets'].shape[1] > 0)\"",
                       &out),
            0)
      << out;
  EXPECT_NE(out.find("'ctrl', 'ctrl_names', "), std::string::npos) << out;
  EXPECT_NE(out.find("'qpos', 'qpos_names', 'qvel', 'qvel_names', 'sensor_names', "
                     "'target_names', 'targets', 'time'] True True"),
            std::string::npos)
      << out;

  const std::string csv = dir + "/h.csv";
  ASSERT_EQ(
      RunCommand(UrlabBinary() + " replay " + file + " --export-csv " + csv + " --short-names",
                 &out),
      0)
      << out;
  ShuffleColumns(csv, dir + "/shuffled.csv");
  const replay::RecordingReader reader = replay::RecordingReader::Open(file);
  replay::CsvImportReport report;
  const replay::Trajectory t = replay::ImportCsv(
      dir + "/shuffled.csv", reader.info().tables,
      std::vector<double>(static_cast<std::size_t>(reader.info().tables.nq), 0), &report);
  EXPECT_TRUE(report.unmatched_columns.empty());
  EXPECT_TRUE(report.unmatched_joints.empty());
  std::vector<double> qpos, qvel;
  for (const replay::Record& r : replay::ReadAllRecords(reader)) {
    if (const auto* f = std::get_if<replay::Frame>(&r)) {
      qpos.insert(qpos.end(), f->qpos.begin(), f->qpos.end());
      qvel.insert(qvel.end(), f->qvel.begin(), f->qvel.end());
    }
  }
  EXPECT_EQ(t.rows(), reader.frame_count());
  EXPECT_EQ(t.qpos, qpos);  // bit for bit (== on doubles; no NaN here)
  EXPECT_EQ(t.qvel, qvel);
}

// How often `what` occurs in `text`.
int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++n;
  }
  return n;
}

// The simulated time of a run's last "[info] sim T s" line (0 without one).
double LastReportedSimTime(const std::string& log) {
  const std::string key = "] [info] sim ";
  const std::size_t at = log.rfind(key);
  return at == std::string::npos ? 0.0 : std::stod(log.substr(at + key.size()));
}

TEST(RecordReplayTest, KilledRecorderLeavesAFileWithAllButTheLastSecond) {
  const std::string dir = testing::MakeTempDir("record_kill");
  const std::string file = dir + "/k.urrec";
  const std::string log = dir + "/log.txt";
  const std::string cmd = "exec " + UrlabBinary() + " record --ports auto " +
                          SourcePath("examples/scenes/humanoid_pd.yaml") + " -o " + file +
                          " --no-network > " + log + " 2>&1";
  const char* argv[] = {"/bin/sh", "-c", cmd.c_str(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ), 0);
  const auto started = Clock::now();
  while (testing::ReadTextFile(log).find("recording to") == std::string::npos) {
    ASSERT_LT(Clock::now() - started, std::chrono::seconds(30)) << testing::ReadTextFile(log);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // Killed once the run reports three seconds simulated (its once-a-second "sim T s" lines): on a
  // loaded machine that takes longer, and the check below is in simulated time.
  while (Count(testing::ReadTextFile(log), "] [info] sim ") < 3) {
    ASSERT_LT(Clock::now() - started, std::chrono::seconds(120)) << testing::ReadTextFile(log);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_FALSE(fs::exists(file));  // never renamed: it did not finish
  ASSERT_TRUE(fs::exists(file + ".part"));

  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + ".part --info", &out), 0) << out;
  EXPECT_NE(out.find("finished:    NO"), std::string::npos) << out;
  const replay::RecordingReader r = replay::RecordingReader::Open(file + ".part", {true});
  EXPECT_NO_THROW(r.Verify());
  // The scene runs at real time and the recorder writes a chunk a second: the readable part
  // covers all but about the last second of what the run had simulated when it was killed (at
  // least its last reported time).
  const double covered = r.last_time() - r.first_time();
  const double reported = LastReportedSimTime(testing::ReadTextFile(log));
  RecordProperty("reported_sim_s", std::to_string(reported));
  RecordProperty("readable_s", std::to_string(covered));
  EXPECT_GT(covered, reported - 1.0 - 0.5)
      << "reported " << reported << " s simulated, readable " << covered << " s";
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + ".part --check", &out), 0) << out;
  EXPECT_NE(out.find("re-simulation identical"), std::string::npos) << out;
}

}  // namespace
}  // namespace urlab

namespace urlab {
namespace {

// A recording whose time goes back at a reset exports one segment at a time.
TEST(RecordReplayTest, ExportsOneSegmentOfARecordingWithAReset) {
  const std::string dir = testing::MakeTempDir("record_segments");
  const std::string file = dir + "/reset.urrec";
  {
    physics::PhysicsEngine engine(
        physics::CompileXmlString("<mujoco><worldbody><body><joint name='s' type='slide'/><geom "
                                  "size='.1'/></body></worldbody>"
                                  "</mujoco>"));
    testing::StepRecording recording(engine, {{}, "", ""});
    replay::RecorderOptions o;
    o.path = file;
    recording.Start(o);
    recording.Step(50);
    engine.Reset();
    recording.Step(50);
    recording.Finish();
  }
  std::string out;
  const std::string csv = dir + "/out.csv";
  EXPECT_NE(RunCommand(UrlabBinary() + " replay " + file + " --export-csv " + csv, &out), 0);
  EXPECT_NE(out.find("2 segments of increasing time; export one with --segment 1..2"),
            std::string::npos)
      << out;
  EXPECT_FALSE(fs::exists(csv));
  ASSERT_EQ(
      RunCommand(UrlabBinary() + " replay " + file + " --export-csv " + csv + " --segment 2", &out),
      0)
      << out;
  EXPECT_NE(out.find("(segment 2 of 2)"), std::string::npos) << out;
  EXPECT_NE(
      RunCommand(UrlabBinary() + " replay " + file + " --export-csv " + csv + " --segment 3", &out),
      0);
  EXPECT_NE(out.find("--segment 3: the recording has 2 segment(s)"), std::string::npos) << out;
}

}  // namespace
}  // namespace urlab
