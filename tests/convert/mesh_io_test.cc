#include "urlab/convert/mesh_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "test_meshes.h"
#include "urlab/convert/decompose.h"
#include "urlab/core/error.h"

namespace urlab::convert {
namespace {

using testing::Box;
using testing::TempDir;

using testing::Write;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MeshIo, StlAndObjRoundTrip) {
  TempDir dir;
  const TriMesh box = Box({0, 0, 0}, {1, 2, 3});
  Write(dir / "box.stl", StlBytes(box));
  Write(dir / "box.obj", ObjBytes(box));
  for (const char* name : {"box.stl", "box.obj"}) {
    TriMesh m = ReadMesh(dir / name);
    const CleanReport r = CleanMesh(m);
    EXPECT_EQ(m.triangles.size(), 12u) << name;
    EXPECT_EQ(m.vertices.size(), 8u) << name;
    EXPECT_TRUE(r.closed()) << name;
    EXPECT_NEAR(SignedVolume(m), 6.0, 1e-6) << name;
  }
}

TEST(MeshIo, AsciiStlAndObjPolygonsAndNegativeIndices) {
  const TriMesh stl = ParseStl(
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid t\n",
      "t.stl");
  EXPECT_EQ(stl.triangles.size(), 1u);
  const TriMesh obj =
      ParseObj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf -4/1 -3/1 -2/1 -1/1\n", "quad.obj");
  EXPECT_EQ(obj.triangles.size(), 2u);
}

TEST(MeshIo, AssimpReadsPly) {
  TempDir dir;
  Write(dir / "tri.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  TriMesh m = ReadMesh(dir / "tri.ply");
  CleanMesh(m);
  EXPECT_EQ(m.triangles.size(), 4u);
  EXPECT_NEAR(SignedVolume(m), 1.0 / 6, 1e-6);
}

TEST(MeshIo, BadFilesNameTheFileAndLine) {
  TempDir dir;
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "missing.stl"); }).find("missing.stl"), std::string::npos);
  Write(dir / "empty.obj", "");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "empty.obj"); }).find("no triangles"), std::string::npos);
  Write(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  EXPECT_NE(
      ErrorOf([&] { ReadMesh(dir / "bad.obj"); }).find("bad.obj:3: face index 7 out of range"),
      std::string::npos);
  Write(dir / "nan.obj", "v 0 0 x\n");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "nan.obj"); }).find("nan.obj:1:"), std::string::npos);
  std::string stl = StlBytes(Box({0, 0, 0}, {1, 1, 1}));
  Write(dir / "cut.stl", stl.substr(0, stl.size() - 30));
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "cut.stl"); }).find("truncated"), std::string::npos);
  Write(dir / "x.xyz123", "hello");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "x.xyz123"); }).find("unknown mesh format"),
            std::string::npos);
  Write(dir / "broken.dae", "<COLLADA>");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "broken.dae"); }).find("broken.dae"), std::string::npos);
  std::filesystem::create_directory(dir / "folder.stl");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "folder.stl"); }).find("folder.stl"), std::string::npos);
}

TEST(MeshIo, CleanReportsDegenerateDuplicateAndNonManifold) {
  TriMesh m = Box({0, 0, 0}, {1, 1, 1});
  m.triangles.push_back(m.triangles[0]);  // duplicate
  m.triangles.push_back({0, 0, 1});       // repeated vertex
  m.vertices.push_back({0.5, 0, 0});      // on the edge 0-1: zero area
  m.triangles.push_back({0, 1, 8});
  m.vertices.push_back({std::nan(""), 0, 0});  // not finite
  m.triangles.push_back({0, 1, 9});
  m.triangles.push_back({0, 1, 42});  // index out of range
  const CleanReport r = CleanMesh(m);
  EXPECT_EQ(r.duplicate_triangles, 1u);
  EXPECT_EQ(r.degenerate_triangles, 2u);
  EXPECT_EQ(r.non_finite_vertices, 1u);
  EXPECT_EQ(r.bad_indices, 1u);
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_TRUE(r.closed());
  EXPECT_NE(r.Summary().find("degenerate"), std::string::npos);
}

TEST(MeshIo, HugeMeshIsSimplifiedWithinBounds) {
  // 320k triangles over a limit of 20k: clustered first, then decomposed, with progress.
  const TriMesh big = testing::Torus(0.05, 0.015, 800, 200);
  ASSERT_EQ(big.triangles.size(), 320000u);
  DecomposeOptions o;
  o.max_triangles = 20000;
  int calls = 0;
  o.progress = [&](double, std::string_view) { ++calls; };
  const Decomposition d = Decompose(big, o);
  EXPECT_GT(calls, 3);
  ASSERT_FALSE(d.notes.empty());
  bool simplified = false;
  for (const std::string& n : d.notes) simplified |= n.find("simplified from 320000") == 0;
  EXPECT_TRUE(simplified);
  EXPECT_GT(d.parts.size(), 2u);
}

}  // namespace
}  // namespace urlab::convert
