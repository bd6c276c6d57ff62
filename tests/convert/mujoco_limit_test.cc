// Meshes MuJoCo refuses as they are (an ASCII STL, a binary STL over 200,000 faces) become
// OBJ files it loads: in MJCF models (PrepareMeshAssets), as a prop's visual mesh
// (BuildPropDocument), and the simplification that bounds them (LimitForMujoco).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "mujoco_test.h"
#include "test_meshes.h"
#include "urlab/convert/mesh_assets.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/convert/prop.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/spec.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::convert {
namespace {

using testing::Box;
using testing::TempDir;
using testing::Torus;

class MujocoLimit : public urlab::testing::MujocoTest {};

using testing::Write;

std::string AsciiStl(const TriMesh& m) {
  std::string s = "solid box\n";
  for (const Triangle& t : m.triangles) {
    s += "facet normal 0 0 0\nouter loop\n";
    for (std::int32_t i : t) {
      const Vec3& v = m.vertices[static_cast<std::size_t>(i)];
      s += "vertex " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " +
           std::to_string(v[2]) + "\n";
    }
    s += "endloop\nendfacet\n";
  }
  return s + "endsolid box\n";
}

std::size_t RepeatedDirectedEdges(const TriMesh& m) {
  std::set<std::pair<std::int32_t, std::int32_t>> seen;
  std::size_t repeated = 0;
  for (const Triangle& t : m.triangles) {
    for (int k = 0; k < 3; ++k) repeated += !seen.emplace(t[k], t[(k + 1) % 3]).second;
  }
  return repeated;
}

// 320,000 triangles: more than MuJoCo reads from an STL.
constexpr double kR = 0.05, kr = 0.015;
TriMesh BigTorus() { return Torus(kR, kr, 800, 200); }

TEST_F(MujocoLimit, StlRefusalFollowsMujocosRule) {
  TempDir dir;
  Write(dir / "ok.stl", StlBytes(Box({0, 0, 0}, {1, 1, 1})));
  Write(dir / "ascii.stl", AsciiStl(Box({0, 0, 0}, {1, 1, 1})));
  Write(dir / "big.stl", StlBytes(BigTorus()));
  Write(dir / "box.obj", ObjBytes(Box({0, 0, 0}, {1, 1, 1})));
  EXPECT_EQ(MujocoStlRefusal(dir / "ok.stl"), "");
  EXPECT_EQ(MujocoStlRefusal(dir / "box.obj"), "");
  EXPECT_EQ(MujocoStlRefusal(dir / "missing.stl"), "");
  EXPECT_NE(MujocoStlRefusal(dir / "ascii.stl").find("ASCII"), std::string::npos);
  EXPECT_NE(MujocoStlRefusal(dir / "big.stl").find("320000 faces"), std::string::npos)
      << MujocoStlRefusal(dir / "big.stl");
  // The refusals are MuJoCo's own.
  for (const char* name : {"ascii.stl", "big.stl"}) {
    Write(dir / "m.xml", "<mujoco><asset><mesh file=\"" + std::string(name) +
                             "\"/></asset><worldbody><geom type=\"mesh\" mesh=\"" +
                             std::filesystem::path(name).stem().string() +
                             "\"/></worldbody></mujoco>");
    EXPECT_THROW(physics::LoadXmlFile(dir / "m.xml"), physics::CompileError) << name;
  }
}

TEST_F(MujocoLimit, LimitForMujocoKeepsTheShapeAndEveryDirectedEdgeOnce) {
  const TriMesh big = BigTorus();
  std::string note;
  EXPECT_EQ(LimitForMujoco(Box({0, 0, 0}, {1, 1, 1}), &note).triangles.size(), 12u);
  EXPECT_EQ(note, "");
  const TriMesh small = LimitForMujoco(big, &note);
  EXPECT_LE(small.triangles.size(), kMujocoMaxStlFaces);
  EXPECT_GT(small.triangles.size(), kMujocoMaxStlFaces / 2) << "simplified too far";
  EXPECT_NE(note.find("simplified from 320000 to"), std::string::npos) << note;
  EXPECT_EQ(RepeatedDirectedEdges(small), 0u);
  // The surface moves by about one grid cell (the torus spans 0.13 m; 1/100 of that at most).
  const double volume = 2 * M_PI * M_PI * kR * kr * kr;
  EXPECT_NEAR(std::abs(SignedVolume(small)), volume, 0.02 * volume);
  double worst = 0;
  for (const Vec3& v : small.vertices) {
    const double ring = std::hypot(v[0], v[1]) - kR;
    worst = std::max(worst, std::abs(std::hypot(ring, v[2]) - kr));
  }
  EXPECT_LT(worst, 0.0013);
}

TEST_F(MujocoLimit, MakeEdgesOrientableDropsOnlyWhatCannotAgree) {
  // Two boxes sharing an edge run the same way by two triangles (a non-manifold edge) plus a
  // flipped triangle in the second box that orientation fixes without dropping.
  TriMesh m = Box({0, 0, 0}, {1, 1, 1});
  TriMesh other = Box({1, 1, 0}, {2, 2, 1});
  std::swap(other.triangles[3][1], other.triangles[3][2]);
  testing::Append(m, other);
  // Weld the boxes' shared corners so the edge (1,1,0)-(1,1,1) is one edge of four triangles.
  for (Triangle& t : m.triangles) {
    for (std::int32_t& i : t) {
      if (i == 8) i = 2;
      if (i == 12) i = 6;
    }
  }
  TriMesh fixed = m;
  const std::size_t dropped = MakeEdgesOrientable(fixed);
  EXPECT_EQ(RepeatedDirectedEdges(fixed), 0u);
  EXPECT_LE(dropped, 2u);
  EXPECT_EQ(fixed.triangles.size() + dropped, m.triangles.size());
  EXPECT_LE(fixed.vertices.size(), 14u);  // the two welded corners' old copies are gone
}

TEST_F(MujocoLimit, MjcfMeshesMujocoRefusesAreConvertedAndCompile) {
  TempDir dir;
  Write(dir / "big.stl", StlBytes(BigTorus()));
  Write(dir / "ascii.stl", AsciiStl(Box({0, 0, 0}, {0.1, 0.1, 0.1})));
  Write(dir / "m.xml", R"(<mujoco>
  <asset>
    <mesh file="big.stl" inertia="exact"/>
    <mesh file="ascii.stl" inertia="exact"/>
  </asset>
  <worldbody>
    <body><freejoint/><geom type="mesh" mesh="big"/></body>
    <body pos="1 0 0"><freejoint/><geom type="mesh" mesh="ascii"/></body>
  </worldbody>
</mujoco>)");
  mjcf::SpecPtr spec = mjcf::ParseFile(dir / "m.xml");
  const MeshAssetReport report = PrepareMeshAssets(spec.get(), dir / "m.xml", dir / "cache");
  ASSERT_EQ(report.steps.size(), 2u);
  EXPECT_NE(report.steps[0].find("320000 faces"), std::string::npos) << report.steps[0];
  EXPECT_NE(report.steps[0].find("simplified from 320000"), std::string::npos) << report.steps[0];
  EXPECT_NE(report.steps[1].find("ASCII"), std::string::npos) << report.steps[1];
  const physics::ModelPtr model(mj_compile(spec.get(), nullptr));
  ASSERT_TRUE(model) << mjs_getError(spec.get());
  ASSERT_EQ(model->nmesh, 2);
  EXPECT_LE(model->mesh_facenum[0], static_cast<int>(kMujocoMaxStlFaces));
  EXPECT_EQ(model->mesh_facenum[1], 12);
  // With exact (signed-volume) inertia the torus weighs its analytic volume at density 1000
  // within 2%: the simplified faces still enclose it and face outwards.
  const double volume = 2 * M_PI * M_PI * kR * kr * kr;
  EXPECT_NEAR(model->body_mass[1], 1000 * volume, 0.02 * 1000 * volume);
}

TEST_F(MujocoLimit, PropWithAHugeStlCompilesWithASimplifiedVisualMesh) {
  TempDir dir;
  Write(dir / "big.stl", StlBytes(BigTorus()));
  PropSpec spec;
  spec.name = "big";
  spec.mesh = dir / "big.stl";
  spec.mode = PropMode::kDynamic;
  spec.decompose.max_parts = 8;
  spec.decompose.max_triangles = 20000;  // the decomposition's own bound, kept small for speed
  const PropDocument prop = BuildPropDocument(spec, dir / "cache");
  const std::string joined = [&] {
    std::string s;
    for (const std::string& line : prop.report) s += line + "\n";
    return s;
  }();
  EXPECT_NE(joined.find("visual mesh: converted"), std::string::npos) << joined;
  const physics::ModelPtr model = physics::CompileXmlString(mjcf::WriteString(prop.doc));
  const int visual = mj_name2id(model.get(), mjOBJ_MESH, kVisualGeomName);
  ASSERT_GE(visual, 0);
  EXPECT_LE(model->mesh_facenum[visual], static_cast<int>(kMujocoMaxStlFaces));
  EXPECT_GT(model->mesh_facenum[visual], static_cast<int>(kMujocoMaxStlFaces / 2));
}

}  // namespace
}  // namespace urlab::convert
