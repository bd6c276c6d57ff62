// Domain randomisation on a real session: the scene's `randomize:` draws at every reset into the
// session's own model (never the compiled original), the same seed draws the same values and
// gives the same trajectory, over 1,000 resets each parameter's draws follow its distribution
// (Kolmogorov-Smirnov against the CDF, fixed seed), observation noise has the configured
// spread, a request's config overrides the scene's, and bad sections name their line.
#include "urlab/world/randomize.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

constexpr const char* kRandomizeArmXml = R"(<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.5" armature="0.01"
             frictionloss="0.02"/>
      <geom name="rod" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="tip" pos="0.3 0 0">
        <joint name="wrist" type="hinge" axis="0 1 0" damping="0.2"/>
        <geom type="sphere" size="0.05" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge" gear="1" ctrllimited="true" ctrlrange="-100 100"/>
    <position name="servo" joint="wrist" kp="20"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
  </sensor>
</mujoco>)";

constexpr const char* kRandomize = R"(randomize:
  gravity:
    z: {uniform: [-0.5, 0.5]}
  arm:
    friction: {uniform: [0.5, 1.5]}
    mass: {log_uniform: [0.5, 2]}
    damping: {normal: [1, 0.1]}
    armature: {uniform: [0.9, 1.1]}
    frictionloss: {log_uniform: [0.1, 10]}
    gain: {uniform: [0.8, 1.2]}
    kp: {normal: [1, 0.05]}
    kv: {uniform: [0.5, 1]}
    qpos_noise: {normal: [0, 0.05]}
)";

class RandomizeTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("randomize");
    testing::WriteTextFile(dir_, "arm.xml", kRandomizeArmXml);
  }
  world::SceneConfig Scene(const std::string& randomize = kRandomize,
                           const std::string& top = "seed: 7\n") {
    return world::ParseScene(top +
                                 "articulations:\n  - name: arm\n    mjcf: arm.xml\n"
                                 "    controller: {type: pd, kp: 10, kv: 1}\n" +
                                 randomize,
                             dir_ + "/scene.yaml");
  }
  std::string dir_;
};

std::vector<double> Trajectory(world::Session& s, int steps) {
  std::vector<double> q;
  for (int i = 0; i < steps; ++i) {
    s.engine().StepSync(1);
    s.engine().WithLockedData([&](mjModel*, mjData* d) {
      q.push_back(d->qpos[0]);
      q.push_back(d->qpos[1]);
    });
  }
  return q;
}

TEST_F(RandomizeTest, SameSeedSameDrawsSameTrajectory) {
  auto a = world::Session::Create(Scene());
  auto b = world::Session::Create(Scene());
  auto c = world::Session::Create(Scene(kRandomize, "seed: 8\n"));
  EXPECT_EQ(a->last_draws(), b->last_draws());  // the first draw, at creation
  EXPECT_NE(a->last_draws(), c->last_draws());
  for (int reset = 0; reset < 3; ++reset) {
    const auto ra = a->ResetRandomized(std::nullopt);
    const auto rb = b->ResetRandomized(std::nullopt);
    EXPECT_EQ(ra.draws, rb.draws);
    EXPECT_EQ(Trajectory(*a, 200), Trajectory(*b, 200));
  }
  // An explicit seed draws the same whatever came before.
  const auto s1 = a->ResetRandomized(42);
  const std::vector<double> t1 = Trajectory(*a, 100);
  c->ResetRandomized(std::nullopt);
  const auto s2 = c->ResetRandomized(42);
  EXPECT_EQ(s1.draws, s2.draws);
  EXPECT_EQ(t1, Trajectory(*c, 100));
  EXPECT_EQ(s1.draws.seed, 42u);
}

TEST_F(RandomizeTest, DrawsAreWrittenIntoTheSessionsOwnModel) {
  const world::SceneConfig scene = Scene();
  const world::CompiledScene nominal = world::BuildScene(scene);
  const mjModel* n = nominal.model.get();
  auto s = world::Session::Create(scene);
  const auto r = s->ResetRandomized(5);
  const auto& d = r.draws.targets.at("arm");
  s->engine().WithLockedData([&](mjModel* m, mjData* data) {
    const int rod = mj_name2id(m, mjOBJ_GEOM, "arm_rod");
    const int link = mj_name2id(m, mjOBJ_BODY, "arm_link");
    const int hinge = m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, "arm_hinge")];
    const int servo = mj_name2id(m, mjOBJ_ACTUATOR, "arm_servo");
    EXPECT_EQ(m->geom_friction[3 * rod], n->geom_friction[3 * rod] * d.at("friction"));
    EXPECT_EQ(m->body_mass[link], n->body_mass[link] * d.at("mass"));
    EXPECT_EQ(m->body_inertia[3 * link + 1], n->body_inertia[3 * link + 1] * d.at("mass"));
    EXPECT_EQ(m->dof_damping[hinge], n->dof_damping[hinge] * d.at("damping"));
    EXPECT_EQ(m->dof_armature[hinge], n->dof_armature[hinge] * d.at("armature"));
    EXPECT_EQ(m->dof_frictionloss[hinge], n->dof_frictionloss[hinge] * d.at("frictionloss"));
    EXPECT_EQ(m->actuator_gainprm[mjNGAIN * servo], 20 * d.at("gain"));
    EXPECT_EQ(m->actuator_biasprm[mjNBIAS * servo + 1], -20 * d.at("gain"));
    EXPECT_EQ(m->opt.gravity[2], n->opt.gravity[2] + r.draws.gravity.at("z"));
    // The reset put the joints at their reference position plus the drawn noise.
    EXPECT_EQ(data->qpos[m->jnt_qposadr[0]], n->qpos0[0] + d.at("qpos_noise.hinge"));
    EXPECT_EQ(data->qpos[m->jnt_qposadr[1]], n->qpos0[1] + d.at("qpos_noise.wrist"));
  });
  auto* pd = dynamic_cast<control::PdController*>(s->Require("arm").control->controller());
  ASSERT_NE(pd, nullptr);
  EXPECT_EQ(pd->gains(0).kp, 10 * d.at("kp"));
  EXPECT_EQ(pd->gains(0).kv, 1 * d.at("kv"));
  // The next reset draws from the nominal values again, not from the last draw.
  const auto r2 = s->ResetRandomized(6);
  s->engine().WithLockedData([&](mjModel* m, mjData*) {
    const int rod = mj_name2id(m, mjOBJ_GEOM, "arm_rod");
    EXPECT_EQ(m->geom_friction[3 * rod],
              n->geom_friction[3 * rod] * r2.draws.targets.at("arm").at("friction"));
  });
}

// Masses and armature drawn: what MuJoCo derives from them (subtree masses, inverse weights,
// actuator_acc0, mean inertia) is as if the model had been compiled with the drawn values.
TEST_F(RandomizeTest, DerivedConstantsFollowTheDrawnMasses) {
  const world::SceneConfig scene = Scene();
  const world::CompiledScene nominal = world::BuildScene(scene);
  auto s = world::Session::Create(scene);
  const auto r = s->ResetRandomized(11);
  const double mass = r.draws.targets.at("arm").at("mass");
  ASSERT_NE(mass, 1.0);
  s->engine().WithLockedData([&](mjModel* m, mjData*) {
    // The reference: the nominal model with the same fields written, its constants recomputed.
    mjModel* ref = mj_copyModel(nullptr, nominal.model.get());
    std::copy_n(m->body_mass, m->nbody, ref->body_mass);
    std::copy_n(m->body_inertia, 3 * m->nbody, ref->body_inertia);
    std::copy_n(m->dof_armature, m->nv, ref->dof_armature);
    mjData* scratch = mj_makeData(ref);
    mj_setConst(ref, scratch);
    double total = 0;
    for (int b = 1; b < m->nbody; ++b) total += m->body_mass[b];
    EXPECT_DOUBLE_EQ(m->body_subtreemass[0], total);
    EXPECT_NE(m->body_subtreemass[0], nominal.model.get()->body_subtreemass[0]);
    for (int b = 0; b < m->nbody; ++b) {
      EXPECT_EQ(m->body_subtreemass[b], ref->body_subtreemass[b]) << b;
      EXPECT_EQ(m->body_invweight0[2 * b], ref->body_invweight0[2 * b]) << b;
    }
    for (int i = 0; i < m->nv; ++i) EXPECT_EQ(m->dof_invweight0[i], ref->dof_invweight0[i]) << i;
    for (int a = 0; a < m->nu; ++a) EXPECT_EQ(m->actuator_acc0[a], ref->actuator_acc0[a]) << a;
    EXPECT_EQ(m->stat.meaninertia, ref->stat.meaninertia);
    mj_deleteData(scratch);
    mj_deleteModel(ref);
  });
  // A reset without mass draws puts the nominal constants back.
  s->ResetRandomized(12, nullptr);
  world::RandomizeConfig none;
  s->ResetRandomized(13, &none);
  s->engine().WithLockedData([&](mjModel* m, mjData*) {
    const mjModel* n = nominal.model.get();
    for (int b = 0; b < m->nbody; ++b) EXPECT_EQ(m->body_subtreemass[b], n->body_subtreemass[b]);
    for (int i = 0; i < m->nv; ++i) EXPECT_EQ(m->dof_invweight0[i], n->dof_invweight0[i]);
  });
}

// Kolmogorov-Smirnov statistic of `x` against `range`'s CDF.
double KsStatistic(std::vector<double> x, const world::RandomRange& range) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  double d = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double f = world::Cdf(range, x[i]);
    d = std::max({d, f - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - f});
  }
  return d;
}

TEST_F(RandomizeTest, ThousandResetsFollowEachConfiguredDistribution) {
  const world::SceneConfig scene = Scene();
  auto s = world::Session::Create(scene);
  std::map<std::string, std::vector<double>> drawn;
  for (int i = 0; i < 1000; ++i) {
    const auto r = s->ResetRandomized(std::nullopt);
    for (const auto& [key, v] : r.draws.targets.at("arm")) drawn[key].push_back(v);
    drawn["gravity.z"].push_back(r.draws.gravity.at("z"));
  }
  std::map<std::string, world::RandomRange> want =
      world::RandomizeOf(scene).config.targets.at("arm");
  want["qpos_noise.hinge"] = want.at("qpos_noise");
  want["qpos_noise.wrist"] = want.at("qpos_noise");
  want.erase("qpos_noise");
  want["gravity.z"] = world::RandomizeOf(scene).config.gravity.at("z");
  ASSERT_EQ(drawn.size(), want.size());
  // 1.63 / sqrt(n): the 1 % critical value; the seed is fixed, so this is a fixed outcome.
  const double critical = 1.63 / std::sqrt(1000.0);
  for (const auto& [key, range] : want) {
    ASSERT_EQ(drawn[key].size(), 1000u) << key;
    const double ks = KsStatistic(drawn[key], range);
    EXPECT_LT(ks, critical) << key << " (" << world::DistributionName(range.dist) << ")";
    // And the test can tell: the same draws against a shifted distribution fail it.
    world::RandomRange shifted = range;
    const double width = range.dist == world::Distribution::kNormal ? range.b : range.b - range.a;
    shifted.a += 0.3 * width;
    shifted.b += range.dist == world::Distribution::kNormal ? 0 : 0.3 * width;
    EXPECT_GT(KsStatistic(drawn[key], shifted), critical) << key << " shifted";
  }
}

TEST_F(RandomizeTest, ObservationNoiseHasTheDrawnSpread) {
  auto s =
      world::Session::Create(Scene("randomize:\n  arm:\n    obs_noise: {uniform: [0.01, "
                                   "0.01]}\n"));
  auto observed = s->engine().SubscribeState("observer", /*observed=*/true);
  auto truth = s->engine().SubscribeEveryStep("truth", 4096);
  s->ResetRandomized(3);
  std::vector<double> err;
  physics::StateFrame f;
  for (int i = 0; i < 2000; ++i) {
    s->engine().StepSync(1);
    double q = 0;
    while (truth->TryPop(&f)) q = f.qpos[0];
    err.push_back(observed->Latest()->qpos[0] - q);
  }
  double mean = 0, var = 0;
  for (double e : err) mean += e / static_cast<double>(err.size());
  for (double e : err) var += (e - mean) * (e - mean) / static_cast<double>(err.size() - 1);
  EXPECT_NEAR(mean, 0, 0.002);
  EXPECT_NEAR(std::sqrt(var), 0.01, 0.001);
  const world::RandomRange n01{world::Distribution::kNormal, 0, 0.01};
  EXPECT_LT(KsStatistic(err, n01), 1.63 / std::sqrt(2000.0));
}

TEST_F(RandomizeTest, RequestConfigOverridesTheScene) {
  auto s = world::Session::Create(Scene(""));
  EXPECT_FALSE(s->randomizes());
  world::RandomizeConfig c;
  c.targets["arm"]["friction"] = {world::Distribution::kUniform, 2, 2};
  const auto r = s->ResetRandomized(1, &c);
  EXPECT_EQ(r.draws.targets.at("arm").at("friction"), 2);
  EXPECT_EQ(r.draws.targets.at("arm").size(), 1u);
  world::RandomizeConfig bad;
  bad.targets["nobody"]["friction"] = {world::Distribution::kUniform, 1, 2};
  EXPECT_THROW(s->ResetRandomized(1, &bad), Error);
  world::RandomizeConfig bad_param;
  bad_param.targets["arm"]["colour"] = {world::Distribution::kUniform, 1, 2};
  EXPECT_THROW(s->ResetRandomized(1, &bad_param), Error);
}

TEST_F(RandomizeTest, BadSectionsNameTheirLine) {
  const auto fails = [&](const std::string& randomize, const std::string& needle) {
    try {
      Scene(randomize);
      ADD_FAILURE() << "accepted: " << randomize;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("scene.yaml:"), std::string::npos) << e.what();
    }
  };
  fails("randomize:\n  robot:\n    friction: {uniform: [0, 1]}\n", "no articulation or prop");
  fails("randomize:\n  arm:\n    colour: {uniform: [0, 1]}\n", "unknown parameter 'colour'");
  fails("randomize:\n  arm:\n    friction: {gamma: [0, 1]}\n", "unknown distribution");
  fails("randomize:\n  arm:\n    friction: {uniform: [2, 1]}\n", "low <= high");
  fails("randomize:\n  arm:\n    mass: {log_uniform: [0, 1]}\n", "0 < low");
  fails("randomize:\n  arm:\n    mass: {normal: [1, -1]}\n", "std >= 0");
  fails("randomize:\n  arm:\n    mass: {uniform: [1]}\n", "list of 2 numbers");
  fails("randomize:\n  gravity:\n    w: {uniform: [0, 1]}\n", "unknown key 'w'");
}

// Issue 38, case 2: every drawn parameter has a range, checked where the section is parsed
// (negative or zero masses, negative damping, armature, gains or noise, gravity 1e308 used to
// pass validate and make the run diverge).
TEST_F(RandomizeTest, EveryParameterHasARangeCheckedWhereParsed) {
  const auto fails = [&](const std::string& randomize, const std::string& field,
                         const std::string& range) {
    try {
      Scene(randomize);
      ADD_FAILURE() << "accepted: " << randomize;
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("scene.yaml:"), std::string::npos) << m;
      EXPECT_NE(m.find(field), std::string::npos) << m;
      EXPECT_NE(m.find(range), std::string::npos) << m;
    }
  };
  fails("randomize:\n  arm:\n    mass: {uniform: [-2, -1]}\n", "randomize.arm.mass",
        "[0.001, 1000]");
  fails("randomize:\n  arm:\n    mass: {uniform: [0, 0]}\n", "randomize.arm.mass", "[0.001, 1000]");
  fails("randomize:\n  arm:\n    armature: {uniform: [-1, 1]}\n", "randomize.arm.armature",
        "[0, 1000]");
  fails("randomize:\n  arm:\n    damping: {normal: [-1, 0.1]}\n", "randomize.arm.damping",
        "[0, 1000]");
  fails("randomize:\n  arm:\n    kp: {uniform: [-1, 1]}\n", "randomize.arm.kp", "[0, 100]");
  fails("randomize:\n  arm:\n    obs_noise: {uniform: [0, 1e300]}\n", "randomize.arm.obs_noise",
        "[0, 10]");
  fails("randomize:\n  arm:\n    qpos_noise: {normal: [0, 1e300]}\n", "randomize.arm.qpos_noise",
        "[-10, 10]");
  fails("randomize:\n  gravity:\n    z: {uniform: [0, 1e308]}\n", "randomize.gravity.z",
        "[-100, 100]");
  fails("randomize:\n  arm:\n    friction: {log_uniform: [1, 1e9]}\n", "randomize.arm.friction",
        "[0, 100]");
  // The edges are fine.
  EXPECT_NO_THROW(
      Scene("randomize:\n  arm:\n    mass: {uniform: [0.001, 1000]}\n"
            "    damping: {uniform: [0, 1000]}\n"));
  // The C++ interface refuses them too (a config that never went through a parser).
  auto s = world::Session::Create(Scene(""));
  world::RandomizeConfig c;
  c.targets["arm"]["mass"] = {world::Distribution::kUniform, -2, -1};
  try {
    s->ResetRandomized(1, &c);
    ADD_FAILURE() << "a negative mass was drawn";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("[0.001, 1000]"), std::string::npos) << e.what();
  }
}

// A normal distribution's tails are cut at the parameter's range: a draw never leaves it.
TEST_F(RandomizeTest, NormalDrawsStayInTheParametersRange) {
  auto s = world::Session::Create(Scene("randomize:\n  arm:\n    mass: {normal: [0.01, 5]}\n"));
  for (int i = 0; i < 200; ++i) {
    const double mass = s->ResetRandomized(std::nullopt).draws.targets.at("arm").at("mass");
    EXPECT_GE(mass, 0.001);
    EXPECT_LE(mass, 1000);
  }
}

}  // namespace
}  // namespace urlab
