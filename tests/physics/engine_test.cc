#include "urlab/physics/engine.h"

#include <gtest/gtest.h>
#include <poll.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "support/wait.h"
#include "urlab/core/clock.h"
#include "urlab/core/doorbell.h"

namespace urlab::physics {
namespace {

using namespace std::chrono_literals;
using testing::kArmXml;
using testing::kHumanoidPath;
using testing::kPendulumXml;

class EngineTest : public urlab::testing::MujocoTest {};

using testing::WaitFor;

double SimTime(PhysicsEngine& e) {
  double t = 0;
  e.WithLockedData([&](mjModel*, mjData* d) { t = d->time; });
  return t;
}

// Waits until the paused physics loop has run `n` more iterations: each applies a read-only
// command (an iteration's first work) and releases its waiter.
void RunPausedIterations(PhysicsEngine& engine, int n) {
  for (int i = 0; i < n; ++i) {
    const std::uint64_t seq = engine.Submit(cmd::Inspect{[](const mjModel*, const mjData*) {}, ""});
    ASSERT_TRUE(engine.WaitForCommand(seq, 5s).ok());
  }
}

TEST_F(EngineTest, StepSyncRunsTheIterationInOrder) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto frames = engine.SubscribeState("test");
  std::vector<std::string> order;
  engine.AddPreStepCallback([&](const mjModel*, mjData*) { order.push_back("pre"); });
  engine.SetApplyControlsHook([&](const mjModel*, mjData* d) {
    order.push_back("controls");
    d->ctrl[0] = 1.0;
  });
  engine.AddPostStepCallback([&](const mjModel*, mjData*) { order.push_back("post"); });
  engine.AddOnPostStep([&](const mjModel*, mjData*) { order.push_back("event"); });
  engine.StepSync(3);
  ASSERT_EQ(order.size(), 12u);
  EXPECT_EQ(order[0], "pre");
  EXPECT_EQ(order[1], "controls");
  EXPECT_EQ(order[2], "post");
  EXPECT_EQ(order[3], "event");
  EXPECT_EQ(engine.step_count(), 3u);
  EXPECT_NEAR(SimTime(engine), 3 * 0.002, 1e-12);
  const StateFrame* r = frames->Latest();
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->step, 3u);
  EXPECT_NEAR(r->time, 0.006, 1e-12);
  EXPECT_EQ(r->xpos.size(), 3u * static_cast<std::size_t>(engine.model()->nbody));
}

TEST_F(EngineTest, StepSyncRefusedWhileRunningUnpaused) {
  PhysicsEngine engine(CompileXmlString(kPendulumXml));
  engine.Start();
  EXPECT_THROW(engine.StepSync(1), Error);
  engine.SetPaused(true);
  const std::uint64_t before = engine.step_count();
  WaitFor([&] { return engine.step_count() == before; }, 20ms);  // let a running step finish
  const double t0 = SimTime(engine);
  engine.StepSync(5);
  EXPECT_NEAR(SimTime(engine) - t0, 5 * 0.002, 1e-9);
  engine.Stop();
}

TEST_F(EngineTest, PauseStopsSteppingButNotCallbacks) {
  PhysicsEngine engine(CompileXmlString(kPendulumXml));
  std::atomic<int> pre{0};
  engine.AddPreStepCallback([&](const mjModel*, mjData*) { pre++; });
  engine.SetPaused(true);
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return pre.load() > 20; }));
  EXPECT_EQ(engine.step_count(), 0u);
  EXPECT_EQ(SimTime(engine), 0.0);
  engine.TogglePause();
  EXPECT_FALSE(engine.paused());
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 20; }));
  engine.Submit(cmd::SetPaused{true});
  RunPausedIterations(engine, 1);  // the pause took effect before this iteration
  const std::uint64_t n = engine.step_count();
  RunPausedIterations(engine, 5);
  EXPECT_EQ(engine.step_count(), n);
  engine.Stop();
  EXPECT_FALSE(engine.running());
}

TEST_F(EngineTest, CustomStepHandlerReplacesMjStep) {
  PhysicsEngine engine(CompileXmlString(kPendulumXml));
  int calls = 0;
  engine.SetCustomStepHandler([&](const mjModel* m, mjData* d) {
    ++calls;
    d->qpos[0] = 0.1 * calls;  // a "replayed" trajectory
    d->time += m->opt.timestep;
    mj_forward(m, d);
  });
  engine.StepSync(10);
  EXPECT_EQ(calls, 10);
  engine.WithLockedData([](mjModel*, mjData* d) {
    EXPECT_DOUBLE_EQ(d->qpos[0], 1.0);
    EXPECT_EQ(d->qvel[0], 0.0);  // mj_step would have integrated gravity
  });
  engine.SetCustomStepHandler(nullptr);
  engine.StepSync(10);
  EXPECT_EQ(calls, 10);
  engine.WithLockedData([](mjModel*, mjData* d) { EXPECT_NE(d->qvel[0], 0.0); });
}

TEST_F(EngineTest, ResetEventIsDeliveredOnTheMainThread) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto main_id = std::this_thread::get_id();
  std::vector<EngineEvent> seen;
  engine.AddEventListener([&](const EngineEvent& e) {
    EXPECT_EQ(std::this_thread::get_id(), main_id);
    seen.push_back(e);
  });
  engine.SetAsFastAsPossible(true);
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 200; }));
  std::thread other([&] { engine.Reset(); });  // requested from a third thread
  other.join();
  ASSERT_TRUE(WaitFor([&] {
    engine.PollEvents();
    return !seen.empty();
  }));
  EXPECT_EQ(seen[0].kind, EngineEventKind::kReset);
  EXPECT_GT(seen[0].sim_time, 0.0);
  engine.Stop();
  // Keyframe reset while stopped is applied immediately.
  engine.ResetToKeyframe("arm_bent");
  engine.WithLockedData([](mjModel*, mjData* d) {
    EXPECT_DOUBLE_EQ(d->qpos[0], 0.8);
    EXPECT_DOUBLE_EQ(d->qpos[1], -1.2);
    EXPECT_EQ(d->time, 0.0);
  });
  engine.PollEvents();
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_NE(seen[1].message.find("'arm_bent'"), std::string::npos);
  EXPECT_THROW(engine.ResetToKeyframe("nope"), Error);
  EXPECT_THROW(engine.ResetToKeyframe(7), Error);
}

TEST_F(EngineTest, SnapshotRestoreDeterminismWithResetAndCallbacks) {
  PhysicsEngine engine(LoadXmlFile(kHumanoidPath));
  // Deterministic inputs that depend only on the simulated state, as a controller would.
  engine.SetApplyControlsHook([](const mjModel* m, mjData* d) {
    for (int u = 0; u < m->nu; ++u) d->ctrl[u] = 0.4 * std::sin(3 * d->time + u);
  });
  engine.AddPreStepCallback(
      [](const mjModel*, mjData* d) { d->xfrc_applied[6 + 2] = std::cos(d->time); });
  engine.StepSync(1000);
  const PhysicsState snap = engine.Snapshot();
  auto run = [&] {
    engine.StepSync(500);
    engine.Reset();
    engine.StepSync(500);
    return engine.Snapshot();
  };
  const PhysicsState a = run();
  engine.Restore(snap);
  const PhysicsState b = run();
  EXPECT_TRUE(a.BitwiseEquals(b));

  // The same through the running thread: restore is queued and applied by the physics thread.
  engine.SetAsFastAsPossible(true);
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 3000; }));
  engine.SetPaused(true);
  engine.Restore(snap);
  const PhysicsState c = run();
  engine.Stop();
  // The paused loop keeps running the hooks, which rewrite ctrl/xfrc_applied for the current time
  // after the last step; the integrated state must match bit for bit.
  PhysicsState c_inputs_as_a = c;
  c_inputs_as_a.ctrl = a.ctrl;
  c_inputs_as_a.xfrc_applied = a.xfrc_applied;
  EXPECT_TRUE(a.BitwiseEquals(c_inputs_as_a));
  EXPECT_THROW(engine.Restore(PhysicsState{}), StateError);
}

TEST_F(EngineTest, DivergenceFromNaNNamesJointAndArticulation) {
  ExpectWarning("QVEL");
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.SetArticulationResolver([](std::string_view name) {
    return name.starts_with("arm_") ? std::string("arm") : std::string();
  });
  const int elbow = mj_name2id(engine.model(), mjOBJ_JOINT, "arm_elbow");
  const int dof = engine.model()->jnt_dofadr[elbow];
  engine.AddPreStepCallback([dof](const mjModel*, mjData* d) {
    if (d->time > 0.1 && d->time < 0.103) d->qvel[dof] = std::numeric_limits<double>::quiet_NaN();
  });
  engine.StepSync(100);
  auto events = engine.DrainEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, EngineEventKind::kDivergence);
  EXPECT_EQ(events[0].joint_id, elbow);
  EXPECT_EQ(events[0].joint_name, "arm_elbow");
  EXPECT_EQ(events[0].articulation, "arm");
  EXPECT_FALSE(events[0].auto_reset);
  EXPECT_NE(events[0].message.find("qvel"), std::string::npos);
}

// A bad control (NaN from a controller) is watched like the other instability warnings and names
// the actuator and the joint it drives.
TEST_F(EngineTest, DivergenceFromBadControlNamesActuatorAndJoint) {
  ExpectWarning("CTRL");
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.SetArticulationResolver([](std::string_view) { return std::string("arm"); });
  engine.SetApplyControlsHook([](const mjModel*, mjData* d) {
    d->ctrl[0] = d->time > 0.05 ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  });
  engine.StepSync(100);
  auto events = engine.DrainEvents();
  ASSERT_EQ(events.size(), 1u);  // one report per episode, not one per bad step
  EXPECT_EQ(events[0].kind, EngineEventKind::kDivergence);
  EXPECT_NE(events[0].message.find("bad ctrl"), std::string::npos) << events[0].message;
  EXPECT_NE(events[0].message.find("arm_shoulder_motor"), std::string::npos);
  EXPECT_EQ(events[0].joint_name, "arm_shoulder");
  EXPECT_EQ(events[0].articulation, "arm");
}

TEST_F(EngineTest, DivergenceFromHugeTimestepWithAutoReset) {
  ExpectWarning("unstable");
  PhysicsEngine::Options options;
  options.reset_on_divergence = true;
  ModelPtr m = CompileXmlString(kArmXml);
  m->opt.timestep = 5.0;  // explodes within a few steps
  PhysicsEngine engine(std::move(m), options);
  engine.SetApplyControlsHook([](const mjModel*, mjData* d) { d->ctrl[0] = 50; });
  engine.StepSync(200);
  auto events = engine.DrainEvents();
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events[0].kind, EngineEventKind::kDivergence);
  EXPECT_TRUE(events[0].auto_reset);
  EXPECT_GE(events[0].joint_id, 0);
  EXPECT_EQ(events[1].kind, EngineEventKind::kReset);
}

TEST_F(EngineTest, NonFiniteStateFromCustomHandlerIsDetected) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  engine.SetCustomStepHandler([](const mjModel*, mjData* d) {
    d->qpos[1] = std::numeric_limits<double>::infinity();
    d->time += 0.002;
  });
  engine.StepSync(5);  // reported once per episode, not per step
  auto events = engine.DrainEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].joint_name, "arm_elbow");
}

TEST_F(EngineTest, MujocoErrorInLoopPausesAndIsReported) {
  PhysicsEngine engine(CompileXmlString(kPendulumXml));
  std::atomic<bool> fail{false};
  const auto id = engine.AddPreStepCallback([&](const mjModel*, mjData*) {
    if (fail.load()) mju_error("injected failure");
  });
  engine.SetAsFastAsPossible(true);
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 50; }));
  fail = true;
  ASSERT_TRUE(WaitFor([&] { return engine.paused(); }));
  RunPausedIterations(engine, 5);  // the latched loop must not re-run the failing callback
  auto events = engine.DrainEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events.back().kind, EngineEventKind::kError);
  EXPECT_NE(events.back().message.find("injected failure"), std::string::npos);
  EXPECT_TRUE(engine.running());  // the thread is alive, only paused
  // Recovers: remove the culprit, unpause, keep stepping.
  engine.SetPaused(true);
  engine.Stop();
  EXPECT_TRUE(engine.RemoveCallback(id));
  const std::uint64_t n = engine.step_count();
  engine.SetPaused(false);
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > n + 50; }));
  engine.Stop();
}

TEST_F(EngineTest, MujocoErrorFromEngineInternalsInStepSync) {
  // mju_error from inside mj_step (here from MuJoCo's control callback, which mj_step calls).
  ModelPtr m = LoadXmlFile(kHumanoidPath);
  PhysicsEngine engine(std::move(m));
  mjcb_control = [](const mjModel*, mjData*) { mju_error("engine internals failed"); };
  EXPECT_THROW(engine.StepSync(1), MujocoError);
  mjcb_control = nullptr;
  EXPECT_TRUE(engine.paused());
  auto events = engine.DrainEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, EngineEventKind::kError);
}

TEST_F(EngineTest, CallbacksCannotReenter) {
  PhysicsEngine engine(CompileXmlString(kPendulumXml));
  bool threw = false;
  engine.AddPreStepCallback([&](const mjModel*, mjData*) {
    if (threw) return;
    threw = true;
    engine.AddPreStepCallback([](const mjModel*, mjData*) {});
  });
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.paused(); }));
  engine.Stop();
  auto events = engine.DrainEvents();
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events[0].message.find("deadlock"), std::string::npos);
}

TEST_F(EngineTest, ResetFromInsideACallbackIsQueued) {
  PhysicsEngine engine(CompileXmlString(kPendulumXml));
  engine.AddPostStepCallback([&](const mjModel*, mjData* d) {
    if (d->time > 0.0099 && d->time < 0.0101) engine.Reset();
  });
  engine.StepSync(5);  // t = 0.010: reset queued
  engine.WithLockedData([](mjModel*, mjData* d) { EXPECT_NEAR(d->time, 0.010, 1e-12); });
  engine.StepSync(1);  // applied first, then one step
  engine.WithLockedData([](mjModel*, mjData* d) { EXPECT_NEAR(d->time, 0.002, 1e-12); });
  EXPECT_EQ(engine.DrainEvents().size(), 1u);
}

// Pacing on the injected clock: one step per period of the clock, none in between; half speed
// doubles the period; a short lag is caught up, a long one restarts the schedule. The real-time
// factor and step rate are measured on the same clock. Exact, whatever the machine's load.
TEST_F(EngineTest, PacingFollowsSpeedOnTheInjectedClock) {
  ManualClock clock;
  PhysicsEngine::Options o;
  o.clock = &clock;
  o.measure_window = 0.1;
  PhysicsEngine engine(CompileXmlString(kPendulumXml), o);  // 2 ms steps
  engine.Start();
  ASSERT_TRUE(clock.WaitForSleeper());
  EXPECT_EQ(engine.step_count(), 1u);  // the first iteration steps at once, then waits
  for (int ms = 1; ms <= 200; ++ms) {
    clock.Advance(1ms);
    ASSERT_TRUE(clock.WaitForSleeper());
    ASSERT_EQ(engine.step_count(), 1u + static_cast<std::uint64_t>(ms / 2)) << "at " << ms << " ms";
  }
  EXPECT_NEAR(SimTime(engine), 101 * 0.002, 1e-12);
  // Two measurement windows of 0.1 s passed; the last one held exactly 50 steps of 2 ms.
  EXPECT_NEAR(engine.real_time_factor(), 1.0, 1e-9);
  EXPECT_NEAR(engine.step_rate(), 500.0, 1e-6);

  engine.SetSpeedPercent(50);  // the current deadline stands; the next ones are 4 ms apart
  clock.Advance(2ms);
  ASSERT_TRUE(clock.WaitForSleeper());
  const std::uint64_t half_start = engine.step_count();
  for (int i = 0; i < 100; ++i) {
    clock.Advance(2ms);
    ASSERT_TRUE(clock.WaitForSleeper());
  }
  EXPECT_EQ(engine.step_count() - half_start, 50u);  // 200 ms at half speed: 50 steps
  EXPECT_NEAR(engine.real_time_factor(), 0.5, 1e-9);
  EXPECT_NEAR(engine.step_rate(), 250.0, 1e-6);

  engine.SetSpeedPercent(100);
  clock.Advance(4ms);  // the pending 4 ms deadline
  ASSERT_TRUE(clock.WaitForSleeper());
  std::uint64_t before = engine.step_count();
  clock.Advance(10ms);  // behind by 5 periods, within the resync threshold: caught up
  ASSERT_TRUE(clock.WaitForSleeper());
  EXPECT_EQ(engine.step_count() - before, 5u);
  before = engine.step_count();
  clock.Advance(1s);  // far behind: one step for the deadline, one at the restarted schedule
  ASSERT_TRUE(clock.WaitForSleeper());
  EXPECT_EQ(engine.step_count() - before, 2u);

  engine.SetSpeedPercent(1);
  EXPECT_EQ(engine.speed_percent(), 5);
  engine.Stop();
}

// A paused engine takes no step however far its clock moves; commands still apply.
TEST_F(EngineTest, PausedEngineTakesNoStepWhateverTheClockDoes) {
  ManualClock clock;
  PhysicsEngine::Options o;
  o.clock = &clock;
  PhysicsEngine engine(CompileXmlString(kPendulumXml), o);
  engine.SetPaused(true);
  engine.Start();
  RunPausedIterations(engine, 3);
  clock.Advance(10s);
  RunPausedIterations(engine, 3);
  EXPECT_EQ(engine.step_count(), 0u);
  EXPECT_EQ(engine.real_time_factor(), 0.0);
  engine.Stop();
}

TEST_F(EngineTest, StateFrameReadableWhileRunning) {
  PhysicsEngine engine(LoadXmlFile(kHumanoidPath));
  engine.SetAsFastAsPossible(true);
  const auto frames = engine.SubscribeState("render");
  std::atomic<bool> done{false};
  std::atomic<int> reads{0};
  std::atomic<bool> ok{true};
  std::thread render([&] {
    double last = -1;
    std::uint64_t last_step = 0;
    while (!done.load()) {
      const StateFrame* s = frames->Latest();
      if (!s) continue;
      if (s->step < last_step) ok = false;
      if (s->step > last_step && s->time <= last && s->time != 0) ok = false;
      for (double v : s->xquat) ok = ok && std::isfinite(v);
      last = s->time;
      last_step = s->step;
      reads++;
    }
  });
  engine.Start();
  ASSERT_TRUE(WaitFor([&] { return engine.step_count() > 2000 && reads.load() > 100; }));
  done = true;
  render.join();
  engine.Stop();
  EXPECT_TRUE(ok.load());
}

// Another thread storms the running loop with every cross-thread command (run under TSan).
TEST_F(EngineTest, StressCommandsFromOtherThreads) {
  PhysicsEngine engine(CompileXmlString(kArmXml));
  const auto frames = engine.SubscribeState("render");
  std::atomic<double> control{0};
  engine.SetApplyControlsHook([&](const mjModel*, mjData* d) { d->ctrl[0] = control.load(); });
  engine.AddPostStepCallback([](const mjModel*, mjData* d) { d->userdata[0] += 1; });
  engine.SetAsFastAsPossible(true);
  engine.Start();
  const PhysicsState snap = engine.Snapshot();
  std::atomic<bool> done{false};
  std::atomic<bool> storm_done{false};
  std::thread storm([&] {
    for (int i = 0; i < 4000;) {
      switch (i++ % 7) {
        case 0:
          engine.Reset();
          break;
        case 1:
          engine.Restore(snap);
          break;
        case 2:
          engine.TogglePause();
          break;
        case 3:
          control.store(std::sin(i));
          break;
        case 4:
          (void)engine.Snapshot();
          break;
        case 5:
          engine.ResetToKeyframe(i % 2);
          break;
        case 6:
          engine.SetSpeedPercent(5 + i % 96);
          try {
            engine.StepSync(1);
          } catch (const Error&) {
          }
          break;
      }
      (void)engine.real_time_factor();
    }
    storm_done = true;
  });
  std::thread render([&] {
    while (!done.load()) (void)frames->Latest();
  });
  int events = 0;
  while (!storm_done.load()) events += engine.PollEvents();
  done = true;
  storm.join();
  render.join();
  engine.Stop();
  events += engine.PollEvents();
  EXPECT_GT(events, 0);
  engine.SetPaused(false);
  engine.StepSync(10);  // still healthy
}

// Running as fast as possible, rings are coalesced, but a consumer that sleeps until the doorbell
// still sees every frame promptly, and the last frame before a pause always rings.
TEST_F(EngineTest, DoorbellWakesTheConsumerForEveryFrameEvenWhenCoalesced) {
  PhysicsEngine::Options o;
  o.as_fast_as_possible = true;
  PhysicsEngine engine(CompileXmlString(kArmXml), o);
  const auto ring = engine.SubscribeEveryStep("test", 1 << 16);
  const auto bell = std::make_shared<Doorbell>();
  engine.AddDoorbell(bell);
  engine.Start();
  StateFrame f = StateFrame::SizedFor(engine.model());
  std::uint64_t taken = 0, last_step = 0;
  int wakes = 0;
  const auto sleep_until_rung = [&] {
    bell->Arm();
    if (ring->size() > 0) {
      bell->Clear();
      return true;
    }
    pollfd p{bell->fd(), POLLIN, 0};
    const bool rung = poll(&p, 1, 2000) == 1;
    bell->Clear();
    ++wakes;
    return rung;
  };
  while (taken < 2000) {
    ASSERT_TRUE(sleep_until_rung()) << "no ring for 2 s with frames flowing";
    while (ring->TryPop(&f)) {
      ++taken;
      last_step = f.step;
    }
  }
  engine.Submit(cmd::SetPaused{true});
  // After the pause: the consumer is woken until it holds the paused frame.
  while (!f.paused) {
    ASSERT_TRUE(sleep_until_rung()) << "the paused frame never rang";
    while (ring->TryPop(&f)) last_step = f.step;
  }
  EXPECT_EQ(last_step, engine.step_count());
  EXPECT_EQ(ring->dropped(), 0u);
  engine.Stop();
}

}  // namespace
}  // namespace urlab::physics
