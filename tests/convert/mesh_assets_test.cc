#include "urlab/convert/mesh_assets.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "mujoco_test.h"
#include "test_meshes.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::convert {
namespace {

using testing::Box;
using testing::TempDir;

class MeshAssets : public urlab::testing::MujocoTest {};

void Write(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

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

TEST_F(MeshAssets, ConvertsOtherFormatsOnceAndKeepsNamesDistinct) {
  TempDir dir;
  Write(dir / "link1.ply", Ply(Box({0, 0, 0}, {0.1, 0.1, 0.1})));
  Write(dir / "link1.stl", StlBytes(Box({0, 0, 0}, {0.2, 0.1, 0.1})));
  Write(dir / "m.xml", R"(<mujoco>
  <asset>
    <mesh file="link1.ply"/>
    <mesh file="link1.stl"/>
  </asset>
  <worldbody>
    <body><freejoint/><geom type="mesh" mesh="link1"/></body>
  </worldbody>
</mujoco>)");
  document::Document doc = mjcf::ReadFile(dir / "m.xml");
  const MeshAssetReport first = PrepareMeshAssets(doc, dir / "cache");
  ASSERT_EQ(first.steps.size(), 2u);
  EXPECT_NE(first.steps[0].find("renamed 'link1_1'"), std::string::npos) << first.steps[0];
  EXPECT_NE(first.steps[1].find("converted to"), std::string::npos) << first.steps[1];
  const physics::ModelPtr model = physics::CompileXmlString(mjcf::WriteString(doc));
  EXPECT_EQ(model->nmesh, 2);
  EXPECT_GE(mj_name2id(model.get(), mjOBJ_MESH, "link1"), 0);
  EXPECT_GE(mj_name2id(model.get(), mjOBJ_MESH, "link1_1"), 0);
  // The PLY box (0.1 wide) is the one the geom uses, converted to OBJ.
  const int geom_mesh = model->geom_dataid[0];
  EXPECT_EQ(std::string(mj_id2name(model.get(), mjOBJ_MESH, geom_mesh)), "link1");
  // Second load: the cached conversion.
  document::Document again = mjcf::ReadFile(dir / "m.xml");
  const MeshAssetReport second = PrepareMeshAssets(again, dir / "cache");
  EXPECT_NE(second.steps[1].find("converted before"), std::string::npos) << second.steps[1];
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
  document::Document doc = mjcf::ReadFile(dir / "visual.xml");
  const MeshAssetReport r = PrepareMeshAssets(doc, dir / "cache");
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(r.warnings[0].where.line, 2);
  EXPECT_NE(r.warnings[0].message.find("collision geometry stays"), std::string::npos);
  const physics::ModelPtr m = physics::CompileXmlString(mjcf::WriteString(doc));
  EXPECT_EQ(m->ngeom, 1);  // the box

  std::string collision = model;
  collision.replace(collision.find("CONTACT"), 7, "");
  Write(dir / "collision.xml", collision);
  document::Document doc2 = mjcf::ReadFile(dir / "collision.xml");
  try {
    PrepareMeshAssets(doc2, dir / "cache");
    FAIL() << "an unreadable collision mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 2);
    EXPECT_NE(std::string(e.what()).find("broken.dae"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace urlab::convert
