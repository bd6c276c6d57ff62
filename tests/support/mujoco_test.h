#pragma once
// Test fixture for everything that touches MuJoCo: installs URLab's MuJoCo handlers and fails the
// test on any MuJoCo warning it did not declare with ExpectWarning().
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "urlab/core/mujoco_handlers.h"

namespace urlab::testing {

class MujocoTest : public ::testing::Test {
 protected:
  MujocoTest();
  void TearDown() override;

  // Declares that a warning containing `substring` is expected (at least once) in this test.
  void ExpectWarning(const std::string& substring);

  // Warnings seen so far in this test (also consumed by TearDown's check).
  std::vector<std::string> SeenWarnings();

  // Returns the warnings seen so far and forgets them (for warnings the test checks itself).
  std::vector<std::string> TakeWarnings();

 private:
  WarningCapture capture_;
  std::vector<std::string> seen_;
  std::vector<std::string> expected_;
};

// Absolute path of a file under tests/data.
std::string TestData(const std::string& relative);
// Absolute path of a file in the source tree.
std::string SourcePath(const std::string& relative);
// Path of the built `urlab` binary.
std::string UrlabBinary();
// "tests/support/with_xvfb.sh SCREEN ": a private virtual display for one command (SCREEN as
// WxHxDEPTH), whose number the server picks itself, so tests running at once never share one.
std::string XvfbRun(const std::string& screen);
// Runs a shell command, returns its exit code; stdout+stderr go to *output when given.
int RunCommand(const std::string& command, std::string* output = nullptr);
// A fresh empty temporary directory, removed when the process exits normally.
std::string MakeTempDir(const std::string& tag);
// Writes `text` to dir/rel (creating folders); returns the file's path.
std::string WriteTextFile(const std::string& dir, const std::string& rel, const std::string& text);
// The whole file's bytes ("" when it cannot be read, e.g. not yet written).
std::string ReadTextFile(const std::string& path);

}  // namespace urlab::testing
