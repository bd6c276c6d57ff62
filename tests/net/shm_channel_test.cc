// The shared-memory channel (src/wire/shm_channel.h) on its own: two threads and two processes
// exchanging requests and replies through a real mapped file, with the server sleeping in
// poll(2) on its wake socket and the client on its futex; a peer killed with SIGKILL is noticed
// (no wedge), files of dead servers are reclaimed, bad attachments are refused.
#include "wire/shm_channel.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace urlab::wire {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

class ShmChannelTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/urlab_shm_test_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string NewPath() const { return dir_ + "/" + NewShmName(); }
  std::size_t Files() const {
    return static_cast<std::size_t>(
        std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }
  std::string dir_;
};

std::vector<std::uint8_t> Bytes(std::string_view s) { return {s.begin(), s.end()}; }

// The reply the echo servers give: the request reversed, then its length.
std::vector<std::uint8_t> Answer(std::span<const std::uint8_t> request) {
  std::vector<std::uint8_t> out(request.rbegin(), request.rend());
  const std::string n = std::to_string(request.size());
  out.insert(out.end(), n.begin(), n.end());
  return out;
}

// Serves `requests` requests like the step server's I/O thread: takes what is waiting, answers,
// and when nothing is, tells the client it sleeps and sleeps in poll on the wake socket.
void Serve(ShmChannel& server, ShmWakeSocket& wake, int requests, bool slow_replies) {
  std::mt19937 rng(7);
  for (int served = 0; served < requests;) {
    if (auto request = server.TakeRequest()) {
      if (slow_replies && rng() % 8 == 0) std::this_thread::sleep_for(200us);  // client sleeps
      const std::vector<std::uint8_t> reply = Answer(*request);
      ASSERT_TRUE(server.WriteReply(reply));
      ++served;
      continue;
    }
    server.Sleeping(true);
    if (!server.request_waiting()) {
      pollfd p{wake.fd(), POLLIN, 0};
      ASSERT_GT(poll(&p, 1, 10000), 0) << "a request never woke the server";
    }
    server.Sleeping(false);
    wake.Drain();
  }
}

// A client loop: random sizes and contents, sometimes pausing so that the server sleeps first.
void Drive(ShmChannel& client, int requests) {
  std::mt19937 rng(11);
  for (int i = 0; i < requests; ++i) {
    std::vector<std::uint8_t> request(rng() % 3000);
    for (auto& b : request) b = static_cast<std::uint8_t>(rng());
    if (rng() % 8 == 0) std::this_thread::sleep_for(300us);
    client.SendRequest(request);
    const auto reply = client.WaitReply(20s, std::chrono::microseconds(rng() % 2 ? 50 : 0));
    const std::vector<std::uint8_t> expected = Answer(request);
    ASSERT_EQ(std::vector<std::uint8_t>(reply.begin(), reply.end()), expected) << "request " << i;
  }
}

TEST_F(ShmChannelTest, TwoThreadsExchangeRequestsAndReplies) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 8192, wake.name());
  EXPECT_FALSE(server.attached());
  ShmChannel client = ShmChannel::Attach(server.path(), server.generation());
  EXPECT_TRUE(server.attached());
  EXPECT_FALSE(server.PeerGone());
  EXPECT_FALSE(client.PeerGone());
  constexpr int kRequests = 3000;
  std::thread t([&] { Serve(server, wake, kRequests, true); });
  Drive(client, kRequests);
  t.join();
}

TEST_F(ShmChannelTest, TwoProcessesExchangeRequestsAndReplies) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 8192, wake.name());
  const std::string path = server.path();
  const std::uint64_t generation = server.generation();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int code = 0;
    try {
      ShmChannel client = ShmChannel::Attach(path, generation);
      Drive(client, 2000);
      code = ::testing::Test::HasFailure() ? 3 : 0;
    } catch (const std::exception&) {
      code = 2;
    }
    _exit(code);
  }
  Serve(server, wake, 2000, true);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(server.PeerGone());  // its channel closed with it
}

TEST_F(ShmChannelTest, AKilledClientIsNoticedByTheServer) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 4096, wake.name());
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShmChannel client = ShmChannel::Attach(server.path(), server.generation());
    client.SendRequest(Bytes("step"));  // then dies waiting for its reply, never closing
    (void)!write(ready[1], "x", 1);
    pause();
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  EXPECT_TRUE(server.attached());
  EXPECT_FALSE(server.PeerGone());
  ASSERT_TRUE(server.TakeRequest().has_value());
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  EXPECT_TRUE(server.PeerGone());
  EXPECT_TRUE(server.WriteReply(Bytes("nobody reads this")));  // never blocks
  close(ready[0]);
  close(ready[1]);
}

TEST_F(ShmChannelTest, AKilledServerIsAnErrorForAWaitingClientBeforeItsTimeout) {
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const std::string path = NewPath();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShmWakeSocket wake;
    ShmChannel server = ShmChannel::Create(path, 4096, 4096, wake.name());
    const std::uint64_t g = server.generation();
    (void)!write(ready[1], &g, sizeof(g));
    pause();  // never answers
    _exit(0);
  }
  std::uint64_t generation = 0;
  ASSERT_EQ(read(ready[0], &generation, sizeof(generation)), sizeof(generation));
  ShmChannel client = ShmChannel::Attach(path, generation);
  client.SendRequest(Bytes("step"));
  std::thread killer([&] {
    std::this_thread::sleep_for(100ms);
    kill(child, SIGKILL);
  });
  // The timeout is far away: the error must come from the server's death, not from it.
  try {
    client.WaitReply(600s, 20us);
    ADD_FAILURE() << "a reply from a dead server";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("died"), std::string::npos) << e.what();
  }
  killer.join();
  waitpid(child, nullptr, 0);
  close(ready[0]);
  close(ready[1]);
}

TEST_F(ShmChannelTest, AServerClosingWakesItsWaitingClient) {
  ShmWakeSocket wake;
  auto server =
      std::make_unique<ShmChannel>(ShmChannel::Create(NewPath(), 4096, 4096, wake.name()));
  ShmChannel client = ShmChannel::Attach(server->path(), server->generation());
  client.SendRequest(Bytes("step"));
  std::thread closer([&] {
    std::this_thread::sleep_for(50ms);
    server.reset();
  });
  EXPECT_THROW(client.WaitReply(600s, 0us), ShmError);
  closer.join();
}

TEST_F(ShmChannelTest, TheServerRemovesItsFileAndStaleFilesAreReclaimed) {
  {
    ShmWakeSocket wake;
    ShmChannel server = ShmChannel::Create(NewPath(), 4096, 4096, wake.name());
    EXPECT_EQ(Files(), 1u);
    // A live server's file is never reclaimed.
    EXPECT_EQ(ShmChannel::ReclaimStale(dir_), 0);
    EXPECT_EQ(Files(), 1u);
  }
  EXPECT_EQ(Files(), 0u);  // removed on close
  // A server killed before any client attached leaves its file: the next one removes it.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShmWakeSocket wake;
    ShmChannel server = ShmChannel::Create(dir_ + "/" + NewShmName(), 4096, 4096, wake.name());
    kill(getpid(), SIGKILL);
  }
  waitpid(child, nullptr, 0);
  EXPECT_EQ(Files(), 1u);
  EXPECT_EQ(ShmChannel::ReclaimStale(dir_), 1);
  EXPECT_EQ(Files(), 0u);
}

TEST_F(ShmChannelTest, BadAttachmentsAndSizesAreRefused) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 4096, wake.name());
  EXPECT_THROW(ShmChannel::Attach(server.path(), server.generation() + 1), ShmError);
  EXPECT_THROW(ShmChannel::Attach(dir_ + "/urlab-shm-none", 1), ShmError);
  EXPECT_THROW(ShmChannel::Create(server.path(), 4096, 4096, wake.name()), ShmError);  // exists
  ShmChannel client = ShmChannel::Attach(server.path(), server.generation());
  EXPECT_THROW(ShmChannel::Attach(server.path(), server.generation()), ShmError);  // second
  EXPECT_THROW(client.SendRequest(std::vector<std::uint8_t>(4097)), ShmError);
  EXPECT_THROW(client.WaitReply(1s, 0us), ShmError);  // nothing sent
  client.SendRequest(Bytes("x"));
  EXPECT_THROW(client.SendRequest(Bytes("y")), ShmError);  // one in flight
  ASSERT_TRUE(server.TakeRequest().has_value());
  EXPECT_FALSE(server.WriteReply(std::vector<std::uint8_t>(4097)));
  EXPECT_TRUE(server.WriteReply(Bytes("ok")));
  const auto reply = client.WaitReply(1s, 0us);
  EXPECT_EQ(std::string(reply.begin(), reply.end()), "ok");
}

// The client's side of the file as a hostile peer sees it: the whole mapping, writable.
class HostileView {
 public:
  explicit HostileView(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_CLOEXEC);
    size_ = static_cast<std::size_t>(lseek(fd_, 0, SEEK_END));
    base_ = static_cast<std::uint8_t*>(
        mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0));
  }
  ~HostileView() {
    munmap(base_, size_);
    close(fd_);
  }
  void Put64(std::size_t at, std::uint64_t v) { std::memcpy(base_ + at, &v, sizeof(v)); }
  void Put32(std::size_t at, std::uint32_t v) { std::memcpy(base_ + at, &v, sizeof(v)); }
  std::uint8_t* base() const { return base_; }
  std::size_t size() const { return size_; }

 private:
  int fd_ = -1;
  std::uint8_t* base_ = nullptr;
  std::size_t size_ = 0;
};

// Issue 38, case 1: the client rewrites the capacities in the header (the server used to read
// them back on every request and write its reply at 4096 + that value: 2^40 crashed it at once,
// file size - 4160 wrote past the mapping). The server keeps the sizes it made the channel
// with: replies land where they always did, lengths beyond its own capacity are refused.
TEST_F(ShmChannelTest, TheServerTakesNoSizeOrOffsetFromTheSharedPage) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 8192, wake.name());
  ShmChannel client = ShmChannel::Attach(server.path(), server.generation());
  HostileView peer(server.path());
  const std::size_t file = peer.size();
  for (const std::uint64_t forged : {std::uint64_t{1} << 40, std::uint64_t{file - 4160},
                                     std::uint64_t{file}, ~std::uint64_t{0}, std::uint64_t{0}}) {
    peer.Put64(ShmLayout::kRequestCapacity, forged);
    peer.Put64(ShmLayout::kReplyCapacity, forged);
    EXPECT_EQ(server.request_capacity(), 4096u);
    EXPECT_EQ(server.reply_capacity(), 8192u);
    client.SendRequest(Bytes("ping"));
    const auto request = server.TakeRequest();
    ASSERT_TRUE(request.has_value()) << forged;
    EXPECT_EQ(std::string(request->begin(), request->end()), "ping");
    EXPECT_FALSE(server.WriteReply(std::vector<std::uint8_t>(8193)));
    ASSERT_TRUE(server.WriteReply(std::vector<std::uint8_t>(8192, 'r'))) << forged;
    const auto reply = client.WaitReply(1s, 0us);
    EXPECT_EQ(reply.size(), 8192u);
    // The reply is where the server put it when it made the channel, not beyond.
    EXPECT_EQ(peer.base()[ShmLayout::kHeaderBytes + 4096], 'r');
  }
  // A length beyond the server's own capacity is a bad request, whatever the header claims.
  peer.Put64(ShmLayout::kRequestCapacity, std::uint64_t{1} << 40);
  peer.Put64(ShmLayout::kRequestLen, 4097);
  peer.Put32(ShmLayout::kRequestSeq, 999);
  bool bad = false;
  EXPECT_FALSE(server.TakeRequest(&bad).has_value());
  EXPECT_TRUE(bad);
}

// The request the server decodes is its own copy: rewriting the slot afterwards changes nothing.
TEST_F(ShmChannelTest, TheServerDecodesItsOwnCopyOfARequest) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 4096, wake.name());
  ShmChannel client = ShmChannel::Attach(server.path(), server.generation());
  HostileView peer(server.path());
  client.SendRequest(Bytes("abcd"));
  const auto request = server.TakeRequest();
  ASSERT_TRUE(request.has_value());
  std::memcpy(peer.base() + ShmLayout::kHeaderBytes, "wxyz", 4);
  EXPECT_EQ(std::string(request->begin(), request->end()), "abcd");
}

// A second client whose attach is refused leaves the channel alone (it used to mark the client
// closed on its way out, so the server dropped the client that had attached).
TEST_F(ShmChannelTest, ARefusedSecondAttachDoesNotCloseTheFirstClient) {
  ShmWakeSocket wake;
  ShmChannel server = ShmChannel::Create(NewPath(), 4096, 4096, wake.name());
  ShmChannel client = ShmChannel::Attach(server.path(), server.generation());
  EXPECT_THROW(ShmChannel::Attach(server.path(), server.generation()), ShmError);
  EXPECT_FALSE(server.PeerGone());
}

}  // namespace
}  // namespace urlab::wire
