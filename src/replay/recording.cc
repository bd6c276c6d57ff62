#include "urlab/replay/recording.h"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "replay/format.h"
#include "replay/io.h"
#include "urlab/core/files.h"
#include "urlab/core/version.h"

namespace urlab::replay {

namespace fs = std::filesystem;
namespace {
using Reason = RecordingError::Reason;
}  // namespace

void DescribeModel(const physics::Model& m, RecordingInfo* info) {
  info->urlab_version = kVersion;
  info->mujoco_version = physics::MujocoVersion();
  info->mjb = m.Mjb();
  info->model_hash = physics::ContentHash(info->mjb);
}

std::string HashText(std::uint64_t hash) { return fmt::format("{:016x}", hash); }

bool IsUncapturedJump(const Marker& m) {
  // The flag; before it existed, only the text said so (files of earlier builds).
  return (m.flags & kMarkerNotCaptured) != 0 || m.text.ends_with(" (not captured)");
}

RecordingReader::RecordingReader(RecordingReader&&) noexcept = default;
RecordingReader& RecordingReader::operator=(RecordingReader&&) noexcept = default;
RecordingReader::~RecordingReader() = default;

namespace {

std::string ChunkName(std::uint32_t number, std::uint64_t offset) {
  return fmt::format("chunk {} (at byte {})", number, offset);
}

}  // namespace

RecordingReader RecordingReader::Open(const std::string& path, Options options) {
  RecordingReader r;
  r.path_ = path;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw RecordingError(Reason::kNotARecording, path,
                         fs::exists(path, ec) ? "not a regular file" : "no such file");
  }
  InputFile file(path);
  r.file_size_ = file.size();
  const std::string head =
      file.Read(0, std::min<std::uint64_t>(format::kFileHeaderSize, r.file_size_));
  const std::uint32_t file_version = format::CheckFileHeader(
      std::span(reinterpret_cast<const std::uint8_t*>(head.data()), head.size()), path);

  // A structural problem ends the readable prefix: thrown, or kept in problem_.
  const auto stop = [&](Reason reason, const std::string& message) {
    if (!options.allow_partial) throw RecordingError(reason, path, message);
    r.problem_ = message;
    r.problem_reason_ = reason;
  };

  std::uint64_t offset = format::kFileHeaderSize;
  std::uint32_t number = 0;
  while (true) {
    if (offset == r.file_size_) {
      if (number == 0) {
        throw RecordingError(Reason::kTruncated, path, "the file ends before its header chunk");
      }
      stop(Reason::kUnfinished,
           fmt::format("unfinished recording: no end chunk after {} data chunk(s) (the recorder "
                       "was stopped without finishing; the chunks written are readable)",
                       r.chunks_.size()));
      break;
    }
    const std::string name = ChunkName(number, offset);
    if (r.file_size_ - offset < format::kChunkHeaderSize) {
      stop(Reason::kTruncated, name + ": the file ends inside its chunk header");
      break;
    }
    const std::string hb = file.Read(offset, format::kChunkHeaderSize);
    format::ChunkHeader h;
    if (!format::DecodeChunkHeader(
            std::span(reinterpret_cast<const std::uint8_t*>(hb.data()), hb.size()), &h)) {
      stop(Reason::kCorrupt, name +
                                 ": no chunk magic number (damaged data, or a damaged "
                                 "length in the chunk before it)");
      break;
    }
    if (h.number != number) {
      stop(Reason::kCorrupt, fmt::format("{}: numbered {} (damaged)", name, h.number));
      break;
    }
    if (h.stored_size > format::kMaxChunkBytes ||
        h.stored_size > r.file_size_ - offset - format::kChunkHeaderSize) {
      stop(Reason::kTruncated,
           fmt::format("{}: the file ends inside the chunk ({} payload bytes declared, {} "
                       "present)",
                       name, h.stored_size, r.file_size_ - offset - format::kChunkHeaderSize));
      break;
    }
    if (number == 0) {
      if (h.kind != format::ChunkKind::kHeader) {
        throw RecordingError(Reason::kCorrupt, path, name + ": the first chunk is not a header");
      }
      const std::string stored = file.Read(offset + format::kChunkHeaderSize, h.stored_size);
      if (format::ChunkCrc(
              std::span(reinterpret_cast<const std::uint8_t*>(hb.data()), format::kChunkCrcBytes),
              stored) != h.crc) {
        throw RecordingError(Reason::kCorrupt, path, name + " (header): checksum mismatch");
      }
      try {
        r.info_ = format::DecodeInfo(
            format::Decompress(stored, h.codec, h.raw_size, format::kMaxHeaderChunkRawBytes));
      } catch (const std::exception& e) {
        throw RecordingError(Reason::kCorrupt, path, name + " (header): " + e.what());
      }
      if (r.info_.format_version != file_version) {
        throw RecordingError(Reason::kVersion, path,
                             fmt::format("header chunk says format version {}, the file header "
                                         "{}",
                                         r.info_.format_version, file_version));
      }
    } else if (h.kind == format::ChunkKind::kEnd) {
      r.finished_ = true;
      if (offset + format::kChunkHeaderSize + h.stored_size != r.file_size_) {
        stop(Reason::kCorrupt, name + ": bytes after the end chunk");
      }
      break;
    } else if (h.kind == format::ChunkKind::kData) {
      if (h.raw_size > format::kMaxDataChunkRawBytes) {
        stop(Reason::kCorrupt,
             fmt::format("{}: declares {} bytes uncompressed, more than the {} MiB a data chunk "
                         "can hold (damaged, or not written by URLab)",
                         name, h.raw_size, format::kMaxDataChunkRawBytes >> 20));
        break;
      }
      // Every frame takes bytes: a chunk cannot declare more frames than it has raw bytes (a
      // forged count would be the recording's length in every report).
      if (h.frames > h.raw_size) {
        stop(Reason::kCorrupt,
             fmt::format("{}: declares {} frames in {} bytes (damaged, or not written by URLab)",
                         name, h.frames, h.raw_size));
        break;
      }
      ChunkInfo c;
      c.number = h.number;
      c.offset = offset;
      c.stored_size = h.stored_size;
      c.raw_size = h.raw_size;
      c.first_step = h.first_step;
      c.last_step = h.last_step;
      c.first_time = h.first_time;
      c.last_time = h.last_time;
      c.frames = h.frames;
      c.starts_with_state = (h.flags & format::kStartsWithState) != 0;
      r.chunks_.push_back(c);
    } else {
      stop(Reason::kCorrupt,
           fmt::format("{}: unknown chunk kind {}", name, static_cast<std::uint32_t>(h.kind)));
      break;
    }
    offset += format::kChunkHeaderSize + h.stored_size;
    ++number;
  }
  return r;
}

std::uint64_t RecordingReader::frame_count() const {
  std::uint64_t n = 0;
  for (const ChunkInfo& c : chunks_) n += c.frames;
  return n;
}

double RecordingReader::first_time() const {
  for (const ChunkInfo& c : chunks_) {
    if (c.frames) return c.first_time;
  }
  return 0;
}

double RecordingReader::last_time() const {
  for (auto it = chunks_.rbegin(); it != chunks_.rend(); ++it) {
    if (it->frames) return it->last_time;
  }
  return 0;
}

std::vector<Record> RecordingReader::ReadChunk(std::size_t index) const {
  if (index >= chunks_.size()) {
    throw Error(
        fmt::format("{}: no data chunk {} (the file has {})", path_, index, chunks_.size()));
  }
  const ChunkInfo& c = chunks_[index];
  const std::string name = ChunkName(c.number, c.offset);
  InputFile file(path_);
  const std::string hb = file.Read(c.offset, format::kChunkHeaderSize);
  format::ChunkHeader h;
  if (!format::DecodeChunkHeader(
          std::span(reinterpret_cast<const std::uint8_t*>(hb.data()), hb.size()), &h)) {
    throw RecordingError(Reason::kCorrupt, path_, name + ": no chunk magic number");
  }
  const std::string stored = file.Read(c.offset + format::kChunkHeaderSize, c.stored_size);
  if (format::ChunkCrc(
          std::span(reinterpret_cast<const std::uint8_t*>(hb.data()), format::kChunkCrcBytes),
          stored) != h.crc) {
    throw RecordingError(Reason::kCorrupt, path_,
                         name +
                             ": checksum mismatch (the chunk is damaged; the chunks before "
                             "it are readable)");
  }
  std::vector<Record> records;
  try {
    records = format::DecodeChunk(
        format::Decompress(stored, h.codec, h.raw_size, format::kMaxDataChunkRawBytes),
        info_.tables, info_.sensordata);
  } catch (const std::exception& e) {
    throw RecordingError(Reason::kCorrupt, path_, name + ": " + e.what());
  }
  // The frames it holds are the number it declares (what frame_count() and the seek use).
  std::uint64_t frames = 0;
  for (const Record& rec : records) frames += std::holds_alternative<Frame>(rec) ? 1 : 0;
  if (frames != h.frames) {
    throw RecordingError(Reason::kCorrupt, path_,
                         fmt::format("{}: declares {} frames, holds {} (damaged, or not written "
                                     "by URLab)",
                                     name, h.frames, frames));
  }
  return records;
}

void RecordingReader::Verify() const {
  for (std::size_t i = 0; i < chunks_.size(); ++i) (void)ReadChunk(i);
}

std::size_t RecordingReader::ChunkAt(double time) const {
  std::size_t best = 0;
  for (std::size_t i = 0; i < chunks_.size(); ++i) {
    if (chunks_[i].frames && chunks_[i].first_time <= time) best = i;
  }
  return best;
}

void WriteRecording(const std::string& path, const RecordingInfo& info,
                    const std::vector<std::vector<Record>>& chunks) {
  const format::Codec codec =
      info.compression == "zstd" ? format::Codec::kZstd : format::Codec::kStored;
  std::string out = format::EncodeFileStart(info, codec);
  std::uint32_t number = 1;
  format::ChunkEncoder enc(info.tables, info.sensordata);
  for (const std::vector<Record>& chunk : chunks) {
    enc.Reset();
    for (const Record& r : chunk) std::visit([&](const auto& x) { enc.Add(x); }, r);
    format::ChunkHeader c = enc.Header(codec);
    c.number = number++;
    out += format::EncodeChunk(c, format::Compress(enc.bytes(), codec));
  }
  out += format::EncodeEndChunk(number, "{}");
  WriteFileAtomic(path, out);
}

std::vector<Record> ReadAllRecords(const RecordingReader& reader) {
  std::vector<Record> all;
  for (std::size_t i = 0; i < reader.chunks().size(); ++i) {
    std::vector<Record> part = reader.ReadChunk(i);
    std::move(part.begin(), part.end(), std::back_inserter(all));
  }
  return all;
}

}  // namespace urlab::replay
