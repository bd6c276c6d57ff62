#pragma once
// The step server's shared-memory transport (docs/network.md, "Shared memory"): one channel
// (wire/shm_channel.h) per session whose client asked for it in `hello` from this host. The
// files live in one folder (/dev/shm by default), are named "urlab-shm-{pid}-{random}", mode
// 0600, and lose their name as soon as the client attached; unattached ones are removed after
// the attach timeout and when the transport closes; files of dead servers found at start are
// removed (ShmChannel::ReclaimStale). One wake socket serves every channel: the I/O thread polls
// it beside its ZeroMQ sockets.
//
// Threading: the network subsystem's I/O thread only (built on the main thread).
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "wire/shm_channel.h"

namespace urlab::net {

struct ShmOptions {
  std::string folder;  // "": /dev/shm when it is a writable folder, else the temporary folder
  std::size_t request_bytes = 0;                    // 0: wire::kMaxRequestBytes
  std::size_t reply_bytes = std::size_t{64} << 20;  // sparse on tmpfs: pages cost when written
  std::chrono::milliseconds attach_timeout{10000};  // an offer nobody attached to is withdrawn
};

class ShmTransport {
 public:
  using Clock = std::chrono::steady_clock;
  using Json = nlohmann::ordered_json;

  explicit ShmTransport(ShmOptions options);  // throws wire::ShmError (no wake socket)
  ~ShmTransport();                            // closes every channel; removes their files

  const std::string& folder() const { return folder_; }
  int wake_fd() const { return wake_.fd(); }
  std::size_t channels() const { return channels_.size(); }

  // A new channel for `session` (replacing one it had): {path, bytes, generation, version}.
  // Throws wire::ShmError when the file cannot be made.
  Json Offer(const std::string& session, Clock::time_point now);
  // Calls `handle(channel, session, bytes)` for each channel with a new request (a request
  // whose length is out of bounds is answered by `bad(channel)`). The bytes stay valid until
  // Reply for that channel.
  void Poll(const std::function<void(std::uint64_t, const std::string&,
                                     std::span<const std::uint8_t>)>& handle,
            const std::function<void(std::uint64_t)>& bad);
  // Answers the request taken last on `channel`: false when the channel is gone or the reply
  // does not fit (nothing written).
  bool Reply(std::uint64_t channel, std::span<const std::uint8_t> bytes, Clock::time_point now);
  bool Has(std::uint64_t channel) const { return channels_.count(channel) > 0; }
  // True when a channel has a request not yet taken.
  bool RequestWaiting() const;
  // True while a client is expected to send its next request soon (the I/O thread spins rather
  // than sleeps): within a few times its recent think time after the last reply.
  bool Expecting(Clock::time_point now) const;
  // Before sleeping in poll: tells every client so (they wake the server); returns true when a
  // request arrived meanwhile (then do not sleep, and call Awake).
  bool PrepareSleep();
  void Awake();
  // At most every sweep period: channels whose client closed or died, or never attached within
  // the timeout, are closed (files removed); returns the sessions whose attached client went
  // away (an offer never taken ends no session). Attached files lose their name here.
  std::vector<std::string> Sweep(Clock::time_point now);
  // Closes the channel of `session` (bye, evicted, its client gone): at once, or right after the
  // reply to the request it is serving (a `bye` sent over the channel itself gets its reply).
  void Close(const std::string& session);

 private:
  struct Channel {
    std::string session;
    wire::ShmChannel channel;
    Clock::time_point offered, last_reply{}, last_request{};
    Clock::duration think{};  // smoothed time from a reply to the next request
    bool answered = true;     // the last request taken was answered
    bool closing = false;     // closed once the request it serves is answered
  };
  std::string folder_;
  ShmOptions options_;
  wire::ShmWakeSocket wake_;
  std::map<std::uint64_t, Channel> channels_;
  std::uint64_t next_ = 1;
  Clock::time_point last_sweep_{};
  bool polling_ = false;  // in Poll's handler: channels closing are erased by Poll
};

// The folder channels are made in: `folder`, or /dev/shm when writable, else the temporary
// folder.
std::string ShmFolder(const std::string& folder);

}  // namespace urlab::net
