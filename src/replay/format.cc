#include "replay/format.h"

#include <fmt/format.h>
#include <mujoco/mujoco.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <memory>
#include <new>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/byte_io.h"
#include "urlab/physics/state.h"

namespace urlab::replay::format {

namespace {

static_assert(std::endian::native == std::endian::little, "recordings are little-endian");

enum RecordType : std::uint8_t {
  kFrame = 1,
  kState = 2,
  kMarker = 3,
  kOptions = 4,
  kGap = 5,
};

enum FrameGroups : std::uint8_t {
  kGroupMocap = 1,
  kGroupQfrc = 2,
  kGroupXfrc = 4,
  kGroupSensors = 8,
  kGroupCommands = 16,  // the applied command frames changed (always in a chunk's first frame)
  // With kGroupCommands (format 3): one byte per command group, 1 where the frame was raw
  // (control_mode raw: the targets were the controls). Absent: no group was raw.
  kGroupRaw = 32,
};
constexpr std::uint8_t kAllGroups =
    kGroupMocap | kGroupQfrc | kGroupXfrc | kGroupSensors | kGroupCommands | kGroupRaw;

template <typename T>
void Put(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out->append(bytes, sizeof(T));
}

using Cursor = internal::ByteReader;

void PutDoubles(std::string* out, const std::vector<double>& v) {
  if (!v.empty()) out->append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
}

std::uint64_t Bits(double v) { return std::bit_cast<std::uint64_t>(v); }

void XorInto(std::vector<double>* values, const std::vector<double>& prev) {
  for (std::size_t i = 0; i < values->size(); ++i) {
    (*values)[i] = std::bit_cast<double>(Bits((*values)[i]) ^ Bits(prev[i]));
  }
}

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

bool SameCommands(const physics::AppliedCommands& a, const physics::AppliedCommands& b) {
  return a.seq == b.seq && a.source == b.source && a.raw == b.raw &&
         SameBits(a.targets, b.targets) && SameBits(a.kp, b.kp) && SameBits(a.kv, b.kv);
}

// Limits on what a header may declare, so damaged bytes cannot ask for absurd allocations.
constexpr int kMaxSize = 100'000'000;

int CheckedSize(const nlohmann::json& j, const char* key) {
  const int v = j.at(key).get<int>();
  if (v < 0 || v > kMaxSize) {
    throw std::runtime_error(std::string("header field ") + key +
                             " out of range: " + std::to_string(v));
  }
  return v;
}

void CheckRange(const std::string& what, const std::string& name, int adr, int dim, int size) {
  if (adr < 0 || dim < 0 || adr > size || dim > size - adr) {
    throw std::runtime_error("header: " + what + " '" + name + "' lies outside its vector (adr " +
                             std::to_string(adr) + ", dim " + std::to_string(dim) + ", size " +
                             std::to_string(size) + ")");
  }
}

nlohmann::json RangesToJson(const std::vector<NamedRange>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (const NamedRange& r : v) a.push_back({r.name, r.adr, r.dim});
  return a;
}

std::vector<NamedRange> RangesFromJson(const nlohmann::json& a, const std::string& what, int size) {
  std::vector<NamedRange> v;
  for (const nlohmann::json& e : a) {
    NamedRange r{e.at(0).get<std::string>(), e.at(1).get<int>(), e.at(2).get<int>()};
    CheckRange(what, r.name, r.adr, r.dim, size);
    v.push_back(std::move(r));
  }
  return v;
}

}  // namespace

std::string FileHeader() {
  std::string h(kFileMagic, sizeof(kFileMagic));
  Put<std::uint32_t>(&h, kRecordingFormatVersion);
  Put<std::uint32_t>(&h, 0);
  return h;
}

std::uint32_t CheckFileHeader(std::span<const std::uint8_t> bytes, const std::string& path) {
  if (bytes.size() < kFileHeaderSize || std::memcmp(bytes.data(), kFileMagic, 8) != 0) {
    throw RecordingError(RecordingError::Reason::kNotARecording, path,
                         "not a URLab recording (no URLABREC magic number at the start)");
  }
  std::uint32_t version = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  if (version >= 1 && version < kOldestRecordingFormatVersion) {
    throw RecordingError(RecordingError::Reason::kVersion, path,
                         fmt::format("recording format version {} was written by a URLab on "
                                     "MuJoCo 2.2.2, whose model this URLab's MuJoCo {} cannot "
                                     "load (it reads format {}): play it with the URLab that "
                                     "recorded it",
                                     version, mj_versionString(), kRecordingFormatVersion));
  }
  if (version < kOldestRecordingFormatVersion || version > kRecordingFormatVersion) {
    throw RecordingError(RecordingError::Reason::kVersion, path,
                         fmt::format("recording format version {} is not supported (this URLab "
                                     "reads version {}{})",
                                     version, kOldestRecordingFormatVersion,
                                     kOldestRecordingFormatVersion == kRecordingFormatVersion
                                         ? std::string()
                                         : fmt::format(" to {}", kRecordingFormatVersion)));
  }
  return version;
}

namespace {

std::string HeaderBytes(const ChunkHeader& h) {
  std::string b;
  Put<std::uint32_t>(&b, kChunkMagic);
  Put<std::uint32_t>(&b, static_cast<std::uint32_t>(h.kind));
  Put<std::uint32_t>(&b, h.number);
  Put<std::uint32_t>(&b, static_cast<std::uint32_t>(h.codec));
  Put<std::uint64_t>(&b, h.stored_size);
  Put<std::uint64_t>(&b, h.raw_size);
  Put<std::uint64_t>(&b, h.first_step);
  Put<std::uint64_t>(&b, h.last_step);
  Put<double>(&b, h.first_time);
  Put<double>(&b, h.last_time);
  Put<std::uint32_t>(&b, h.frames);
  Put<std::uint32_t>(&b, h.flags);
  return b;  // 72 bytes; the CRC follows, then zero padding to kChunkHeaderSize
}

}  // namespace

std::uint32_t ChunkCrc(std::span<const std::uint8_t> header_bytes, std::string_view stored) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, header_bytes.data(), static_cast<uInt>(header_bytes.size()));
  std::size_t done = 0;
  while (done < stored.size()) {  // crc32 takes at most 4 GiB at a time
    const std::size_t n = std::min<std::size_t>(stored.size() - done, 1u << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(stored.data() + done), static_cast<uInt>(n));
    done += n;
  }
  return static_cast<std::uint32_t>(crc);
}

std::string EncodeChunk(ChunkHeader header, std::string_view stored) {
  header.stored_size = stored.size();
  std::string b = HeaderBytes(header);
  // The CRC covers the header (without the CRC itself) and the payload.
  const std::uint32_t crc =
      ChunkCrc(std::span(reinterpret_cast<const std::uint8_t*>(b.data()), b.size()), stored);
  Put<std::uint32_t>(&b, crc);
  b.resize(kChunkHeaderSize, '\0');
  b.append(stored);
  return b;
}

bool DecodeChunkHeader(std::span<const std::uint8_t> bytes, ChunkHeader* out) {
  if (bytes.size() < kChunkHeaderSize) return false;
  Cursor c(std::string_view(reinterpret_cast<const char*>(bytes.data()), kChunkHeaderSize),
           "chunk header");
  if (c.Get<std::uint32_t>() != kChunkMagic) return false;
  ChunkHeader h;
  h.kind = static_cast<ChunkKind>(c.Get<std::uint32_t>());
  h.number = c.Get<std::uint32_t>();
  h.codec = static_cast<Codec>(c.Get<std::uint32_t>());
  h.stored_size = c.Get<std::uint64_t>();
  h.raw_size = c.Get<std::uint64_t>();
  h.first_step = c.Get<std::uint64_t>();
  h.last_step = c.Get<std::uint64_t>();
  h.first_time = c.Get<double>();
  h.last_time = c.Get<double>();
  h.frames = c.Get<std::uint32_t>();
  h.flags = c.Get<std::uint32_t>();
  h.crc = c.Get<std::uint32_t>();
  *out = h;
  return true;
}

std::string Compress(std::string_view raw, Codec codec, int level) {
  if (codec == Codec::kStored) return std::string(raw);
  std::string out(ZSTD_compressBound(raw.size()), '\0');
  const std::size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), level);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

std::string Decompress(std::string_view stored, Codec codec, std::uint64_t raw_size,
                       std::uint64_t max_raw_size) {
  if (raw_size > max_raw_size) {
    throw std::runtime_error(fmt::format(
        "declares {} bytes uncompressed, more than the {} MiB such a chunk can hold (damaged, or "
        "not written by URLab)",
        raw_size, max_raw_size >> 20));
  }
  if (codec == Codec::kStored) {
    if (stored.size() != raw_size) throw std::runtime_error("stored payload size mismatch");
    return std::string(stored);
  }
  if (codec != Codec::kZstd) {
    throw std::runtime_error("unknown compression codec " +
                             std::to_string(static_cast<std::uint32_t>(codec)));
  }
  const unsigned long long content = ZSTD_getFrameContentSize(stored.data(), stored.size());
  if (content == ZSTD_CONTENTSIZE_ERROR || content != raw_size) {
    throw std::runtime_error("zstd frame does not declare the chunk's size");
  }
  std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  if (!ctx) throw std::bad_alloc();
  // Grown as zstd produces bytes: a false declaration costs nothing, a real one what it holds.
  std::string out(static_cast<std::size_t>(std::min<std::uint64_t>(
                      raw_size, std::max<std::uint64_t>(8 * stored.size(), 1u << 20))),
                  '\0');
  ZSTD_inBuffer in{stored.data(), stored.size(), 0};
  std::size_t produced = 0;
  while (true) {
    if (produced == out.size()) {
      if (out.size() == raw_size) {
        // All declared bytes are out; the frame must end without producing more.
        char extra = 0;
        ZSTD_outBuffer probe{&extra, 1, 0};
        const std::size_t r = ZSTD_decompressStream(ctx.get(), &probe, &in);
        if (ZSTD_isError(r)) {
          throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(r));
        }
        if (probe.pos > 0) throw std::runtime_error("zstd payload is longer than declared");
        if (r == 0) break;
        if (in.pos == in.size) throw std::runtime_error("zstd payload is truncated");
        continue;
      }
      out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(raw_size, 2 * out.size())));
    }
    ZSTD_outBuffer ob{out.data(), out.size(), produced};
    const std::size_t r = ZSTD_decompressStream(ctx.get(), &ob, &in);
    if (ZSTD_isError(r)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(r));
    const bool progressed = ob.pos > produced;
    produced = ob.pos;
    if (r == 0) break;  // the frame is complete
    if (!progressed && in.pos == in.size && produced < out.size()) {
      throw std::runtime_error("zstd payload is truncated");
    }
  }
  if (produced != raw_size) throw std::runtime_error("zstd payload is shorter than declared");
  if (in.pos != in.size) throw std::runtime_error("bytes after the zstd frame");
  return out;
}

std::string EncodeFileStart(const RecordingInfo& info, Codec codec, int level) {
  ChunkHeader h;
  h.kind = ChunkKind::kHeader;
  h.number = 0;
  h.codec = codec;
  const std::string raw = EncodeInfo(info);
  h.raw_size = raw.size();
  return FileHeader() + EncodeChunk(h, Compress(raw, codec, level));
}

std::string EncodeEndChunk(std::uint32_t number, std::string_view totals_json) {
  ChunkHeader h;
  h.kind = ChunkKind::kEnd;
  h.number = number;
  h.raw_size = totals_json.size();
  return EncodeChunk(h, totals_json);
}

std::string EncodeInfo(const RecordingInfo& info) {
  const ModelTables& t = info.tables;
  nlohmann::json joints = nlohmann::json::array();
  for (const JointEntry& j : t.joints) {
    joints.push_back({j.name, j.articulation, j.short_name, j.type, j.qposadr, j.dofadr});
  }
  nlohmann::json groups = nlohmann::json::array();
  for (const physics::CommandGroupLayout& g : t.command_groups) {
    groups.push_back({g.name, g.actuators});
  }
  nlohmann::json j = {{"format_version", kRecordingFormatVersion},
                      {"kind", info.kind},
                      {"urlab_version", info.urlab_version},
                      {"mujoco_version", info.mujoco_version},
                      {"model_hash", HashText(info.model_hash)},
                      {"created", info.created},
                      {"scene", info.scene},
                      {"sensordata", info.sensordata},
                      {"keyframe_interval", info.keyframe_interval},
                      {"compression", info.compression},
                      {"tables",
                       {{"nq", t.nq},
                        {"nv", t.nv},
                        {"na", t.na},
                        {"nu", t.nu},
                        {"nbody", t.nbody},
                        {"nmocap", t.nmocap},
                        {"nsensordata", t.nsensordata},
                        {"timestep", t.timestep},
                        {"articulations", t.articulations},
                        {"joints", joints},
                        {"actuators", RangesToJson(t.actuators)},
                        {"sensors", RangesToJson(t.sensors)},
                        {"mocap_bodies", RangesToJson(t.mocap_bodies)},
                        {"bodies", t.bodies},
                        {"command_groups", groups}}}};
  const std::string text = j.dump();
  std::string out;
  Put<std::uint64_t>(&out, text.size());
  out += text;
  Put<std::uint64_t>(&out, info.mjcf.size());
  out += info.mjcf;
  Put<std::uint64_t>(&out, info.mjb.size());
  out += info.mjb;
  return out;
}

RecordingInfo DecodeInfo(std::string_view payload) {
  Cursor c(payload, "header chunk");
  const std::string_view text = c.GetBytes(c.Get<std::uint64_t>());
  RecordingInfo info;
  info.mjcf = std::string(c.GetBytes(c.Get<std::uint64_t>()));
  info.mjb = std::string(c.GetBytes(c.Get<std::uint64_t>()));
  if (!c.done()) throw std::runtime_error("header chunk has bytes after the model");
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    info.format_version = j.at("format_version").get<std::uint32_t>();
    info.kind = j.at("kind").get<std::string>();
    info.urlab_version = j.at("urlab_version").get<std::string>();
    info.mujoco_version = j.at("mujoco_version").get<std::string>();
    const std::string hash = j.at("model_hash").get<std::string>();
    std::size_t used = 0;
    info.model_hash = std::stoull(hash, &used, 16);
    if (used != hash.size() || hash.size() != 16) throw std::runtime_error("bad model_hash");
    info.created = j.at("created").get<std::string>();
    info.scene = j.at("scene").get<std::string>();
    info.sensordata = j.at("sensordata").get<bool>();
    info.keyframe_interval = j.at("keyframe_interval").get<double>();
    info.compression = j.at("compression").get<std::string>();
    const nlohmann::json& tj = j.at("tables");
    ModelTables& t = info.tables;
    t.nq = CheckedSize(tj, "nq");
    t.nv = CheckedSize(tj, "nv");
    t.na = CheckedSize(tj, "na");
    t.nu = CheckedSize(tj, "nu");
    t.nbody = CheckedSize(tj, "nbody");
    t.nmocap = CheckedSize(tj, "nmocap");
    t.nsensordata = CheckedSize(tj, "nsensordata");
    t.timestep = tj.at("timestep").get<double>();
    t.articulations = tj.at("articulations").get<std::vector<std::string>>();
    for (const nlohmann::json& e : tj.at("joints")) {
      JointEntry je;
      je.name = e.at(0).get<std::string>();
      je.articulation = e.at(1).get<std::string>();
      je.short_name = e.at(2).get<std::string>();
      je.type = e.at(3).get<int>();
      je.qposadr = e.at(4).get<int>();
      je.dofadr = e.at(5).get<int>();
      if (je.type < mjJNT_FREE || je.type > mjJNT_HINGE) {
        throw std::runtime_error("header: joint '" + je.name + "' has an unknown type");
      }
      je.nq = JointQposWidth(je.type);
      je.nv = JointDofWidth(je.type);
      CheckRange("joint", je.name, je.qposadr, je.nq, t.nq);
      CheckRange("joint", je.name, je.dofadr, je.nv, t.nv);
      t.joints.push_back(std::move(je));
    }
    t.actuators = RangesFromJson(tj.at("actuators"), "actuator", t.nu);
    t.sensors = RangesFromJson(tj.at("sensors"), "sensor", t.nsensordata);
    t.mocap_bodies = RangesFromJson(tj.at("mocap_bodies"), "mocap body", t.nmocap);
    t.bodies = tj.at("bodies").get<std::vector<std::string>>();
    if (static_cast<int>(t.bodies.size()) != t.nbody) {
      throw std::runtime_error("header: the body table does not have nbody names");
    }
    if (tj.contains("command_groups")) {
      for (const nlohmann::json& e : tj.at("command_groups")) {
        physics::CommandGroupLayout g;
        g.name = e.at(0).get<std::string>();
        g.actuators = e.at(1).get<std::vector<int>>();
        for (int a : g.actuators) {
          if (a < 0 || a >= t.nu) {
            throw std::runtime_error("header: command group '" + g.name + "' names actuator " +
                                     std::to_string(a) + " of " + std::to_string(t.nu));
          }
        }
        t.command_groups.push_back(std::move(g));
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("header JSON: ") + e.what());
  }
  return info;
}

// ---- ChunkEncoder ----

ChunkEncoder::ChunkEncoder(const ModelTables& tables, bool sensordata)
    : tables_(tables), sensordata_(sensordata) {
  Reset();
}

void ChunkEncoder::Reset() {
  out_.clear();
  frames_ = 0;
  starts_with_state_ = false;
  first_step_ = last_step_ = 0;
  first_time_ = last_time_ = 0;
  have_prev_ = false;
  have_commands_ = false;
  const auto z = [](int n) { return std::vector<double>(static_cast<std::size_t>(n), 0.0); };
  qpos_ = z(tables_.nq);
  qvel_ = z(tables_.nv);
  act_ = z(tables_.na);
  ctrl_ = z(tables_.nu);
  sensordata_prev_ = z(sensordata_ ? tables_.nsensordata : 0);
  mocap_pos_ = z(3 * tables_.nmocap);
  mocap_quat_ = z(4 * tables_.nmocap);
  qfrc_ = z(tables_.nv);
  xfrc_ = z(6 * tables_.nbody);
}

ChunkHeader ChunkEncoder::Header(Codec codec) const {
  ChunkHeader h;
  h.kind = ChunkKind::kData;
  h.codec = codec;
  h.raw_size = out_.size();
  h.first_step = first_step_;
  h.last_step = last_step_;
  h.first_time = first_time_;
  h.last_time = last_time_;
  h.frames = frames_;
  h.flags = starts_with_state_ ? kStartsWithState : 0;
  return h;
}

void ChunkEncoder::Begin(std::uint8_t type) {
  record_start_ = out_.size();
  out_.push_back(static_cast<char>(type));
  Put<std::uint32_t>(&out_, 0);  // body length, filled by End
}

void ChunkEncoder::End() {
  const std::uint32_t n = static_cast<std::uint32_t>(out_.size() - record_start_ - 5);
  std::memcpy(out_.data() + record_start_ + 1, &n, 4);
}

void ChunkEncoder::PutXor(const std::vector<double>& now, std::vector<double>* prev) {
  for (std::size_t i = 0; i < now.size(); ++i) {
    Put<std::uint64_t>(&out_, Bits(now[i]) ^ Bits((*prev)[i]));
  }
  *prev = now;
}

void ChunkEncoder::Add(const physics::StateFrame& f) {
  if (frames_ == 0) {
    first_step_ = f.step;
    first_time_ = f.time;
  }
  last_step_ = f.step;
  last_time_ = f.time;
  ++frames_;
  std::uint8_t groups = 0;
  if (tables_.nmocap > 0 &&
      (!have_prev_ || !SameBits(f.mocap_pos, mocap_pos_) || !SameBits(f.mocap_quat, mocap_quat_))) {
    groups |= kGroupMocap;
  }
  if (!SameBits(f.qfrc_applied, qfrc_)) groups |= kGroupQfrc;
  if (!SameBits(f.xfrc_applied, xfrc_)) groups |= kGroupXfrc;
  if (sensordata_) groups |= kGroupSensors;
  const bool commands = !tables_.command_groups.empty() && !f.commands.empty();
  if (commands && (!have_commands_ || !SameCommands(f.commands, commands_))) {
    groups |= kGroupCommands;
    if (std::any_of(f.commands.raw.begin(), f.commands.raw.end(), [](auto r) { return r != 0; })) {
      groups |= kGroupRaw;
    }
  }
  Begin(kFrame);
  Put<double>(&out_, f.time);
  Put<std::uint64_t>(&out_, f.step);
  out_.push_back(static_cast<char>(groups));
  PutXor(f.qpos, &qpos_);
  PutXor(f.qvel, &qvel_);
  PutXor(f.act, &act_);
  PutXor(f.ctrl, &ctrl_);
  if (groups & kGroupMocap) {
    PutDoubles(&out_, f.mocap_pos);
    PutDoubles(&out_, f.mocap_quat);
    mocap_pos_ = f.mocap_pos;
    mocap_quat_ = f.mocap_quat;
  }
  if (groups & kGroupQfrc) {
    PutDoubles(&out_, f.qfrc_applied);
    qfrc_ = f.qfrc_applied;
  }
  if (groups & kGroupXfrc) {  // the nonzero rows
    std::uint32_t rows = 0;
    const std::size_t count_at = out_.size();
    Put<std::uint32_t>(&out_, 0);
    for (int b = 0; b < tables_.nbody; ++b) {
      const double* row = f.xfrc_applied.data() + 6 * b;
      bool zero = true;
      for (int k = 0; k < 6; ++k) zero = zero && Bits(row[k]) == 0;
      if (zero) continue;
      Put<std::uint32_t>(&out_, static_cast<std::uint32_t>(b));
      out_.append(reinterpret_cast<const char*>(row), 6 * sizeof(double));
      ++rows;
    }
    std::memcpy(out_.data() + count_at, &rows, 4);
    xfrc_ = f.xfrc_applied;
  }
  if (groups & kGroupSensors) PutXor(f.sensordata, &sensordata_prev_);
  if (groups & kGroupCommands) {  // per group seq and source, then targets, kp, kv, raw
    for (std::size_t g = 0; g < f.commands.seq.size(); ++g) {
      Put<std::uint64_t>(&out_, f.commands.seq[g]);
      out_.push_back(static_cast<char>(f.commands.source[g]));
    }
    PutDoubles(&out_, f.commands.targets);
    PutDoubles(&out_, f.commands.kp);
    PutDoubles(&out_, f.commands.kv);
    if (groups & kGroupRaw) {
      for (std::uint8_t r : f.commands.raw) out_.push_back(static_cast<char>(r != 0 ? 1 : 0));
    }
    commands_ = f.commands;
    have_commands_ = true;
  }
  have_prev_ = true;
  End();
}

void ChunkEncoder::Add(const Frame& f) {
  scratch_.time = f.time;
  scratch_.step = f.step;
  scratch_.stepped = true;
  scratch_.qpos = f.qpos;
  scratch_.qvel = f.qvel;
  scratch_.act = f.act;
  scratch_.ctrl = f.ctrl;
  scratch_.mocap_pos = f.mocap_pos;
  scratch_.mocap_quat = f.mocap_quat;
  scratch_.qfrc_applied = f.qfrc_applied;
  scratch_.xfrc_applied = f.xfrc_applied;
  scratch_.commands = f.commands;
  scratch_.sensordata = f.sensordata;
  Add(scratch_);
}

void ChunkEncoder::Add(const StateRecord& s) {
  if (out_.empty()) starts_with_state_ = s.jump == 0;
  Begin(kState);
  Put<std::uint32_t>(&out_, s.jump);
  const std::vector<std::uint8_t> bytes = physics::SerializeState(s.state);
  out_.append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  End();
}

void ChunkEncoder::Add(const Marker& m) {
  Begin(kMarker);
  Put<std::uint32_t>(&out_, m.flags);
  Put<double>(&out_, m.time);
  Put<std::uint64_t>(&out_, m.step);
  out_ += m.text;
  End();
}

void ChunkEncoder::Add(const OptionsRecord& o) {
  Begin(kOptions);
  out_.append(reinterpret_cast<const char*>(o.option.data()), o.option.size());
  End();
}

void ChunkEncoder::Add(const Gap& g) {
  Begin(kGap);
  Put<std::uint64_t>(&out_, g.dropped);
  Put<std::uint64_t>(&out_, g.after_step);
  End();
}

// ---- DecodeChunk ----

std::vector<Record> DecodeChunk(std::string_view raw, const ModelTables& t, bool sensordata) {
  std::vector<Record> records;
  Cursor c(raw, "chunk");
  const auto z = [](int n) { return std::vector<double>(static_cast<std::size_t>(n), 0.0); };
  std::vector<double> qpos = z(t.nq), qvel = z(t.nv), act = z(t.na), ctrl = z(t.nu);
  std::vector<double> sens = z(sensordata ? t.nsensordata : 0);
  std::vector<double> mocap_pos = z(3 * t.nmocap), mocap_quat = z(4 * t.nmocap);
  std::vector<double> qfrc = z(t.nv), xfrc = z(6 * t.nbody);
  bool have_mocap = t.nmocap == 0;
  physics::AppliedCommands commands = physics::AppliedCommands::SizedFor(t.command_groups);
  bool have_commands = false;  // a recorder may start before the first controlled step
  std::size_t index = 0;
  while (!c.done()) {
    const std::string where = "record " + std::to_string(index);
    const auto type = c.Get<std::uint8_t>();
    const auto length = c.Get<std::uint32_t>();
    Cursor r(c.GetBytes(length), "record");
    try {
      switch (type) {
        case kFrame: {
          Frame f;
          f.time = r.Get<double>();
          f.step = r.Get<std::uint64_t>();
          const auto groups = r.Get<std::uint8_t>();
          if (groups & ~kAllGroups) {
            throw std::runtime_error("unknown frame fields");
          }
          const auto unxor = [&](std::vector<double>* out, std::vector<double>* prev) {
            r.GetDoubles(out, prev->size());
            XorInto(out, *prev);
            *prev = *out;
          };
          unxor(&f.qpos, &qpos);
          unxor(&f.qvel, &qvel);
          unxor(&f.act, &act);
          unxor(&f.ctrl, &ctrl);
          if (groups & kGroupMocap) {
            r.GetDoubles(&mocap_pos, mocap_pos.size());
            r.GetDoubles(&mocap_quat, mocap_quat.size());
            have_mocap = true;
          } else if (!have_mocap) {
            throw std::runtime_error("the chunk's first frame has no mocap poses");
          }
          if (groups & kGroupQfrc) r.GetDoubles(&qfrc, qfrc.size());
          if (groups & kGroupXfrc) {
            std::fill(xfrc.begin(), xfrc.end(), 0.0);
            const auto rows = r.Get<std::uint32_t>();
            for (std::uint32_t k = 0; k < rows; ++k) {
              const auto body = r.Get<std::uint32_t>();
              if (body >= static_cast<std::uint32_t>(t.nbody)) {
                throw std::runtime_error("applied force on body " + std::to_string(body) + " of " +
                                         std::to_string(t.nbody));
              }
              std::vector<double> row;
              r.GetDoubles(&row, 6);
              std::copy(row.begin(), row.end(), xfrc.begin() + 6 * body);
            }
          }
          if (groups & kGroupSensors) {
            if (!sensordata) throw std::runtime_error("sensordata in a file without it");
            unxor(&f.sensordata, &sens);
          }
          f.mocap_pos = mocap_pos;
          f.mocap_quat = mocap_quat;
          if (groups & kGroupCommands) {
            if (t.command_groups.empty()) {
              throw std::runtime_error("command frames in a file without command groups");
            }
            for (std::size_t g = 0; g < commands.seq.size(); ++g) {
              commands.seq[g] = r.Get<std::uint64_t>();
              commands.source[g] = r.Get<std::uint8_t>();
            }
            r.GetDoubles(&commands.targets, commands.targets.size());
            r.GetDoubles(&commands.kp, commands.kp.size());
            r.GetDoubles(&commands.kv, commands.kv.size());
            std::fill(commands.raw.begin(), commands.raw.end(), 0);
            if (groups & kGroupRaw) {
              for (std::uint8_t& flag : commands.raw) {
                flag = r.Get<std::uint8_t>();
                if (flag > 1) throw std::runtime_error("a raw flag that is neither 0 nor 1");
              }
            }
            have_commands = true;
          } else if (groups & kGroupRaw) {
            throw std::runtime_error("raw flags without command frames");
          }
          f.qfrc_applied = qfrc;
          f.xfrc_applied = xfrc;
          if (have_commands) f.commands = commands;
          records.emplace_back(std::move(f));
          break;
        }
        case kState: {
          StateRecord s;
          s.jump = r.Get<std::uint32_t>();
          const std::string_view bytes = r.GetBytes(r.remaining());
          s.state = physics::DeserializeState(
              std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
          if (s.state.layout.nq != t.nq || s.state.layout.nv != t.nv || s.state.layout.na != t.na ||
              s.state.layout.nu != t.nu || s.state.layout.nbody != t.nbody ||
              s.state.layout.nmocap != t.nmocap) {
            throw std::runtime_error("state of another model (" + s.state.layout.str() + ")");
          }
          records.emplace_back(std::move(s));
          break;
        }
        case kMarker: {
          Marker m;
          m.flags = r.Get<std::uint32_t>();
          m.time = r.Get<double>();
          m.step = r.Get<std::uint64_t>();
          m.text = std::string(r.GetBytes(r.remaining()));
          records.emplace_back(std::move(m));
          break;
        }
        case kOptions: {
          const std::string_view bytes = r.GetBytes(r.remaining());
          if (bytes.size() != sizeof(mjOption)) {
            throw std::runtime_error("physics options of " + std::to_string(bytes.size()) +
                                     " bytes (this MuJoCo's are " +
                                     std::to_string(sizeof(mjOption)) + ")");
          }
          OptionsRecord o;
          o.option.assign(bytes.begin(), bytes.end());
          records.emplace_back(std::move(o));
          break;
        }
        case kGap: {
          Gap g;
          g.dropped = r.Get<std::uint64_t>();
          g.after_step = r.Get<std::uint64_t>();
          records.emplace_back(g);
          break;
        }
        default:
          throw std::runtime_error("unknown record type " + std::to_string(type));
      }
      if (!r.done()) throw std::runtime_error("has bytes after its fields");
    } catch (const physics::StateError& e) {
      throw std::runtime_error(where + ": " + e.what());
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(where + ": " + e.what());
    }
    ++index;
  }
  return records;
}

}  // namespace urlab::replay::format
