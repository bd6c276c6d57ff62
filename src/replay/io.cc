#include "replay/io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "urlab/replay/recording.h"

namespace urlab::replay {

namespace fs = std::filesystem;

InputFile::InputFile(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd_ < 0 || ::fstat(fd_, &st) != 0) {
    const std::string why = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    throw RecordingError(RecordingError::Reason::kNotARecording, path, "cannot open: " + why);
  }
  size_ = static_cast<std::uint64_t>(st.st_size);
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::string InputFile::Read(std::uint64_t offset, std::uint64_t n) const {
  if (offset > size_ || n > size_ - offset) {
    throw RecordingError(RecordingError::Reason::kTruncated, path_,
                         "the file ends at byte " + std::to_string(size_) + ", before byte " +
                             std::to_string(offset + n));
  }
  std::string out(n, '\0');
  std::uint64_t done = 0;
  while (done < n) {
    const ssize_t got =
        ::pread(fd_, out.data() + done, n - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      throw RecordingError(RecordingError::Reason::kTruncated, path_,
                           std::string("read failed at byte ") + std::to_string(offset + done) +
                               (got < 0 ? std::string(": ") + std::strerror(errno) : ""));
    }
    done += static_cast<std::uint64_t>(got);
  }
  return out;
}

PartFile::PartFile(std::string path) : path_(std::move(path)) {
  const fs::path parent = fs::path(path_).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  fd_ = ::open(part_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(path_ + ": cannot write: " + std::strerror(errno));
}

PartFile::~PartFile() {
  if (fd_ >= 0) ::close(fd_);
}

void PartFile::Discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!finished_) ::unlink(part_path().c_str());
}

void PartFile::Append(std::string_view bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw Error(part_path() + ": write failed: " + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
  bytes_ += bytes.size();
}

void PartFile::Finish() {
  if (::fsync(fd_) != 0) throw Error(part_path() + ": fsync failed: " + std::strerror(errno));
  ::close(fd_);
  fd_ = -1;
  if (::rename(part_path().c_str(), path_.c_str()) != 0) {
    throw Error(path_ + ": rename from .part failed: " + std::strerror(errno));
  }
  finished_ = true;
}

}  // namespace urlab::replay
