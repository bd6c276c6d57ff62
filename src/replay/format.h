#pragma once
// The byte layout of recording files (see include/urlab/replay/recording.h): the file header,
// chunk headers, the header chunk's payload and the records of data chunks. Internal to the
// replay module. Pure functions and small stateful codecs; one thread each.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/physics/state_frame.h"
#include "urlab/replay/recording.h"

namespace urlab::replay::format {

inline constexpr char kFileMagic[8] = {'U', 'R', 'L', 'A', 'B', 'R', 'E', 'C'};
inline constexpr std::size_t kFileHeaderSize = 16;
inline constexpr std::uint32_t kChunkMagic = 0x4b4e4843;  // "CHNK"
inline constexpr std::size_t kChunkHeaderSize = 80;
inline constexpr std::size_t kChunkCrcBytes = 72;  // the header bytes the CRC covers
// A chunk payload larger than this is damage, not data (a recorder flushes far smaller ones;
// the header chunk holds the model, which may be large).
inline constexpr std::uint64_t kMaxChunkBytes = 1ull << 31;
// The most a chunk may declare uncompressed, checked before anything is allocated (a small file
// can declare gigabytes, and a zstd frame can expand 30000-fold). A data chunk: the recorder
// closes a chunk once its records pass kDataChunkFlushBytes (normally at a keyframe, long before),
// so one record more than that is the most it writes. The header chunk: the tables, the model's
// MJCF text and its MJB, which carries the meshes and height fields.
inline constexpr std::uint64_t kDataChunkFlushBytes = 32ull << 20;
inline constexpr std::uint64_t kMaxDataChunkRawBytes = 64ull << 20;
inline constexpr std::uint64_t kMaxHeaderChunkRawBytes = 512ull << 20;

enum class ChunkKind : std::uint32_t { kHeader = 1, kData = 2, kEnd = 3 };
enum class Codec : std::uint32_t { kStored = 0, kZstd = 1 };

struct ChunkHeader {
  ChunkKind kind = ChunkKind::kData;
  std::uint32_t number = 0;
  Codec codec = Codec::kStored;
  std::uint64_t stored_size = 0;
  std::uint64_t raw_size = 0;
  std::uint32_t crc = 0;  // of the header's other bytes and the stored payload
  std::uint64_t first_step = 0, last_step = 0;
  double first_time = 0, last_time = 0;
  std::uint32_t frames = 0;
  std::uint32_t flags = 0;  // kStartsWithState
};
inline constexpr std::uint32_t kStartsWithState = 1;

std::string FileHeader();
// The file's format version. Throws RecordingError (kNotARecording / kVersion, naming the
// version) naming `path`.
std::uint32_t CheckFileHeader(std::span<const std::uint8_t> bytes, const std::string& path);

// The 64 header bytes, CRC computed over them and `stored` payload.
std::string EncodeChunk(ChunkHeader header, std::string_view stored);
// Parses a chunk header (false when its magic is wrong); the CRC is checked separately.
bool DecodeChunkHeader(std::span<const std::uint8_t> bytes, ChunkHeader* out);
std::uint32_t ChunkCrc(std::span<const std::uint8_t> header_bytes, std::string_view stored);

// zstd at `level`, or the bytes themselves for kStored.
std::string Compress(std::string_view raw, Codec codec, int level = 3);
// Throws std::runtime_error with zstd's reason when the bytes do not decompress to `raw_size`, and
// before allocating anything when `raw_size` is larger than `max_raw_size`. Memory grows with the
// bytes zstd actually produces, never to a declared size ahead of them.
std::string Decompress(std::string_view stored, Codec codec, std::uint64_t raw_size,
                       std::uint64_t max_raw_size);

// The start of every recording file: the file header, then chunk 0 holding EncodeInfo(info).
std::string EncodeFileStart(const RecordingInfo& info, Codec codec, int level = 3);
// The end chunk numbered `number`, its payload the totals as JSON text (stored).
std::string EncodeEndChunk(std::uint32_t number, std::string_view totals_json);

// The header chunk's payload (format 2): u64 length + JSON, u64 length + MJCF, u64 length + MJB,
// u64 length + the model's extensions. Always written in the current format.
std::string EncodeInfo(const RecordingInfo& info);
// Reads a header chunk. Throws std::runtime_error naming the field at fault.
RecordingInfo DecodeInfo(std::string_view payload);

// Encodes records into one chunk's raw payload. Array fields of a frame are stored XORed with
// the previous frame's bits (zstd then compresses the mostly-zero bytes well); mocap poses and
// applied forces only when they changed (absent: as before; at the start of a chunk: zero
// forces, and the mocap poses always written).
class ChunkEncoder {
 public:
  ChunkEncoder(const ModelTables& tables, bool sensordata);
  void Add(const physics::StateFrame& frame);
  void Add(const Frame& frame);
  void Add(const StateRecord& state);
  void Add(const Marker& marker);
  void Add(const OptionsRecord& options);
  void Add(const Gap& gap);
  // The payload so far; Reset() starts a new chunk.
  const std::string& bytes() const { return out_; }
  bool empty() const { return out_.empty(); }
  // The data chunk header that describes bytes() (number 0: the writer numbers it).
  ChunkHeader Header(Codec codec) const;
  void Reset();

 private:
  void Begin(std::uint8_t type);
  void End();
  void PutXor(const std::vector<double>& now, std::vector<double>* prev);

  ModelTables tables_;
  bool sensordata_;
  physics::StateFrame scratch_;  // Add(Frame) goes through the StateFrame path
  std::string out_;
  std::size_t record_start_ = 0;
  std::uint32_t frames_ = 0;
  bool starts_with_state_ = false;
  std::uint64_t first_step_ = 0, last_step_ = 0;
  double first_time_ = 0, last_time_ = 0;
  bool have_prev_ = false;
  physics::AppliedCommands commands_;  // the last command frames written in this chunk
  bool have_commands_ = false;
  std::vector<double> qpos_, qvel_, act_, ctrl_, sensordata_prev_;
  std::vector<double> mocap_pos_, mocap_quat_, qfrc_, xfrc_;
};

// Decodes one chunk's raw payload. Throws std::runtime_error saying which record is bad.
std::vector<Record> DecodeChunk(std::string_view raw, const ModelTables& tables, bool sensordata);

}  // namespace urlab::replay::format
