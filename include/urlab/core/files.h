#pragma once
// Files that come from users and files we write for them.
//
// Inputs: ReadInputFile refuses, before reading anything, what is not a regular file (a FIFO,
// a device such as /dev/zero, a folder) and files larger than a limit, with a located message.
//
// Outputs follow one rule, here and nowhere else (ResolveOutput, OutputFile, WriteFileAtomic):
// - a regular file or nothing at the target: written to a temporary in the target's folder and
//   renamed into place once complete (an interrupted write never leaves a truncated file);
// - a device, a FIFO or a socket (/dev/null, /dev/stdout on a pipe, a named pipe): written in
//   place, never renamed over (a device node is never replaced by a regular file);
// - a symbolic link: never replaced; the rule applies to what it points to (a dangling link gets
//   the file it names); a link through /proc/self/fd (/dev/stdout, /dev/fd/N) is written in
//   place, so `--export-csv /dev/stdout > out.csv` writes through the shell's descriptor;
// - a folder, or "" as a path: refused, saying why;
// - a file the command reads: refused (RefuseOverwritingInput, which each command calls with
//   the files it read).
// A write error (ENOSPC from /dev/full, EPIPE from a closed pipe, EFBIG) is an Error naming the
// path; the process ignores SIGPIPE and SIGXFSZ so that these arrive as errors.
//
// Thread: any; no shared state (one OutputFile per thread).
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/core/error.h"

namespace urlab {

// Largest text input (MJCF, YAML) we read: anything bigger is a mistake, not a model.
constexpr std::uintmax_t kMaxTextInputBytes = 64ull << 20;

// Throws InputError unless `path` is a regular file (symlinks followed) of at most `max_bytes`.
// `what` names it in messages ("model file", "scene file", "include file"); the error is located
// at `referenced_from` when given (the element or key that named the file), else at the path.
void CheckInputFile(const std::string& path, const std::string& what,
                    const SourceLocation& referenced_from = {},
                    std::uintmax_t max_bytes = kMaxTextInputBytes);

// CheckInputFile, then the whole file.
std::string ReadInputFile(const std::string& path, const std::string& what,
                          const SourceLocation& referenced_from = {},
                          std::uintmax_t max_bytes = kMaxTextInputBytes);

// Where and how an output path is written (the rule above). Throws Error naming `path` for "", a
// folder, a symlink loop; does not create anything.
struct OutputTarget {
  enum class Mode {
    kReplace,  // a regular file or nothing: temporary, then rename over `file`
    kInPlace,  // a device, FIFO or socket (or a /proc/self/fd link): opened and written as is
  };
  std::string path;  // as the user gave it, for messages
  std::string file;  // what is written: `path` with symbolic links followed
  Mode mode = Mode::kReplace;
  std::string kind;  // "a device", "a FIFO (named pipe)"...; "" for a regular file or nothing
  // One of this process's descriptors (/dev/stdout, /proc/self/fd/N): written through a
  // duplicate of it, so the bytes land at its offset, between what the process prints.
  int descriptor = -1;
};
OutputTarget ResolveOutput(const std::string& path);

// A file written over time (a recording) or at once (WriteFileAtomic), following the output rule.
// In replace mode the bytes go to a temporary next to the target (missing folders are created)
// and Commit flushes it to disk and renames it into place; in place, they go straight to the
// device or FIFO (opening a FIFO waits for its reader) and Commit closes it.
class OutputFile {
 public:
  struct Options {
    // "" : a hidden unique temporary ".NAME.urlab-tmp-XXXXXX", removed when not committed.
    // A suffix such as ".part": the temporary is NAME + suffix, kept when not committed (a
    // crash-recovery file), and never truncated: an existing one is refused with
    // `existing_temporary_hint` in the message.
    std::string temporary_suffix;
    std::string existing_temporary_hint;
  };
  // Throws Error naming the path (a folder, a FIFO nobody reads is not refused: it blocks).
  explicit OutputFile(const std::string& path, Options options = {});
  // Not committed: a unique temporary is removed, a named one (".part") stays.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Appends all of `bytes` (retrying short writes); throws Error with the system's reason
  // ("No space left on device", "Broken pipe", "File too large"), naming the file written.
  void Write(std::string_view bytes);
  // Replace mode: fsync, close, `before_rename(temporary)` when given, rename over the target,
  // fsync its folder. In place: close. Throws Error; the temporary then stays or goes as the
  // destructor says.
  void Commit(const std::function<void(const std::string&)>& before_rename = {});
  // Closes and removes the temporary (replace mode); in place, only closes.
  void Discard();

  const OutputTarget& target() const { return target_; }
  bool in_place() const { return target_.mode == OutputTarget::Mode::kInPlace; }
  // The file the bytes go to now: the temporary, or the target itself in place.
  const std::string& writing_to() const { return writing_; }
  std::uint64_t bytes() const { return bytes_; }
  bool committed() const { return committed_; }

 private:
  [[noreturn]] void Fail(const std::string& what, int err);
  OutputTarget target_;
  Options options_;
  std::string writing_;
  int fd_ = -1;
  std::uint64_t bytes_ = 0;
  bool committed_ = false;
};

// Writes `bytes` to `path` by the output rule: a regular or absent target gets a temporary next
// to it, flushed to disk and renamed over it (atomic on POSIX): until the rename an existing file
// is untouched; a kill at any point leaves the old file or the new one, never a mix (at worst a
// stray temporary ".NAME.urlab-tmp-XXXXXX" next to it). A device or FIFO is written in place; a
// symlink is followed. `before_rename`, when given, is called with the temporary's path once it
// is complete (for tests; not called in place). Throws Error naming `path`.
void WriteFileAtomic(const std::string& path, std::string_view bytes,
                     const std::function<void(const std::string&)>& before_rename = {});

// Several outputs of one command, written all or none: Add checks each target and writes its
// bytes to a temporary (in place targets are only checked), Commit then writes the in-place ones
// and renames the others. A failure before Commit leaves every target untouched.
class StagedOutputs {
 public:
  StagedOutputs();
  ~StagedOutputs();  // uncommitted temporaries are removed
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  void Add(const std::string& path, std::string bytes);
  void Commit();

 private:
  struct Staged {
    std::unique_ptr<OutputFile> file;  // replace mode, written
    std::string path;                  // in place: as given, written at Commit
    std::string resolved;              // what is written (OutputTarget::file)
    std::string bytes;
  };
  std::vector<Staged> staged_;
};

// Throws InputError when `output` names the same file as one of `inputs` (compared with
// std::filesystem::equivalent, so links and other spellings of a path are caught). `what` names
// the output in the message ("--save-xml").
void RefuseOverwritingInput(const std::string& output, const std::vector<std::string>& inputs,
                            const std::string& what);

}  // namespace urlab
