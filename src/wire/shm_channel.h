#pragma once
// The step server's shared-memory channel (docs/network.md, "Shared memory"): one file, mapped by
// one server and one client on the same host, carrying the same encoded requests and replies as
// ZeroMQ, one request in flight at a time.
//
// Layout (little-endian; offsets in bytes, the Python client reads the same numbers):
//   0    magic "URLABSHM"          8  u32 version (1)        12 u32 header bytes (4096)
//   16   u64 request capacity     24  u64 reply capacity     32 u64 generation (random, != 0)
//   40   u32 server pid           44  u32 client pid         48 u32 client attached (0/1)
//   52   u32 server closed        56  u32 client closed
//   64   u32 server sleeping (own cache line: the server waits in poll, not on this word)
//   128  u32 client waiting (own cache line: the client sleeps on the reply sequence word)
//   192  u32 request sequence, 200 u64 request length          (own cache line)
//   256  u32 reply sequence,   264 u64 reply length            (own cache line)
//   320  char[108] the server's wake socket (an abstract unix datagram name, NUL-terminated)
//   4096 request bytes; 4096 + request capacity: reply bytes
//
// Protocol. The client writes the request bytes and length, then the request sequence (release);
// then, after a full fence, if `server sleeping` is set it sends one datagram to the wake socket
// (the server sleeps in poll(2) beside its ZeroMQ sockets, so it cannot sleep on a futex). The
// server writes the reply bytes and length, then the reply sequence = the request's sequence
// (release); then, after a full fence, if `client waiting` is set it FUTEX_WAKEs the reply
// sequence word. Each side spins about as long as it expects the other to take, then sleeps: a
// wake-up from sleep on a virtual machine costs tens of microseconds, a spin hand-over well
// under one.
//
// Liveness: each side holds an open-file-description lock on one byte of the file (the server
// byte 0, the client byte 1) for as long as the channel is open; the kernel drops it when the
// process dies, however it dies. Each side asks for the other's lock while waiting (PeerGone),
// so a dead peer is an error within the waiter's timeout, never a wedge. A file whose byte 0 is
// unlocked belongs to no live server (ReclaimStale). The server unlinks the file as soon as the
// client attached (both keep their mappings), so a crash of both leaves nothing behind.
//
// Trust: each side takes every size and offset it uses (capacities, the file's size, where the
// reply starts) from its own memory, set when it made or attached the channel, never from the
// shared page, which the other side can rewrite at any time; lengths read from the page are
// checked against those before use, and the server copies a request out of the mapping before
// it is decoded (the client cannot change it under the decoder).
//
// Threading: a channel object is used by one thread at a time; the two ends are in different
// threads or processes and meet only through the atomics of the mapped header.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace urlab::wire {

// A channel that cannot be made, attached or used (the message says which file and why).
class ShmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ShmLayout {
  static constexpr std::uint32_t kVersion = 1;
  static constexpr std::size_t kHeaderBytes = 4096;
  static constexpr std::size_t kMagic = 0, kVersionAt = 8, kHeaderBytesAt = 12,
                               kRequestCapacity = 16, kReplyCapacity = 24, kGeneration = 32,
                               kServerPid = 40, kClientPid = 44, kClientAttached = 48,
                               kServerClosed = 52, kClientClosed = 56, kServerSleeping = 64,
                               kClientWaiting = 128, kRequestSeq = 192, kRequestLen = 200,
                               kReplySeq = 256, kReplyLen = 264, kWakeName = 320,
                               kWakeNameBytes = 108;
  static constexpr char kMagicText[9] = "URLABSHM";
  // File names the server makes: "urlab-shm-{pid}-{random}" (ReclaimStale looks only at these).
  static constexpr std::string_view kFilePrefix = "urlab-shm-";
};

class ShmChannel {
 public:
  using Clock = std::chrono::steady_clock;

  // Server: creates `path` (must not exist; mode 0600) with room for a request of
  // `request_bytes` and a reply of `reply_bytes`, locks byte 0 and writes the header (the magic
  // last). `wake_name`: the server's wake socket. Throws ShmError.
  static ShmChannel Create(const std::string& path, std::size_t request_bytes,
                           std::size_t reply_bytes, std::string_view wake_name);
  // Client: maps `path`, checks magic, version, sizes and `generation` (from the offer), locks
  // byte 1 and marks the channel attached. Throws ShmError.
  static ShmChannel Attach(const std::string& path, std::uint64_t generation);

  ShmChannel(ShmChannel&& other) noexcept;
  ShmChannel& operator=(ShmChannel&& other) noexcept;
  ShmChannel(const ShmChannel&) = delete;
  ShmChannel& operator=(const ShmChannel&) = delete;
  // Marks this side closed (waking a waiting client), unmaps, closes; a server that made the
  // file and still has it named unlinks it.
  ~ShmChannel();

  const std::string& path() const { return path_; }
  std::uint64_t generation() const { return generation_; }
  std::size_t request_capacity() const { return request_cap_; }
  std::size_t reply_capacity() const { return reply_cap_; }
  std::size_t file_bytes() const { return size_; }

  // ---- Client ----
  // Publishes one request (throws ShmError when larger than the capacity or when a reply is
  // still outstanding) and wakes the server if it sleeps.
  void SendRequest(std::span<const std::uint8_t> bytes);
  // Waits for the reply to the last request: spins for up to `spin`, then sleeps on the reply
  // sequence word in slices, checking that the server lives. The bytes stay valid until the next
  // SendRequest. Throws ShmError when `timeout` passes, the server closed or died.
  std::span<const std::uint8_t> WaitReply(std::chrono::nanoseconds timeout,
                                          std::chrono::nanoseconds spin);
  // A reply is outstanding (sent, not yet returned by WaitReply).
  bool awaiting_reply() const { return awaiting_; }

  // ---- Server ----
  // The client attached (then the server unlinks the file: Unlink).
  bool attached() const;
  // A request is waiting that TakeRequest has not returned.
  bool request_waiting() const;
  // The new request, if any: a copy in this object's memory, valid until the next TakeRequest.
  // Nothing when none waits or the client published a length beyond the capacity (then `*bad`
  // is set).
  std::optional<std::span<const std::uint8_t>> TakeRequest(bool* bad = nullptr);
  // Answers the request taken last; false (nothing written) when `bytes` exceed the capacity.
  bool WriteReply(std::span<const std::uint8_t> bytes);
  // Tells the client whether the server is about to sleep in poll (then it sends a wake-up).
  // After Sleeping(true) the caller checks request_waiting() once more before it sleeps.
  void Sleeping(bool sleeping);
  // Removes the file's name (the mappings stay); idempotent.
  void Unlink();

  // ---- Both ----
  // The other side closed or died (its lock is gone). Costs a system call.
  bool PeerGone() const;

  // Removes files "urlab-shm-*" in `folder` whose server is gone (byte 0 unlocked and a complete
  // header, or no header and older than a minute). Returns how many were removed.
  static int ReclaimStale(const std::string& folder);

 private:
  ShmChannel() = default;
  void Release();
  std::uint8_t* at(std::size_t offset) const { return base_ + offset; }

  std::string path_;
  int fd_ = -1;
  std::uint8_t* base_ = nullptr;
  std::size_t size_ = 0;
  // Set when the channel was made or attached; the header's copies are for the other side only.
  std::size_t request_cap_ = 0, reply_cap_ = 0;
  std::uint64_t generation_ = 0;
  bool server_ = false;
  bool attached_ = false;  // client: attached (only then does closing mark the client closed)
  bool named_ = false;     // the server's file still has its name
  // Client: the sequence of the last request, and whether its reply is outstanding.
  std::uint32_t seq_ = 0;
  bool awaiting_ = false;
  int wake_fd_ = -1;  // client: the datagram socket that wakes the server
  // Server: the sequence of the last request taken.
  std::uint32_t taken_ = 0;
  std::vector<std::uint8_t> request_;  // server: the request taken last, copied
};

// The server's wake socket: an abstract unix datagram socket (no file) named
// "urlab-shm-{pid}-{random}", which clients of every channel send one byte to.
class ShmWakeSocket {
 public:
  ShmWakeSocket();  // throws ShmError
  ~ShmWakeSocket();
  ShmWakeSocket(const ShmWakeSocket&) = delete;
  ShmWakeSocket& operator=(const ShmWakeSocket&) = delete;
  int fd() const { return fd_; }
  const std::string& name() const { return name_; }
  void Drain();

 private:
  int fd_ = -1;
  std::string name_;
};

// "urlab-shm-{pid}-{16 random hex digits}".
std::string NewShmName();

}  // namespace urlab::wire
