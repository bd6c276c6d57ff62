#pragma once
// Recording files (.urrec): what a recorder wrote, read back chunk by chunk.
//
// Layout (little-endian). A 16-byte file header: the magic "URLABREC", the format version (u32)
// and a reserved u32. Then chunks, each an 80-byte chunk header (magic "CHNK", kind, number,
// codec, stored and raw payload sizes, a CRC-32 of the header's other fields and the stored
// payload, and the chunk's first/last step, first/last time and frame count) and its payload,
// zstd-compressed or stored:
// - chunk 0, the header, three sections each a u64 length and its bytes: JSON metadata (format,
//   URLab and MuJoCo versions, model hash, creation time, scene, options, the name tables), the
//   composed scene's MJCF text, and the compiled model (MJB, of the MuJoCo named) as it was when
//   the recording started (its physics options included), so a recording replays without the
//   files it was made from. The model hash is physics::ContentHash of the MJB;
// - data chunks: records in order. Every data chunk normally starts with a full PhysicsState
//   (a keyframe: seeking restores it), then frames (one per physics step: time, step, qpos,
//   qvel, act, ctrl, and when they changed the mocap poses and applied forces; sensordata when
//   recorded; when they changed, the command frames applied, with their raw flags),
//   markers where the state jumped (reset, restore, set state, options), the state
//   right after each jump, changed physics options, and gaps (frames the recorder's ring lost);
// - an end chunk (totals) once the recording was finished and renamed into place.
// Format 4 came with MuJoCo 3 (the MJB is MuJoCo 3's; the header names the MuJoCo version).
// Formats 1 to 3 hold MuJoCo 2.2.2 models, which MuJoCo 3 cannot load: they are refused with a
// message saying so, as is any other version.
// A recorder writes "NAME.part" and renames it when finished; a crash leaves the .part file with
// every chunk flushed before it (a chunk spans at most about a second). A truncated or damaged
// chunk ends the readable prefix: the chunks before it stay readable, and the error names it.
//
// Thread: a RecordingReader is used by one thread at a time.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state.h"
#include "urlab/replay/tables.h"

namespace urlab::replay {

// The version written; kOldestRecordingFormatVersion..kRecordingFormatVersion are read.
inline constexpr std::uint32_t kRecordingFormatVersion = 4;
inline constexpr std::uint32_t kOldestRecordingFormatVersion = 4;

// A file that is not a readable recording (bad magic, unsupported version, damaged or truncated
// chunk, wrong model). what() names the file, and the chunk when one is at fault.
class RecordingError : public InputError {
 public:
  enum class Reason {
    kNotARecording,  // no magic number, or not a file of ours
    kVersion,        // a format version this build does not read
    kTruncated,      // the file ends inside a chunk
    kCorrupt,        // a checksum, a size or a record does not hold
    kUnfinished,     // no end chunk: the recorder was killed (the chunks are fine)
    kWrongModel,     // recorded with another model than the one it is played on
  };
  RecordingError(Reason reason, const std::string& path, const std::string& message)
      : InputError(SourceLocation{path, 0}, message), reason_(reason) {}
  Reason reason() const { return reason_; }

 private:
  Reason reason_;
};

// What the header chunk says.
struct RecordingInfo {
  std::uint32_t format_version = kRecordingFormatVersion;
  std::string kind = "recording";  // "recording" or "snapshot"
  std::string urlab_version;
  std::string mujoco_version;    // of the MuJoCo that wrote the MJB, e.g. "3.17.0"
  std::uint64_t model_hash = 0;  // physics::Model::Hash of the recorded model
  std::string created;           // UTC, ISO 8601
  std::string scene;             // the scene file it was recorded from ("" when unknown)
  std::string mjcf;              // the composed scene's MJCF
  std::string mjb;               // the compiled model, MuJoCo binary
  ModelTables tables;
  bool sensordata = false;           // frames carry sensordata
  double keyframe_interval = 1;      // simulated seconds between keyframes
  std::string compression = "zstd";  // "zstd" or "none"
};

// Sets info->urlab_version, info->mujoco_version, info->mjb and info->model_hash from `m` (saving
// the model once). Reads the mjModel: where its owner allows (the engine's: WithLockedData).
void DescribeModel(const physics::Model& m, RecordingInfo* info);
// 16 hexadecimal digits.
std::string HashText(std::uint64_t hash);

// One physics step as recorded.
struct Frame {
  double time = 0;
  std::uint64_t step = 0;
  std::vector<double> qpos, qvel, act, ctrl;
  std::vector<double> mocap_pos, mocap_quat;       // 3 / 4 per mocap body
  std::vector<double> qfrc_applied, xfrc_applied;  // nv / 6 per body, as the step used them
  std::vector<double> sensordata;                  // empty unless recorded
  // The command frames the step applied, laid out by the tables' command_groups (empty when the
  // recording has none).
  physics::AppliedCommands commands;
};

// The full state at a point of the recording: a chunk's keyframe (`jump` 0) or the state right
// after a discontinuity (`jump`: physics::Discontinuity flags). It holds before the next frame.
struct StateRecord {
  std::uint32_t jump = 0;
  physics::PhysicsState state;
};

// A marker's flag beside the physics::Discontinuity ones: the recorder could not capture the
// state after this jump (an automatic reset after a divergence), so a re-simulation waits for the
// next keyframe. Recordings made before the flag existed say so only in the marker's text
// ("... (not captured)"), which IsUncapturedJump also reads.
inline constexpr std::uint32_t kMarkerNotCaptured = 1u << 31;

// Where the state jumped, and why (the frame after it follows the jump).
struct Marker {
  std::uint32_t flags = 0;  // physics::Discontinuity, and kMarkerNotCaptured
  double time = 0;
  std::uint64_t step = 0;
  std::string text;  // DiscontinuityString(flags)
};

// True for a jump whose state the recorder did not capture (kMarkerNotCaptured).
bool IsUncapturedJump(const Marker& m);

// Physics options changed (the whole mjOption after the change, raw bytes of the struct of the
// MuJoCo the header names).
struct OptionsRecord {
  std::vector<std::uint8_t> option;
};

// Frames the recorder lost (its ring was full): re-simulation cannot cross a gap.
struct Gap {
  std::uint64_t dropped = 0;
  std::uint64_t after_step = 0;  // last step recorded before the gap
};

using Record = std::variant<Frame, StateRecord, Marker, OptionsRecord, Gap>;

// What a chunk header says, without reading its payload.
struct ChunkInfo {
  std::uint32_t number = 0;
  std::uint64_t offset = 0;  // of its chunk header in the file
  std::uint64_t stored_size = 0;
  std::uint64_t raw_size = 0;
  std::uint64_t first_step = 0, last_step = 0;
  double first_time = 0, last_time = 0;
  std::uint32_t frames = 0;
  bool starts_with_state = false;
};

class RecordingReader {
 public:
  struct Options {
    // Keep the readable prefix of a truncated or damaged file (problem() says what is wrong)
    // instead of throwing.
    bool allow_partial = false;
  };
  // Reads the file header, the header chunk and every chunk header (not the data payloads).
  // Throws RecordingError naming the file (and chunk) for a file that is not a recording, an
  // unsupported version, or (unless allow_partial) a damaged or truncated chunk or a missing
  // end chunk.
  static RecordingReader Open(const std::string& path, Options options);
  static RecordingReader Open(const std::string& path) { return Open(path, Options{}); }
  RecordingReader(RecordingReader&&) noexcept;
  RecordingReader& operator=(RecordingReader&&) noexcept;
  ~RecordingReader();

  const std::string& path() const { return path_; }
  const RecordingInfo& info() const { return info_; }
  // Data chunks, in order (the end chunk is not listed).
  const std::vector<ChunkInfo>& chunks() const { return chunks_; }
  // True when the file ended with its end chunk (a finished recording).
  bool finished() const { return finished_; }
  // What is wrong with a partial file ("" when nothing is), and why the readable prefix ends
  // (kUnfinished or kTruncated: a recorder that died; kCorrupt: damaged or forged).
  const std::string& problem() const { return problem_; }
  RecordingError::Reason problem_reason() const { return problem_reason_; }
  std::uint64_t frame_count() const;
  double first_time() const;
  double last_time() const;

  // Reads, checks and decodes one data chunk (index into chunks()). Throws RecordingError
  // naming the chunk when its checksum, compression or records are bad.
  std::vector<Record> ReadChunk(std::size_t index) const;
  // Every data chunk's checksum and records; throws at the first bad one.
  void Verify() const;
  // The index of the chunk holding `time` (the last chunk starting at or before it).
  std::size_t ChunkAt(double time) const;

 private:
  RecordingReader() = default;
  std::string path_;
  RecordingInfo info_;
  std::vector<ChunkInfo> chunks_;
  bool finished_ = false;
  std::string problem_;
  RecordingError::Reason problem_reason_ = RecordingError::Reason::kUnfinished;
  std::uint64_t file_size_ = 0;
};

// Writes a complete recording (header, one data chunk per element of `chunks`, end chunk) to
// `path` atomically: snapshots, edited or converted recordings, tests. Frames must be sized for
// info.tables. Throws Error naming the path.
void WriteRecording(const std::string& path, const RecordingInfo& info,
                    const std::vector<std::vector<Record>>& chunks);

// Every frame of a recording, in order, with the records between them (for tests and small
// files; a player reads chunk by chunk).
std::vector<Record> ReadAllRecords(const RecordingReader& reader);

}  // namespace urlab::replay
