// Terrain in scenes: a ball rolling down a heightfield sampled from a ramp follows the path it
// takes on the ramp mesh itself; the second build reads the cached grid; errors at their line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "convert/test_meshes.h"
#include "mujoco_test.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/physics/model.h"
#include "urlab/world/scene.h"

namespace urlab {
namespace {

// A ramp 1 m long falling 0.3 m along x, 0.6 m wide: convex, so MuJoCo's mesh collision is
// exact and the two paths can be compared.
double Ramp(double x, double) { return 0.3 - 0.3 * x; }

constexpr const char* kBall = R"(<mujoco model="ball">
  <option timestep="0.001"/>
  <worldbody>
    <body name="ball" pos="0.1 0.3 0.32">
      <freejoint/>
      <geom type="sphere" size="0.03" density="1000"/>
    </body>
  </worldbody>
</mujoco>)";

constexpr const char* kRampMesh = R"(<mujoco model="ramp">
  <asset><mesh name="ramp" file="ramp.obj"/></asset>
  <worldbody><geom type="mesh" mesh="ramp"/></worldbody>
</mujoco>)";

class TerrainTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("terrain");
    setenv("URLAB_CACHE_DIR", (dir_ + "/cache").c_str(), 1);
    testing::WriteTextFile(dir_, "ball.xml", kBall);
    testing::WriteTextFile(dir_, "ramp.xml", kRampMesh);
    std::ofstream(dir_ + "/ramp.obj")
        << convert::ObjBytes(convert::testing::TerrainSlab(Ramp, 1.0, 20, -0.05));
  }
  void TearDown() override {
    unsetenv("URLAB_CACHE_DIR");
    testing::MujocoTest::TearDown();
  }
  world::SceneConfig Scene(const std::string& yaml) {
    return world::ParseScene(yaml, dir_ + "/scene.yaml");
  }
  // The ball's path: its position every 0.01 s for 0.8 s.
  std::vector<std::array<double, 3>> Roll(const world::CompiledScene& s) {
    const mjModel* m = s.model.get();
    physics::DataPtr d = physics::MakeData(m);
    const int ball = mj_name2id(m, mjOBJ_BODY, "ball_ball");
    std::vector<std::array<double, 3>> path;
    for (int i = 0; i < 800; ++i) {
      mj_step(m, d.get());
      if (i % 10 == 9) {
        path.push_back({d->xpos[3 * ball], d->xpos[3 * ball + 1], d->xpos[3 * ball + 2]});
      }
    }
    return path;
  }
  std::string dir_;
};

TEST_F(TerrainTest, BallRollsOnTheHeightfieldAsOnTheMesh) {
  const world::CompiledScene on_mesh = world::BuildScene(Scene(R"(options: {timestep: 0.001}
articulations:
  - {name: ramp, mjcf: ramp.xml}
  - {name: ball, mjcf: ball.xml}
)"));
  const world::CompiledScene on_hfield = world::BuildScene(Scene(R"(options: {timestep: 0.001}
articulations:
  - {name: ball, mjcf: ball.xml}
terrain:
  - name: ground
    meshes: [ramp.obj]
    resolution: 0.02
)"));
  ASSERT_EQ(on_hfield.terrain.size(), 1u);
  EXPECT_GE(on_hfield.terrain[0].geom, 0);
  EXPECT_EQ(on_hfield.model->geom_type[on_hfield.terrain[0].geom], mjGEOM_HFIELD);
  const auto a = Roll(on_mesh), b = Roll(on_hfield);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(a.back()[0], 0.5) << "the ball rolled down the ramp (towards +x)";
  // The same path: every hfield position within 3 cm (one ball diameter) of the mesh path.
  // MuJoCo 2.2.2's hfield contacts (triangle prisms) roll the ball about 13% slower than its mesh
  // contact and let it drift up to 2 cm sideways, at any grid resolution (0.1 to 0.01 m give the
  // same), so this is the engine's contact model, not the sampling: the distance travelled is
  // compared within 20%.
  auto to_path = [&](const std::array<double, 3>& p) {
    double best = 1e9;
    for (const auto& q : a)
      best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
    return best;
  };
  for (std::size_t i = 0; i < b.size(); i += 10) {
    EXPECT_LT(to_path(b[i]), 0.03) << "at " << 0.01 * (i + 1) << " s: hfield (" << b[i][0] << ", "
                                   << b[i][1] << ", " << b[i][2] << ") is off the mesh path";
  }
  const double on_mesh_travel = std::hypot(a.back()[0] - 0.1, a.back()[1] - 0.3);
  const double on_hfield_travel = std::hypot(b.back()[0] - 0.1, b.back()[1] - 0.3);
  EXPECT_NEAR(on_hfield_travel / on_mesh_travel, 1.0, 0.2);
  std::printf("ball travel in 0.8 s: mesh %.3f m, heightfield %.3f m\n", on_mesh_travel,
              on_hfield_travel);
}

TEST_F(TerrainTest, SecondBuildUsesTheCachedGrid) {
  const std::string yaml = R"(articulations:
  - {name: ball, mjcf: ball.xml}
terrain:
  - {name: ground, meshes: [ramp.obj], resolution: 0.05}
)";
  EXPECT_FALSE(world::BuildScene(Scene(yaml)).terrain[0].from_cache);
  EXPECT_TRUE(world::BuildScene(Scene(yaml)).terrain[0].from_cache);
}

TEST_F(TerrainTest, BadEntriesNameTheLine) {
  auto error_of = [&](const std::string& terrain) {
    try {
      Scene("articulations:\n  - {name: ball, mjcf: ball.xml}\nterrain:\n" + terrain);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("  - {name: g}\n").find("scene.yaml:4: g: give meshes or png"),
            std::string::npos)
      << error_of("  - {name: g}\n");
  EXPECT_NE(error_of("  - {name: g, meshes: [nope.obj]}\n").find("nope.obj"), std::string::npos);
  EXPECT_NE(error_of("  - {name: g, png: ramp.obj}\n").find("needs size"), std::string::npos);
  EXPECT_NE(error_of("  - {name: g, meshes: [ramp.obj], resolution: 0}\n").find("resolution"),
            std::string::npos);
  EXPECT_NE(error_of("  - {name: g, meshes: [ramp.obj], bounds: [1, 1, 0, 2]}\n").find("x max"),
            std::string::npos);
  EXPECT_NE(error_of("  - {name: ball, meshes: [ramp.obj]}\n").find("used twice"),
            std::string::npos);
}

// A PNG chunk: length, type, data, CRC-32 (computed here bit by bit).
std::string PngChunk(const std::string& type, const std::string& data) {
  auto be32 = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                       static_cast<char>(v >> 8), static_cast<char>(v)};
  };
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char c : type + data) {
    crc ^= static_cast<std::uint8_t>(c);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(~crc);
}

// An 8-bit grey PNG of `width` x `height` whose IDAT is `idat` (a zlib stream).
std::string Png(std::uint32_t width, std::uint32_t height, const std::string& idat) {
  auto be32 = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                       static_cast<char>(v >> 8), static_cast<char>(v)};
  };
  return std::string("\x89PNG\r\n\x1a\n", 8) +
         PngChunk("IHDR", be32(width) + be32(height) + std::string("\x08\x00\x00\x00\x00", 5)) +
         PngChunk("IDAT", idat) + PngChunk("IEND", "");
}

// Issue 38, case 9: a PNG height map MuJoCo cannot decode (not a PNG; image data of the wrong
// size) was MuJoCo's error on the composed model's line, with no line of the scene file in its
// first line. It is checked when the terrain is built: the entry's line, the file, the reason.
TEST_F(TerrainTest, BadPngHeightMapsNameTheEntrysLine) {
  auto error_of = [&](const std::string& png_bytes) {
    std::ofstream(dir_ + "/map.png", std::ios::binary) << png_bytes;
    try {
      (void)world::BuildScene(
          Scene("articulations:\n  - {name: ball, mjcf: ball.xml}\n"
                "terrain:\n  - {name: g, png: map.png, size: [1, 1, 0.2, "
                "0.1]}\n"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // zlib's stored block of 3 bytes (one filter byte and two pixels): a valid 2 x 1 image.
  const std::string stored2x1("\x78\x01\x01\x03\x00\xfc\xff\x00\x10\x20\x00\x43\x00\x31", 14);
  EXPECT_EQ(error_of(Png(2, 1, stored2x1)), "");
  const std::string prefix = "scene.yaml:4: g: " + dir_ + "/map.png: ";
  std::string e = error_of("hello, not a png at all");
  EXPECT_NE(e.find(prefix + "not a PNG"), std::string::npos) << e;
  e = error_of(Png(100000, 100000, stored2x1));
  EXPECT_NE(e.find(prefix), std::string::npos) << e;
  EXPECT_NE(e.find("100000 x 100000"), std::string::npos) << e;
  e = error_of(Png(3, 1, stored2x1));  // 3 pixels wide, 2 pixels of data
  EXPECT_NE(e.find(prefix), std::string::npos) << e;
  EXPECT_NE(e.find("image data"), std::string::npos) << e;
  e = error_of(Png(2, 1, stored2x1).substr(0, 40));
  EXPECT_NE(e.find(prefix), std::string::npos) << e;
}

}  // namespace
}  // namespace urlab
