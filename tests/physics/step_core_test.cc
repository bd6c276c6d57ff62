// The step core: one iteration without a thread or a clock. The engine's loop, StepSync, its
// lockstep windows and the replay's re-simulation advance it; here it is driven directly.
#include "urlab/physics/step_core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/engine.h"

namespace urlab::physics {
namespace {

using namespace std::chrono_literals;
using testing::kArmXml;
using testing::kHumanoidPath;

class StepCoreTest : public urlab::testing::MujocoTest {};

void Controls(const mjModel* m, mjData* d) {
  for (int u = 0; u < m->nu; ++u) d->ctrl[u] = 0.4 * std::sin(3 * d->time + u);
}

// The engine's StepSync and a bare core advance the same function: the same inputs give the
// same trajectory bit for bit, one-shot forces and a mid-run reset included.
TEST_F(StepCoreTest, AdvancesExactlyAsTheEngineSteps) {
  PhysicsEngine engine(LoadXmlFile(kHumanoidPath));
  StepCore core(LoadXmlFile(kHumanoidPath));
  engine.SetApplyControlsHook(Controls);
  core.SetApplyControlsHook(Controls);
  const auto drive = [](auto submit, auto step) {
    step(200);
    submit(Command(cmd::ApplyForce{1, {0, 0, 40}, {0, 0, 0}, 5}));
    step(200);
    submit(Command(cmd::Reset{}));
    step(100);
  };
  drive([&](Command c) { engine.Submit(std::move(c)); }, [&](int n) { engine.StepSync(n); });
  drive(
      [&](Command c) {
        core.Validate(c);
        core.commands().Push(std::move(c));
      },
      [&](int n) {
        for (int i = 0; i < n; ++i) core.Advance({.force_step = true});
      });
  EXPECT_EQ(core.step_count(), engine.step_count());
  EXPECT_TRUE(engine.Snapshot().BitwiseEquals(CaptureState(core.model(), core.data())));
}

// Queued commands are applied at the top of the next iteration, in order, and their waiters are
// released once the frame that shows them is published; a step window runs its n iterations even
// while paused and holds back the commands behind it.
TEST_F(StepCoreTest, AppliesCommandsAndStepWindowsWithoutAThread) {
  StepCore core(CompileXmlString(kArmXml));
  const auto frames = core.publisher().SubscribeLatest("test");
  int controls = 0;
  core.SetApplyControlsHook([&](const mjModel*, mjData*) { ++controls; });
  core.SetPaused(true);
  const std::uint64_t a = core.commands().Push(cmd::SetQpos{0, {0.3}});
  const std::uint64_t window = core.commands().Push(cmd::Step{3});
  const std::uint64_t behind = core.commands().Push(cmd::SetQpos{0, {0.1}});
  StepCore::Iteration it = core.Advance();
  EXPECT_TRUE(it.stepped);  // the window's first iteration
  EXPECT_EQ(core.commands().last_applied(), a);
  EXPECT_EQ(controls, 1);
  core.Advance();
  it = core.Advance();
  EXPECT_TRUE(it.window_ended);
  EXPECT_TRUE(it.urgent);
  EXPECT_EQ(core.commands().last_applied(), window);
  EXPECT_EQ(core.step_count(), 3u);
  EXPECT_EQ(frames->Latest()->command_seq, window);
  it = core.Advance();  // paused: the command behind the window, no step
  EXPECT_FALSE(it.stepped);
  EXPECT_TRUE(it.published);
  EXPECT_EQ(core.commands().last_applied(), behind);
  EXPECT_EQ(core.data()->qpos[0], 0.1);
  EXPECT_EQ(core.step_count(), 3u);
  EXPECT_EQ(controls, 3);
  EXPECT_FALSE(core.Advance().published);  // nothing to show
}

// After a failure the latch holds while paused: commands still apply, hooks stay quiet and a step
// window fails at once; unpausing clears it.
TEST_F(StepCoreTest, ErrorLatchKeepsHooksQuietUntilUnpaused) {
  StepCore core(CompileXmlString(kArmXml));
  std::vector<EngineEvent> events;
  core.SetEventSink([&](EngineEvent e) { events.push_back(std::move(e)); });
  int pre = 0;
  core.AddHook(StepCore::HookKind::kPreStep, [&](const mjModel*, mjData*) { ++pre; });
  core.Fail(Error("injected"));
  EXPECT_TRUE(core.paused());
  EXPECT_TRUE(core.error_latched());
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, EngineEventKind::kError);
  const std::uint64_t set = core.commands().Push(cmd::SetQpos{0, {0.2}});
  const std::uint64_t step = core.commands().Push(cmd::Step{2});
  core.Advance();
  EXPECT_EQ(pre, 0);
  EXPECT_EQ(core.data()->qpos[0], 0.2);
  EXPECT_EQ(core.commands().Wait(set, 0s).status, CommandStatus::kApplied);
  const CommandResult r = core.commands().Wait(step, 0s);
  EXPECT_EQ(r.status, CommandStatus::kFailed);
  EXPECT_NE(r.error.find("unpause"), std::string::npos) << r.error;
  core.SetPaused(false);
  EXPECT_FALSE(core.error_latched());
  EXPECT_TRUE(core.Advance().stepped);
  EXPECT_EQ(pre, 1);
}

// Each command kind is declared once (command_kinds.cc): every alternative of Command has its own
// name, and validation refuses what cannot apply before anything is queued.
TEST_F(StepCoreTest, EveryCommandKindHasOneNameAndItsValidation) {
  std::set<std::string> names;
  const auto name_of = [&]<std::size_t... I>(std::index_sequence<I...>) {
    (names.insert(CommandName(Command(std::in_place_index<I>))), ...);
  };
  name_of(std::make_index_sequence<std::variant_size_v<Command>>());
  EXPECT_EQ(names.size(), std::variant_size_v<Command>);
  EXPECT_EQ(names.count(""), 0u);
  StepCore core(CompileXmlString(kArmXml));
  EXPECT_THROW(core.Validate(cmd::SetQvel{static_cast<int>(core.model()->nv), {1.0}}), Error);
  EXPECT_THROW(core.Validate(cmd::ResetKeyframe{99}), Error);
  EXPECT_THROW(core.Validate(cmd::Step{0}), Error);
  EXPECT_THROW(core.Validate(cmd::Inspect{}), Error);
  EXPECT_NO_THROW(core.Validate(cmd::Forward{}));
  EXPECT_FALSE(core.commands().pending());
}

}  // namespace
}  // namespace urlab::physics
