#include "replay/io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "urlab/replay/recording.h"

namespace urlab::replay {

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
  OutputFile::Options o;
  o.temporary_suffix = ".part";
  o.existing_temporary_hint =
      "an unfinished recording (a crash or a kill?), which this would destroy. Recover it with "
      "`urlab replay " +
      path_ +
      ".part --info` (replay and its exports read it up to its last readable chunk), then move "
      "or delete it, or record to another file";
  out_ = std::make_unique<OutputFile>(path_, std::move(o));
}

PartFile::~PartFile() = default;

void PartFile::Discard() { out_->Discard(); }

void PartFile::Append(std::string_view bytes) { out_->Write(bytes); }

void PartFile::Finish() { out_->Commit(); }

}  // namespace urlab::replay
