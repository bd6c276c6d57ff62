#include "wire/shm_channel.h"

#include <dirent.h>
#include <fcntl.h>
#include <linux/futex.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <random>
#include <thread>
#include <utility>

namespace urlab::wire {

namespace {

using L = ShmLayout;
constexpr std::size_t kPage = 4096;
// How long the client sleeps on the reply word before it checks that the server lives.
constexpr auto kSleepSlice = std::chrono::milliseconds(50);
// A file without a complete header is another server's being made, unless it is this old.
constexpr auto kUnfinishedAge = std::chrono::seconds(60);

std::size_t RoundUp(std::size_t n) { return (n + kPage - 1) / kPage * kPage; }

std::string Errno(const std::string& what, const std::string& path) {
  return "shared memory " + path + ": " + what + ": " + std::strerror(errno);
}

std::atomic_ref<std::uint32_t> Word(std::uint8_t* p) {
  return std::atomic_ref<std::uint32_t>(*reinterpret_cast<std::uint32_t*>(p));
}
std::atomic_ref<std::uint64_t> Word64(std::uint8_t* p) {
  return std::atomic_ref<std::uint64_t>(*reinterpret_cast<std::uint64_t*>(p));
}

void FutexWake(std::uint8_t* word) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word), FUTEX_WAKE, INT_MAX, nullptr, nullptr,
          0);
}

// Sleeps while *word == expected, at most `for_how_long` (a wake-up, a changed word or a signal
// end it early; the caller checks again).
void FutexWait(std::uint8_t* word, std::uint32_t expected, std::chrono::nanoseconds for_how_long) {
  const auto ns = std::max<std::int64_t>(for_how_long.count(), 1000);
  timespec ts{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word), FUTEX_WAIT, expected, &ts, nullptr, 0);
}

// An open-file-description write lock on one byte: held until the file is closed by every
// descriptor of this open (process death included).
bool LockByte(int fd, off_t byte) {
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = byte;
  fl.l_len = 1;
  return fcntl(fd, F_OFD_SETLK, &fl) == 0;
}

// True when some open of the file (another process's, or another open in this one) holds a lock
// on `byte`.
bool ByteLocked(int fd, off_t byte) {
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = byte;
  fl.l_len = 1;
  if (fcntl(fd, F_OFD_GETLK, &fl) != 0) return true;  // cannot tell: assume alive
  return fl.l_type != F_UNLCK;
}

inline void CpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

std::uint64_t RandomNonZero() {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::uint64_t v = 0;
  while (v == 0) v = rng();
  return v;
}

sockaddr_un AbstractAddress(std::string_view name, socklen_t* len) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  const std::size_t n = std::min(name.size(), sizeof(a.sun_path) - 1);
  std::memcpy(a.sun_path + 1, name.data(), n);  // sun_path[0] == 0: the abstract namespace
  *len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + n);
  return a;
}

}  // namespace

std::string NewShmName() {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*s%d-%016llx", static_cast<int>(L::kFilePrefix.size()),
                L::kFilePrefix.data(), static_cast<int>(getpid()),
                static_cast<unsigned long long>(RandomNonZero()));
  return buf;
}

// ---------------------------------------------------------------------------------------------
// Making, attaching, releasing

ShmChannel ShmChannel::Create(const std::string& path, std::size_t request_bytes,
                              std::size_t reply_bytes, std::string_view wake_name) {
  if (wake_name.size() >= L::kWakeNameBytes) throw ShmError("shared memory: wake name too long");
  ShmChannel c;
  c.path_ = path;
  c.server_ = true;
  const std::size_t request_cap = RoundUp(std::max<std::size_t>(request_bytes, 1));
  const std::size_t reply_cap = RoundUp(std::max<std::size_t>(reply_bytes, 1));
  c.size_ = L::kHeaderBytes + request_cap + reply_cap;
  c.fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (c.fd_ < 0) throw ShmError(Errno("cannot create", path));
  c.named_ = true;  // from here on the destructor unlinks it
  if (!LockByte(c.fd_, 0)) throw ShmError(Errno("cannot lock", path));
  if (ftruncate(c.fd_, static_cast<off_t>(c.size_)) != 0) {
    throw ShmError(Errno("cannot size", path));
  }
  void* p = mmap(nullptr, c.size_, PROT_READ | PROT_WRITE, MAP_SHARED, c.fd_, 0);
  if (p == MAP_FAILED) throw ShmError(Errno("cannot map", path));
  c.base_ = static_cast<std::uint8_t*>(p);
  Word(c.at(L::kVersionAt)).store(L::kVersion, std::memory_order_relaxed);
  Word(c.at(L::kHeaderBytesAt)).store(L::kHeaderBytes, std::memory_order_relaxed);
  Word64(c.at(L::kRequestCapacity)).store(request_cap, std::memory_order_relaxed);
  Word64(c.at(L::kReplyCapacity)).store(reply_cap, std::memory_order_relaxed);
  c.request_cap_ = request_cap;
  c.reply_cap_ = reply_cap;
  c.generation_ = RandomNonZero();
  Word64(c.at(L::kGeneration)).store(c.generation_, std::memory_order_relaxed);
  Word(c.at(L::kServerPid)).store(static_cast<std::uint32_t>(getpid()), std::memory_order_relaxed);
  std::memcpy(c.at(L::kWakeName), wake_name.data(), wake_name.size());
  // The magic last (a release store): a reader that sees it sees the whole header.
  Word64(c.at(L::kMagic))
      .store(*reinterpret_cast<const std::uint64_t*>(L::kMagicText), std::memory_order_release);
  return c;
}

ShmChannel ShmChannel::Attach(const std::string& path, std::uint64_t generation) {
  ShmChannel c;
  c.path_ = path;
  c.fd_ = open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW);
  if (c.fd_ < 0) throw ShmError(Errno("cannot open", path));
  struct stat st {};
  if (fstat(c.fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    throw ShmError("shared memory " + path + ": not a regular file");
  }
  if (st.st_uid != geteuid()) throw ShmError("shared memory " + path + ": owned by another user");
  if (static_cast<std::size_t>(st.st_size) < L::kHeaderBytes) {
    throw ShmError("shared memory " + path + ": shorter than its header");
  }
  c.size_ = static_cast<std::size_t>(st.st_size);
  void* p = mmap(nullptr, c.size_, PROT_READ | PROT_WRITE, MAP_SHARED, c.fd_, 0);
  if (p == MAP_FAILED) throw ShmError(Errno("cannot map", path));
  c.base_ = static_cast<std::uint8_t*>(p);
  if (Word64(c.at(L::kMagic)).load(std::memory_order_acquire) !=
      *reinterpret_cast<const std::uint64_t*>(L::kMagicText)) {
    throw ShmError("shared memory " + path + ": no URLab channel header");
  }
  const std::uint32_t version = Word(c.at(L::kVersionAt)).load(std::memory_order_relaxed);
  if (version != L::kVersion) {
    throw ShmError("shared memory " + path + ": channel version " + std::to_string(version) +
                   ", this client speaks " + std::to_string(L::kVersion));
  }
  const std::uint64_t req = Word64(c.at(L::kRequestCapacity)).load(std::memory_order_relaxed);
  const std::uint64_t rep = Word64(c.at(L::kReplyCapacity)).load(std::memory_order_relaxed);
  if (req > c.size_ || rep > c.size_ || L::kHeaderBytes + req + rep != c.size_) {
    throw ShmError("shared memory " + path + ": its sizes do not add up to the file's");
  }
  c.request_cap_ = static_cast<std::size_t>(req);
  c.reply_cap_ = static_cast<std::size_t>(rep);
  c.generation_ = generation;
  if (Word64(c.at(L::kGeneration)).load(std::memory_order_relaxed) != generation) {
    throw ShmError("shared memory " + path + ": another channel than the one offered");
  }
  if (!ByteLocked(c.fd_, 0)) throw ShmError("shared memory " + path + ": its server is gone");
  if (Word(c.at(L::kClientAttached)).load(std::memory_order_acquire) != 0 || !LockByte(c.fd_, 1)) {
    throw ShmError("shared memory " + path + ": another client attached already");
  }
  c.seq_ = Word(c.at(L::kRequestSeq)).load(std::memory_order_acquire);
  // The wake socket: connected once, so each wake-up is one send.
  char name[L::kWakeNameBytes];
  std::memcpy(name, c.at(L::kWakeName), sizeof(name));
  name[sizeof(name) - 1] = 0;
  c.wake_fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  socklen_t len = 0;
  const sockaddr_un a = AbstractAddress(name, &len);
  if (c.wake_fd_ < 0 || connect(c.wake_fd_, reinterpret_cast<const sockaddr*>(&a), len) != 0) {
    throw ShmError(Errno("cannot reach the server's wake socket", path));
  }
  Word(c.at(L::kClientPid)).store(static_cast<std::uint32_t>(getpid()), std::memory_order_relaxed);
  Word(c.at(L::kClientAttached)).store(1, std::memory_order_release);
  c.attached_ = true;
  return c;
}

ShmChannel::ShmChannel(ShmChannel&& o) noexcept { *this = std::move(o); }

ShmChannel& ShmChannel::operator=(ShmChannel&& o) noexcept {
  if (this != &o) {
    Release();
    path_ = std::move(o.path_);
    fd_ = std::exchange(o.fd_, -1);
    base_ = std::exchange(o.base_, nullptr);
    size_ = std::exchange(o.size_, 0);
    request_cap_ = o.request_cap_;
    reply_cap_ = o.reply_cap_;
    generation_ = o.generation_;
    server_ = o.server_;
    attached_ = std::exchange(o.attached_, false);
    named_ = std::exchange(o.named_, false);
    seq_ = o.seq_;
    awaiting_ = o.awaiting_;
    wake_fd_ = std::exchange(o.wake_fd_, -1);
    taken_ = o.taken_;
    request_ = std::move(o.request_);
  }
  return *this;
}

ShmChannel::~ShmChannel() { Release(); }

void ShmChannel::Release() {
  if (base_) {
    if (server_) {
      Word(at(L::kServerClosed)).store(1, std::memory_order_seq_cst);
      FutexWake(at(L::kReplySeq));  // a client asleep on its reply sees the server closed
    } else if (attached_) {
      // (A client whose attach failed leaves the header alone: the channel may be another's.)
      Word(at(L::kClientClosed)).store(1, std::memory_order_seq_cst);
    }
    munmap(base_, size_);
    base_ = nullptr;
  }
  if (named_) Unlink();
  if (wake_fd_ >= 0) close(wake_fd_);
  wake_fd_ = -1;
  if (fd_ >= 0) close(fd_);  // drops this side's lock
  fd_ = -1;
}

void ShmChannel::Unlink() {
  if (!named_) return;
  named_ = false;
  unlink(path_.c_str());
}

bool ShmChannel::PeerGone() const {
  if (server_) {
    if (Word(at(L::kClientClosed)).load(std::memory_order_acquire) != 0) return true;
    return attached() && !ByteLocked(fd_, 1);
  }
  if (Word(at(L::kServerClosed)).load(std::memory_order_acquire) != 0) return true;
  return !ByteLocked(fd_, 0);
}

// ---------------------------------------------------------------------------------------------
// Client

void ShmChannel::SendRequest(std::span<const std::uint8_t> bytes) {
  if (awaiting_) throw ShmError("shared memory " + path_ + ": a reply is still outstanding");
  if (bytes.size() > request_cap_) {
    throw ShmError("shared memory " + path_ + ": a request of " + std::to_string(bytes.size()) +
                   " bytes (capacity " + std::to_string(request_cap_) + ")");
  }
  if (!bytes.empty()) std::memcpy(at(L::kHeaderBytes), bytes.data(), bytes.size());
  Word64(at(L::kRequestLen)).store(bytes.size(), std::memory_order_relaxed);
  if (++seq_ == 0) ++seq_;  // 0 is "nothing yet"
  awaiting_ = true;
  // Dekker with the server's Sleeping(true) + request_waiting(): one of us sees the other.
  Word(at(L::kRequestSeq)).store(seq_, std::memory_order_seq_cst);
  if (Word(at(L::kServerSleeping)).load(std::memory_order_seq_cst) != 0) {
    const char one = 1;
    [[maybe_unused]] const ssize_t n = send(wake_fd_, &one, 1, MSG_DONTWAIT | MSG_NOSIGNAL);
  }
}

std::span<const std::uint8_t> ShmChannel::WaitReply(std::chrono::nanoseconds timeout,
                                                    std::chrono::nanoseconds spin) {
  if (!awaiting_) throw ShmError("shared memory " + path_ + ": no request to wait for");
  std::uint8_t* seq_word = at(L::kReplySeq);
  const auto ready = [&] { return Word(seq_word).load(std::memory_order_acquire) == seq_; };
  auto now = Clock::now();
  const auto deadline = now + timeout;
  const auto spin_until = now + spin;
  for (unsigned i = 0; !ready(); ++i) {
    if (now < spin_until) {
      CpuRelax();
      if ((i & 31) == 31) std::this_thread::yield();  // let a partner on this core run
      now = Clock::now();
      continue;
    }
    // Sleep on the reply word (Dekker with WriteReply: it wakes us if it sees the flag).
    Word(at(L::kClientWaiting)).store(1, std::memory_order_seq_cst);
    const std::uint32_t seen = Word(seq_word).load(std::memory_order_seq_cst);
    if (seen != seq_) {
      FutexWait(seq_word, seen, std::min<std::chrono::nanoseconds>(kSleepSlice, deadline - now));
    }
    Word(at(L::kClientWaiting)).store(0, std::memory_order_relaxed);
    if (ready()) break;
    if (PeerGone()) {
      awaiting_ = false;
      throw ShmError("shared memory " + path_ + ": the server closed the channel or died");
    }
    now = Clock::now();
    if (now >= deadline) {
      // The reply may still come: this channel is out of step now, so it is no longer usable.
      throw ShmError("shared memory " + path_ + ": no reply within the timeout");
    }
  }
  awaiting_ = false;
  const std::uint64_t len = Word64(at(L::kReplyLen)).load(std::memory_order_relaxed);
  if (len > reply_cap_) throw ShmError("shared memory " + path_ + ": a reply beyond bounds");
  return {at(L::kHeaderBytes + request_cap_), static_cast<std::size_t>(len)};
}

// ---------------------------------------------------------------------------------------------
// Server

bool ShmChannel::attached() const {
  return Word(at(L::kClientAttached)).load(std::memory_order_acquire) != 0;
}

bool ShmChannel::request_waiting() const {
  return Word(at(L::kRequestSeq)).load(std::memory_order_seq_cst) != taken_;
}

std::optional<std::span<const std::uint8_t>> ShmChannel::TakeRequest(bool* bad) {
  const std::uint32_t seq = Word(at(L::kRequestSeq)).load(std::memory_order_acquire);
  if (seq == taken_) return std::nullopt;
  taken_ = seq;
  const std::uint64_t len = Word64(at(L::kRequestLen)).load(std::memory_order_relaxed);
  if (len > request_cap_) {
    if (bad) *bad = true;
    return std::nullopt;
  }
  // A private copy: the client may rewrite the slot while the server decodes.
  request_.assign(at(L::kHeaderBytes), at(L::kHeaderBytes) + len);
  return std::span<const std::uint8_t>(request_);
}

bool ShmChannel::WriteReply(std::span<const std::uint8_t> bytes) {
  if (bytes.size() > reply_cap_) return false;
  if (!bytes.empty()) {
    std::memcpy(at(L::kHeaderBytes + request_cap_), bytes.data(), bytes.size());
  }
  Word64(at(L::kReplyLen)).store(bytes.size(), std::memory_order_relaxed);
  Word(at(L::kReplySeq)).store(taken_, std::memory_order_seq_cst);
  if (Word(at(L::kClientWaiting)).load(std::memory_order_seq_cst) != 0) {
    FutexWake(at(L::kReplySeq));
  }
  return true;
}

void ShmChannel::Sleeping(bool sleeping) {
  Word(at(L::kServerSleeping)).store(sleeping ? 1 : 0, std::memory_order_seq_cst);
}

int ShmChannel::ReclaimStale(const std::string& folder) {
  DIR* dir = opendir(folder.c_str());
  if (!dir) return 0;
  int removed = 0;
  const auto now = std::chrono::system_clock::now();
  while (const dirent* e = readdir(dir)) {
    const std::string name = e->d_name;
    if (!name.starts_with(L::kFilePrefix)) continue;
    const std::string path = folder + "/" + name;
    const int fd = open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd < 0) continue;  // another user's, or gone
    struct stat st {};
    bool remove = false;
    if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == geteuid() &&
        !ByteLocked(fd, 0)) {
      std::uint64_t magic = 0;
      const bool complete = pread(fd, &magic, sizeof(magic), 0) == sizeof(magic) &&
                            magic == *reinterpret_cast<const std::uint64_t*>(L::kMagicText);
      const auto age = now - std::chrono::system_clock::from_time_t(st.st_mtime);
      remove = complete || age > kUnfinishedAge;
    }
    close(fd);
    if (remove && unlink(path.c_str()) == 0) ++removed;
  }
  closedir(dir);
  return removed;
}

// ---------------------------------------------------------------------------------------------
// The server's wake socket

ShmWakeSocket::ShmWakeSocket() : name_(NewShmName()) {
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0)
    throw ShmError(std::string("shared memory: no wake socket: ") + std::strerror(errno));
  socklen_t len = 0;
  const sockaddr_un a = AbstractAddress(name_, &len);
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&a), len) != 0) {
    const std::string why = std::strerror(errno);
    close(fd_);
    throw ShmError("shared memory: cannot bind the wake socket: " + why);
  }
}

ShmWakeSocket::~ShmWakeSocket() {
  if (fd_ >= 0) close(fd_);
}

void ShmWakeSocket::Drain() {
  char buf[64];
  while (recv(fd_, buf, sizeof(buf), MSG_DONTWAIT) > 0) {
  }
}

}  // namespace urlab::wire
