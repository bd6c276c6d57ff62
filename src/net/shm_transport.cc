#include "net/shm_transport.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "wire/request_limits.h"

namespace urlab::net {

namespace {

// How often channels are checked for a client gone (a system call each).
constexpr auto kSweepPeriod = std::chrono::milliseconds(200);
// The I/O thread spins for the next request for this many of the client's recent think times,
// within these bounds (beyond, it sleeps and the client's request wakes it).
constexpr int kThinkFactor = 3;
constexpr auto kMinExpect = std::chrono::microseconds(30);
constexpr auto kMaxExpect = std::chrono::microseconds(1000);

}  // namespace

std::string ShmFolder(const std::string& folder) {
  if (!folder.empty()) return folder;
  if (access("/dev/shm", W_OK | X_OK) == 0 && std::filesystem::is_directory("/dev/shm")) {
    return "/dev/shm";
  }
  return std::filesystem::temp_directory_path().string();
}

ShmTransport::ShmTransport(ShmOptions options)
    : folder_(ShmFolder(options.folder)), options_(std::move(options)) {
  if (options_.request_bytes == 0) options_.request_bytes = wire::kMaxRequestBytes;
  if (const int n = wire::ShmChannel::ReclaimStale(folder_); n > 0) {
    spdlog::info("step server: removed {} shared-memory file(s) of servers gone from {}", n,
                 folder_);
  }
}

ShmTransport::~ShmTransport() = default;  // each channel marks itself closed, unlinks its file

ShmTransport::Json ShmTransport::Offer(const std::string& session, Clock::time_point now) {
  Close(session);
  const std::string path = folder_ + "/" + wire::NewShmName();
  Channel c{
      session,
      wire::ShmChannel::Create(path, options_.request_bytes, options_.reply_bytes, wake_.name()),
      now};
  Json offer{{"path", path},
             {"bytes", c.channel.file_bytes()},
             {"generation", c.channel.generation()},
             {"version", wire::ShmLayout::kVersion}};
  channels_.emplace(next_++, std::move(c));
  return offer;
}

void ShmTransport::Poll(const std::function<void(std::uint64_t, const std::string&,
                                                 std::span<const std::uint8_t>)>& handle,
                        const std::function<void(std::uint64_t)>& bad) {
  // By id, not by iterator: a request may close channels, its own among them (bye, eviction).
  std::vector<std::uint64_t> ids;
  ids.reserve(channels_.size());
  for (const auto& kv : channels_) ids.push_back(kv.first);
  for (const std::uint64_t id : ids) {
    const auto it = channels_.find(id);
    if (it == channels_.end()) continue;
    Channel& c = it->second;
    bool out_of_bounds = false;
    const auto bytes = c.channel.TakeRequest(&out_of_bounds);
    if (!bytes && !out_of_bounds) continue;
    const auto now = Clock::now();
    if (c.last_reply != Clock::time_point{}) {
      const Clock::duration t = now - c.last_reply;
      c.think = c.think == Clock::duration{} ? t : (c.think * 7 + t) / 8;
    }
    c.last_request = now;
    c.answered = false;
    polling_ = true;  // a channel closed while its request is handled goes after it
    if (bytes) {
      handle(id, std::string(c.session), *bytes);
    } else {
      bad(id);
    }
    polling_ = false;
    if (const auto after = channels_.find(id);
        after != channels_.end() && after->second.closing && after->second.answered) {
      channels_.erase(after);
    }
  }
}

bool ShmTransport::Reply(std::uint64_t channel, std::span<const std::uint8_t> bytes,
                         Clock::time_point now) {
  const auto it = channels_.find(channel);
  if (it == channels_.end()) return false;
  if (!it->second.channel.WriteReply(bytes)) return false;
  it->second.last_reply = now;
  it->second.answered = true;
  if (it->second.closing && !polling_) channels_.erase(it);
  return true;
}

bool ShmTransport::RequestWaiting() const {
  for (const auto& [id, c] : channels_) {
    if (c.channel.request_waiting()) return true;
  }
  return false;
}

bool ShmTransport::Expecting(Clock::time_point now) const {
  for (const auto& [id, c] : channels_) {
    if (!c.answered || c.last_reply == Clock::time_point{}) continue;
    const auto window = std::clamp<Clock::duration>(c.think * kThinkFactor, kMinExpect, kMaxExpect);
    if (now - c.last_reply < window) return true;
  }
  return false;
}

bool ShmTransport::PrepareSleep() {
  for (auto& [id, c] : channels_) c.channel.Sleeping(true);
  if (RequestWaiting()) {
    Awake();
    return true;
  }
  return false;
}

void ShmTransport::Awake() {
  for (auto& [id, c] : channels_) c.channel.Sleeping(false);
  wake_.Drain();
}

std::vector<std::string> ShmTransport::Sweep(Clock::time_point now) {
  std::vector<std::string> gone;
  if (now - last_sweep_ < kSweepPeriod) return gone;
  last_sweep_ = now;
  for (auto it = channels_.begin(); it != channels_.end();) {
    Channel& c = it->second;
    bool drop = false;
    if (c.channel.attached()) {
      c.channel.Unlink();  // both sides have it mapped: the name is no longer needed
      drop = c.channel.PeerGone();
      if (drop) {
        spdlog::info("step server: the shared-memory client of session {} closed or died",
                     c.session);
      }
    } else if (now - c.offered > options_.attach_timeout) {
      drop = true;
      spdlog::info("step server: nobody attached to the shared-memory channel of session {}",
                   c.session);
    }
    if (drop) {
      if (c.channel.attached()) gone.push_back(c.session);  // an unused offer ends no session
      it = channels_.erase(it);
    } else {
      ++it;
    }
  }
  return gone;
}

void ShmTransport::Close(const std::string& session) {
  for (auto it = channels_.begin(); it != channels_.end();) {
    Channel& c = it->second;
    if (c.session != session) {
      ++it;
    } else if (!c.answered) {
      c.closing = true;  // Reply closes it
      ++it;
    } else {
      it = channels_.erase(it);
    }
  }
}

}  // namespace urlab::net
