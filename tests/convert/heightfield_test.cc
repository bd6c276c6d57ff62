#include "urlab/convert/heightfield.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>

#include "mujoco_test.h"
#include "test_meshes.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::convert {
namespace {

using testing::TempDir;

double Sinusoid(double x, double y) {
  return 0.05 * std::sin(2 * M_PI * x / 0.5) * std::cos(2 * M_PI * y / 0.7) + 0.02 * x;
}

class Heightfield : public urlab::testing::MujocoTest {};

TEST_F(Heightfield, SampledSinusoidMatchesTheSurfaceWithinTheGridResolution) {
  TempDir dir;
  std::ofstream(dir / "hills.obj") << ObjBytes(testing::TerrainSlab(Sinusoid, 1.0, 100, -0.1));
  TerrainSpec spec;
  spec.name = "hills";
  spec.meshes = {{dir / "hills.obj"}};
  spec.resolution = 0.02;
  const TerrainDocument t = BuildTerrainDocument(spec, dir / "cache");
  EXPECT_FALSE(t.cache_hit);
  EXPECT_EQ(t.grid.cols, 51);
  EXPECT_EQ(t.grid.rows, 51);
  EXPECT_EQ(t.grid.misses, 0u);
  // At the grid points: the mesh (1 cm facets) itself.
  double worst = 0;
  for (int r = 0; r < t.grid.rows; ++r) {
    for (int c = 0; c < t.grid.cols; ++c) {
      const double x = t.grid.x0 + c * t.grid.dx, y = t.grid.y0 + r * t.grid.dy;
      worst = std::max(
          worst,
          std::abs(t.grid.heights[static_cast<std::size_t>(r * t.grid.cols + c)] - Sinusoid(x, y)));
    }
  }
  EXPECT_LT(worst, 5e-4);
  // Between grid points, through MuJoCo's hfield: curvature * resolution^2 / 8 is about 6e-4.
  const physics::ModelPtr m = physics::CompileXmlString(mjcf::WriteString(t.doc));
  physics::DataPtr d = physics::MakeData(m.get());
  mj_forward(m.get(), d.get());
  double between = 0;
  for (int i = 0; i < 400; ++i) {
    const double x = 0.01 + 0.98 * std::fmod(i * 0.618034, 1.0);
    const double y = 0.01 + 0.98 * std::fmod(i * 0.414214, 1.0);
    const mjtNum start[3] = {x, y, 1.0}, down[3] = {0, 0, -1};
    int geom = -1;
    const mjtNum dist = mj_ray(m.get(), d.get(), start, down, nullptr, 1, -1, &geom, nullptr);
    ASSERT_GE(dist, 0) << x << " " << y;
    between = std::max(between, std::abs((1.0 - dist) - Sinusoid(x, y)));
  }
  EXPECT_LT(between, 2e-3) << "the heightfield is not where the surface is (rows flipped?)";
}

TEST_F(Heightfield, SecondBuildIsACacheHit) {
  TempDir dir;
  std::ofstream(dir / "hills.obj") << ObjBytes(testing::TerrainSlab(Sinusoid, 1.0, 200, -0.1));
  TerrainSpec spec;
  spec.meshes = {{dir / "hills.obj"}};
  spec.resolution = 0.004;
  auto time = [&](bool* hit) {
    const auto t0 = std::chrono::steady_clock::now();
    const TerrainDocument t = BuildTerrainDocument(spec, dir / "cache");
    *hit = t.cache_hit;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  bool hit = true;
  const double miss_s = time(&hit);
  EXPECT_FALSE(hit);
  const double hit_s = time(&hit);
  EXPECT_TRUE(hit);
  std::printf("heightfield 251 x 251 from an 80k-triangle mesh: miss %.4f s, hit %.4f s (%.0fx)\n",
              miss_s, hit_s, miss_s / std::max(hit_s, 1e-9));
  // Another resolution is another entry.
  spec.resolution = 0.01;
  time(&hit);
  EXPECT_FALSE(hit);
}

TEST_F(Heightfield, BadInputNamesTheTerrainOrFile) {
  TempDir dir;
  TerrainSpec spec;
  spec.name = "ground";
  spec.meshes = {{dir / "missing.obj"}};
  try {
    BuildTerrainDocument(spec, dir / "cache");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.obj"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "hills.obj") << ObjBytes(testing::TerrainSlab(Sinusoid, 1.0, 10, -0.1));
  spec.meshes = {{dir / "hills.obj"}};
  spec.bounds = std::array<double, 4>{5, 5, 6, 6};  // nothing there
  try {
    BuildTerrainDocument(spec, dir / "cache");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no ray hit"), std::string::npos) << e.what();
  }
  spec.bounds.reset();
  spec.resolution = 1e-5;
  try {
    BuildTerrainDocument(spec, dir / "cache");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("raise resolution"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace urlab::convert
