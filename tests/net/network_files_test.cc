// NetworkFiles::NameOf: the path a user gives (the 2026 client sends it as typed, usually
// absolute) taken as a name in the files folder only when it lies directly in that folder;
// everything else keeps its refusal (docs/network.md, "Files").
#include "net/network_files.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "support/mujoco_test.h"
#include "urlab/ops/error.h"

namespace urlab::net::network_files_tests {
namespace {

namespace fs = std::filesystem;

// The code NameOf refuses `given` with ("" when it is taken).
std::string Refusal(const NetworkFiles& files, const std::string& given) {
  try {
    files.NameOf(given, "path");
  } catch (const ops::OpError& e) {
    EXPECT_NE(e.message.find("'path'"), std::string::npos) << "the field: " << e.message;
    return e.code;
  }
  return "";
}

class NetworkFilesNameOfTest : public ::testing::Test {
 protected:
  void SetUp() override { fs::create_directories(dir_); }
  const std::string root_ = urlab::testing::MakeTempDir("network_files");
  const std::string dir_ = root_ + "/files";
  NetworkFiles files_{dir_, {}};
};

TEST_F(NetworkFilesNameOfTest, AnAbsolutePathDirectlyInTheFolderIsItsName) {
  EXPECT_EQ(files_.NameOf(dir_ + "/run.urrec", "path"), "run.urrec");
  EXPECT_EQ(files_.NameOf(dir_ + "/./run.urrec", "path"), "run.urrec");
  EXPECT_EQ(files_.NameOf(dir_ + "/../files/run.urrec", "path"), "run.urrec");
  EXPECT_EQ(files_.NameOf(dir_ + "//run.urrec", "path"), "run.urrec");
  // The folder reached through a link to it: still the folder (the file is opened as
  // dir/name, never through the link).
  fs::create_directory_symlink(dir_, root_ + "/alias");
  EXPECT_EQ(files_.NameOf(root_ + "/alias/run.urrec", "path"), "run.urrec");
}

TEST_F(NetworkFilesNameOfTest, NamesAndRelativePathsPassUnchangedForPathOfToJudge) {
  EXPECT_EQ(files_.NameOf("run.urrec", "path"), "run.urrec");
  EXPECT_EQ(files_.NameOf("../run.urrec", "path"), "../run.urrec");
  EXPECT_EQ(files_.NameOf("", "path"), "");
  EXPECT_THROW(files_.PathOf(files_.NameOf("../run.urrec", "path"), "path"), ops::OpError);
}

TEST_F(NetworkFilesNameOfTest, AnAbsolutePathAnywhereElseIsRefused) {
  EXPECT_EQ(Refusal(files_, "/etc/passwd"), "bad_file_name");
  EXPECT_EQ(Refusal(files_, root_ + "/run.urrec"), "bad_file_name");     // the folder above
  EXPECT_EQ(Refusal(files_, dir_ + "/../run.urrec"), "bad_file_name");   // escapes by ..
  EXPECT_EQ(Refusal(files_, dir_ + "/sub/run.urrec"), "bad_file_name");  // a subfolder
  EXPECT_EQ(Refusal(files_, dir_ + "/"), "bad_file_name");               // the folder itself
  EXPECT_EQ(Refusal(files_, dir_), "bad_file_name");
  EXPECT_EQ(Refusal(files_, dir_ + "files"), "bad_file_name");  // a sibling sharing its start
  // A link inside the folder to a folder outside it: not the folder.
  fs::create_directories(root_ + "/elsewhere");
  fs::create_directory_symlink(root_ + "/elsewhere", dir_ + "/out");
  EXPECT_EQ(Refusal(files_, dir_ + "/out/run.urrec"), "bad_file_name");
  // A leaf that is a link out is a name in the folder here; writing and reading refuse it.
  fs::create_symlink(root_ + "/elsewhere/target", dir_ + "/link.urrec");
  EXPECT_EQ(files_.NameOf(dir_ + "/link.urrec", "path"), "link.urrec");
  try {
    files_.ForWriting("link.urrec", "path", true);
    ADD_FAILURE() << "a link written";
  } catch (const ops::OpError& e) {
    EXPECT_EQ(e.code, "path_not_writable") << e.message;
  }
  try {
    files_.ForReading("link.urrec", "path");
    ADD_FAILURE() << "a link read";
  } catch (const ops::OpError& e) {
    EXPECT_EQ(e.code, "path_not_readable") << e.message;
  }
}

}  // namespace
}  // namespace urlab::net::network_files_tests
