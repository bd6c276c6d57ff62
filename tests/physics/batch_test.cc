// Batched environments: N copies of one model stepped through the step core by K threads. The
// same actions and seeds give the same trajectory bit for bit, in every environment and in a
// single engine; the thread count never changes a bit; seeds drive the reset noise.
#include "urlab/physics/batch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/engine.h"

namespace urlab::physics {
namespace {

using testing::kArmXml;
using testing::kHumanoidPath;

class BatchTest : public urlab::testing::MujocoTest {};

// Deterministic actions: a function of the step, the environment and the actuator.
double Action(int step, int env, int u, bool per_env) {
  return 0.4 * std::sin(0.05 * step + u + (per_env ? 0.7 * env : 0.0));
}

std::vector<double> Actions(const Batch& b, int step, bool per_env) {
  std::vector<double> a(static_cast<std::size_t>(b.envs() * b.action_size()));
  for (int i = 0; i < b.envs(); ++i) {
    for (int u = 0; u < b.action_size(); ++u) {
      a[static_cast<std::size_t>(i * b.action_size() + u)] = Action(step, i, u, per_env);
    }
  }
  return a;
}

bool SameBits(const double* a, const double* b, std::size_t n) {
  return std::memcmp(a, b, n * sizeof(double)) == 0;
}

TEST_F(BatchTest, SameActionsGiveEveryEnvironmentTheSingleEngineTrajectory) {
  const Model model(LoadXmlFile(kHumanoidPath));
  BatchOptions o;
  o.envs = 5;
  o.threads = 2;
  Batch batch(model, o);
  PhysicsEngine engine(model.Copy());
  int step = 0;
  engine.SetApplyControlsHook([&](const mjModel* m, mjData* d) {
    for (int u = 0; u < m->nu; ++u) d->ctrl[u] = Action(step, 0, u, false);
  });
  const std::size_t row = static_cast<std::size_t>(batch.observation_size());
  std::vector<double> obs(row * 5);
  std::vector<std::uint8_t> done(5, 9);
  for (step = 0; step < 300; ++step) {
    batch.Step(Actions(batch, step, false), obs, done);
    engine.StepSync(1);
  }
  EXPECT_EQ(done, std::vector<std::uint8_t>(5, 0));
  std::vector<double> expected(row);
  engine.WithLockedData([&](mjModel* m, mjData* d) {
    mju_copy(expected.data(), d->qpos, m->nq);
    mju_copy(expected.data() + m->nq, d->qvel, m->nv);
    mju_copy(expected.data() + m->nq + m->nv, d->sensordata, m->nsensordata);
  });
  for (int i = 0; i < 5; ++i) {
    EXPECT_TRUE(SameBits(obs.data() + row * static_cast<std::size_t>(i), expected.data(), row))
        << "environment " << i;
    EXPECT_EQ(batch.env(i).data()->time, engine.Snapshot().time);
    EXPECT_EQ(batch.episode_steps(i), 300u);
  }
}

TEST_F(BatchTest, TheThreadCountChangesNoBit) {
  const Model model(LoadXmlFile(kHumanoidPath));
  std::vector<std::vector<double>> results;
  for (int threads : {1, 2, 3}) {
    BatchOptions o;
    o.envs = 7;
    o.threads = threads;
    o.reset_noise = 0.01;
    o.seed = 42;
    Batch batch(model, o);
    EXPECT_EQ(batch.threads(), threads);
    std::vector<double> obs(static_cast<std::size_t>(7 * batch.observation_size()));
    for (int step = 0; step < 200; ++step) batch.Step(Actions(batch, step, true), obs);
    results.push_back(obs);
  }
  EXPECT_TRUE(SameBits(results[0].data(), results[1].data(), results[0].size()));
  EXPECT_TRUE(SameBits(results[0].data(), results[2].data(), results[0].size()));
}

TEST_F(BatchTest, AStepInTwoHalvesIsTheSameStepAndOverlapsTheCallersWork) {
  // StepBegin starts the workers, the caller works on something of its own (an engine's own
  // simulation), StepEnd finishes: the same bits as Step, whatever the caller did meanwhile.
  const Model model(LoadXmlFile(kHumanoidPath));
  BatchOptions o;
  o.envs = 6;
  o.threads = 2;
  o.reset_noise = 0.01;
  o.seed = 7;
  Batch whole(model, o), halves(model, o);
  const DataPtr own = MakeData(model.get());
  const std::size_t row = static_cast<std::size_t>(whole.observation_size());
  std::vector<double> a(row * 6), b(row * 6);
  std::vector<std::uint8_t> done_a(6), done_b(6);
  for (int step = 0; step < 100; ++step) {
    const std::vector<double> actions = Actions(whole, step, true);
    whole.Step(actions, a, done_a);
    halves.StepBegin(actions, b, done_b);
    mj_step(model.get(), own.get());  // the caller's own work
    halves.StepEnd();
  }
  EXPECT_TRUE(SameBits(a.data(), b.data(), a.size()));
  EXPECT_EQ(done_a, done_b);
  // A step begun and never ended is finished by the next one (or Settle).
  const std::vector<double> first = Actions(halves, 100, true), second = Actions(halves, 101, true);
  halves.StepBegin(first, b, done_b);
  halves.Step(second, b, done_b);
  whole.Step(first, a, done_a);
  whole.Step(second, a, done_a);
  EXPECT_TRUE(SameBits(a.data(), b.data(), a.size()));
  halves.StepBegin(first, b, done_b);
  halves.Settle();
}

TEST_F(BatchTest, IterationsInOneCallAreThatManyCallsOfOne) {
  // A frame skip in one call (each environment's iterations back to back on one thread) gives
  // the bits of that many calls of one iteration: observations, done flags (any iteration's
  // end), auto-resets mid-call (an episode limit of 7 against 5 iterations a call) and skipped
  // environments included.
  const Model model(LoadXmlFile(kHumanoidPath));
  BatchOptions o;
  o.envs = 6;
  o.threads = 2;
  o.reset_noise = 0.01;
  o.seed = 3;
  o.auto_reset = true;
  o.max_episode_steps = 7;
  Batch one(model, o), many(model, o);
  const std::size_t row = static_cast<std::size_t>(one.observation_size());
  std::vector<double> a(row * 6), b(row * 6);
  std::vector<std::uint8_t> done_a(6), done_b(6), any(6);
  std::vector<std::uint8_t> skip(6, 0);
  for (int step = 0; step < 40; ++step) {
    const std::vector<double> actions = Actions(one, step, true);
    skip[static_cast<std::size_t>(step % 6)] = step % 4 == 0;  // now and then one sits out
    std::fill(any.begin(), any.end(), 0);
    for (int k = 0; k < 5; ++k) {
      one.Step(actions, a, done_a, skip);
      for (std::size_t i = 0; i < 6; ++i) any[i] |= done_a[i];
    }
    many.Step(actions, b, done_b, skip, 5);
    ASSERT_TRUE(SameBits(a.data(), b.data(), a.size())) << "step " << step;
    ASSERT_EQ(any, done_b) << "step " << step;
    skip[static_cast<std::size_t>(step % 6)] = 0;
  }
  for (int i = 0; i < 6; ++i) EXPECT_EQ(one.episode_steps(i), many.episode_steps(i));
  EXPECT_THROW(many.Step(Actions(many, 0, true), b, done_b, {}, 0), Error);
}

TEST_F(BatchTest, SeedsDriveTheResetNoise) {
  const Model model(LoadXmlFile(kHumanoidPath));
  BatchOptions o;
  o.envs = 3;
  o.threads = 2;
  o.reset_noise = 0.01;
  Batch batch(model, o);
  batch.Reset(0, 7);
  batch.Reset(1, 7);
  batch.Reset(2, 8);
  const std::size_t row = static_cast<std::size_t>(batch.observation_size());
  std::vector<double> obs(row * 3);
  for (int step = 0; step < 100; ++step) batch.Step(Actions(batch, step, false), obs);
  EXPECT_TRUE(SameBits(obs.data(), obs.data() + row, row));       // same seed: same bits
  EXPECT_FALSE(SameBits(obs.data(), obs.data() + 2 * row, row));  // another seed: another run
  // The noise moved the start away from the default state, and a reset without a seed goes on
  // with the generator (another draw).
  std::vector<double> first(row * 3), second(row * 3);
  batch.Reset(0, 7);
  batch.Observe(first);
  batch.Reset(0);
  batch.Observe(second);
  EXPECT_FALSE(SameBits(first.data(), second.data(), row));
  EXPECT_NE(first[0], model->qpos0[0]);
}

// A custom reset state (a running scene's initial state) comes before the noise; skipped
// environments are not stepped (their actions ignored, done 0); ResetBatchState gives an
// environment outside the batch the same start for the same seed.
TEST_F(BatchTest, CustomResetStateSkipMaskAndResetBatchState) {
  BatchOptions o;
  o.envs = 2;
  o.threads = 2;
  o.reset_noise = 0.01;
  o.reset_state = [](const mjModel* m, mjData* d) {
    mj_resetData(m, d);
    d->qpos[0] = 0.3;
  };
  const Model model(CompileXmlString(kArmXml));
  Batch batch(model, o);
  const std::size_t row = static_cast<std::size_t>(batch.observation_size());
  std::vector<double> start(row * 2), obs(row * 2);
  batch.Reset(0, 5);
  batch.Reset(1, 6);
  batch.Observe(start);
  EXPECT_NEAR(start[0], 0.3, 0.01);
  EXPECT_NE(start[0], 0.3);  // the noise came after the custom state
  // An mjData outside the batch reset with the same seed starts with the same bits.
  DataPtr d = MakeData(model.get());
  std::mt19937_64 rng(5);
  ResetBatchState(o, rng, model.get(), d.get());
  mj_forward(model.get(), d.get());
  EXPECT_EQ(d->qpos[0], start[0]);
  // Environment 1 skipped: unchanged, not done; environment 0 stepped.
  std::vector<std::uint8_t> done(2, 9);
  const std::vector<std::uint8_t> skip = {0, 1};
  const std::vector<double> actions(static_cast<std::size_t>(2 * batch.action_size()), 0.5);
  batch.Step(actions, obs, done, skip);
  EXPECT_TRUE(SameBits(obs.data() + row, start.data() + row, row));
  EXPECT_FALSE(SameBits(obs.data(), start.data(), row));
  EXPECT_EQ(done, (std::vector<std::uint8_t>{0, 0}));
  EXPECT_EQ(batch.episode_steps(0), 1u);
  EXPECT_EQ(batch.episode_steps(1), 0u);
  const std::vector<std::uint8_t> bad(3, 0);
  EXPECT_THROW(batch.Step(actions, obs, done, bad), Error);
}

// A law that doubles the actions and counts its calls (per environment, from its own thread).
class DoublingLaw : public ControlLaw {
 public:
  void Apply(const mjModel* m, mjData* d) override {
    for (int u = 0; u < m->nu; ++u) d->ctrl[u] *= 2;
    ++applied;
  }
  void Restart() override { ++restarted; }
  int applied = 0, restarted = 0;
};

TEST_F(BatchTest, AControlLawTurnsEachEnvironmentsActionsIntoItsControls) {
  const Model model(CompileXmlString(kArmXml));
  std::vector<DoublingLaw*> laws;
  BatchOptions o;
  o.envs = 3;
  o.threads = 2;
  o.max_episode_steps = 7;
  o.auto_reset = true;
  o.control = [&](int) {
    auto law = std::make_unique<DoublingLaw>();
    laws.push_back(law.get());
    return law;
  };
  Batch with_law(model, o);
  ASSERT_EQ(laws.size(), 3u);
  for (DoublingLaw* law : laws) EXPECT_EQ(law->restarted, 1);  // the first reset
  BatchOptions plain = o;
  plain.control = nullptr;
  Batch without(model, plain);
  const std::size_t row = static_cast<std::size_t>(with_law.observation_size());
  std::vector<double> a(row * 3), b(row * 3);
  for (int step = 0; step < 10; ++step) {
    std::vector<double> actions = Actions(with_law, step, true), doubled = actions;
    for (double& x : doubled) x *= 2;
    with_law.Step(actions, a, {}, {}, 2);
    without.Step(doubled, b, {}, {}, 2);
    ASSERT_TRUE(SameBits(a.data(), b.data(), row * 3)) << "step " << step;
  }
  for (DoublingLaw* law : laws) {
    EXPECT_EQ(law->applied, 20);   // before every physics step
    EXPECT_EQ(law->restarted, 3);  // and again at each auto-reset (steps 7 and 14)
  }
  with_law.Reset(1, 5);
  EXPECT_EQ(laws[1]->restarted, 4);
}

TEST_F(BatchTest, AutoResetStartsANewEpisodeAtTheStepLimit) {
  BatchOptions o;
  o.envs = 2;
  o.threads = 2;
  o.max_episode_steps = 10;
  o.auto_reset = true;
  o.keyframe = 1;  // arm_bent
  Batch batch(Model(CompileXmlString(kArmXml)), o);
  const std::size_t row = static_cast<std::size_t>(batch.observation_size());
  std::vector<double> start(row * 2), obs(row * 2);
  batch.Observe(start);
  EXPECT_EQ(start[0], 0.8);  // the keyframe's shoulder angle
  std::vector<std::uint8_t> done(2);
  const std::vector<double> actions(static_cast<std::size_t>(2 * batch.action_size()), 0.5);
  for (int step = 1; step <= 10; ++step) {
    batch.Step(actions, obs, done);
    EXPECT_EQ(done[0], step == 10 ? 1 : 0) << step;
  }
  EXPECT_EQ(batch.episode_steps(0), 0u);
  EXPECT_TRUE(SameBits(obs.data(), start.data(), row * 2));  // the new episode's first state
}

TEST_F(BatchTest, DivergedEnvironmentEndsItsEpisodeAlone) {
  ExpectWarning("CTRL");
  BatchOptions o;
  o.envs = 3;
  o.threads = 2;
  o.auto_reset = true;
  Batch batch(Model(CompileXmlString(kArmXml)), o);
  std::vector<double> actions(static_cast<std::size_t>(3 * batch.action_size()), 0.1);
  std::vector<std::uint8_t> done(3);
  batch.Step(actions, {}, done);
  actions[static_cast<std::size_t>(batch.action_size())] = std::nan("");  // environment 1
  batch.Step(actions, {}, done);
  EXPECT_EQ(done, (std::vector<std::uint8_t>{0, 1, 0}));
  EXPECT_EQ(batch.episode_steps(0), 2u);
  EXPECT_EQ(batch.episode_steps(1), 0u);  // reset
}

TEST_F(BatchTest, BadArgumentsAreRefusedBeforeAnythingSteps) {
  const Model model(CompileXmlString(kArmXml));
  EXPECT_THROW(Batch(model, BatchOptions{.envs = 0}), Error);
  EXPECT_THROW(Batch(model, BatchOptions{.envs = 1, .threads = -1}), Error);
  EXPECT_THROW(Batch(model, BatchOptions{.envs = 1, .keyframe = 5}), Error);
  Batch batch(model, BatchOptions{.envs = 2, .threads = 1});
  std::vector<double> actions(static_cast<std::size_t>(2 * batch.action_size()));
  std::vector<double> obs(static_cast<std::size_t>(2 * batch.observation_size()));
  try {
    batch.Step(std::span<const double>(actions).first(3), obs);
    FAIL() << "short actions accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("expected " + std::to_string(actions.size())),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(batch.Step(actions, std::span<double>(obs).first(1)), Error);
  EXPECT_EQ(batch.episode_steps(0), 0u);
  EXPECT_THROW(batch.Reset(2), Error);
}

}  // namespace
}  // namespace urlab::physics
