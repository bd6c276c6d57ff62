#pragma once
// Writing documents back to MJCF text. Attribute values are written exactly as held, so an
// element nobody edited comes out as it was read. <include>s were already flattened by the
// reader; asset file paths are written resolved (absolute, or relative to a chosen folder) and
// the <compiler> meshdir/texturedir/strippath attributes they consumed are left out, so the
// output loads from any working directory. Thread: any.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "urlab/document/document.h"

namespace urlab::mjcf {

struct WriteOptions {
  // Folder that asset paths are written relative to; empty writes absolute paths.
  std::string relative_to;
  // When set, every asset path is written as file_name(resolved absolute path) instead (e.g. a
  // bare name for a model shipped with its assets in a virtual file system); relative_to is then
  // not used.
  std::function<std::string(const std::string& resolved)> file_name;
};

// For each output line (index 0 = line 1), the element that starts on it (nullptr for closing
// tags). Lets a MuJoCo message about "line N" of the written text point at the source element.
using LineMap = std::vector<const document::Element*>;

// MJCF text of `doc`.
std::string WriteString(const document::Document& doc, const WriteOptions& options = {},
                        LineMap* line_map = nullptr);

// The line number a MuJoCo compiler message names ("line N" / "line = N"), if any.
std::optional<size_t> CompileMessageLine(const std::string& message);

// Rewrites a MuJoCo compiler message that mentions "line N" of text written with `line_map`
// so that it also names the source element and its file:line.
std::string ExplainCompileMessage(const std::string& message, const LineMap& line_map);

// Writes `doc` to `path` with asset paths relative to the file's folder (so the folder can be
// moved with its assets' relative layout) or absolute when `absolute_paths`. Missing folders are
// created and the file is written atomically (urlab::WriteFileAtomic): an existing file is
// replaced whole or not at all. Throws Error on I/O failure.
void WriteFile(const document::Document& doc, const std::string& path, bool absolute_paths = false);

}  // namespace urlab::mjcf
