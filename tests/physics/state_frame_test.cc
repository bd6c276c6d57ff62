// State frames: any number of subscribers read the newest frame without blocking the physics
// thread or seeing each other's progress; an every-step ring gets every frame in order and counts
// what it had to drop. Run under TSan in CI.
#include "urlab/physics/state_frame.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "support/wait.h"
#include "urlab/physics/engine.h"

namespace urlab::physics {
namespace {

using namespace std::chrono_literals;
using testing::kArmXml;
using testing::kHumanoidPath;
using testing::WaitFor;

class StateFrameTest : public urlab::testing::MujocoTest {};

TEST_F(StateFrameTest, FrameHoldsTheWholeStateOfAStep) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto sub = engine.SubscribeState("reader");
  const StateFrame* first = sub->Latest();  // subscribing publishes the current state
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->step, 0u);
  engine.StepSync(3);
  const StateFrame* f = sub->Latest();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->step, 3u);
  engine.WithLockedData([&](mjModel* m, mjData* d) {
    EXPECT_EQ(f->time, d->time);
    EXPECT_EQ(f->qpos, std::vector<mjtNum>(d->qpos, d->qpos + m->nq));
    EXPECT_EQ(f->qvel, std::vector<mjtNum>(d->qvel, d->qvel + m->nv));
    EXPECT_EQ(f->act, std::vector<mjtNum>(d->act, d->act + m->na));
    EXPECT_EQ(f->ctrl, std::vector<mjtNum>(d->ctrl, d->ctrl + m->nu));
    EXPECT_EQ(f->qacc, std::vector<mjtNum>(d->qacc, d->qacc + m->nv));
    EXPECT_EQ(f->sensordata, std::vector<mjtNum>(d->sensordata, d->sensordata + m->nsensordata));
    EXPECT_EQ(f->xpos, std::vector<mjtNum>(d->xpos, d->xpos + 3 * m->nbody));
    EXPECT_EQ(f->xquat, std::vector<mjtNum>(d->xquat, d->xquat + 4 * m->nbody));
    EXPECT_EQ(f->mocap_pos, std::vector<mjtNum>(d->mocap_pos, d->mocap_pos + 3 * m->nmocap));
    EXPECT_EQ(f->ncon, d->ncon);
  });
  EXPECT_FALSE(f->paused);
  EXPECT_EQ(f->discontinuity, 0u);
  engine.Reset();
  f = sub->Latest();
  EXPECT_EQ(f->discontinuity, kDiscontinuityReset);
  EXPECT_EQ(f->epoch, 1u);
  EXPECT_EQ(f->time, 0.0);
}

// A frame names the forces its step used (one-shot forces included), so a recorder can
// re-simulate the run; the persistent xfrc_applied is put back bit for bit after the step.
TEST_F(StateFrameTest, FrameReportsTheAppliedForcesOfItsStep) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto ring = engine.SubscribeEveryStep("recorder", 16);
  const int box = mj_name2id(engine.model(), mjOBJ_BODY, "box");
  const double persistent = 0.1;  // not exactly representable: x + f - f would not give it back
  engine.WithLockedData([&](mjModel*, mjData* d) {
    d->xfrc_applied[6 * box + 1] = persistent;
    d->qfrc_applied[0] = 0.25;
  });
  engine.Submit(cmd::ApplyForce{box, {2.0, 0.3, 0}, {0, 0, 0}});
  engine.StepSync(2);
  StateFrame f;
  ASSERT_TRUE(ring->TryPop(&f));  // the command's own frame (no step)
  EXPECT_FALSE(f.stepped);
  ASSERT_TRUE(ring->TryPop(&f));
  EXPECT_TRUE(f.stepped);
  EXPECT_EQ(f.xfrc_applied[6 * box], 2.0);
  EXPECT_EQ(f.xfrc_applied[6 * box + 1], persistent + 0.3);
  EXPECT_EQ(f.qfrc_applied[0], 0.25);
  ASSERT_TRUE(ring->TryPop(&f));
  EXPECT_TRUE(f.stepped);
  EXPECT_EQ(f.xfrc_applied[6 * box], 0.0);  // one step only
  EXPECT_EQ(f.xfrc_applied[6 * box + 1], persistent);
  engine.WithLockedData(
      [&](mjModel*, mjData* d) { EXPECT_EQ(d->xfrc_applied[6 * box + 1], persistent); });
  // An inactive ring is skipped: nothing copied, nothing dropped.
  ring->SetActive(false);
  engine.StepSync(20);
  EXPECT_EQ(ring->size(), 0u);
  EXPECT_EQ(ring->dropped(), 0u);
  ring->SetActive(true);
  engine.StepSync(1);
  EXPECT_EQ(ring->size(), 1u);
}

TEST_F(StateFrameTest, SubscribingWhileRunningIsRefused) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.Start();
  EXPECT_THROW(engine.SubscribeState("late"), Error);
  EXPECT_THROW(engine.SubscribeEveryStep("late", 8), Error);
  engine.Stop();
  EXPECT_NE(engine.SubscribeState("after"), nullptr);
}

// Three readers of different speeds: each sees frames in increasing step order, complete
// (time matches the step), and a stalled reader does not hold the others or the loop back.
TEST_F(StateFrameTest, ManyReadersEachSeeTheNewestFrameIndependently) {
  PhysicsEngine engine(LoadXmlFile(kHumanoidPath));
  engine.SetAsFastAsPossible(true);
  const double dt = engine.model()->opt.timestep;
  std::vector<std::shared_ptr<StateSubscription>> subs;
  for (const char* n : {"fast", "slow", "stalled"}) subs.push_back(engine.SubscribeState(n));
  std::atomic<bool> done{false};
  std::atomic<bool> ok{true};
  std::atomic<int> fast_reads{0}, slow_reads{0};
  const auto reader = [&](StateSubscription* s, std::chrono::microseconds pause,
                          std::atomic<int>* reads) {
    std::uint64_t last = 0;
    while (!done.load()) {
      const StateFrame* f = s->Latest();
      if (f->step < last) ok = false;
      // A torn frame would mix steps: time and step are written together with the arrays.
      if (std::abs(f->time - static_cast<double>(f->step) * dt) > 1e-6) ok = false;
      for (double v : f->qpos) ok = ok && std::isfinite(v);
      last = f->step;
      reads->fetch_add(1);
      std::this_thread::sleep_for(pause);
    }
  };
  engine.Start();
  std::thread fast(reader, subs[0].get(), 0us, &fast_reads);
  std::thread slow(reader, subs[1].get(), 5ms, &slow_reads);
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 3000 && slow_reads.load() > 20; }));
  done = true;
  fast.join();
  slow.join();
  engine.Stop();
  EXPECT_TRUE(ok.load());
  EXPECT_GT(fast_reads.load(), slow_reads.load());
  // The stalled reader never read, yet it has the newest frame waiting.
  EXPECT_TRUE(subs[2]->has_new());
  EXPECT_EQ(subs[2]->Latest()->step, engine.step_count());
  EXPECT_EQ(subs[0]->published(), subs[2]->published());
}

// The every-step ring: a reader that keeps up sees every step once, in order; a full ring drops
// new frames and counts them, never blocking the physics thread.
TEST_F(StateFrameTest, EveryStepRingDeliversEveryFrameInOrderAndCountsDrops) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.SetAsFastAsPossible(true);
  const auto ring = engine.SubscribeEveryStep("recorder", 256);
  const auto full = engine.SubscribeEveryStep("never_read", 16);
  std::atomic<bool> done{false};
  std::vector<std::uint64_t> steps;
  std::thread consumer([&] {
    StateFrame f = StateFrame::SizedFor(engine.model());
    while (true) {
      const bool stop = done.load();
      while (ring->TryPop(&f)) steps.push_back(f.step);
      if (stop) break;
      std::this_thread::sleep_for(100us);
    }
  });
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 5000; }));
  engine.Stop();
  done = true;
  consumer.join();
  const std::uint64_t total = engine.step_count();
  ASSERT_EQ(steps.size() + ring->dropped(), total);
  // Whatever was delivered is in order; with no drops it is every step.
  for (std::size_t i = 1; i < steps.size(); ++i) ASSERT_LT(steps[i - 1], steps[i]);
  if (ring->dropped() == 0) {
    for (std::size_t i = 0; i < steps.size(); ++i) ASSERT_EQ(steps[i], i + 1);
  }
  EXPECT_EQ(full->size(), 16u);
  EXPECT_EQ(full->dropped(), total - 16);
  StateFrame f;
  ASSERT_TRUE(full->TryPop(&f));
  EXPECT_EQ(f.step, 1u);  // the oldest kept, the newest dropped
}

// A paused loop publishes a frame when it pauses and after each command, and not otherwise.
TEST_F(StateFrameTest, PausedLoopPublishesOnPauseAndCommandsOnly) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto sub = engine.SubscribeState("viewer");
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 10; }));
  engine.SetPaused(true);
  ASSERT_TRUE(WaitFor([&] { return sub->Latest()->paused; }));
  const std::uint64_t n = sub->published();
  std::this_thread::sleep_for(30ms);
  EXPECT_EQ(sub->published(), n);
  const std::uint64_t seq = engine.Reset();
  EXPECT_TRUE(engine.WaitForCommand(seq, 5s).ok());
  ASSERT_TRUE(WaitFor([&] { return sub->published() == n + 1; }));
  const StateFrame* f = sub->Latest();
  EXPECT_EQ(f->command_seq, seq);
  EXPECT_EQ(f->time, 0.0);
  EXPECT_TRUE(f->paused);
  engine.Stop();
}

}  // namespace
}  // namespace urlab::physics
