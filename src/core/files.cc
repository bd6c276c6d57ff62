#include "urlab/core/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
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

void WriteFileAtomic(const std::string& path, std::string_view bytes,
                     const std::function<void(const std::string&)>& before_rename) {
  if (path.empty()) throw Error("cannot write a file with an empty name");
  const fs::path target = fs::absolute(fs::path(path)).lexically_normal();
  if (!target.has_filename()) WriteFailed(path, "it names a folder, not a file");
  std::error_code ec;
  if (fs::is_directory(target, ec)) WriteFailed(path, "it is a folder");
  const fs::path folder = target.parent_path();
  fs::create_directories(folder, ec);
  if (ec) WriteFailed(path, "cannot create folder " + folder.string() + ": " + ec.message());

  // -O3: a false -Wrestrict inside std::string's operator+ (GCC PR 105329 / 105651).
  URLAB_GCC_IGNORE("-Wrestrict")
  std::string temp = (folder / ("." + target.filename().string() + ".urlab-tmp-XXXXXX")).string();
  URLAB_GCC_RESTORE
  const int fd = ::mkstemp(temp.data());
  if (fd < 0)
    WriteFailed(path, std::string("cannot create a temporary file: ") + std::strerror(errno));
  auto fail = [&](const std::string& why) {
    ::close(fd);
    ::unlink(temp.c_str());
    WriteFailed(path, why);
  };
  // mkstemp makes the file 0600; give it the mode a plain open() would have.
  if (::fchmod(fd, static_cast<mode_t>(0666) & ~CurrentUmask()) != 0) {
    fail(std::string("chmod: ") + std::strerror(errno));
  }
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(std::strerror(errno));
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) fail(std::string("fsync: ") + std::strerror(errno));
  if (::close(fd) != 0) {
    ::unlink(temp.c_str());
    WriteFailed(path, std::string("close: ") + std::strerror(errno));
  }
  if (before_rename) before_rename(temp);
  if (::rename(temp.c_str(), target.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(temp.c_str());
    WriteFailed(path, "rename: " + why);
  }
  // Make the rename itself durable.
  const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
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
