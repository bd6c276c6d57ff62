// InProcessBatch and its C interface: a batch of the humanoid scene inside the test's process,
// with real MuJoCo and the batch's real stepping threads.
#include "urlab/embed/in_process_batch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/embed/urlab_batch.h"

namespace urlab::embed {
namespace {

using ::testing::HasSubstr;

std::string Humanoid() { return urlab::testing::SourcePath("examples/scenes/humanoid_pd.yaml"); }

// `steps` sets of actions for `envs` environments, uniform within each actuator's range.
std::vector<std::vector<double>> Actions(const InProcessBatch& b, int steps, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::vector<double>> out;
  for (int s = 0; s < steps; ++s) {
    std::vector<double> a;
    for (int e = 0; e < b.envs(); ++e) {
      for (int i = 0; i < b.action_size(); ++i) {
        std::uniform_real_distribution<double> u(b.action_low()[i], b.action_high()[i]);
        a.push_back(u(rng));
      }
    }
    out.push_back(std::move(a));
  }
  return out;
}

// The observation rows after each step of `actions` from a reset with `seed`.
std::vector<std::vector<double>> Episodes(const InProcessOptions& o, std::uint64_t seed,
                                          int steps) {
  InProcessBatch b(Humanoid(), o);
  std::vector<std::optional<std::uint64_t>> seeds;
  for (int e = 0; e < o.envs; ++e) seeds.push_back(seed + static_cast<std::uint64_t>(e));
  b.Reset({}, seeds);
  std::vector<std::vector<double>> rows;
  for (const std::vector<double>& a : Actions(b, steps, 3)) rows.push_back(b.Step(a).obs);
  return rows;
}

class InProcessBatchTest : public urlab::testing::MujocoTest {};

TEST_F(InProcessBatchTest, SizesAndBoundsAreTheScenesModel) {
  InProcessBatch b(Humanoid(), {.envs = 3, .threads = 2});
  EXPECT_EQ(b.envs(), 3);
  EXPECT_EQ(b.threads(), 2);
  EXPECT_EQ(b.action_size(), 21);
  EXPECT_EQ(b.nq(), 28);
  EXPECT_EQ(b.nv(), 27);
  EXPECT_EQ(b.observation_size(), b.nq() + b.nv() + b.nsensordata());
  ASSERT_EQ(b.action_low().size(), 21u);
  for (int i = 0; i < 21; ++i) EXPECT_LT(b.action_low()[i], b.action_high()[i]);
  EXPECT_THAT(b.actuator_names().front(), HasSubstr("abdomen"));
  EXPECT_DOUBLE_EQ(b.timestep(), 0.005);
  const world::BatchResult& r = b.Step(std::vector<double>(3 * 21, 0.0));
  EXPECT_EQ(r.obs.size(), 3u * static_cast<std::size_t>(b.observation_size()));
  EXPECT_THAT(r.episode_steps, ::testing::ElementsAre(1u, 1u, 1u));
  for (double t : r.time) EXPECT_DOUBLE_EQ(t, 0.005);
}

TEST_F(InProcessBatchTest, SameSeedsSameEpisodesWhicheverTheThreads) {
  const InProcessOptions one{.envs = 4, .threads = 1, .reset_noise = 0.05};
  InProcessOptions two = one;
  two.threads = 2;
  const auto a = Episodes(one, 11, 30);
  const auto b = Episodes(two, 11, 30);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t s = 0; s < a.size(); ++s) {
    ASSERT_EQ(std::memcmp(a[s].data(), b[s].data(), a[s].size() * sizeof(double)), 0)
        << "step " << s;
  }
  // Another seed gives another episode (the noise is drawn from it).
  const auto c = Episodes(one, 12, 1);
  EXPECT_NE(std::memcmp(a[0].data(), c[0].data(), a[0].size() * sizeof(double)), 0);
}

TEST_F(InProcessBatchTest, AnEnvironmentRunsItsSeedsEpisodeWhateverItsIndex) {
  // Environment 2 of 3 (in the batch) and environment 0 of 1 (the engine's own), both reset
  // with seed 40 and given the same actions, step through the same states.
  const int steps = 20;
  std::vector<std::vector<double>> three, single;
  std::vector<double> row_actions;
  {
    InProcessBatch b(Humanoid(), {.envs = 3, .threads = 2, .reset_noise = 0.05});
    const std::vector<std::optional<std::uint64_t>> seeds = {1, 2, 40};
    b.Reset({}, seeds);
    const auto actions = Actions(b, steps, 5);
    const std::size_t row = static_cast<std::size_t>(b.observation_size());
    for (const auto& a : actions) {
      const auto& obs = b.Step(a).obs;
      three.emplace_back(obs.begin() + static_cast<std::ptrdiff_t>(2 * row), obs.end());
      row_actions.insert(row_actions.end(), a.begin() + 2 * 21, a.end());
    }
  }
  {
    InProcessBatch b(Humanoid(), {.envs = 1, .threads = 1, .reset_noise = 0.05});
    const std::vector<int> envs = {0};
    const std::vector<std::optional<std::uint64_t>> seeds = {40};
    b.Reset(envs, seeds);
    for (int s = 0; s < steps; ++s) {
      const std::span<const double> a(row_actions.data() + s * 21, 21);
      single.push_back(b.Step(a).obs);
    }
  }
  for (int s = 0; s < steps; ++s) {
    ASSERT_EQ(three[s], single[s]) << "step " << s;
  }
}

TEST_F(InProcessBatchTest, EpisodesEndAndResetAtTheNextStep) {
  InProcessBatch b(Humanoid(), {.envs = 2, .threads = 2, .max_episode_steps = 3});
  const std::vector<double> zero(2 * 21, 0.0);
  for (int s = 1; s <= 2; ++s) {
    EXPECT_THAT(b.Step(zero).done, ::testing::ElementsAre(0, 0)) << s;
  }
  const world::BatchResult& third = b.Step(zero);
  EXPECT_THAT(third.done, ::testing::ElementsAre(1, 1));
  EXPECT_THAT(third.episode_steps, ::testing::ElementsAre(3u, 3u));
  // Gymnasium's next-step autoreset: this step resets them and ignores their actions.
  const world::BatchResult& fourth = b.Step(zero);
  EXPECT_THAT(fourth.reset, ::testing::ElementsAre(1, 1));
  EXPECT_THAT(fourth.done, ::testing::ElementsAre(0, 0));
  EXPECT_THAT(fourth.episode_steps, ::testing::ElementsAre(0u, 0u));
  for (double t : fourth.time) EXPECT_DOUBLE_EQ(t, 0.0);
}

TEST_F(InProcessBatchTest, BadArraysAreRefusedNamingTheField) {
  InProcessBatch b(Humanoid(), {.envs = 2, .threads = 2});
  const auto message = [&](auto&& fn) -> std::string {
    try {
      fn();
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_THAT(message([&] { b.Step(std::vector<double>(41, 0.0)); }),
              HasSubstr("actions hold 41 values, expected 42 (2 environments x 21 actuators)"));
  std::vector<double> a(42, 0.0);
  a[21 + 3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(message([&] { b.Step(a); }),
              HasSubstr("actions: environment 1, actuator 3 is not a finite number"));
  a[21 + 3] = 1e10;  // beyond the actions' range, as the step server refuses it
  EXPECT_THAT(message([&] { b.Step(a); }), HasSubstr("actions must be"));
  a[21 + 3] = 0;
  const std::vector<std::uint8_t> flags(3, 0);
  EXPECT_THAT(message([&] { b.Step(a, flags); }),
              HasSubstr("reset holds 3 flags, expected one per environment (2)"));
  EXPECT_THAT(message([&] { b.Step(a, {}, 0); }), HasSubstr("n_steps must be at least 1"));
  const std::vector<int> nine = {9};
  EXPECT_THAT(message([&] { b.Reset(nine); }), HasSubstr("no environment 9"));
  const std::vector<int> zero = {0};
  const std::vector<std::optional<std::uint64_t>> huge = {std::uint64_t{1} << 60};
  EXPECT_THAT(message([&] { b.Reset(zero, huge); }),
              HasSubstr("seeds: 1152921504606846976 is not"));
  // Nothing was stepped by the refused requests.
  EXPECT_THAT(b.Step(a).episode_steps, ::testing::ElementsAre(1u, 1u));
}

TEST_F(InProcessBatchTest, BadOptionsAreNamedAsTheyAreHere) {
  const auto message = [](InProcessOptions o) -> std::string {
    try {
      InProcessBatch b(Humanoid(), o);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_THAT(message({.envs = 0}), HasSubstr("envs must be at least 1 (got 0)"));
  EXPECT_THAT(message({.envs = 2, .threads = -1}), HasSubstr("threads must be 0"));
  EXPECT_THAT(message({.envs = 2, .max_episode_steps = -5}), HasSubstr("max_episode_steps"));
  EXPECT_THAT(message({.envs = 2, .reset_noise = std::nan("")}), HasSubstr("reset_noise"));
  EXPECT_EQ(message({.envs = 2}), "no error");
}

TEST_F(InProcessBatchTest, BatchesPlaySideBySideAndAMissingSceneIsNamed) {
  {
    // A training and an evaluation batch in one process: each steps its own environments, and
    // the evaluation one runs the episode it runs alone.
    std::vector<double> alone;
    {
      InProcessBatch eval(Humanoid(), {.envs = 1, .threads = 1, .reset_noise = 0.05});
      for (const std::vector<double>& a : Actions(eval, 20, 5)) alone = eval.Step(a).obs;
    }
    InProcessBatch train(Humanoid(), {.envs = 2, .threads = 1, .reset_noise = 0.05});
    InProcessBatch eval(Humanoid(), {.envs = 1, .threads = 1, .reset_noise = 0.05});
    const std::vector<std::vector<double>> train_actions = Actions(train, 20, 9);
    std::vector<double> beside;
    int s = 0;
    for (const std::vector<double>& a : Actions(eval, 20, 5)) {
      train.Step(train_actions[static_cast<std::size_t>(s++)]);
      beside = eval.Step(a).obs;
    }
    EXPECT_EQ(beside, alone);
  }
  try {
    InProcessBatch missing("/no/such/scene.yaml", {.envs = 2});
    FAIL() << "a missing scene loaded";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("/no/such/scene.yaml"));
  }
  InProcessBatch after(Humanoid(), {.envs = 1});  // the failed one left nothing behind
}

TEST_F(InProcessBatchTest, TheCInterfaceStepsAndReportsErrors) {
  ASSERT_EQ(urlab_batch_abi(), URLAB_BATCH_ABI);
  char error[512] = {};
  urlab_batch_options o{};
  o.envs = 2;
  o.threads = 2;
  o.auto_reset = 1;
  EXPECT_EQ(urlab_batch_open("/no/such/scene.yaml", &o, error, sizeof error), nullptr);
  EXPECT_THAT(error, HasSubstr("/no/such/scene.yaml"));
  urlab_batch* b = urlab_batch_open(Humanoid().c_str(), &o, error, sizeof error);
  ASSERT_NE(b, nullptr) << error;
  urlab_batch_sizes sizes{};
  ASSERT_EQ(urlab_batch_get_sizes(b, &sizes), 0);
  EXPECT_EQ(sizes.envs, 2);
  EXPECT_EQ(sizes.nu, 21);
  EXPECT_EQ(sizes.obs_size, sizes.nq + sizes.nv + sizes.nsensordata);
  std::vector<double> low(21), high(21);
  ASSERT_EQ(urlab_batch_action_bounds(b, low.data(), high.data()), 0);
  EXPECT_LT(low[0], high[0]);
  const std::size_t need = urlab_batch_actuator_names(b, nullptr, 0);
  std::string names(need, '\0');
  urlab_batch_actuator_names(b, names.data(), names.size());
  EXPECT_THAT(names, HasSubstr("abdomen"));

  std::vector<double> obs(2 * static_cast<std::size_t>(sizes.obs_size)), time(2);
  std::vector<std::uint8_t> done(2), reset(2);
  std::vector<std::uint32_t> episode(2);
  urlab_batch_outputs out{obs.data(), done.data(), reset.data(), time.data(), episode.data(), 0};
  const std::uint64_t seeds[2] = {5, 6};
  ASSERT_EQ(urlab_batch_reset(b, nullptr, 0, seeds, nullptr, &out, error, sizeof error), 0)
      << error;
  std::vector<double> actions(42, 0.1);
  ASSERT_EQ(urlab_batch_step(b, actions.data(), nullptr, 2, &out, error, sizeof error), 0) << error;
  EXPECT_THAT(episode, ::testing::ElementsAre(2u, 2u));
  EXPECT_DOUBLE_EQ(time[1], 0.01);
  EXPECT_GT(out.seconds, 0);
  actions[5] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(urlab_batch_step(b, actions.data(), nullptr, 1, &out, error, sizeof error), -1);
  EXPECT_THAT(error, HasSubstr("environment 0, actuator 5 is not a finite number"));
  const int bad[1] = {2};
  EXPECT_EQ(urlab_batch_reset(b, bad, 1, nullptr, nullptr, &out, error, sizeof error), -1);
  EXPECT_THAT(error, HasSubstr("no environment 2"));
  urlab_batch_close(b);
}

// urlab_batch_copy_model / copy_data (MuJoCo's Python bindings take these): an exact copy of an
// environment's model and whole mjData, between steps; bad indices and mismatched data refused.
TEST_F(InProcessBatchTest, TheCInterfaceCopiesAnEnvironmentsModelAndData) {
  EXPECT_EQ(urlab_batch_mujoco_version(), mj_version());
  char error[512] = {};
  urlab_batch_options o{};
  o.envs = 3;
  o.threads = 2;
  o.auto_reset = 1;
  urlab_batch* b = urlab_batch_open(Humanoid().c_str(), &o, error, sizeof error);
  ASSERT_NE(b, nullptr) << error;
  urlab_batch_sizes sizes{};
  ASSERT_EQ(urlab_batch_get_sizes(b, &sizes), 0);
  std::vector<double> obs(3 * static_cast<std::size_t>(sizes.obs_size));
  urlab_batch_outputs out{obs.data(), nullptr, nullptr, nullptr, nullptr, 0};
  const std::uint64_t seeds[3] = {1, 2, 3};
  ASSERT_EQ(urlab_batch_reset(b, nullptr, 0, seeds, nullptr, &out, error, sizeof error), 0);
  std::vector<double> actions(3 * static_cast<std::size_t>(sizes.nu), 0.2);
  ASSERT_EQ(urlab_batch_step(b, actions.data(), nullptr, 5, &out, error, sizeof error), 0);

  mjModel* m = static_cast<mjModel*>(urlab_batch_copy_model(b, 2, error, sizeof error));
  ASSERT_NE(m, nullptr) << error;
  EXPECT_EQ(m->nq, sizes.nq);
  EXPECT_EQ(m->nv, sizes.nv);
  EXPECT_EQ(m->nu, sizes.nu);
  EXPECT_DOUBLE_EQ(m->opt.timestep, sizes.timestep);
  mjData* d = mj_makeData(m);
  ASSERT_NE(d, nullptr);
  for (int env = 0; env < 3; ++env) {
    ASSERT_EQ(urlab_batch_copy_data(b, env, d, error, sizeof error), 0) << error;
    const double* row = obs.data() + static_cast<std::size_t>(env) * sizes.obs_size;
    for (int i = 0; i < sizes.nq; ++i) EXPECT_EQ(d->qpos[i], row[i]) << "env " << env;
    for (int i = 0; i < sizes.nv; ++i) EXPECT_EQ(d->qvel[i], row[sizes.nq + i]);
    for (int i = 0; i < sizes.nsensordata; ++i) {
      EXPECT_EQ(d->sensordata[i], row[sizes.nq + sizes.nv + i]);
    }
    EXPECT_DOUBLE_EQ(d->time, 5 * sizes.timestep);
  }
  // A copy: stepping it moves nothing in the batch.
  mj_step(m, d);
  mjData* again = mj_makeData(m);
  ASSERT_EQ(urlab_batch_copy_data(b, 2, again, error, sizeof error), 0) << error;
  EXPECT_DOUBLE_EQ(again->time, 5 * sizes.timestep);
  mj_deleteData(again);

  EXPECT_EQ(urlab_batch_copy_model(b, 3, error, sizeof error), nullptr);
  EXPECT_THAT(error, HasSubstr("no environment 3"));
  EXPECT_EQ(urlab_batch_copy_data(b, -1, d, error, sizeof error), -1);
  EXPECT_THAT(error, HasSubstr("no environment -1"));
  EXPECT_EQ(urlab_batch_copy_data(b, 0, nullptr, error, sizeof error), -1);
  EXPECT_THAT(error, HasSubstr("no mjData"));
  mjModel* other = mj_loadXML(urlab::testing::SourcePath("examples/models/servo_arm.xml").c_str(),
                              nullptr, error, sizeof error);
  ASSERT_NE(other, nullptr) << error;
  mjData* small = mj_makeData(other);
  EXPECT_EQ(urlab_batch_copy_data(b, 0, small, error, sizeof error), -1);
  EXPECT_THAT(error, HasSubstr("other sizes"));
  mj_deleteData(small);
  mj_deleteModel(other);
  mj_deleteData(d);
  mj_deleteModel(m);
  urlab_batch_close(b);
}

}  // namespace
}  // namespace urlab::embed
