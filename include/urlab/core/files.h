#pragma once
// Files that come from users and files we write for them.
//
// Inputs: ReadInputFile refuses, before reading anything, what is not a regular file (a FIFO,
// a device such as /dev/zero, a folder) and files larger than a limit, with a located message.
// Outputs: WriteFileAtomic writes a temporary file in the target folder and renames it into
// place, so an interrupted write never leaves a truncated file; RefuseOverwritingInput refuses an
// output path that is one of the files a command read.
//
// Thread: any; no shared state.
#include <cstdint>
#include <functional>
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

// Writes `bytes` to `path`: creates missing folders, writes a temporary file next to it, flushes
// it to disk and renames it over `path` (atomic on POSIX). Until the rename an existing file at
// `path` is untouched; a kill at any point leaves the old file or the new one, never a mix (at
// worst a stray temporary ".NAME.urlab-tmp-XXXXXX" next to it). `before_rename`, when given, is
// called with the temporary's path once it is complete (for tests). Throws Error naming `path`.
void WriteFileAtomic(const std::string& path, std::string_view bytes,
                     const std::function<void(const std::string&)>& before_rename = {});

// Throws InputError when `output` names the same file as one of `inputs` (compared with
// std::filesystem::equivalent, so links and other spellings of a path are caught). `what` names
// the output in the message ("--save-xml").
void RefuseOverwritingInput(const std::string& output, const std::vector<std::string>& inputs,
                            const std::string& what);

}  // namespace urlab
