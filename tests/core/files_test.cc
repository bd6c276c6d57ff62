// Input files (regular files of sane size only) and the output rule: atomic replacement of
// regular files, in-place writes to devices and FIFOs, symlinks followed, folders refused, crash
// files never truncated, several outputs all or none.
#include "urlab/core/files.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

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

// A device node like /dev/null (1,3) or /dev/full (1,7) in `dir`, so that a wrong rename replaces
// our node, never the system's; the system's own node when this process may not make one.
std::string DeviceNode(const std::string& dir, const std::string& name, unsigned minor) {
  const std::string path = dir + "/" + name;
  if (::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, minor)) == 0) return path;
  return "/dev/" + name;
}

bool IsCharDevice(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

TEST(OutputRuleTest, AFifoIsWrittenInPlaceForItsReader) {
  const std::string dir = testing::MakeTempDir("out_fifo");
  const std::string fifo = dir + "/stream.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string text = "time,q\n" + std::string(200000, '1') + "\n";  // > a pipe's buffer
  std::string got;
  bool eof = false;
  std::thread reader([&] {
    // Non-blocking, with a deadline: a writer that replaced the FIFO must fail the test, not hang.
    const int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    if (fd < 0) return;
    bool writer_seen = false;
    char buf[65536];
    for (int idle = 0; idle < 300;) {  // 30 s without data
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) {
        ++idle;
        continue;
      }
      const ssize_t n = ::read(fd, buf, sizeof(buf));
      if (n > 0) {
        got.append(buf, static_cast<std::size_t>(n));
        writer_seen = true;
        idle = 0;
      } else if (n == 0 && writer_seen) {
        eof = true;
        break;
      } else {
        ++idle;
        ::usleep(100000);
      }
    }
    ::close(fd);
  });
  std::string error;
  try {
    WriteFileAtomic(fifo, text);
  } catch (const std::exception& e) {
    error = e.what();
  }
  reader.join();
  EXPECT_EQ(error, "");
  EXPECT_TRUE(eof);
  EXPECT_EQ(got, text);
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
  EXPECT_EQ(ResolveOutput(fifo).mode, OutputTarget::Mode::kInPlace);
  EXPECT_EQ(ResolveOutput(fifo).kind, "a FIFO (named pipe)");
}

TEST(OutputRuleTest, DevNullTakesAnythingAndStaysADevice) {
  const std::string dir = testing::MakeTempDir("out_null");
  const std::string null = DeviceNode(dir, "null", 3);
  EXPECT_NO_THROW(WriteFileAtomic(null, std::string(1 << 20, 'x')));
  EXPECT_TRUE(IsCharDevice(null)) << null << " was replaced by a regular file";
  OutputFile out(null);
  EXPECT_TRUE(out.in_place());
  out.Write("abc");
  out.Commit();
  EXPECT_TRUE(IsCharDevice(null));
  // Nothing else appeared next to it (no temporary).
  if (null.rfind(dir, 0) == 0) {
    int entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
    EXPECT_EQ(entries, 1);
  }
}

TEST(OutputRuleTest, DevFullIsANoSpaceErrorAndStaysADevice) {
  const std::string dir = testing::MakeTempDir("out_full");
  const std::string full = DeviceNode(dir, "full", 7);
  const std::string e = ErrorOf([&] { WriteFileAtomic(full, "data"); });
  EXPECT_NE(e.find(full), std::string::npos) << e;
  EXPECT_NE(e.find("No space left on device"), std::string::npos) << e;
  EXPECT_TRUE(IsCharDevice(full)) << full << " was replaced by a regular file";
}

TEST(OutputRuleTest, ASymlinkIsWrittenThroughNeverReplaced) {
  const std::string dir = testing::MakeTempDir("out_link");
  const std::string real = testing::WriteTextFile(dir, "data/real.csv", "old\n");
  fs::create_symlink("data/real.csv", dir + "/link.csv");  // relative, as users make them
  WriteFileAtomic(dir + "/link.csv", "new\n");
  EXPECT_TRUE(fs::is_symlink(dir + "/link.csv"));
  EXPECT_EQ(fs::read_symlink(dir + "/link.csv"), "data/real.csv");
  EXPECT_EQ(testing::ReadTextFile(real), "new\n");
  // A chain of links ends at the same file.
  fs::create_symlink(dir + "/link.csv", dir + "/link2.csv");
  WriteFileAtomic(dir + "/link2.csv", "newer\n");
  EXPECT_TRUE(fs::is_symlink(dir + "/link2.csv"));
  EXPECT_EQ(testing::ReadTextFile(real), "newer\n");
  // A link to a device is followed to the device.
  const std::string full = DeviceNode(dir, "full", 7);
  fs::create_symlink(full, dir + "/to_full");
  EXPECT_NE(ErrorOf([&] { WriteFileAtomic(dir + "/to_full", "x"); }).find("No space left"),
            std::string::npos);
  EXPECT_TRUE(fs::is_symlink(dir + "/to_full"));
}

TEST(OutputRuleTest, ADanglingSymlinkGetsTheFileItNames) {
  const std::string dir = testing::MakeTempDir("out_dangling");
  fs::create_symlink(dir + "/later/target.bin", dir + "/out.bin");
  WriteFileAtomic(dir + "/out.bin", "bytes");
  EXPECT_TRUE(fs::is_symlink(dir + "/out.bin"));
  EXPECT_EQ(testing::ReadTextFile(dir + "/later/target.bin"), "bytes");
  // A loop is an error, not a hang.
  fs::create_symlink(dir + "/b", dir + "/a");
  fs::create_symlink(dir + "/a", dir + "/b");
  EXPECT_NE(ErrorOf([&] { WriteFileAtomic(dir + "/a", "x"); }).find("symbolic links"),
            std::string::npos);
}

TEST(OutputRuleTest, AFolderIsAClearErrorAndIsLeftAlone) {
  const std::string dir = testing::MakeTempDir("out_folder");
  fs::create_directories(dir + "/results");
  testing::WriteTextFile(dir, "results/keep.txt", "keep");
  for (const std::string& target : {dir + "/results", dir + "/results/"}) {
    const std::string e = ErrorOf([&] { WriteFileAtomic(target, "x"); });
    EXPECT_NE(e.find("folder"), std::string::npos) << target << ": " << e;
  }
  fs::create_symlink(dir + "/results", dir + "/to_results");
  EXPECT_NE(ErrorOf([&] { WriteFileAtomic(dir + "/to_results", "x"); }).find("folder"),
            std::string::npos);
  EXPECT_TRUE(fs::is_directory(dir + "/results"));
  EXPECT_EQ(testing::ReadTextFile(dir + "/results/keep.txt"), "keep");
  EXPECT_NE(ErrorOf([] { WriteFileAtomic("", "x"); }).find("empty"), std::string::npos);
}

TEST(OutputRuleTest, ADescriptorLinkIsWrittenThroughTheDescriptor) {
  // /dev/stdout is /proc/self/fd/1: on a pipe the bytes go down the pipe, ...
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  WriteFileAtomic("/proc/self/fd/" + std::to_string(fds[1]), "through the pipe");
  ::close(fds[1]);
  char buf[64] = {};
  EXPECT_EQ(::read(fds[0], buf, sizeof(buf) - 1), 16);
  EXPECT_STREQ(buf, "through the pipe");
  ::close(fds[0]);
  // ... and into a file (`> out.csv`), after what was printed, in the same file (not replaced).
  const std::string dir = testing::MakeTempDir("out_fd");
  const std::string file = dir + "/out.csv";
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, "printed\n", 8), 8);
  struct stat before {};
  ASSERT_EQ(::stat(file.c_str(), &before), 0);
  WriteFileAtomic("/dev/fd/" + std::to_string(fd), "exported\n");
  ASSERT_EQ(::write(fd, "after\n", 6), 6);  // at the descriptor's offset, after the export
  ::close(fd);
  struct stat after {};
  ASSERT_EQ(::stat(file.c_str(), &after), 0);
  EXPECT_EQ(before.st_ino, after.st_ino);
  EXPECT_EQ(testing::ReadTextFile(file), "printed\nexported\nafter\n");
}

TEST(OutputRuleTest, ANamedTemporaryIsNeverTruncated) {
  const std::string dir = testing::MakeTempDir("out_part");
  const std::string path = dir + "/run.urrec";
  const std::string crashed = testing::WriteTextFile(dir, "run.urrec.part", "crashed recording");
  OutputFile::Options o;
  o.temporary_suffix = ".part";
  o.existing_temporary_hint = "recover it first";
  const std::string e = ErrorOf([&] { OutputFile out(path, o); });
  EXPECT_NE(e.find("run.urrec.part already exists: recover it first"), std::string::npos) << e;
  EXPECT_EQ(testing::ReadTextFile(crashed), "crashed recording");
  // Once it is moved away, a new one is written, kept when not committed, renamed on commit.
  fs::rename(crashed, dir + "/recovered.urrec");
  {
    OutputFile out(path, o);
    EXPECT_EQ(out.writing_to(), crashed);
    out.Write("chunk 1");
  }
  EXPECT_EQ(testing::ReadTextFile(crashed), "chunk 1");
  fs::remove(crashed);
  OutputFile out(path, o);
  out.Write("whole");
  out.Commit();
  EXPECT_EQ(testing::ReadTextFile(path), "whole");
  EXPECT_FALSE(fs::exists(crashed));
}

TEST(OutputRuleTest, StagedOutputsAreWrittenAllOrNone) {
  const std::string dir = testing::MakeTempDir("out_staged");
  const std::string xml = testing::WriteTextFile(dir, "model.xml", "old xml");
  fs::create_directories(dir + "/model.mjb");  // the second output cannot be written
  {
    StagedOutputs outputs;
    outputs.Add(xml, "new xml");
    EXPECT_NE(ErrorOf([&] { outputs.Add(dir + "/model.mjb", "mjb"); }).find("folder"),
              std::string::npos);
  }  // never committed
  EXPECT_EQ(testing::ReadTextFile(xml), "old xml");
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 2) << "a temporary was left behind";
  // Two outputs naming one file are refused; good ones are committed together.
  StagedOutputs same;
  same.Add(xml, "a");
  EXPECT_NE(ErrorOf([&] { same.Add(dir + "/./model.xml", "b"); }).find("same file"),
            std::string::npos);
  StagedOutputs both;
  both.Add(xml, "new xml");
  both.Add(dir + "/out/model2.mjb", "mjb");
  EXPECT_EQ(testing::ReadTextFile(xml), "old xml");
  both.Commit();
  EXPECT_EQ(testing::ReadTextFile(xml), "new xml");
  EXPECT_EQ(testing::ReadTextFile(dir + "/out/model2.mjb"), "mjb");
}

TEST(OutputRuleTest, AReplacedFileKeepsItsMode) {
  const std::string dir = testing::MakeTempDir("out_mode");
  const std::string path = testing::WriteTextFile(dir, "run.sh", "old");
  fs::permissions(path, fs::perms(0750));
  WriteFileAtomic(path, "new");
  EXPECT_EQ(static_cast<int>(fs::status(path).permissions()) & 0777, 0750);
}

}  // namespace
}  // namespace urlab
