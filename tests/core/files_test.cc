// Input files (regular files of sane size only) and atomic outputs that never land on an input.
#include "urlab/core/files.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "mujoco_test.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(FilesTest, WriteFileAtomicLeavesTheOldFileIntactUntilTheRename) {
  const std::string dir = testing::MakeTempDir("atomic");
  const std::string path = dir + "/model.xml";
  std::ofstream(path) << "<mujoco><!-- the good old file --></mujoco>\n";
  const std::string old_text = testing::ReadTextFile(path);
  const std::string new_text(1 << 20, 'x');  // 1 MiB
  bool checked = false;
  WriteFileAtomic(path, new_text, [&](const std::string& temp) {
    // Everything is written, nothing renamed: the target is still the old file.
    EXPECT_EQ(testing::ReadTextFile(path), old_text);
    EXPECT_EQ(testing::ReadTextFile(temp), new_text);
    EXPECT_EQ(fs::path(temp).parent_path(), fs::path(path).parent_path());
    checked = true;
  });
  EXPECT_TRUE(checked);
  EXPECT_EQ(testing::ReadTextFile(path), new_text);
  // No temporary is left behind.
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) entries += e.is_regular_file();
  EXPECT_EQ(entries, 1);
}

TEST(FilesTest, AKillDuringTheWriteCannotTruncateAGoodFile) {
  const std::string dir = testing::MakeTempDir("atomic_kill");
  const std::string path = dir + "/scene_compiled.xml";
  std::ofstream(path) << "<mujoco model=\"good\"/>\n";
  const std::string old_text = testing::ReadTextFile(path);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // The child is killed at the worst moment: the whole new text written, not yet renamed.
    WriteFileAtomic(path, std::string(4 << 20, 'y'),
                    [](const std::string&) { ::kill(::getpid(), SIGKILL); });
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  EXPECT_EQ(testing::ReadTextFile(path), old_text);
}

TEST(FilesTest, WriteFileAtomicCreatesMissingFoldersAndKeepsTheUsualMode) {
  const std::string dir = testing::MakeTempDir("atomic_dirs");
  const std::string path = dir + "/a/b/c/out.mjb";
  WriteFileAtomic(path, "bytes");
  EXPECT_EQ(testing::ReadTextFile(path), "bytes");
  struct stat st;
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  const mode_t mask = ::umask(0);
  ::umask(mask);
  EXPECT_EQ(st.st_mode & 0777, 0666 & ~mask);
  // A folder is not a file to write.
  EXPECT_NE(ErrorOf([&] { WriteFileAtomic(dir + "/a", "x"); }).find("folder"), std::string::npos);
}

TEST(FilesTest, OutputsNeverOverwriteAnInput) {
  const std::string dir = testing::MakeTempDir("no_overwrite");
  const std::string in = testing::WriteTextFile(dir, "a.xml", "<mujoco/>");
  const std::string inc = testing::WriteTextFile(dir, "parts/inc.xml", "<mujoco/>");
  fs::create_symlink(in, dir + "/link.xml");
  const std::vector<std::string> inputs = {in, inc};
  for (const std::string& out :
       {in, dir + "/./a.xml", dir + "/parts/../a.xml", dir + "/link.xml", inc}) {
    const std::string e = ErrorOf([&] { RefuseOverwritingInput(out, inputs, "-o"); });
    EXPECT_NE(e.find("would overwrite"), std::string::npos) << out << ": " << e;
  }
  EXPECT_NO_THROW(RefuseOverwritingInput(dir + "/b.xml", inputs, "-o"));  // does not exist
  testing::WriteTextFile(dir, "c.xml", "<mujoco/>");
  EXPECT_NO_THROW(RefuseOverwritingInput(dir + "/c.xml", inputs, "-o"));  // another file
}

TEST(FilesTest, InputsMustBeRegularFilesOfSaneSize) {
  const std::string dir = testing::MakeTempDir("inputs");
  const std::string fifo = dir + "/pipe.xml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Refused before opening (opening a FIFO would block).
  EXPECT_NE(ErrorOf([&] { ReadInputFile(fifo, "model file"); }).find("FIFO"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadInputFile("/dev/zero", "model file"); }).find("a device"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadInputFile(dir, "scene file"); }).find("a folder"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadInputFile(dir + "/nope.xml", "model file"); }).find("not found"),
            std::string::npos);
  // Absurdly large: refused from its size, without reading it (a sparse file).
  const std::string big = dir + "/big.xml";
  std::ofstream(big) << "<mujoco/>";
  fs::resize_file(big, kMaxTextInputBytes + 1);
  const std::string e = ErrorOf([&] { ReadInputFile(big, "model file"); });
  EXPECT_NE(e.find("larger than the 64 MiB"), std::string::npos) << e;
  // Located at the place that named the file when given.
  try {
    CheckInputFile(fifo, "include file", {"main.xml", 4});
    FAIL();
  } catch (const InputError& err) {
    EXPECT_EQ(err.where().file, "main.xml");
    EXPECT_EQ(err.where().line, 4);
  }
  EXPECT_EQ(ReadInputFile(big, "model file", {}, kMaxTextInputBytes + 1).size(),
            kMaxTextInputBytes + 1);
}

}  // namespace
}  // namespace urlab
