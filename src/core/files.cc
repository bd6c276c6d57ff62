#include "urlab/core/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/gcc_workarounds.h"

namespace urlab {

namespace fs = std::filesystem;

namespace {

SourceLocation Where(const std::string& path, const SourceLocation& referenced_from) {
  return referenced_from.file.empty() ? SourceLocation{path, 0} : referenced_from;
}

// What a non-regular file is, for messages.
std::string Kind(const fs::file_status& s) {
  switch (s.type()) {
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::fifo:
      return "a FIFO (named pipe)";
    case fs::file_type::character:
    case fs::file_type::block:
      return "a device";
    case fs::file_type::socket:
      return "a socket";
    default:
      return "not a regular file";
  }
}

// The process umask, read without changing it (umask() would race with other threads).
mode_t CurrentUmask() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Umask:", 0) == 0)
      return static_cast<mode_t>(std::stoul(line.substr(6), nullptr, 8));
  }
  return 022;
}

[[noreturn]] void WriteFailed(const std::string& path, const std::string& why) {
  throw Error(path + ": cannot write: " + why);
}

}  // namespace

void CheckInputFile(const std::string& path, const std::string& what,
                    const SourceLocation& referenced_from, std::uintmax_t max_bytes) {
  std::error_code ec;
  const fs::file_status s = fs::status(path, ec);
  if (ec || !fs::exists(s)) {
    throw InputError(Where(path, referenced_from), what + " '" + path + "' not found");
  }
  if (!fs::is_regular_file(s)) {
    throw InputError(Where(path, referenced_from),
                     what + " '" + path + "' is " + Kind(s) + ", not a regular file");
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (!ec && size > max_bytes) {
    throw InputError(Where(path, referenced_from),
                     what + " '" + path + "' is " + std::to_string(size >> 20) +
                         " MiB, larger than the " + std::to_string(max_bytes >> 20) +
                         " MiB URLab reads");
  }
}

std::string ReadInputFile(const std::string& path, const std::string& what,
                          const SourceLocation& referenced_from, std::uintmax_t max_bytes) {
  CheckInputFile(path, what, referenced_from, max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError({path, 0}, "cannot open " + what + ": " + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

namespace {

// What a non-regular file is, from stat, for messages.
std::string KindOfMode(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISREG(mode)) return "a file descriptor's file";
  return "not a regular file";
}

bool UnderProc(const fs::path& p) {
  auto it = p.begin();
  return it != p.end() && ++it != p.end() && *it == "proc";
}

// N when `p` is /proc/<this process>/fd/N, else -1.
int OwnDescriptor(const fs::path& p) {
  const std::string prefix = "/proc/" + std::to_string(::getpid()) + "/fd/";
  const std::string s = p.string();
  if (s.rfind(prefix, 0) != 0 || s.size() == prefix.size()) return -1;
  int n = 0;
  for (std::size_t i = prefix.size(); i < s.size(); ++i) {
    if (s[i] < '0' || s[i] > '9' || n > 1000000) return -1;
    n = n * 10 + (s[i] - '0');
  }
  return n;
}

void FsyncFolder(const fs::path& folder) {
  const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

}  // namespace

OutputTarget ResolveOutput(const std::string& path) {
  if (path.empty()) throw Error("an output file name is empty");
  OutputTarget t;
  t.path = path;
  fs::path p = fs::absolute(fs::path(path)).lexically_normal();
  std::error_code ec;
  if (!p.has_filename()) {
    WriteFailed(path, fs::is_directory(p, ec) ? "it is a folder" : "it names a folder, not a file");
  }
  for (int hops = 0;; ++hops) {
    if (hops > 40) WriteFailed(path, "too many levels of symbolic links");
    // The folder with its own links resolved: /dev/fd/1 and /dev/stdout lead into /proc.
    fs::path parent = fs::weakly_canonical(p.parent_path(), ec);
    if (ec) parent = p.parent_path();
    p = parent / p.filename();
    struct stat st {};
    if (UnderProc(p)) {
      // A descriptor link (/proc/self/fd/N): what it names may have no path (a pipe), and
      // replacing it would bypass the descriptor; write through it.
      if (::stat(p.c_str(), &st) != 0) WriteFailed(path, std::strerror(errno));
      if (S_ISDIR(st.st_mode)) WriteFailed(path, "it is a folder");
      t.file = p.string();
      t.mode = OutputTarget::Mode::kInPlace;
      t.kind = KindOfMode(st.st_mode);
      t.descriptor = OwnDescriptor(p);
      return t;
    }
    if (::lstat(p.c_str(), &st) != 0) {
      if (errno != ENOENT) WriteFailed(path, std::strerror(errno));
      t.file = p.string();  // nothing there (a dangling link's target, too): created
      return t;
    }
    if (S_ISLNK(st.st_mode)) {
      const fs::path to = fs::read_symlink(p, ec);
      if (ec)
        WriteFailed(path, "cannot read the symbolic link " + p.string() + ": " + ec.message());
      p = (to.is_absolute() ? to : p.parent_path() / to).lexically_normal();
      if (!p.has_filename()) p = p.parent_path();
      continue;
    }
    if (S_ISDIR(st.st_mode)) {
      WriteFailed(path, p.string() == fs::absolute(path).lexically_normal().string()
                            ? "it is a folder"
                            : "it is a link to the folder " + p.string());
    }
    t.file = p.string();
    if (!S_ISREG(st.st_mode)) {
      t.mode = OutputTarget::Mode::kInPlace;
      t.kind = KindOfMode(st.st_mode);
    }
    return t;
  }
}

OutputFile::OutputFile(const std::string& path, Options options)
    : target_(ResolveOutput(path)), options_(std::move(options)) {
  if (in_place()) {
    writing_ = target_.file;
    if (target_.descriptor >= 0) {
      // Our own stdout (or another descriptor): what was printed goes first, and what is printed
      // after follows, at the descriptor's own offset.
      if (target_.descriptor == STDOUT_FILENO) std::fflush(stdout);
      if (target_.descriptor == STDERR_FILENO) std::fflush(stderr);
      fd_ = ::fcntl(target_.descriptor, F_DUPFD_CLOEXEC, 0);
      if (fd_ < 0) Fail("cannot use descriptor " + std::to_string(target_.descriptor), errno);
      return;
    }
    fd_ = ::open(writing_.c_str(), O_WRONLY | O_APPEND | O_NOCTTY | O_CLOEXEC);
    if (fd_ < 0) {
      const int err = errno;
      Fail("cannot open " + target_.kind +
               (err == ENXIO ? " (a socket, or a FIFO or device nobody reads)" : ""),
           err);
    }
    return;
  }
  const fs::path target(target_.file);
  const fs::path folder = target.parent_path();
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) WriteFailed(path, "cannot create folder " + folder.string() + ": " + ec.message());
  // A new file gets the mode a plain open() would give; a replaced one keeps its own.
  struct stat old {};
  const mode_t mode = ::stat(target_.file.c_str(), &old) == 0
                          ? (old.st_mode & 07777)
                          : (static_cast<mode_t>(0666) & ~CurrentUmask());
  if (options_.temporary_suffix.empty()) {
    // -O3: a false -Wrestrict inside std::string's operator+ (GCC PR 105329 / 105651).
    URLAB_GCC_IGNORE("-Wrestrict")
    writing_ = (folder / ("." + target.filename().string() + ".urlab-tmp-XXXXXX")).string();
    URLAB_GCC_RESTORE
    fd_ = ::mkstemp(writing_.data());
    if (fd_ < 0) Fail("cannot create a temporary file in " + folder.string(), errno);
    ::fcntl(fd_, F_SETFD, FD_CLOEXEC);
  } else {
    writing_ = target_.file + options_.temporary_suffix;
    // Never truncated: an existing one may be the only copy of something (a crash's recording).
    fd_ = ::open(writing_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ < 0) {
      const int err = errno;
      if (err == EEXIST) {
        WriteFailed(path, writing_ + " already exists" +
                              (options_.existing_temporary_hint.empty()
                                   ? std::string()
                                   : ": " + options_.existing_temporary_hint));
      }
      Fail("cannot create " + writing_, err);
    }
  }
  if (::fchmod(fd_, mode) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    ::unlink(writing_.c_str());  // just made by us, empty
    Fail("chmod " + writing_, err);
  }
}

OutputFile::~OutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !in_place() && options_.temporary_suffix.empty() && !writing_.empty()) {
    ::unlink(writing_.c_str());
  }
}

void OutputFile::Fail(const std::string& what, int err) {
  WriteFailed(target_.path, what + ": " + std::strerror(err));
}

void OutputFile::Write(std::string_view bytes) {
  if (fd_ < 0) WriteFailed(target_.path, "the file is closed");
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      Fail(writing_ == target_.path ? "write" : "write to " + writing_, err);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    bytes_ += static_cast<std::uint64_t>(n);
  }
}

void OutputFile::Commit(const std::function<void(const std::string&)>& before_rename) {
  if (fd_ < 0) WriteFailed(target_.path, "the file is closed");
  if (!in_place() && ::fsync(fd_) != 0) Fail("fsync " + writing_, errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) Fail("close", errno);
  if (in_place()) {
    committed_ = true;
    return;
  }
  if (before_rename) before_rename(writing_);
  if (::rename(writing_.c_str(), target_.file.c_str()) != 0) {
    Fail("rename " + writing_ + " to " + target_.file, errno);
  }
  committed_ = true;
  FsyncFolder(fs::path(target_.file).parent_path());  // the rename itself, durable
}

void OutputFile::Discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!committed_ && !in_place() && !writing_.empty()) ::unlink(writing_.c_str());
}

void WriteFileAtomic(const std::string& path, std::string_view bytes,
                     const std::function<void(const std::string&)>& before_rename) {
  OutputFile out(path);
  out.Write(bytes);
  out.Commit(before_rename);
}

StagedOutputs::StagedOutputs() = default;
StagedOutputs::~StagedOutputs() = default;

void StagedOutputs::Add(const std::string& path, std::string bytes) {
  const OutputTarget t = ResolveOutput(path);
  for (const Staged& s : staged_) {
    if (s.resolved == t.file) {
      WriteFailed(path, "another output of this command names the same file");
    }
  }
  Staged s;
  s.resolved = t.file;
  if (t.mode == OutputTarget::Mode::kInPlace) {
    s.path = path;
    s.bytes = std::move(bytes);
  } else {
    s.file = std::make_unique<OutputFile>(path);
    s.file->Write(bytes);
  }
  staged_.push_back(std::move(s));
}

void StagedOutputs::Commit() {
  // In place first (a device can refuse, a full /dev/full): nothing is renamed yet then.
  for (Staged& s : staged_) {
    if (!s.file) WriteFileAtomic(s.path, s.bytes);
  }
  for (Staged& s : staged_) {
    if (s.file) s.file->Commit();
  }
}

void RefuseOverwritingInput(const std::string& output, const std::vector<std::string>& inputs,
                            const std::string& what) {
  std::error_code ec;
  if (!fs::exists(output, ec)) return;
  for (const std::string& in : inputs) {
    if (fs::equivalent(output, in, ec) && !ec) {
      throw InputError({output, 0}, what + " would overwrite '" + in +
                                        "', which this command reads; choose another output file");
    }
  }
}

}  // namespace urlab
