#include "ply_header.h"

#include <fmt/format.h>

#include <charconv>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::convert::internal {

namespace {

// Size in bytes of a PLY scalar type, 0 when unknown.
int TypeSize(std::string_view t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" ||
      t == "float32") {
    return 4;
  }
  if (t == "double" || t == "float64") return 8;
  return 0;
}

std::vector<std::string_view> Words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t min_bytes = 0;  // per element
  int line = 0;
};

}  // namespace

void CheckPlyHeader(std::string_view bytes, std::uint64_t file_size, const std::string& path) {
  auto fail = [&](int line, const std::string& what) {
    throw InputError({path, line}, "PLY header: " + what);
  };
  if (!bytes.starts_with("ply")) fail(1, "the file does not start with 'ply'");
  const std::size_t end = bytes.substr(0, kMaxPlyHeaderBytes).find("end_header");
  if (end == std::string_view::npos) {
    fail(0, fmt::format("no 'end_header' in the first {} KiB", kMaxPlyHeaderBytes / 1024));
  }
  std::size_t body = bytes.find('\n', end);
  body = body == std::string_view::npos ? bytes.size() : body + 1;
  bool ascii = true;
  std::vector<Element> elements;
  int line = 0;
  std::size_t pos = 0;
  while (pos < end) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string_view::npos || eol > end) eol = end;
    ++line;
    const auto w = Words(bytes.substr(pos, eol - pos));
    pos = eol + 1;
    if (w.empty()) continue;
    if (w[0] == "format") {
      if (w.size() < 2) fail(line, "'format' needs a type");
      if (w[1] == "ascii") {
        ascii = true;
      } else if (w[1] == "binary_little_endian" || w[1] == "binary_big_endian") {
        ascii = false;
      } else {
        fail(line, fmt::format("unknown format '{}'", w[1]));
      }
    } else if (w[0] == "element") {
      if (w.size() < 3) fail(line, "'element' needs a name and a count");
      Element e;
      e.name = std::string(w[1]);
      e.line = line;
      const auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
      if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size()) {
        fail(line, fmt::format("element '{}': count '{}' is not a whole number", w[1], w[2]));
      }
      elements.push_back(std::move(e));
    } else if (w[0] == "property") {
      if (elements.empty()) fail(line, "a property before any element");
      Element& e = elements.back();
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() < 5) fail(line, "'property list' needs a count type, a value type and a name");
        const int count_size = TypeSize(w[2]);
        if (!count_size || !TypeSize(w[3])) fail(line, "unknown property type");
        e.min_bytes += ascii ? 2 : static_cast<std::uint64_t>(count_size);  // an empty list
      } else {
        if (w.size() < 3) fail(line, "'property' needs a type and a name");
        const int size = TypeSize(w[1]);
        if (!size) fail(line, fmt::format("unknown property type '{}'", w[1]));
        e.min_bytes += ascii ? 2 : static_cast<std::uint64_t>(size);
      }
    }
  }
  const std::uint64_t available = file_size > body ? file_size - body : 0;
  std::uint64_t needed = 0;
  for (const Element& e : elements) {
    const std::uint64_t per = std::max<std::uint64_t>(e.min_bytes, 1);
    if (e.count > available / per || needed + e.count * per > available) {
      fail(e.line, fmt::format("declares {} '{}' elements (at least {} bytes each), but only {} "
                               "bytes follow the header: the file is truncated or its header "
                               "is wrong",
                               e.count, e.name, per, available - std::min(available, needed)));
    }
    needed += e.count * per;
  }
}

}  // namespace urlab::convert::internal
