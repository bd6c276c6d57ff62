#include "urlab/mjcf/writer.h"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <optional>

#include "urlab/core/files.h"

namespace urlab::mjcf {

namespace fs = std::filesystem;
using document::Document;
using document::Element;

namespace {

void AppendEscaped(std::string& out, std::string_view v) {
  for (char c : v) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\n':
        out += "&#10;";
        break;
      case '\r':
        out += "&#13;";
        break;
      case '\t':
        out += "&#9;";
        break;
      default:
        out += c;
    }
  }
}

// Compiler attributes consumed by path resolution (paths are written resolved).
bool IsConsumedCompilerAttribute(const Element& e, std::string_view name) {
  return e.tag() == "compiler" &&
         (name == "meshdir" || name == "texturedir" || name == "strippath");
}

class Writer {
 public:
  Writer(const WriteOptions& options, LineMap* line_map) : options_(options), line_map_(line_map) {}

  void Write(const Element& e, int depth, std::string& out) const {
    if (line_map_) line_map_->push_back(&e);
    out.append(static_cast<size_t>(depth) * 2, ' ');
    out += '<';
    out += e.tag();
    for (const document::Attribute& a : e.attributes()) {
      if (IsConsumedCompilerAttribute(e, a.name)) continue;
      out += ' ';
      out += a.name;
      out += "=\"";
      if (a.spec && a.spec->type == document::ValueType::kFile) {
        AppendEscaped(out, FilePath(e, a.name));
      } else {
        AppendEscaped(out, a.value);
      }
      out += '"';
    }
    if (e.children().empty()) {
      out += "/>\n";
      return;
    }
    out += ">\n";
    for (const auto& c : e.children()) Write(*c, depth + 1, out);
    if (line_map_) line_map_->push_back(nullptr);
    out.append(static_cast<size_t>(depth) * 2, ' ');
    out += "</";
    out += e.tag();
    out += ">\n";
  }

 private:
  std::string FilePath(const Element& e, std::string_view name) const {
    const std::string resolved = *e.ResolvedFile(name);
    if (options_.file_name) return options_.file_name(resolved);
    if (options_.relative_to.empty()) return resolved;
    const fs::path rel = fs::path(resolved).lexically_relative(options_.relative_to);
    return rel.empty() ? resolved : rel.string();
  }

  const WriteOptions& options_;
  LineMap* line_map_;
};

}  // namespace

std::string WriteString(const Document& doc, const WriteOptions& options, LineMap* line_map) {
  std::string out;
  out.reserve(1 << 16);
  if (line_map) line_map->clear();
  Writer(options, line_map).Write(doc.root(), 0, out);
  return out;
}

std::optional<size_t> CompileMessageLine(const std::string& message) {
  // MuJoCo ends its compiler messages with "..., line N" (or "line = N").
  for (size_t at = message.rfind("line"); at != std::string::npos;
       at = at == 0 ? std::string::npos : message.rfind("line", at - 1)) {
    size_t i = at + 4;
    while (i < message.size() && (message[i] == ' ' || message[i] == '=')) ++i;
    size_t j = i;
    while (j < message.size() && std::isdigit(static_cast<unsigned char>(message[j]))) ++j;
    if (j > i) return std::stoul(message.substr(i, j - i));
  }
  return std::nullopt;
}

std::string ExplainCompileMessage(const std::string& message, const LineMap& line_map) {
  const std::optional<size_t> line = CompileMessageLine(message);
  if (!line || *line == 0 || *line > line_map.size() || !line_map[*line - 1]) return message;
  return message + "\n  in " + line_map[*line - 1]->Describe();
}

void WriteFile(const Document& doc, const std::string& path, bool absolute_paths) {
  WriteOptions options;
  if (!absolute_paths) {
    options.relative_to = fs::absolute(fs::path(path)).parent_path().lexically_normal().string();
  }
  // Missing folders are created; a temporary file is renamed into place (never a truncated file).
  WriteFileAtomic(path, WriteString(doc, options));
}

}  // namespace urlab::mjcf
