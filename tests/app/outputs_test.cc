// The output rule from the command line, with the real binary: devices and FIFOs written in place
// (never replaced), symlinks followed, folders and crashed recordings refused; a recording that
// fails, a closed pipe, a failed ffmpeg and an empty output name are errors with the right exit
// code; several outputs are written all or none; global options may follow the subcommand.
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "mujoco_test.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::SourcePath;
using testing::UrlabBinary;
using testing::XvfbRun;

// A device node like /dev/null (1,3) or /dev/full (1,7) in `dir` (so that a wrong rename replaces
// ours, not the system's), or the system's when we may not make one.
std::string DeviceNode(const std::string& dir, const std::string& name, unsigned minor) {
  const std::string path = dir + "/" + name;
  if (::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, minor)) == 0) return path;
  return "/dev/" + name;
}

bool IsCharDevice(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

// `urlab record` of the small pendulum model, headless, for `seconds` of wall time.
std::string Record(const std::string& output, double seconds = 0.5) {
  return UrlabBinary() + " record --ports auto " + SourcePath("examples/models/pendulum_arm.xml") +
         " -o " + output + " --duration " + std::to_string(seconds) + " --no-network --no-cameras";
}

TEST(OutputsCli, RecordToDevicesWritesInPlaceAndReportsAFullOne) {
  const std::string dir = testing::MakeTempDir("cli_out_dev");
  const std::string null = DeviceNode(dir, "null", 3);
  std::string out;
  EXPECT_EQ(RunCommand(Record(null), &out), 0) << out;
  EXPECT_TRUE(IsCharDevice(null)) << null << " was replaced";
  EXPECT_FALSE(fs::exists(null + ".part"));
  const std::string full = DeviceNode(dir, "full", 7);
  EXPECT_EQ(RunCommand(Record(full), &out), 1) << out;
  EXPECT_NE(out.find("No space left on device"), std::string::npos) << out;
  EXPECT_TRUE(IsCharDevice(full)) << full << " was replaced";
  EXPECT_FALSE(fs::exists(full + ".part"));
}

TEST(OutputsCli, RecordToAFolderIsAnErrorThatStrandsNothing) {
  const std::string dir = testing::MakeTempDir("cli_out_folder");
  fs::create_directories(dir + "/run.urrec");
  std::string out;
  EXPECT_EQ(RunCommand(Record(dir + "/run.urrec"), &out), 1) << out;
  EXPECT_NE(out.find("folder"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir + "/run.urrec.part"));
  EXPECT_TRUE(fs::is_directory(dir + "/run.urrec"));
}

TEST(OutputsCli, ACrashedRecordingIsNeverOverwritten) {
  const std::string dir = testing::MakeTempDir("cli_out_part");
  const std::string file = dir + "/run.urrec";
  const std::string part = testing::WriteTextFile(dir, "run.urrec.part", "crashed recording");
  std::string out;
  EXPECT_EQ(RunCommand(Record(file), &out), 1) << out;
  EXPECT_NE(out.find("urlab replay " + part), std::string::npos) << out;
  EXPECT_EQ(testing::ReadTextFile(part), "crashed recording");
  EXPECT_FALSE(fs::exists(file));
}

TEST(OutputsCli, RecordAndExportThroughSymlinks) {
  const std::string dir = testing::MakeTempDir("cli_out_link");
  fs::create_directories(dir + "/store");
  fs::create_symlink(dir + "/store/run.urrec", dir + "/latest.urrec");  // dangling until written
  std::string out;
  ASSERT_EQ(RunCommand(Record(dir + "/latest.urrec"), &out), 0) << out;
  EXPECT_TRUE(fs::is_symlink(dir + "/latest.urrec"));
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + dir + "/store/run.urrec --info", &out), 0)
      << out;
  EXPECT_NE(out.find("finished:    yes"), std::string::npos) << out;
  // --export-csv /dev/stdout writes to standard output (a pipe here), not over the link.
  ASSERT_EQ(
      RunCommand(UrlabBinary() + " replay " + dir + "/latest.urrec --export-csv /dev/stdout", &out),
      0)
      << out;
  EXPECT_EQ(out.rfind("time,", 0), 0u) << out.substr(0, 400);
  EXPECT_TRUE(fs::is_symlink("/dev/stdout"));
  // ... and through the shell's redirection into a file, with the summary after it.
  const std::string csv = dir + "/out.csv";
  ASSERT_EQ(RunCommand(UrlabBinary() + " --log-level off replay " + dir +
                           "/latest.urrec --export-csv /dev/stdout > " + csv,
                       &out),
            0)
      << out;
  const std::string text = testing::ReadTextFile(csv);
  EXPECT_EQ(text.rfind("time,", 0), 0u) << text.substr(0, 200);
  EXPECT_NE(text.find("wrote /dev/stdout: "), std::string::npos);
}

TEST(OutputsCli, ARecordingThatRunsOutOfSpaceExitsOneAndKeepsThePart) {
  const std::string dir = testing::MakeTempDir("cli_out_fsize");
  std::string out;
  ASSERT_EQ(RunCommand(Record(dir + "/short.urrec", 0.3), &out), 0) << out;
  // A file size limit just above the header: the first chunks do not fit (EFBIG, which the
  // kernel signals with SIGXFSZ unless it is ignored).
  const auto limit = fs::file_size(dir + "/short.urrec") + 1;
  const std::string file = dir + "/long.urrec";
  const int code =
      RunCommand("prlimit --fsize=" + std::to_string(limit) + " " + Record(file, 4), &out);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("File too large"), std::string::npos) << out;
  EXPECT_NE(out.find("kept in " + file + ".part"), std::string::npos) << out;
  EXPECT_NE(out.find("recording: " + file), std::string::npos) << out;
  ASSERT_TRUE(fs::exists(file + ".part"));
  EXPECT_FALSE(fs::exists(file));
  // What was kept opens (up to its last whole chunk).
  EXPECT_EQ(RunCommand(UrlabBinary() + " replay " + file + ".part --info", &out), 0) << out;
}

TEST(OutputsCli, AClosedPipeDoesNotKillARecording) {
  const std::string dir = testing::MakeTempDir("cli_out_pipe");
  const std::string file = dir + "/piped.urrec";
  std::string out;
  // `head -1` closes the pipe after the first log line; the recording goes on to its end.
  ASSERT_EQ(RunCommand("bash -c '" + Record(file, 2) +
                           " 2>&1 | head -1; echo \"urlab exit ${PIPESTATUS[0]}\"'",
                       &out),
            0)
      << out;
  // Not killed by SIGPIPE (141); its printed summary was lost, an ordinary error (exit 1).
  EXPECT_NE(out.find("urlab exit 1"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(file)) << out;
  EXPECT_FALSE(fs::exists(file + ".part"));
  ASSERT_EQ(RunCommand(UrlabBinary() + " replay " + file + " --info", &out), 0) << out;
  EXPECT_NE(out.find("finished:    yes"), std::string::npos) << out;
}

TEST(OutputsCli, CompileWritesBothOutputsOrNeither) {
  const std::string dir = testing::MakeTempDir("cli_out_staged");
  const std::string model = SourcePath("examples/models/pendulum_arm.xml");
  fs::create_directories(dir + "/taken.mjb");
  std::string out;
  EXPECT_EQ(RunCommand(UrlabBinary() + " compile " + model + " --save-xml " + dir +
                           "/model.xml --save-mjb " + dir + "/taken.mjb",
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("taken.mjb"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir + "/model.xml")) << "--save-xml was written without --save-mjb";
  // An empty output name is a usage error, not a silent "no output".
  for (const char* option : {"--save-xml", "--save-mjb"}) {
    const int code = RunCommand(UrlabBinary() + " compile " + model + " " + option + " \"\"", &out);
    EXPECT_GE(code, 105) << option << out;
    EXPECT_LE(code, 109) << option << out;
    EXPECT_NE(out.find("may not be empty"), std::string::npos) << out;
  }
  EXPECT_NE(RunCommand(Record("\"\""), &out), 0);
  EXPECT_NE(out.find("may not be empty"), std::string::npos) << out;
  // Both good: both written.
  ASSERT_EQ(RunCommand(UrlabBinary() + " compile " + model + " --save-xml " + dir +
                           "/model.xml --save-mjb " + dir + "/model.mjb",
                       &out),
            0)
      << out;
  EXPECT_TRUE(fs::exists(dir + "/model.xml"));
  EXPECT_TRUE(fs::exists(dir + "/model.mjb"));
}

TEST(OutputsCli, GlobalOptionsMayFollowTheSubcommand) {
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " compile --json " +
                           SourcePath("examples/models/pendulum_arm.xml") + " --log-level off",
                       &out),
            0)
      << out;
  EXPECT_TRUE(nlohmann::json::accept(out)) << out;  // no log line mixed in
  ASSERT_EQ(RunCommand(UrlabBinary() + " mjcf roundtrip " +
                           SourcePath("examples/models/pendulum_arm.xml") +
                           " -o /dev/null --log-level warn",
                       &out),
            0)
      << out;
  EXPECT_EQ(out, "");
}

TEST(OutputsCli, AFailedCameraVideoExitsOne) {
  const std::string dir = testing::MakeTempDir("cli_out_video");
  testing::WriteTextFile(dir, "file.txt", "not a folder");
  const std::string video = dir + "/file.txt/wrist.mp4";  // ffmpeg cannot create it
  std::string out;
  EXPECT_EQ(RunCommand(UrlabBinary() + " record --ports auto " +
                           testing::TestData("cameras/two_cameras.yaml") +
                           " --no-network --duration 1 --video rig/wrist " + video,
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("urlab: error: video " + video + ": ffmpeg failed"), std::string::npos) << out;
  EXPECT_NE(out.find("nothing was kept"), std::string::npos) << out;
}

TEST(OutputsCli, AFailedViewerVideoExitsOne) {
  if (RunCommand("command -v Xvfb", nullptr) != 0) GTEST_SKIP() << "no Xvfb";
  const std::string dir = testing::MakeTempDir("cli_out_view_video");
  testing::WriteTextFile(dir, "file.txt", "not a folder");
  const std::string video = dir + "/file.txt/window.mp4";
  std::string out;
  EXPECT_EQ(RunCommand(XvfbRun("1280x1024x24") + UrlabBinary() + " view " +
                           SourcePath("examples/models/pendulum_arm.xml") +
                           " --no-network --no-cameras --duration 1 --width 160 --height 120 "
                           "--video " +
                           video,
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("urlab: error: video " + video + ": ffmpeg failed"), std::string::npos) << out;
}

}  // namespace
}  // namespace urlab
