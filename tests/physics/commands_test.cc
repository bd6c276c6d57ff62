// The engine's command queue: every command applied exactly once, in submission order, from any
// number of threads; waiters released when their command took effect; the physics thread tells
// the command listeners and marks discontinuities in the state frames. Run under TSan in CI.
#include "urlab/physics/commands.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
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
using testing::WaitFor;

class CommandsTest : public urlab::testing::MujocoTest {};

double Qpos(PhysicsEngine& e, int i) {
  double v = 0;
  e.WithLockedData([&](mjModel*, mjData* d) { v = d->qpos[i]; });
  return v;
}

// Two commands that land in the same iteration are both applied, in order: Restore then Reset
// ends in the reset state; two custom resets both take effect (the old single pending slot
// dropped the first).
TEST_F(CommandsTest, CommandsInOneIterationAreAllAppliedInOrder) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto frames = engine.SubscribeEveryStep("test", 4096);
  engine.SetAsFastAsPossible(true);
  engine.StepSync(50);
  const PhysicsState mid = engine.Snapshot();
  ASSERT_GT(mid.time, 0);
  engine.SetPaused(true);  // a paused loop still applies commands (and publishes a frame then)
  engine.Start();
  std::uint64_t restore = 0, reset = 0, a = 0, b = 0;
  // Holding the step mutex keeps the loop out, so everything below is applied in one iteration.
  engine.WithLockedData([&](mjModel*, mjData*) {
    restore = engine.Restore(mid);
    reset = engine.Reset();
    a = engine.ResetWith([](const mjModel*, mjData* d) { d->qpos[0] = 0.25; }, "a");
    b = engine.ResetWith([](const mjModel*, mjData* d) { d->qpos[1] = -0.5; }, "b");
  });
  EXPECT_EQ(engine.WaitForCommand(b, 5s).status, CommandStatus::kApplied);
  EXPECT_LT(restore, reset);
  EXPECT_LT(reset, a);
  EXPECT_LT(a, b);
  engine.Stop();
  std::vector<std::string> messages;
  for (const EngineEvent& e : engine.DrainEvents()) messages.push_back(e.message);
  ASSERT_EQ(messages.size(), 4u);
  EXPECT_EQ(messages[0].rfind("restored", 0), 0u);
  EXPECT_EQ(messages[1], "reset");
  EXPECT_EQ(messages[2], "a");
  EXPECT_EQ(messages[3], "b");
  // Both custom resets acted; the full reset came after the restore, so time started over.
  EXPECT_DOUBLE_EQ(Qpos(engine, 0), 0.25);
  EXPECT_DOUBLE_EQ(Qpos(engine, 1), -0.5);
  // One frame after the four commands carries all of their discontinuities.
  StateFrame f;
  bool marked = false;
  while (frames->TryPop(&f)) {
    if (f.command_seq == b) {
      EXPECT_EQ(f.discontinuity, kDiscontinuityReset | kDiscontinuityRestore);
      EXPECT_EQ(f.time, 0.0);  // the reset came last
      marked = true;
      break;
    }
  }
  EXPECT_TRUE(marked);
}

// Several threads issue thousands of mixed commands at a running loop. Every command is applied
// exactly once, sequence numbers are applied in order with none missing, each thread's waits are
// released, and the loop stays healthy.
TEST_F(CommandsTest, ThousandsOfMixedCommandsFromSeveralThreadsApplyOnceInOrder) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.SetAsFastAsPossible(true);
  const PhysicsState start = engine.Snapshot();
  constexpr int kThreads = 4;
  constexpr int kPerThread = 1500;
  // Physics-thread bookkeeping, read after Stop.
  std::vector<std::uint64_t> applied_seqs;
  applied_seqs.reserve(kThreads * kPerThread);
  int failures = 0;
  engine.AddCommandListener([&](const AppliedCommand& c, const mjModel*, const mjData*) {
    applied_seqs.push_back(c.seq);
    if (!c.error.empty()) ++failures;
  });
  std::vector<std::atomic<int>> custom_runs(kThreads * kPerThread);
  std::atomic<int> waits_ok{0}, waits_bad{0};
  std::vector<std::vector<std::uint64_t>> issued(kThreads);
  engine.Start();
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kPerThread; ++i) {
        const int id = t * kPerThread + i;
        std::uint64_t seq = 0;
        switch (i % 10) {
          case 0:
            seq = engine.ResetWith(
                [&custom_runs, id](const mjModel*, mjData*) { custom_runs[id].fetch_add(1); },
                "custom");
            break;
          case 1:
            seq = engine.Submit(cmd::SetQpos{0, {0.01 * (i % 7)}});
            break;
          case 2:
            seq = engine.Submit(cmd::SetQvel{1, {0.1}});
            break;
          case 3:
            seq = engine.Submit(cmd::SetMocap{0, {0.3, 0, 0.5 + 0.001 * (i % 5)}, {1, 0, 0, 0}});
            break;
          case 4:
            seq = engine.Submit(cmd::ApplyForce{3, {0, 0, 0.5}, {0, 0, 0}});
            break;
          case 5:
            seq = engine.Submit(cmd::SetOptions{[](mjOption& o) { o.gravity[2] = -9.81; }, "g"});
            break;
          case 6:
            seq = engine.Submit(cmd::SetPaused{false});
            break;
          case 7:
            seq = engine.Restore(start);
            break;
          case 8:
            seq = engine.ResetToKeyframe(i % 2);
            break;
          default:
            seq = engine.Reset();
            break;
        }
        issued[t].push_back(seq);
        if (i % 50 == 49) {  // wait for some: the reply-only-when-applied path
          const CommandResult r = engine.WaitForCommand(seq, 10s);
          (r.ok() && engine.last_applied_command() >= seq ? waits_ok : waits_bad).fetch_add(1);
        }
      }
    });
  }
  for (std::thread& th : threads) th.join();
  std::uint64_t newest = 0;
  for (const auto& v : issued) newest = std::max(newest, v.back());
  EXPECT_EQ(engine.WaitForCommand(newest, 10s).status, CommandStatus::kApplied);
  engine.Stop();

  constexpr int kTotal = kThreads * kPerThread;
  ASSERT_EQ(static_cast<int>(applied_seqs.size()), kTotal);
  for (int i = 0; i < kTotal; ++i) {
    ASSERT_EQ(applied_seqs[static_cast<std::size_t>(i)], static_cast<std::uint64_t>(i + 1))
        << "applied out of order or twice at position " << i;
  }
  for (const auto& v : issued) {  // each thread's own commands in its own order
    for (std::size_t i = 1; i < v.size(); ++i) ASSERT_LT(v[i - 1], v[i]);
  }
  int custom = 0;
  for (int id = 0; id < kTotal; ++id) {
    if (id % kPerThread % 10 == 0) {
      ASSERT_EQ(custom_runs[static_cast<std::size_t>(id)].load(), 1) << "custom reset " << id;
      ++custom;
    }
  }
  EXPECT_EQ(custom, kThreads * kPerThread / 10);
  EXPECT_EQ(failures, 0);
  EXPECT_EQ(waits_ok.load(), kThreads * kPerThread / 50);
  EXPECT_EQ(waits_bad.load(), 0);
  // Every one-shot force was taken off again.
  engine.WithLockedData([](mjModel* m, mjData* d) {
    for (int i = 0; i < 6 * m->nbody; ++i) EXPECT_EQ(d->xfrc_applied[i], 0.0) << i;
  });
  engine.StepSync(10);  // still healthy
}

TEST_F(CommandsTest, WaitReportsTimeoutUnknownAndFailure) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  EXPECT_EQ(engine.WaitForCommand(12345, 1ms).status, CommandStatus::kUnknown);
  // Not running: applied at once on the caller's thread.
  const std::uint64_t ok = engine.Submit(cmd::SetQpos{0, {0.3}});
  EXPECT_EQ(engine.WaitForCommand(ok, 0s).status, CommandStatus::kApplied);
  EXPECT_DOUBLE_EQ(Qpos(engine, 0), 0.3);
  // A command that throws while being applied fails alone; the engine goes on.
  const std::uint64_t bad = engine.ResetWith(
      [](const mjModel*, mjData*) { throw std::runtime_error("no such pose"); }, "bad");
  const CommandResult r = engine.WaitForCommand(bad, 0s);
  EXPECT_EQ(r.status, CommandStatus::kFailed);
  EXPECT_NE(r.error.find("no such pose"), std::string::npos) << r.error;
  const std::uint64_t opt =
      engine.Submit(cmd::SetOptions{[](mjOption& o) { o.timestep = -1; }, "bad timestep"});
  EXPECT_EQ(engine.WaitForCommand(opt, 0s).status, CommandStatus::kFailed);
  EXPECT_DOUBLE_EQ(engine.model()->opt.timestep, 0.002);  // left as it was
  // A paused, running loop still applies commands; a wait that ends first says so.
  engine.SetPaused(true);
  engine.Start();
  std::uint64_t late = 0;
  engine.WithLockedData([&](mjModel*, mjData*) {
    late = engine.Submit(cmd::SetQpos{0, {0.1}});
    EXPECT_EQ(engine.WaitForCommand(late, 5ms).status, CommandStatus::kTimeout);
  });
  EXPECT_EQ(engine.WaitForCommand(late, 5s).status, CommandStatus::kApplied);
  engine.Stop();
  EXPECT_DOUBLE_EQ(Qpos(engine, 0), 0.1);
}

TEST_F(CommandsTest, BadCommandsAreRefusedAtOnceAndNothingIsQueued) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const std::uint64_t before = engine.last_applied_command();
  EXPECT_THROW(engine.Submit(cmd::SetQpos{8, {1, 2}}), Error);  // past nq = 9
  EXPECT_THROW(engine.Submit(cmd::SetQpos{-1, {1}}), Error);
  EXPECT_THROW(engine.Submit(cmd::SetQpos{0, {}}), Error);
  EXPECT_THROW(engine.Submit(cmd::SetQvel{0, {std::nan("")}}), Error);
  EXPECT_THROW(engine.Submit(cmd::SetMocap{1, {0, 0, 0}, {1, 0, 0, 0}}), Error);  // nmocap = 1
  EXPECT_THROW(engine.Submit(cmd::SetMocap{0, {0, 0, 0}, {0, 0, 0, 0}}), Error);
  EXPECT_THROW(engine.Submit(cmd::ApplyForce{99, {1, 0, 0}, {0, 0, 0}}), Error);
  EXPECT_THROW(engine.Submit(cmd::ApplyForce{1, {INFINITY, 0, 0}, {0, 0, 0}}), Error);
  EXPECT_THROW(engine.Submit(cmd::ResetKeyframe{7}), Error);
  EXPECT_THROW(engine.Submit(cmd::SetOptions{}), Error);
  PhysicsState wrong;
  EXPECT_THROW(engine.Restore(wrong), StateError);
  EXPECT_EQ(engine.last_applied_command(), before);
}

TEST_F(CommandsTest, OneShotForceActsForOneStepAndMocapAndOptionsApply) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const int box = mj_name2id(engine.model(), mjOBJ_BODY, "box");
  engine.Submit(cmd::SetOptions{[](mjOption& o) { o.gravity[2] = 0; }, "zero g"});
  engine.Submit(cmd::ApplyForce{box, {2.0, 0, 0}, {0, 0, 0}});
  engine.StepSync(1);
  double vx = 0;
  engine.WithLockedData([&](mjModel* m, mjData* d) {
    const int dof = m->jnt_dofadr[m->body_jntadr[box]];
    vx = d->qvel[dof];
    EXPECT_EQ(d->xfrc_applied[6 * box], 0.0);  // removed after its step
  });
  // F/m * dt = 2 / 0.2 * 0.002 (the box rests on the floor with gravity off: no friction).
  EXPECT_NEAR(vx, 0.02, 1e-6);
  engine.StepSync(5);
  engine.WithLockedData([&](mjModel* m, mjData* d) {
    EXPECT_NEAR(d->qvel[m->jnt_dofadr[m->body_jntadr[box]]], vx, 1e-9);  // no more push
  });
  engine.Submit(cmd::SetMocap{0, {1, 2, 3}, {2, 0, 0, 0}});
  engine.WithLockedData([](mjModel*, mjData* d) {
    EXPECT_DOUBLE_EQ(d->mocap_pos[1], 2.0);
    EXPECT_DOUBLE_EQ(d->mocap_quat[0], 1.0);  // normalised
  });
}

// The physics thread tells the command listeners about every applied command with the
// discontinuity it caused, so a recorder can mark resets and restores.
TEST_F(CommandsTest, ListenersSeeResetsAndRestoresWithTheirDiscontinuity) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  std::vector<std::pair<std::string, std::uint32_t>> seen;
  engine.AddCommandListener([&](const AppliedCommand& c, const mjModel*, const mjData*) {
    seen.emplace_back(c.name, c.discontinuity);
  });
  const PhysicsState s = engine.Snapshot();
  engine.Reset();
  engine.Restore(s);
  engine.ResetToKeyframe("arm_bent");
  engine.Submit(cmd::SetQpos{0, {0.1}});
  engine.Submit(cmd::SetMocap{0, {0, 0, 1}, {1, 0, 0, 0}});
  engine.Submit(cmd::SetOptions{[](mjOption& o) { o.timestep = 0.001; }, "dt"});
  using P = std::pair<std::string, std::uint32_t>;
  EXPECT_EQ(seen, (std::vector<P>{{"reset", kDiscontinuityReset},
                                  {"restore", kDiscontinuityRestore},
                                  {"reset_keyframe", kDiscontinuityReset},
                                  {"set_qpos", kDiscontinuitySetState},
                                  {"set_mocap", kNoDiscontinuity},
                                  {"set_options", kDiscontinuityOptions}}));
  EXPECT_EQ(DiscontinuityString(kDiscontinuityReset | kDiscontinuityOptions), "reset|options");
}

// Lockstep: a step command runs exactly n full iterations (controls every iteration) even while
// paused, is finished after the last one with the frame that shows it, and holds back the
// commands queued behind it until then.
TEST_F(CommandsTest, StepCommandRunsExactlyNIterationsThenReleasesItsWaiter) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto frames = engine.SubscribeState("server");
  std::atomic<int> controls{0};
  engine.SetApplyControlsHook([&](const mjModel*, mjData*) { controls.fetch_add(1); });
  // Not running: the caller's thread runs the window.
  const std::uint64_t first = engine.Submit(cmd::Step{5});
  EXPECT_TRUE(engine.WaitForCommand(first, 0s).ok());
  EXPECT_EQ(engine.step_count(), 5u);
  EXPECT_EQ(controls.load(), 5);
  // Running but paused (direct mode): the loop waits for requests.
  engine.SetPaused(true);
  engine.Start();
  for (int round = 0; round < 50; ++round) {
    const std::uint64_t before = engine.step_count();
    const int n = 1 + round % 7;
    const std::uint64_t seq = engine.Submit(cmd::Step{n});
    ASSERT_TRUE(engine.WaitForCommand(seq, 5s).ok());
    EXPECT_EQ(engine.step_count(), before + static_cast<std::uint64_t>(n));
    const StateFrame* f = frames->Latest();
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->command_seq, seq);  // the frame a reply reads shows the whole window
    EXPECT_EQ(f->step, before + static_cast<std::uint64_t>(n));
  }
  // A command behind a long window waits for it.
  const std::uint64_t before = engine.step_count();
  const std::uint64_t window = engine.Submit(cmd::Step{2000});
  const std::uint64_t behind = engine.Submit(cmd::SetQpos{0, {0.2}});
  ASSERT_TRUE(engine.WaitForCommand(behind, 10s).ok());
  EXPECT_TRUE(engine.WaitForCommand(window, 0s).ok());
  EXPECT_EQ(engine.step_count(), before + 2000);
  for (int i = 0; i < 5; ++i) {  // iterations of the paused loop: none steps without a request
    const std::uint64_t seq = engine.Submit(cmd::Inspect{[](const mjModel*, const mjData*) {}, ""});
    ASSERT_TRUE(engine.WaitForCommand(seq, 5s).ok());
  }
  EXPECT_EQ(engine.step_count(), before + 2000);
  engine.Stop();
  EXPECT_DOUBLE_EQ(Qpos(engine, 0), 0.2);
  EXPECT_THROW(engine.Submit(cmd::Step{0}), Error);
}

TEST_F(CommandsTest, StepWindowThatFailsReportsTheError) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.SetCustomStepHandler([](const mjModel*, mjData* d) {
    if (d->time > 0.01) throw std::runtime_error("replay ran out");
    d->time += 0.002;
  });
  engine.SetPaused(true);
  engine.Start();
  const std::uint64_t seq = engine.Submit(cmd::Step{100});
  const CommandResult r = engine.WaitForCommand(seq, 5s);
  EXPECT_EQ(r.status, CommandStatus::kFailed);
  EXPECT_NE(r.error.find("replay ran out"), std::string::npos) << r.error;
  // While the error latch holds, a step request fails at once instead of waiting forever.
  const CommandResult latched = engine.WaitForCommand(engine.Submit(cmd::Step{1}), 5s);
  EXPECT_EQ(latched.status, CommandStatus::kFailed);
  EXPECT_NE(latched.error.find("unpause"), std::string::npos) << latched.error;
  engine.Stop();
  int errors = 0;
  for (const EngineEvent& e : engine.DrainEvents()) errors += e.kind == EngineEventKind::kError;
  EXPECT_EQ(errors, 1);
}

}  // namespace
}  // namespace urlab::physics
