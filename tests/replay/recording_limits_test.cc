// A recording's declared sizes are bounded before anything is allocated: a 69 KB file whose
// chunk declares 2 GiB, or whose zstd frame really expands to 80 MiB, is refused as damaged,
// in a child process whose address space could not hold the declared size.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <new>
#include <span>
#include <string>

#include "replay/format.h"
#include "support/mujoco_test.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {
namespace {

// A zstd frame by hand (RFC 8878): magic, a header declaring `declared` content bytes (4-byte
// field, window 2^17), then `blocks`. No checksum.
std::string ZstdFrame(std::uint32_t declared, const std::string& blocks) {
  std::string f = {'\x28', '\xb5', '\x2f', '\xfd'};
  f += static_cast<char>(0x80);  // frame header descriptor: 4-byte content size, not single segment
  f += static_cast<char>((17 - 10) << 3);  // window descriptor: 128 KiB
  for (int i = 0; i < 4; ++i) f += static_cast<char>((declared >> (8 * i)) & 0xff);
  return f + blocks;
}

std::string BlockHeader(bool last, int type, std::uint32_t size) {
  const std::uint32_t v = (last ? 1u : 0u) | (static_cast<std::uint32_t>(type) << 1) | (size << 3);
  return {static_cast<char>(v & 0xff), static_cast<char>((v >> 8) & 0xff),
          static_cast<char>((v >> 16) & 0xff)};
}

// One raw block of `n` bytes.
std::string RawBlock(std::size_t n) {
  return BlockHeader(true, 0, static_cast<std::uint32_t>(n)) + std::string(n, '\x01');
}

// `total` zero bytes as RLE blocks of 128 KiB: 4 stored bytes per 128 KiB (a zstd bomb).
std::string RleBlocks(std::uint64_t total) {
  std::string out;
  constexpr std::uint32_t kBlock = 128u << 10;
  for (std::uint64_t done = 0; done < total; done += kBlock) {
    const auto n = static_cast<std::uint32_t>(std::min<std::uint64_t>(kBlock, total - done));
    out += BlockHeader(done + n == total, 1, n) + std::string(1, '\0');
  }
  return out;
}

// A real recording's file header and header chunk, then one data chunk declaring `raw_size`
// with `stored` as its zstd payload, then the end chunk. `header_raw_size`, when set, is what
// the header chunk declares instead (its payload then cannot match: checked after the size).
std::string CraftedRecording(std::uint64_t raw_size, const std::string& stored,
                             std::uint64_t header_raw_size = 0) {
  const std::string seed =
      testing::ReadTextFile(URLAB_SOURCE_DIR "/fuzz/corpus/fuzz_recording/zstd_keyframes.urrec");
  format::ChunkHeader h;
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(seed.data());
  EXPECT_TRUE(format::DecodeChunkHeader(
      std::span(bytes + format::kFileHeaderSize, format::kChunkHeaderSize), &h));
  const std::string header_stored =
      seed.substr(format::kFileHeaderSize + format::kChunkHeaderSize, h.stored_size);
  if (header_raw_size) h.raw_size = header_raw_size;
  // The seed's own file header: its header chunk is of the seed's format version.
  std::string out = seed.substr(0, format::kFileHeaderSize) + format::EncodeChunk(h, header_stored);
  format::ChunkHeader d;
  d.kind = format::ChunkKind::kData;
  d.number = 1;
  d.codec = format::Codec::kZstd;
  d.raw_size = raw_size;
  d.frames = 1;
  out += format::EncodeChunk(d, stored);
  return out + format::EncodeEndChunk(2, "{}");
}

// Runs `body` in a child whose address space may grow by `headroom` bytes only; returns its
// exit code (the body's, or 90 for std::bad_alloc, 91 for another exception).
int InLimitedChild(std::uint64_t headroom, const std::function<int()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::uint64_t vm_kb = 0;
    std::ifstream status("/proc/self/status");
    for (std::string line; std::getline(status, line);) {
      if (line.rfind("VmSize:", 0) == 0) vm_kb = std::stoull(line.substr(7));
    }
    const rlimit lim{vm_kb * 1024 + headroom, vm_kb * 1024 + headroom};
    ::setrlimit(RLIMIT_AS, &lim);
    int code = 91;
    try {
      code = body();
    } catch (const std::bad_alloc&) {
      code = 90;
    } catch (...) {
    }
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Opens `path` as `replay --info` does (keeping the readable prefix) and reads every chunk: 0 when
// the damage is reported with `expected` in the message, 1 when it is not reported at all, 2 when
// it is reported without `expected`.
int OpenAndReadAll(const std::string& path, const std::string& expected) {
  std::string message;
  try {
    const RecordingReader r = RecordingReader::Open(path, {true});
    message = r.problem();
    for (std::size_t i = 0; i < r.chunks().size(); ++i) (void)r.ReadChunk(i);
  } catch (const RecordingError& e) {
    message = e.what();
  }
  if (message.empty()) return 1;
  return message.find(expected) != std::string::npos ? 0 : 2;
}

TEST(RecordingLimitsTest, AChunkDeclaringTwoGibIsRefusedBeforeAllocating) {
  const std::string dir = testing::MakeTempDir("limits_2gib");
  const std::string path = dir + "/declares_2gib.urrec";
  const std::string stored = ZstdFrame(0x80000000u, RawBlock(60000));
  std::ofstream(path, std::ios::binary) << CraftedRecording(0x80000000ull, stored);
  EXPECT_LT(std::filesystem::file_size(path), 70000u);
  // 256 MiB more address space than the process has: 2 GiB cannot be allocated in it.
  EXPECT_EQ(InLimitedChild(256ull << 20, [&] { return OpenAndReadAll(path, "declares"); }), 0);
  // Strict opening names the chunk and the limit.
  try {
    (void)RecordingReader::Open(path);
    FAIL() << "opened";
  } catch (const RecordingError& e) {
    EXPECT_EQ(e.reason(), RecordingError::Reason::kCorrupt);
    EXPECT_NE(std::string(e.what()).find("declares 2147483648 bytes uncompressed"),
              std::string::npos)
        << e.what();
  }
}

TEST(RecordingLimitsTest, AHeaderChunkDeclaringTwoGibIsRefusedBeforeAllocating) {
  const std::string dir = testing::MakeTempDir("limits_header");
  const std::string path = dir + "/header_2gib.urrec";
  std::ofstream(path, std::ios::binary)
      << CraftedRecording(10, ZstdFrame(10, RawBlock(10)), 0x80000000ull);
  EXPECT_EQ(InLimitedChild(256ull << 20, [&] { return OpenAndReadAll(path, "declares"); }), 0);
}

TEST(RecordingLimitsTest, AZstdBombBeyondTheChunkLimitIsRefused) {
  const std::string dir = testing::MakeTempDir("limits_bomb");
  const std::string path = dir + "/bomb.urrec";
  constexpr std::uint64_t kBomb = 80ull << 20;  // really expands to 80 MiB from ~2.5 KB
  std::ofstream(path, std::ios::binary)
      << CraftedRecording(kBomb, ZstdFrame(static_cast<std::uint32_t>(kBomb), RleBlocks(kBomb)));
  EXPECT_EQ(InLimitedChild(32ull << 20, [&] { return OpenAndReadAll(path, "declares"); }), 0);
}

TEST(RecordingLimitsTest, MemoryFollowsTheBytesZstdProducesNotTheDeclaredSize) {
  // Under the data chunk limit, but the frame holds 60 KB, not the 48 MiB it declares: refused
  // without ever holding 48 MiB.
  const std::string dir = testing::MakeTempDir("limits_lie");
  const std::string path = dir + "/lie.urrec";
  constexpr std::uint32_t kDeclared = 48u << 20;
  std::ofstream(path, std::ios::binary)
      << CraftedRecording(kDeclared, ZstdFrame(kDeclared, RawBlock(60000)));
  EXPECT_EQ(InLimitedChild(24ull << 20, [&] { return OpenAndReadAll(path, "chunk 1"); }), 0);
  // The limits leave room for what the recorder writes: a chunk closes at the flush size.
  static_assert(format::kDataChunkFlushBytes * 2 <= format::kMaxDataChunkRawBytes);
}

// Issue 38, case 9: a data chunk whose header claims 0xFFFFFFFF frames (with a checksum to
// match) was reported as 4,294,968,295 steps by `replay --info`, exit 0. A chunk cannot hold
// more frames than bytes, and the frames it holds must be the number it declares: the reader
// stops before it (strict: an error naming the chunk), and `replay --info` exits 1.
TEST(RecordingLimitsTest, AChunkClaimingMoreFramesThanItHoldsIsDamaged) {
  const std::string dir = testing::MakeTempDir("limits_frames");
  const std::string seed =
      testing::ReadTextFile(URLAB_SOURCE_DIR "/fuzz/corpus/fuzz_recording/zstd_keyframes.urrec");
  // The first data chunk (after the header chunk), its frame count forged, its CRC recomputed.
  std::size_t offset = format::kFileHeaderSize;
  std::string forged;
  std::uint64_t real_frames = 0;
  for (int chunk = 0; offset < seed.size(); ++chunk) {
    format::ChunkHeader h;
    ASSERT_TRUE(format::DecodeChunkHeader(
        std::span(reinterpret_cast<const std::uint8_t*>(seed.data()) + offset,
                  format::kChunkHeaderSize),
        &h));
    const std::size_t size = format::kChunkHeaderSize + h.stored_size;
    if (h.kind == format::ChunkKind::kData) real_frames += h.frames;
    if (chunk == 1) {
      ASSERT_EQ(h.kind, format::ChunkKind::kData);
      const std::string stored = seed.substr(offset + format::kChunkHeaderSize, h.stored_size);
      h.frames = 0xFFFFFFFFu;
      forged = seed.substr(0, offset) + format::EncodeChunk(h, stored) + seed.substr(offset + size);
    }
    offset += size;
  }
  ASSERT_FALSE(forged.empty());
  ASSERT_GT(real_frames, 0u);
  const std::string path = dir + "/forged.urrec";
  std::ofstream(path, std::ios::binary) << forged;
  try {
    (void)RecordingReader::Open(path);
    FAIL() << "opened";
  } catch (const RecordingError& e) {
    EXPECT_EQ(e.reason(), RecordingError::Reason::kCorrupt);
    EXPECT_NE(std::string(e.what()).find("4294967295 frames"), std::string::npos) << e.what();
  }
  const RecordingReader partial = RecordingReader::Open(path, {true});
  EXPECT_LT(partial.frame_count(), real_frames);
  EXPECT_NE(partial.problem().find("frames"), std::string::npos) << partial.problem();
  std::string log;
  EXPECT_EQ(testing::RunCommand(testing::UrlabBinary() + " replay " + path + " --info", &log), 1)
      << log;
  EXPECT_EQ(log.find("4294968"), std::string::npos) << log;
  EXPECT_NE(log.find("4294967295 frames"), std::string::npos) << log;
}

}  // namespace
}  // namespace urlab::replay
