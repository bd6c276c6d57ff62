#pragma once
// Files of the replay module: positioned reads of a recording, and an output file written as
// "NAME.part" and renamed into place when finished (a crash leaves the .part file, never a
// half-written NAME). Internal; one thread per object.
#include <cstdint>
#include <string>
#include <string_view>

namespace urlab::replay {

class InputFile {
 public:
  // Throws RecordingError (kNotARecording) when it cannot be opened.
  explicit InputFile(const std::string& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  std::uint64_t size() const { return size_; }
  // `n` bytes at `offset`; throws RecordingError (kTruncated) when the file is shorter.
  std::string Read(std::uint64_t offset, std::uint64_t n) const;

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

class PartFile {
 public:
  // Creates "path.part" (missing folders too), replacing a stale one. Throws Error naming the
  // path (e.g. a folder that cannot be written).
  explicit PartFile(std::string path);
  // Closes the file; an unfinished .part file stays (nothing written is lost): Discard removes it.
  ~PartFile();
  PartFile(const PartFile&) = delete;
  PartFile& operator=(const PartFile&) = delete;
  // Appends and hands the bytes to the kernel (a killed process loses nothing written).
  void Append(std::string_view bytes);
  // Flushes to disk and renames "path.part" to "path".
  void Finish();
  // Closes and removes the .part file (a recording thrown away).
  void Discard();
  std::uint64_t bytes() const { return bytes_; }
  const std::string& path() const { return path_; }
  std::string part_path() const { return path_ + ".part"; }

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
  bool finished_ = false;
};

}  // namespace urlab::replay
