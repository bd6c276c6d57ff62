// libFuzzer target for the step server's shared-memory channel (src/wire/shm_channel.h,
// src/net/shm_transport.h) with the client as a hostile peer: a StepServer over a real
// world::Session (the arm of fuzz_support.h, engine not started) offers a channel in `hello`;
// the harness attaches to it, then, for each input, rewrites words of the channel's header the
// way a client process can (capacities, lengths, sequences, flags, the wake name: any word of
// the 4096 header bytes) and publishes a request of any bytes, up to the server's real request
// limit (kMaxRequestBytes, the channel's request capacity; tools/fuzz.sh's -max_len is asked
// from this target). The server must never crash or touch memory beyond its mapping (ASan), and
// a reply it publishes must lie within the capacity it made the channel with and be a map whose
// "op" is "error" or ends in "_ok".
//
// Input: byte 0: the number of header writes (its low 4 bits); each write is 11 bytes: u16
// offset (little-endian; taken modulo the header's size, aligned down to 4), u8 width (even: 4
// bytes, odd: 8, aligned down to 8), u64 value; the rest is the request. The request's bytes and
// length are written first, then the header writes (so they can forge the length), then the
// request sequence is bumped. Every 20-byte "@@@@@@@@@@@@@@@@@@@@" in the request becomes the
// session id (as in fuzz_step_request). Each input gets a fresh hello and channel, and its
// session says bye afterwards over ZeroMQ. URLAB_FUZZ_VERBOSE=1 prints what each input did.
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "fuzz_support.h"
#include "net/step_server.h"
#include "net/topic_table.h"
#include "urlab/physics/commands.h"
#include "wire/request_limits.h"
#include "wire/shm_channel.h"

namespace {

using Json = nlohmann::json;
using L = urlab::wire::ShmLayout;
constexpr std::string_view kPlaceholder = "@@@@@@@@@@@@@@@@@@@@";
constexpr std::size_t kWriteBytes = 11;
constexpr std::size_t kMaxWrites = 15;

struct Fixture {
  std::shared_ptr<urlab::world::Session> session = urlab::fuzz::MakeArmSession();
  std::vector<urlab::net::ArticulationTopics> tables = urlab::net::BuildTopicTables(*session);
  std::shared_ptr<urlab::physics::StateSubscription> state =
      session->engine().SubscribeState("fuzz_shm_channel");
  mjOption options = session->engine().model()->opt;
  zmq::context_t context{1};
  std::unique_ptr<urlab::net::StepServer> server;
  std::optional<zmq::socket_t> client;

  Fixture() {
    urlab::net::StepServerOptions o;
    o.endpoint = "inproc://urlab-fuzz-shm";
    o.files_dir = urlab::fuzz::TempDir() + "/files";
    o.shared_memory = true;
    o.shm.folder = urlab::fuzz::TempDir() + "/shm";
    std::filesystem::create_directories(o.shm.folder);
    server = std::make_unique<urlab::net::StepServer>(*session, tables, state, o);
    if (server->Bind(context).empty()) __builtin_trap();
    client.emplace(context, zmq::socket_type::dealer);
    client->set(zmq::sockopt::linger, 0);
    client->set(zmq::sockopt::rcvtimeo, 1000);
    client->connect(o.endpoint);
  }
};

Fixture& F() {
  static Fixture f;
  return f;
}

void Serve(urlab::net::StepServer& server) {
  server.HandleIncoming();
  server.Service(urlab::net::StepServer::Clock::now());
}

// A ZeroMQ request; the reply (null when none came).
Json Call(Fixture& f, const Json& request) {
  const std::vector<std::uint8_t> bytes = Json::to_msgpack(request);
  f.client->send(zmq::buffer(bytes), zmq::send_flags::none);
  for (int attempt = 0; attempt < 200; ++attempt) {
    Serve(*f.server);
    zmq::message_t m;
    if (f.client->recv(m, attempt < 10 ? zmq::recv_flags::dontwait : zmq::recv_flags::none)) {
      const auto* b = static_cast<const std::uint8_t*>(m.data());
      return Json::from_msgpack(b, b + m.size(), true, false);
    }
  }
  return nullptr;
}

// The hostile side's own mapping of the whole file.
class Mapping {
 public:
  explicit Mapping(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd_ < 0) __builtin_trap();
    size_ = static_cast<std::size_t>(lseek(fd_, 0, SEEK_END));
    void* p = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
    if (p == MAP_FAILED) __builtin_trap();
    base_ = static_cast<std::uint8_t*>(p);
  }
  ~Mapping() {
    munmap(base_, size_);
    close(fd_);
  }
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  std::uint8_t* at(std::size_t offset) const { return base_ + offset; }
  template <typename T>
  T Get(std::size_t offset) const {
    T v;
    std::memcpy(&v, base_ + offset, sizeof(v));
    return v;
  }
  template <typename T>
  void Put(std::size_t offset, T v) {
    __atomic_store(reinterpret_cast<T*>(base_ + offset), &v, __ATOMIC_SEQ_CST);
  }

 private:
  int fd_ = -1;
  std::uint8_t* base_ = nullptr;
  std::size_t size_ = 0;
};

Json CheckReply(std::span<const std::uint8_t> bytes) {
  const bool json = !bytes.empty() && (bytes[0] == '{' || bytes[0] == ' ' || bytes[0] == '\n');
  const Json reply = json ? Json::parse(bytes.begin(), bytes.end(), nullptr, false)
                          : Json::from_msgpack(bytes.begin(), bytes.end(), true, false);
  if (reply.is_discarded() || !reply.is_object()) __builtin_trap();
  const auto op = reply.find("op");
  if (op == reply.end() || !op->is_string()) __builtin_trap();
  const std::string name = op->get<std::string>();
  if (name != "error" && (name.size() < 3 || name.compare(name.size() - 3, 3, "_ok") != 0)) {
    __builtin_trap();
  }
  return reply;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // The header writes and a request as large as the channel takes.
  urlab::fuzz::AnswerMaxLenQuery(1 + kMaxWrites * kWriteBytes + urlab::wire::kMaxRequestBytes);
  (void)F();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = F();
  const bool verbose = std::getenv("URLAB_FUZZ_VERBOSE") != nullptr;
  urlab::physics::PhysicsEngine& engine = f.session->engine();
  const mjOption saved = f.options;
  (void)engine.Submit(urlab::physics::cmd::SetOptions{[saved](mjOption& o) { o = saved; },
                                                      "fuzz: options as built"});
  (void)engine.Submit(urlab::physics::cmd::SetPaused{false});
  (void)f.session->ResetToInitialState();
  std::error_code ec;
  std::filesystem::remove_all(urlab::fuzz::TempDir() + "/files", ec);

  Json hello = Call(f, {{"op", "hello"}, {"shm", true}});
  if (hello.is_object() && !hello.contains("shm")) {
    // Channels of sessions gone are released (a closed client's within the sweep period): a
    // channel is offered again soon, or they leak.
    (void)Call(f, {{"op", "bye"}, {"session_id", hello.value("session_id", "")}});
    usleep(250000);
    Serve(*f.server);
    hello = Call(f, {{"op", "hello"}, {"shm", true}});
  }
  if (!hello.is_object() || !hello.contains("shm")) __builtin_trap();
  const std::string id = hello.value("session_id", std::string());
  if (id.size() != kPlaceholder.size()) __builtin_trap();
  const std::string path = hello["shm"]["path"].get<std::string>();
  std::string opened;  // a session the input's own hello opened
  {
    // The legitimate attach (locks byte 1, marks the channel attached), then the hostile side.
    urlab::wire::ShmChannel attached =
        urlab::wire::ShmChannel::Attach(path, hello["shm"]["generation"].get<std::uint64_t>());
    const std::size_t request_cap = attached.request_capacity();
    const std::size_t reply_cap = attached.reply_capacity();
    Mapping peer(path);

    // Parse the input.
    const std::size_t writes = size == 0 ? 0 : std::min<std::size_t>(data[0] & 15, kMaxWrites);
    std::size_t at = size == 0 ? 0 : 1;
    struct Write {
      std::size_t offset;
      bool wide;
      std::uint64_t value;
    };
    std::vector<Write> header;
    for (std::size_t i = 0; i < writes && at + kWriteBytes <= size; ++i, at += kWriteBytes) {
      Write w{};
      w.offset =
          (static_cast<std::size_t>(data[at]) | std::size_t{data[at + 1]} << 8) % L::kHeaderBytes;
      w.wide = (data[at + 2] & 1) != 0;
      w.offset &= w.wide ? ~std::size_t{7} : ~std::size_t{3};
      std::memcpy(&w.value, data + at + 3, sizeof(w.value));
      header.push_back(w);
    }
    std::string request(reinterpret_cast<const char*>(data) + at, size - at);
    for (std::size_t p = request.find(kPlaceholder); p != std::string::npos;
         p = request.find(kPlaceholder, p + id.size())) {
      request.replace(p, kPlaceholder.size(), id);
    }
    if (request.size() > request_cap) request.resize(request_cap);

    // Publish: bytes, length, the header writes, then the sequence.
    std::memcpy(peer.at(L::kHeaderBytes), request.data(), request.size());
    peer.Put<std::uint64_t>(L::kRequestLen, request.size());
    for (const Write& w : header) {
      if (w.wide) {
        peer.Put<std::uint64_t>(w.offset, w.value);
      } else {
        peer.Put<std::uint32_t>(w.offset, static_cast<std::uint32_t>(w.value));
      }
    }
    const std::uint32_t seq = peer.Get<std::uint32_t>(L::kRequestSeq) + 1;
    peer.Put<std::uint32_t>(L::kRequestSeq, seq);

    // Serve until the reply sequence moves (or give up: the writes may hide the request).
    const std::uint32_t reply_seq = peer.Get<std::uint32_t>(L::kReplySeq);
    bool replied = false;
    for (int attempt = 0; attempt < 2000 && !replied; ++attempt) {
      Serve(*f.server);
      replied = peer.Get<std::uint32_t>(L::kReplySeq) != reply_seq;
    }
    if (replied) {
      // The server wrote within the capacities it made the channel with; the header's copies
      // may be forged, so the reply is read where the server puts it.
      const std::uint64_t len = peer.Get<std::uint64_t>(L::kReplyLen);
      if (len > reply_cap) __builtin_trap();
      const Json reply =
          CheckReply({peer.at(L::kHeaderBytes + request_cap), static_cast<std::size_t>(len)});
      if (reply.value("op", "") == "hello_ok") opened = reply.value("session_id", "");
      if (verbose) std::fprintf(stderr, "reply of %llu bytes\n", (unsigned long long)len);
    } else if (verbose) {
      std::fprintf(stderr, "no reply (%zu header writes)\n", header.size());
    }
  }  // the client side closes (marks the channel closed, drops its lock)

  // Back to no clients and live mode; the channel goes with its session.
  (void)Call(f, {{"op", "set_mode"}, {"session_id", id}, {"mode", "live"}, {"force", true}});
  (void)Call(f, {{"op", "bye"}, {"session_id", id}});
  if (!opened.empty()) (void)Call(f, {{"op", "bye"}, {"session_id", opened}});
  (void)engine.DrainEvents();
  return 0;
}
