#include "urlab/convert/mesh_assets.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "mujoco_test.h"
#include "test_meshes.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/mjcf/spec.h"
#include "urlab/physics/model.h"

namespace urlab::convert {
namespace {

using testing::Box;
using testing::TempDir;

class MeshAssets : public urlab::testing::MujocoTest {};

// The model at `path` with its meshes prepared, compiled by MuJoCo.
struct Prepared {
  mjcf::SpecPtr spec;
  MeshAssetReport report;
};
Prepared Prepare(const std::filesystem::path& path, const std::filesystem::path& cache) {
  Prepared p;
  p.spec = mjcf::ParseFile(path);
  p.report = PrepareMeshAssets(p.spec.get(), path, cache);
  return p;
}
physics::ModelPtr CompileSpec(mjSpec* spec) {
  mjModel* m = mj_compile(spec, nullptr);
  EXPECT_NE(m, nullptr) << mjs_getError(spec);
  return physics::ModelPtr(m);
}

using testing::Write;

std::string Coordinates(const Vec3& v) {
  return std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
}

std::string Ply(const TriMesh& m) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(m.vertices.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                  std::to_string(m.triangles.size()) +
                  "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& v : m.vertices) s += Coordinates(v);
  for (const Triangle& t : m.triangles) {
    s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
         "\n";
  }
  return s;
}

TEST_F(MeshAssets, ConvertsOtherFormatsOnceUnderTheNameMujocoGivesThem) {
  TempDir dir;
  Write(dir / "link1.ply", Ply(Box({0, 0, 0}, {0.1, 0.1, 0.1})));
  Write(dir / "link2.stl", StlBytes(Box({0, 0, 0}, {0.2, 0.1, 0.1})));
  Write(dir / "m.xml", R"(<mujoco>
  <asset>
    <mesh file="link1.ply"/>
    <mesh file="link2.stl"/>
  </asset>
  <worldbody>
    <body><freejoint/><geom type="mesh" mesh="link1"/></body>
  </worldbody>
</mujoco>)");
  Prepared p = Prepare(dir / "m.xml", dir / "cache");
  const MeshAssetReport& first = p.report;
  ASSERT_EQ(first.steps.size(), 1u);
  EXPECT_NE(first.steps[0].find("converted to"), std::string::npos) << first.steps[0];
  const physics::ModelPtr model = CompileSpec(p.spec.get());
  ASSERT_TRUE(model);
  EXPECT_EQ(model->nmesh, 2);
  // The PLY box (0.1 wide), converted to OBJ, keeps the name MuJoCo gives the PLY file.
  const int geom_mesh = model->geom_dataid[0];
  EXPECT_EQ(std::string(mj_id2name(model.get(), mjOBJ_MESH, geom_mesh)), "link1");
  EXPECT_GE(mj_name2id(model.get(), mjOBJ_MESH, "link2"), 0);
  // Second load: the cached conversion.
  const MeshAssetReport second = Prepare(dir / "m.xml", dir / "cache").report;
  EXPECT_NE(second.steps[0].find("converted before"), std::string::npos) << second.steps[0];
}

// Two meshes MuJoCo names the same from their files (link1.ply and link1.stl): MuJoCo's parser
// refuses the model, naming the repeated name and its line.
TEST_F(MeshAssets, ImplicitNamesThatClashAreRefusedAtTheirLine) {
  TempDir dir;
  Write(dir / "link1.ply", Ply(Box({0, 0, 0}, {0.1, 0.1, 0.1})));
  Write(dir / "link1.stl", StlBytes(Box({0, 0, 0}, {0.2, 0.1, 0.1})));
  Write(dir / "m.xml", R"(<mujoco>
  <asset>
    <mesh file="link1.ply"/>
    <mesh file="link1.stl"/>
  </asset>
</mujoco>)");
  try {
    Prepare(dir / "m.xml", dir / "cache");
    FAIL() << "two meshes named link1 were accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 4) << e.what();
    EXPECT_NE(std::string(e.what()).find("repeated name 'link1'"), std::string::npos) << e.what();
  }
}

TEST_F(MeshAssets, UnreadableVisualMeshIsDroppedUnreadableCollisionMeshIsAnError) {
  TempDir dir;
  Write(dir / "broken.dae", "<COLLADA>");
  const std::string model = R"(<mujoco>
  <asset><mesh name="look" file="broken.dae"/></asset>
  <worldbody>
    <body><freejoint/><geom type="box" size="0.1 0.1 0.1"/>
      <geom type="mesh" mesh="look" CONTACT/></body>
  </worldbody>
</mujoco>)";
  std::string visual = model;
  visual.replace(visual.find("CONTACT"), 7, R"(contype="0" conaffinity="0")");
  Write(dir / "visual.xml", visual);
  Prepared p = Prepare(dir / "visual.xml", dir / "cache");
  const MeshAssetReport& r = p.report;
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(r.warnings[0].where.line, 2);
  EXPECT_NE(r.warnings[0].message.find("collision geometry stays"), std::string::npos);
  const physics::ModelPtr m = CompileSpec(p.spec.get());
  ASSERT_TRUE(m);
  EXPECT_EQ(m->ngeom, 1);  // the box

  std::string collision = model;
  collision.replace(collision.find("CONTACT"), 7, "");
  Write(dir / "collision.xml", collision);
  try {
    Prepare(dir / "collision.xml", dir / "cache");
    FAIL() << "an unreadable collision mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 2);
    EXPECT_NE(std::string(e.what()).find("broken.dae"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace urlab::convert
