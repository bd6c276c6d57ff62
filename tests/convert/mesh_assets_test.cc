#include "urlab/convert/mesh_assets.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "mujoco_test.h"
#include "test_meshes.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/mjcf/bridge.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::convert {
namespace {

using testing::Box;
using testing::TempDir;

class MeshAssets : public urlab::testing::MujocoTest {};

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

// The bridge corpus's model with wound-inconsistently meshes (reference3x_test compares it with
// MuJoCo 3.x): 2.2.2 alone rejects it; after the repair both meshes weigh what their volumes do.
TEST_F(MeshAssets, FacesThatDisagreeAreOrientedInACachedCopy) {
  TempDir dir;
  const std::string path = urlab::testing::TestData("mjcf/bridge3x/mesh_orientation.xml");
  document::Document plain = mjcf::ReadFile(path);
  mjcf::ApplyBridge(plain);
  try {
    physics::CompileXmlString(mjcf::WriteString(plain));
    FAIL() << "MuJoCo 2.2.2 compiled the crate's inconsistently wound OBJ";
  } catch (const physics::CompileError& e) {
    EXPECT_NE(std::string(e.what()).find("inconsistent orientation"), std::string::npos)
        << e.what();
  }

  document::Document doc = mjcf::ReadFile(path);
  mjcf::ApplyBridge(doc);  // sets exactmeshinertia, so the STL's faces count too
  const MeshAssetReport r = PrepareMeshAssets(doc, dir / "cache");
  ASSERT_EQ(r.bridge_changes.size(), 2u);
  for (const mjcf::BridgeChange& c : r.bridge_changes) {
    EXPECT_EQ(c.rule, "mesh.orientation");
    EXPECT_EQ(c.kind, mjcf::BridgeChange::Kind::kTranslated);
  }
  EXPECT_EQ(r.bridge_changes[0].where.line, 10);
  EXPECT_NE(r.bridge_changes[0].what.find("3 of 12 triangles reversed"), std::string::npos)
      << r.bridge_changes[0].what;  // the right quad (two triangles) and one top triangle
  EXPECT_EQ(r.bridge_changes[1].where.line, 11);
  EXPECT_NE(r.bridge_changes[1].what.find("1 of 8 triangles reversed"), std::string::npos)
      << r.bridge_changes[1].what;
  const physics::ModelPtr m = physics::CompileXmlString(mjcf::WriteString(doc));
  EXPECT_NEAR(m->body_mass[mj_name2id(m.get(), mjOBJ_BODY, "crate")], 1000 * 0.2 * 0.1 * 0.06,
              1e-6);
  EXPECT_NEAR(m->body_mass[mj_name2id(m.get(), mjOBJ_BODY, "wedge")], 1000 * 0.5 * 0.2 * 0.1 * 0.08,
              1e-6);
  // The mesh names stay the document's; a second load uses the cached copies.
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_MESH, "crate"), 0);
  document::Document again = mjcf::ReadFile(path);
  mjcf::ApplyBridge(again);
  const MeshAssetReport second = PrepareMeshAssets(again, dir / "cache");
  ASSERT_EQ(second.bridge_changes.size(), 2u);
  EXPECT_EQ(second.bridge_changes[0].what, r.bridge_changes[0].what);
}

TEST_F(MeshAssets, ConsistentMeshesStayAndUnrepairableOnesAreAWarning) {
  TempDir dir;
  Write(dir / "box.obj", ObjBytes(Box({0, 0, 0}, {0.1, 0.1, 0.1})));
  // Edge 1-2 in three triangles: no orientation makes every edge run both ways once.
  Write(dir / "fin.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
  Write(dir / "m.xml", R"(<mujoco>
  <asset>
    <mesh file="box.obj"/>
    <mesh file="fin.obj"/>
  </asset>
  <worldbody>
    <body><freejoint/><geom type="mesh" mesh="box"/></body>
    <geom type="mesh" mesh="fin"/>
  </worldbody>
</mujoco>)");
  document::Document doc = mjcf::ReadFile(dir / "m.xml");
  const MeshAssetReport r = PrepareMeshAssets(doc, dir / "cache");
  EXPECT_TRUE(r.bridge_changes.empty());
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(r.warnings[0].where.line, 4);
  EXPECT_NE(r.warnings[0].message.find("cannot be oriented consistently"), std::string::npos)
      << r.warnings[0].message;
  EXPECT_EQ(doc.root().FirstChild("asset")->children()[0]->GetOr("file", ""), "box.obj");
}

}  // namespace
}  // namespace urlab::convert
