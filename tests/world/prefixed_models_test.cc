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

// Models the composer refuses on purpose, with the reason it must give.
struct Refusal {
  const char* file_suffix;
  const char* message;
};
constexpr Refusal kRefused[] = {
    {"corpus/coordinate_global.xml", "coordinate=\"global\" cannot be composed"},
};

std::vector<std::string> ModelFiles() {
  return testing::ModelFilesIn({"/usr/share/mujoco/model", testing::TestData("mjcf/corpus"),
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
    if (path.size() < std::strlen(r.file_suffix) ||
        path.compare(path.size() - std::strlen(r.file_suffix), std::string::npos, r.file_suffix) !=
            0) {
      continue;
    }
    try {
      world::BuildScene(OneArticulation(path));
      FAIL() << "composed a model the composer must refuse: " << path;
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
  // Every keyframe, filled in after compilation by the composer, equals the file's own.
  for (int i = 0; i < a->nkey * a->nq; ++i) ASSERT_EQ(m->key_qpos[i], a->key_qpos[i]) << i;
  for (int i = 0; i < a->nkey * a->nv; ++i) ASSERT_EQ(m->key_qvel[i], a->key_qvel[i]) << i;
  for (int i = 0; i < a->nkey * a->nu; ++i) ASSERT_EQ(m->key_ctrl[i], a->key_ctrl[i]) << i;
  for (int i = 0; i < a->nkey * a->na; ++i) ASSERT_EQ(m->key_act[i], a->key_act[i]) << i;
  for (int i = 0; i < a->nkey; ++i) ASSERT_EQ(m->key_time[i], a->key_time[i]) << i;
  for (int i = 0; i < a->nkey * 3 * a->nmocap; ++i) ASSERT_EQ(m->key_mpos[i], a->key_mpos[i]) << i;
  for (int i = 0; i < a->nkey * 4 * a->nmocap; ++i) {
    ASSERT_EQ(m->key_mquat[i], a->key_mquat[i]) << i;
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
