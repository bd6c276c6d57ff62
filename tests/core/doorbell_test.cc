#include "urlab/core/doorbell.h"

#include <gtest/gtest.h>
#include <poll.h>

#include <atomic>
#include <thread>

namespace urlab {
namespace {

bool Readable(const Doorbell& bell, int timeout_ms) {
  pollfd p{bell.fd(), POLLIN, 0};
  return poll(&p, 1, timeout_ms) == 1 && (p.revents & POLLIN);
}

TEST(DoorbellTest, RingsOnlyWhileArmed) {
  Doorbell bell;
  bell.Ring();  // not armed: no write
  EXPECT_FALSE(Readable(bell, 0));
  bell.Arm();
  bell.Ring();
  EXPECT_TRUE(Readable(bell, 0));
  bell.Ring();  // disarmed by the first ring: still one pending wake-up
  bell.Clear();
  EXPECT_FALSE(Readable(bell, 0));
}

// The consumer's protocol (arm, check for work, sleep) never misses a ring from another thread.
TEST(DoorbellTest, NoWakeUpIsLostBetweenThreads) {
  Doorbell bell;
  std::atomic<int> produced{0};
  constexpr int kItems = 20000;
  std::thread producer([&] {
    for (int i = 0; i < kItems; ++i) {
      produced.fetch_add(1);
      bell.Ring();
    }
  });
  int consumed = 0;
  while (consumed < kItems) {
    bell.Arm();
    if (produced.load() > consumed) {
      bell.Clear();
      consumed = produced.load();
      continue;
    }
    ASSERT_TRUE(Readable(bell, 5000)) << "a ring was lost at " << consumed;
    bell.Clear();
  }
  producer.join();
}

}  // namespace
}  // namespace urlab
