// Every model we know goes through the path `urlab run` takes: composed as a one-articulation
// scene named "r" (every name and reference prefixed "r_"), compiled, stepped. The result must be
// the model loaded on its own (read, bridged, compiled without a prefix): same sizes, same
// keyframes, a bit-identical 100-step zero-control trajectory, finite state.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>

#include "model_files.h"
#include "mujoco_test.h"
#include "urlab/physics/trajectory_compare.h"
#include "urlab/world/scene.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

// Models the composition refuses on purpose, with the reason it must give.
struct Refusal {
  const char* file_suffix;
  const char* message;
};
constexpr Refusal kRefused[] = {
    {"corpus/custom_user.xml", "does not carry tuples"},
    {"corpus/sensors_all.xml", "does not carry tuples"},
};

std::vector<std::string> ModelFiles() {
  return testing::ModelFilesIn({testing::MujocoCorpusDir(), testing::TestData("mjcf/corpus"),
                                testing::TestData("mjcf/dialect3x"),
                                testing::TestData("mjcf/robots")});
}

world::SceneConfig OneArticulation(const std::string& path) {
  world::SceneConfig scene;
  scene.path = path;
  world::ArticulationConfig a;
  a.name = "r";
  a.mjcf = path;
  scene.articulations.push_back(a);
  return scene;
}

class PrefixedModelTest : public testing::MujocoTest,
                          public ::testing::WithParamInterface<std::string> {};

TEST_P(PrefixedModelTest, ComposedAsArticulationRunsLikeTheFileAlone) {
  const std::string path = GetParam();
  std::optional<world::CompiledScene> alone;
  try {
    alone.emplace(world::BuildModel(path));
  } catch (const Error& e) {
    GTEST_SKIP() << "not a standalone model (it does not load on its own): " << e.what();
  }
  const size_t alone_warnings = TakeWarnings().size();

  for (const Refusal& r : kRefused) {
    if (!path.ends_with(r.file_suffix)) continue;
    try {
      world::BuildScene(OneArticulation(path));
      FAIL() << "composed a model the composition must refuse: " << path;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(r.message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path + ":"), std::string::npos) << e.what();
    }
    return;
  }

  world::CompiledScene scene = world::BuildScene(OneArticulation(path));
  // The same model compiles with the same warnings (their text names prefixed elements).
  EXPECT_EQ(TakeWarnings().size(), alone_warnings);
  const mjModel* a = alone->model.get();
  const mjModel* m = scene.model.get();
  ASSERT_EQ(physics::CompareSizes(a, m), "") << path;
  // Every named keyframe (attached with the articulation by MuJoCo) equals the file's own.
  // (MuJoCo puts the unnamed keys a <size nkey> pads with first, so keys are matched by name.)
  for (int ka = 0; ka < a->nkey; ++ka) {
    const std::string name = a->names + a->name_keyadr[ka];
    if (name.empty()) continue;
    const int km = mj_name2id(m, mjOBJ_KEY, ("r_" + name).c_str());
    ASSERT_GE(km, 0) << name;
    auto row = [](const mjtNum* base, int k, mjtSize n) { return base + k * n; };
    for (const auto& [field, n] : std::vector<std::pair<mjtNum * mjModel::*, mjtSize>>{
             {&mjModel::key_qpos, a->nq},
             {&mjModel::key_qvel, a->nv},
             {&mjModel::key_ctrl, a->nu},
             {&mjModel::key_act, a->na},
             {&mjModel::key_mpos, 3 * a->nmocap},
             {&mjModel::key_mquat, 4 * a->nmocap}}) {
      for (mjtSize i = 0; i < n; ++i) {
        ASSERT_EQ(row(m->*field, km, n)[i], row(a->*field, ka, n)[i]) << name << " " << i;
      }
    }
    ASSERT_EQ(m->key_time[km], a->key_time[ka]) << name;
  }
  // Names: every body of the file is there with the prefix.
  for (int b = 1; b < a->nbody; ++b) {
    const std::string name = a->names + a->name_bodyadr[b];
    if (!name.empty()) {
      EXPECT_GE(mj_name2id(m, mjOBJ_BODY, ("r_" + name).c_str()), 0) << name;
    }
  }
  EXPECT_EQ(physics::CompareTrajectories(a, m, 100), "") << path;
  physics::DataPtr d = physics::MakeData(m);
  for (int i = 0; i < 100; ++i) mj_step(m, d.get());
  for (int i = 0; i < m->nq; ++i) ASSERT_TRUE(std::isfinite(d->qpos[i])) << i;
  for (int i = 0; i < m->nv; ++i) ASSERT_TRUE(std::isfinite(d->qvel[i])) << i;
  EXPECT_EQ(TakeWarnings().size(), 0u);
}

INSTANTIATE_TEST_SUITE_P(AllModels, PrefixedModelTest, ::testing::ValuesIn(ModelFiles()),
                         testing::ModelTestName);

}  // namespace
}  // namespace urlab
