#include "urlab/replay/npz.h"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <climits>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
#include <string>
#include <string_view>

#include "urlab/core/error.h"
#include "urlab/core/files.h"

namespace urlab::replay {

namespace {

// Sizes and offsets in a zip without ZIP64 are 32-bit, and 0xFFFFFFFF means "see ZIP64".
constexpr std::uint64_t kZipLimit = 0xFFFFFFFFull;
constexpr std::size_t kLocalHeaderBytes = 30;
constexpr std::size_t kCentralHeaderBytes = 46;
constexpr std::size_t kEndRecordBytes = 22;
// MS-DOS date of 1980-01-01 (time 00:00): every entry gets it, so the output is reproducible.
constexpr std::uint16_t kDosDate = (0 << 9) | (1 << 5) | 1;

void Put16(std::string* out, std::uint32_t v) {
  *out += static_cast<char>(v & 0xFF);
  *out += static_cast<char>((v >> 8) & 0xFF);
}

void Put32(std::string* out, std::uint64_t v) {
  for (int i = 0; i < 4; ++i) *out += static_cast<char>((v >> (8 * i)) & 0xFF);
}

// The NPY 1.0 preamble of an array: magic, version, header length and the header dictionary,
// padded with spaces and ended by "\n" so the data starts at a multiple of 64 bytes.
std::string NpyHeader(const std::vector<std::size_t>& shape, const std::string& descr) {
  std::string dims;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    dims += (i ? ", " : "") + std::to_string(shape[i]);
  }
  if (shape.size() == 1) dims += ',';
  std::string dict =
      "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (" + dims + "), }";
  const std::size_t preamble = 10;  // magic (6), version (2), header length (2)
  const std::size_t unpadded = preamble + dict.size() + 1;
  dict.append((64 - unpadded % 64) % 64, ' ');
  dict += '\n';
  std::string out = "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  Put16(&out, static_cast<std::uint32_t>(dict.size()));
  return out + dict;
}

// An array to write, without copying its values: doubles, or strings when `text` is set.
struct ArrayView {
  std::string_view name;
  std::vector<std::size_t> shape;
  const std::vector<double>& data;
  const std::vector<std::string>* text = nullptr;
};

// UTF-8 to code points (a malformed sequence becomes U+FFFD).
std::u32string Utf32(std::string_view s) {
  std::u32string out;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const int extra = c < 0x80         ? 0
                      : (c >> 5) == 6  ? 1
                      : (c >> 4) == 14 ? 2
                      : (c >> 3) == 30 ? 3
                                       : -1;
    char32_t cp = extra == 0 ? c : extra == 1 ? c & 0x1F : extra == 2 ? c & 0x0F : c & 0x07;
    bool ok = extra >= 0 && i + static_cast<std::size_t>(extra) < s.size();
    for (int k = 1; ok && k <= extra; ++k) {
      const auto n = static_cast<unsigned char>(s[i + static_cast<std::size_t>(k)]);
      ok = (n & 0xC0) == 0x80;
      cp = (cp << 6) | (n & 0x3F);
    }
    out += ok ? cp : U'\uFFFD';
    i += ok ? 1 + static_cast<std::size_t>(extra) : 1;
  }
  return out;
}

// The payload of a string array: each string as `width` UTF-32LE code units, zero padded.
std::string TextPayload(const std::vector<std::u32string>& strings, std::size_t width) {
  std::string out;
  out.reserve(strings.size() * width * 4);
  for (const std::u32string& s : strings) {
    for (std::size_t k = 0; k < width; ++k) {
      const std::uint32_t v = k < s.size() ? static_cast<std::uint32_t>(s[k]) : 0;
      for (int b = 0; b < 4; ++b) out += static_cast<char>((v >> (8 * b)) & 0xFF);
    }
  }
  return out;
}

struct Entry {
  std::string file_name;  // name.npy
  std::string npy_header;
  const ArrayView* array = nullptr;
  std::string text;          // the payload of a string array
  std::uint64_t size = 0;    // npy header + data
  std::uint64_t offset = 0;  // of the local header in the archive
  std::uint32_t crc = 0;
};

std::uint32_t Crc32(std::uint32_t crc, const char* data, std::size_t size) {
  constexpr std::size_t kChunk = 1u << 30;  // zlib's crc32 takes a 32-bit length
  while (size > 0) {
    const std::size_t n = size < kChunk ? size : kChunk;
    crc = static_cast<std::uint32_t>(
        crc32(crc, reinterpret_cast<const Bytef*>(data), static_cast<uInt>(n)));
    data += n;
    size -= n;
  }
  return crc;
}

// `name` for a message: control characters (NUL among them) as \xNN.
std::string Printable(std::string_view name) {
  std::string out;
  for (const char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) {
      out += fmt::format("\\x{:02x}", static_cast<unsigned char>(c));
    } else {
      out += c;
    }
  }
  return out;
}

bool IsAscii(std::string_view s) {
  for (const char c : s) {
    if (static_cast<unsigned char>(c) >= 0x80) return false;
  }
  return true;
}

void Write(const std::string& path, const std::vector<ArrayView>& arrays) {
  const auto fail = [&](const std::string& why) {
    throw Error(path + ": cannot write .npz: " + why);
  };
  if (arrays.size() > 0xFFFF)
    fail(fmt::format("{} arrays, a zip holds at most 65535", arrays.size()));
  std::vector<Entry> entries;
  std::set<std::string_view> names;
  std::uint64_t offset = 0;
  for (const ArrayView& a : arrays) {
    if (a.name.empty()) fail("an array has an empty name");
    if (a.name.find_first_of(std::string_view("/\\\0", 3)) != std::string_view::npos) {
      fail(fmt::format("array name '{}' contains '/', '\\' or NUL", Printable(a.name)));
    }
    if (!names.insert(a.name).second) {
      fail(fmt::format("two arrays are named '{}'", Printable(a.name)));
    }
    std::size_t count = 1;
    for (const std::size_t d : a.shape) {
      if (d != 0 && count > std::numeric_limits<std::size_t>::max() / d) {
        fail(fmt::format("array '{}': its shape's product overflows", Printable(a.name)));
      }
      count *= d;
    }
    const std::size_t values = a.text ? a.text->size() : a.data.size();
    if (count != values || (a.text && !a.data.empty())) {
      fail(fmt::format("array '{}': its shape holds {} values but it has {}", Printable(a.name),
                       count, a.text && !a.data.empty() ? a.data.size() + values : values));
    }
    Entry e;
    std::string descr = "<f8";
    if (a.text) {
      std::vector<std::u32string> strings;
      std::size_t width = 1;  // numpy's '<U0' is odd; one code unit at least
      for (const std::string& s : *a.text) {
        strings.push_back(Utf32(s));
        width = std::max(width, strings.back().size());
      }
      descr = "<U" + std::to_string(width);
      e.text = TextPayload(strings, width);
    }
    e.file_name = std::string(a.name) + ".npy";
    if (e.file_name.size() > 0xFFFF)
      fail(fmt::format("array name '{}' is too long", Printable(a.name)));
    e.npy_header = NpyHeader(a.shape, descr);
    if (e.npy_header.size() - 10 > 0xFFFF) {
      fail(fmt::format("array '{}' has too many dimensions for an NPY 1.0 header",
                       Printable(a.name)));
    }
    e.array = &a;
    if (a.data.size() > (kZipLimit - e.npy_header.size()) / sizeof(double)) {
      fail(fmt::format("array '{}' is 4 GiB or more (ZIP64 is not supported)", Printable(a.name)));
    }
    if (e.text.size() > kZipLimit - e.npy_header.size()) {
      fail(fmt::format("array '{}' is 4 GiB or more (ZIP64 is not supported)", Printable(a.name)));
    }
    e.size = e.npy_header.size() + (a.text ? e.text.size() : a.data.size() * sizeof(double));
    e.offset = offset;
    offset += kLocalHeaderBytes + e.file_name.size() + e.size;
    entries.push_back(std::move(e));
  }
  const std::uint64_t central_offset = offset;
  std::uint64_t central_size = 0;
  for (const Entry& e : entries) central_size += kCentralHeaderBytes + e.file_name.size();
  const std::uint64_t total = central_offset + central_size + kEndRecordBytes;
  if (total >= kZipLimit) fail("the archive would be 4 GiB or more (ZIP64 is not supported)");

  std::string out;
  out.reserve(static_cast<std::size_t>(total));
  for (Entry& e : entries) {
    const std::uint16_t flags = IsAscii(e.file_name) ? 0 : 0x800;  // bit 11: UTF-8 name
    Put32(&out, 0x04034b50);                                       // local file header
    Put16(&out, 20);                                               // version needed: 2.0
    Put16(&out, flags);
    Put16(&out, 0);  // method: stored
    Put16(&out, 0);  // time
    Put16(&out, kDosDate);
    const std::size_t crc_at = out.size();
    Put32(&out, 0);  // CRC-32, filled in below
    Put32(&out, e.size);
    Put32(&out, e.size);
    Put16(&out, static_cast<std::uint32_t>(e.file_name.size()));
    Put16(&out, 0);  // extra field length
    out += e.file_name;
    const std::size_t data_at = out.size();
    out += e.npy_header;
    const std::vector<double>& data = e.array->data;
    if (e.array->text) {
      out += e.text;
    } else if constexpr (std::endian::native == std::endian::little) {
      out.append(reinterpret_cast<const char*>(data.data()), data.size() * sizeof(double));
    } else {
      for (const double v : data) {
        const auto bits = std::bit_cast<std::uint64_t>(v);
        for (int i = 0; i < 8; ++i) out += static_cast<char>((bits >> (8 * i)) & 0xFF);
      }
    }
    e.crc = Crc32(static_cast<std::uint32_t>(crc32(0, nullptr, 0)), out.data() + data_at,
                  out.size() - data_at);
    for (int i = 0; i < 4; ++i) out[crc_at + i] = static_cast<char>((e.crc >> (8 * i)) & 0xFF);
  }
  for (const Entry& e : entries) {
    Put32(&out, 0x02014b50);  // central directory header
    Put16(&out, 20);          // version made by: 2.0, MS-DOS attributes
    Put16(&out, 20);          // version needed: 2.0
    Put16(&out, IsAscii(e.file_name) ? 0 : 0x800);
    Put16(&out, 0);  // method: stored
    Put16(&out, 0);  // time
    Put16(&out, kDosDate);
    Put32(&out, e.crc);
    Put32(&out, e.size);
    Put32(&out, e.size);
    Put16(&out, static_cast<std::uint32_t>(e.file_name.size()));
    Put16(&out, 0);  // extra field length
    Put16(&out, 0);  // comment length
    Put16(&out, 0);  // disk number
    Put16(&out, 0);  // internal attributes
    Put32(&out, 0);  // external attributes
    Put32(&out, e.offset);
    out += e.file_name;
  }
  Put32(&out, 0x06054b50);  // end of central directory
  Put16(&out, 0);           // this disk
  Put16(&out, 0);           // disk of the central directory
  Put16(&out, static_cast<std::uint32_t>(entries.size()));
  Put16(&out, static_cast<std::uint32_t>(entries.size()));
  Put32(&out, central_size);
  Put32(&out, central_offset);
  Put16(&out, 0);  // comment length
  WriteFileAtomic(path, out);
}

}  // namespace

void WriteNpz(const std::string& path, const std::vector<NpyArray>& arrays) {
  std::vector<ArrayView> views;
  views.reserve(arrays.size());
  for (const NpyArray& a : arrays) {
    views.push_back({a.name, a.shape, a.data, a.strings ? &a.text : nullptr});
  }
  Write(path, views);
}

void ExportNpz(const std::string& path, const ModelTables& tables, const Trajectory& traj,
               const std::vector<NpyArray>& extra) {
  traj.Check(tables);
  const std::size_t rows = traj.rows();
  std::vector<ArrayView> arrays;
  arrays.push_back({"time", {rows}, traj.time, nullptr});
  arrays.push_back({"qpos", {rows, static_cast<std::size_t>(traj.nq)}, traj.qpos, nullptr});
  if (traj.has_qvel()) {
    arrays.push_back({"qvel", {rows, static_cast<std::size_t>(traj.nv)}, traj.qvel, nullptr});
  }
  for (const NpyArray& a : extra) {
    arrays.push_back({a.name, a.shape, a.data, a.strings ? &a.text : nullptr});
  }
  Write(path, arrays);
}

namespace {

// "{art}/{short}" for an element of an articulation (the longest prefix), else the full name.
std::string Display(const std::vector<std::string>& articulations, const std::string& full) {
  const std::string* best = nullptr;
  for (const std::string& a : articulations) {
    if (full.size() > a.size() + 1 && full.starts_with(a) && full[a.size()] == '_' &&
        (!best || a.size() > best->size())) {
      best = &a;
    }
  }
  return best ? *best + "/" + full.substr(best->size() + 1) : full;
}

// One name per value: `name` alone for one value, "name[i]" for each of several.
void AddValues(std::vector<std::string>* out, const std::string& name, int count) {
  for (int k = 0; k < count; ++k)
    out->push_back(count == 1 ? name : fmt::format("{}[{}]", name, k));
}

NpyArray Names(std::string name, std::vector<std::string> values) {
  NpyArray a;
  a.name = std::move(name);
  a.shape = {values.size()};
  a.text = std::move(values);
  a.strings = true;
  return a;
}

}  // namespace

std::vector<NpyArray> ExportArrays(const ModelTables& tables, std::size_t rows,
                                   const NpzExtras& extras) {
  std::vector<NpyArray> out;
  const auto per_row = [rows](const std::vector<double>& v) { return rows ? v.size() / rows : 0; };
  out.push_back({"ctrl", {rows, static_cast<std::size_t>(tables.nu)}, extras.ctrl, {}, false});
  if (!extras.targets.empty()) {
    out.push_back({"targets", {rows, per_row(extras.targets)}, extras.targets, {}, false});
  }
  if (!extras.sensordata.empty()) {
    out.push_back({"sensordata", {rows, per_row(extras.sensordata)}, extras.sensordata, {}, false});
  }
  const std::vector<std::string>& arts = tables.articulations;
  std::vector<std::string> qpos(static_cast<std::size_t>(tables.nq));
  std::vector<std::string> qvel(static_cast<std::size_t>(tables.nv));
  std::vector<std::string> joints, owners;
  for (const JointEntry& j : tables.joints) {
    const std::string shown = j.articulation.empty() ? j.name : j.articulation + "/" + j.short_name;
    joints.push_back(j.short_name.empty() ? j.name : j.short_name);
    owners.push_back(j.articulation);
    for (int k = 0; k < j.nq; ++k) {
      qpos.at(static_cast<std::size_t>(j.qposadr + k)) =
          j.nq == 1 ? shown : fmt::format("{}[{}]", shown, k);
    }
    for (int k = 0; k < j.nv; ++k) {
      qvel.at(static_cast<std::size_t>(j.dofadr + k)) =
          j.nv == 1 ? shown : fmt::format("{}[{}]", shown, k);
    }
  }
  std::vector<std::string> ctrl(static_cast<std::size_t>(tables.nu));
  for (const NamedRange& a : tables.actuators) {
    if (a.adr >= 0 && a.adr < tables.nu)
      ctrl[static_cast<std::size_t>(a.adr)] = Display(arts, a.name);
  }
  std::vector<std::string> targets;
  for (const physics::CommandGroupLayout& g : tables.command_groups) {
    for (int id : g.actuators) {
      targets.push_back(id >= 0 && id < tables.nu ? ctrl[static_cast<std::size_t>(id)] : "?");
    }
  }
  std::vector<std::string> sensors;
  for (const NamedRange& s : tables.sensors) AddValues(&sensors, Display(arts, s.name), s.dim);
  out.push_back(Names("qpos_names", std::move(qpos)));
  out.push_back(Names("qvel_names", std::move(qvel)));
  out.push_back(Names("ctrl_names", std::move(ctrl)));
  if (!extras.targets.empty()) out.push_back(Names("target_names", std::move(targets)));
  out.push_back(Names("sensor_names", std::move(sensors)));
  out.push_back(Names("joint_names", std::move(joints)));
  out.push_back(Names("joint_articulations", std::move(owners)));
  out.push_back(Names("articulations", arts));
  return out;
}

}  // namespace urlab::replay
