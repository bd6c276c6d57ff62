#pragma once
// Files of the replay module: positioned reads of a recording, and an output file written as
// "NAME.part" and renamed into place when finished (a crash leaves the .part file, never a
// half-written NAME). Internal; one thread per object.
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "urlab/core/files.h"

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

// A recording being written, by the output rule of urlab/core/files.h: to "path.part", renamed
// to "path" by Finish (a crash leaves the .part file, never a half-written NAME); a device or
// FIFO (/dev/null, a pipe) is written in place; a symlink gets the recording through the link.
class PartFile {
 public:
  // Creates "path.part" (missing folders too). Never truncates an existing .part (it may be a
  // crashed recording's only copy): refuses it, saying how to recover it. Throws Error naming the
  // path (a folder, a folder that cannot be written, an existing .part).
  explicit PartFile(std::string path);
  // Closes the file; an unfinished .part file stays (nothing written is lost): Discard removes it.
  ~PartFile();
  PartFile(const PartFile&) = delete;
  PartFile& operator=(const PartFile&) = delete;
  // Appends and hands the bytes to the kernel (a killed process loses nothing written).
  void Append(std::string_view bytes);
  // Flushes to disk and renames "path.part" to "path" (in place: closes).
  void Finish();
  // Closes and removes the .part file (a recording thrown away).
  void Discard();
  std::uint64_t bytes() const { return out_->bytes(); }
  const std::string& path() const { return path_; }
  // The file written until Finish: "path.part", or the device or FIFO itself.
  const std::string& part_path() const { return out_->writing_to(); }
  // Written straight to a device or FIFO: nothing to read back.
  bool in_place() const { return out_->in_place(); }

 private:
  std::string path_;
  std::unique_ptr<OutputFile> out_;
};

}  // namespace urlab::replay
