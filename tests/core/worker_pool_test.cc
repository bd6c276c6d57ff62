// The persistent worker pool: every part of every job runs exactly once, on distinct threads,
// with the owner's writes visible to the parts and theirs to the owner (run under TSan in CI).
#include "core/worker_pool.h"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "urlab/core/error.h"

namespace urlab {
namespace {

TEST(WorkerPoolTest, RunsEveryPartOncePerJobOnItsOwnThread) {
  WorkerPool pool(3);
  EXPECT_EQ(pool.threads(), 3);
  std::vector<long> sums(3, 0);
  std::vector<std::thread::id> ids(3);
  for (int job = 1; job <= 2000; ++job) {
    std::vector<int> input(3, job);  // written by the owner before Run
    pool.Run([&](int part) {
      sums[static_cast<std::size_t>(part)] += input[static_cast<std::size_t>(part)];
      ids[static_cast<std::size_t>(part)] = std::this_thread::get_id();
    });
    ASSERT_EQ(sums[0], sums[2]);  // read by the owner after Run
  }
  for (long s : sums) EXPECT_EQ(s, 2000L * 2001 / 2);
  EXPECT_EQ(ids[0], std::this_thread::get_id());  // part 0 is the owner's
  EXPECT_EQ(std::set<std::thread::id>(ids.begin(), ids.end()).size(), 3u);
}

TEST(WorkerPoolTest, PartExceptionIsRethrownAfterEveryPartFinished) {
  WorkerPool pool(2);
  std::vector<int> ran(2, 0);
  EXPECT_THROW(pool.Run([&](int part) {
    ran[static_cast<std::size_t>(part)] = 1;
    if (part == 1) throw std::runtime_error("part 1 failed");
  }),
               std::runtime_error);
  EXPECT_EQ(ran, (std::vector<int>{1, 1}));
  pool.Run([&](int part) { ran[static_cast<std::size_t>(part)] = 2; });  // still usable
  EXPECT_EQ(ran, (std::vector<int>{2, 2}));
}

TEST(WorkerPoolTest, OneThreadIsTheOwnerAloneAndZeroIsRefused) {
  WorkerPool pool(1);
  int calls = 0;
  pool.Run([&](int part) { calls += part + 1; });
  EXPECT_EQ(calls, 1);
  EXPECT_THROW(WorkerPool(0), Error);
}

}  // namespace
}  // namespace urlab
