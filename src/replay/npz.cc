#include "urlab/replay/npz.h"

#include <fmt/format.h>
#include <zlib.h>

#include <bit>
#include <climits>
#include <cstdint>
#include <cstring>
#include <limits>
#include <set>
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
std::string NpyHeader(const std::vector<std::size_t>& shape) {
  std::string dims;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    dims += (i ? ", " : "") + std::to_string(shape[i]);
  }
  if (shape.size() == 1) dims += ',';
  std::string dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + dims + "), }";
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

// An array to write, without copying its values.
struct ArrayView {
  std::string_view name;
  std::vector<std::size_t> shape;
  const std::vector<double>& data;
};

struct Entry {
  std::string file_name;  // name.npy
  std::string npy_header;
  const ArrayView* array = nullptr;
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
    if (count != a.data.size()) {
      fail(fmt::format("array '{}': its shape holds {} values but it has {}", Printable(a.name),
                       count, a.data.size()));
    }
    Entry e;
    e.file_name = std::string(a.name) + ".npy";
    if (e.file_name.size() > 0xFFFF)
      fail(fmt::format("array name '{}' is too long", Printable(a.name)));
    e.npy_header = NpyHeader(a.shape);
    if (e.npy_header.size() - 10 > 0xFFFF) {
      fail(fmt::format("array '{}' has too many dimensions for an NPY 1.0 header",
                       Printable(a.name)));
    }
    e.array = &a;
    if (a.data.size() > (kZipLimit - e.npy_header.size()) / sizeof(double)) {
      fail(fmt::format("array '{}' is 4 GiB or more (ZIP64 is not supported)", Printable(a.name)));
    }
    e.size = e.npy_header.size() + a.data.size() * sizeof(double);
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
    if constexpr (std::endian::native == std::endian::little) {
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
  for (const NpyArray& a : arrays) views.push_back({a.name, a.shape, a.data});
  Write(path, views);
}

void ExportNpz(const std::string& path, const ModelTables& tables, const Trajectory& traj,
               const std::vector<NpyArray>& extra) {
  traj.Check(tables);
  const std::size_t rows = traj.rows();
  std::vector<ArrayView> arrays;
  arrays.push_back({"time", {rows}, traj.time});
  arrays.push_back({"qpos", {rows, static_cast<std::size_t>(traj.nq)}, traj.qpos});
  if (traj.has_qvel()) {
    arrays.push_back({"qvel", {rows, static_cast<std::size_t>(traj.nv)}, traj.qvel});
  }
  for (const NpyArray& a : extra) arrays.push_back({a.name, a.shape, a.data});
  Write(path, arrays);
}

}  // namespace urlab::replay
