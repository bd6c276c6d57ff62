#include "mujoco_test.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace urlab::testing {

namespace {
struct HandlerInstaller {
  HandlerInstaller() { InstallMujocoHandlers(); }
};
const HandlerInstaller kInstaller;
}  // namespace

MujocoTest::MujocoTest() { InstallMujocoHandlers(); }

void MujocoTest::ExpectWarning(const std::string& substring) { expected_.push_back(substring); }

std::vector<std::string> MujocoTest::SeenWarnings() {
  for (auto& w : capture_.Take()) seen_.push_back(std::move(w));
  return seen_;
}

std::vector<std::string> MujocoTest::TakeWarnings() {
  std::vector<std::string> out = SeenWarnings();
  seen_.clear();
  return out;
}

void MujocoTest::TearDown() {
  const std::vector<std::string> seen = SeenWarnings();
  for (const std::string& w : seen) {
    bool ok = false;
    for (const std::string& e : expected_) ok = ok || w.find(e) != std::string::npos;
    EXPECT_TRUE(ok) << "unexpected MuJoCo warning: " << w;
  }
  for (const std::string& e : expected_) {
    bool found = false;
    for (const std::string& w : seen) found = found || w.find(e) != std::string::npos;
    EXPECT_TRUE(found) << "expected a MuJoCo warning containing '" << e << "'";
  }
}

std::string TestData(const std::string& relative) {
  return std::string(URLAB_TEST_DATA_DIR) + "/" + relative;
}

std::string SourcePath(const std::string& relative) {
  return std::string(URLAB_SOURCE_DIR) + "/" + relative;
}

std::string UrlabBinary() { return URLAB_BINARY; }

std::string XvfbRun(const std::string& screen) {
  // Xvfb picks a free display number itself (xvfb-run -a can hand two runs started together one
  // server, whose end then takes the other's display away).
  return SourcePath("tests/support/with_xvfb.sh") + " " + screen + " ";
}

int RunCommand(const std::string& command, std::string* output) {
  std::string full = command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buf;
  std::string out;
  while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string WriteTextFile(const std::string& dir, const std::string& rel, const std::string& text) {
  const std::filesystem::path p = std::filesystem::path(dir) / rel;
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p.string();
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string MakeTempDir(const std::string& tag) {
  namespace fs = std::filesystem;
  std::string templ = (fs::temp_directory_path() / ("urlab_" + tag + "_XXXXXX")).string();
  char* made = mkdtemp(templ.data());
  if (!made) throw std::runtime_error("mkdtemp failed for " + templ);
  static std::vector<std::string> to_remove;
  static const struct Cleaner {
    ~Cleaner() {
      std::error_code ec;
      for (const auto& d : to_remove) std::filesystem::remove_all(d, ec);
    }
  } cleaner;
  to_remove.push_back(made);
  return made;
}

}  // namespace urlab::testing
