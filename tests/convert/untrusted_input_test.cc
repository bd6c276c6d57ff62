// Mesh files are untrusted: a binary STL whose triangle count disagrees with its data, a PLY
// header declaring more elements than the file holds, a flat mesh MuJoCo cannot use as the
// visual mesh (refused before the decomposition, not after), and a decomposition that is
// cancelled stops in every worker and leaves nothing cached.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <thread>

#include "mujoco_test.h"
#include "test_meshes.h"
#include "urlab/convert/decompose.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/convert/prop.h"
#include "urlab/core/error.h"

namespace urlab::convert {
namespace {

using testing::Box;
using testing::TempDir;
using testing::Torus;
using testing::Write;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Decomposition files in cache folder `dir`.
int CachedDecompositions(const std::string& dir) {
  int n = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    n += e.path().filename().string().starts_with("decomposition-");
  }
  return n;
}

// A binary STL of `mesh` whose header counts `count` triangles and begins with `header`.
std::string StlWithCount(const TriMesh& mesh, std::uint32_t count, const std::string& header) {
  std::string bytes = StlBytes(mesh, header);
  std::memcpy(bytes.data() + 80, &count, 4);
  return bytes;
}

TEST(UntrustedMesh, BinaryStlWhoseCountIsLowerThanItsDataIsRefused) {
  TempDir dir;
  const TriMesh box = Box({0, 0, 0}, {1, 1, 1});  // 12 triangles
  // With a "solid" header it used to be read as ASCII (no triangles or a few); without, as 5 of
  // the 12 triangles. Both silently.
  for (const std::string header : {"solid exported by a CAD tool", "binary header"}) {
    Write(dir / "low.stl", StlWithCount(box, 5, header));
    const std::string error = ErrorOf([&] { ReadMesh(dir / "low.stl"); });
    EXPECT_NE(error.find("header says 5 triangles but the file holds 12 triangle records"),
              std::string::npos)
        << header << ": " << error;
    EXPECT_NE(error.find(dir / "low.stl"), std::string::npos) << error;
  }
  // The right count still reads, also with a "solid" header, and so do a few padding bytes.
  Write(dir / "ok.stl", StlWithCount(box, 12, "solid but binary") + std::string(7, '\0'));
  EXPECT_EQ(ReadMesh(dir / "ok.stl").triangles.size(), 12u);
  // An ASCII STL is still ASCII.
  Write(dir / "ascii.stl",
        "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
        "   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n");
  EXPECT_EQ(ReadMesh(dir / "ascii.stl").triangles.size(), 1u);
}

TEST(UntrustedMesh, PlyCountsAreBoundedByTheFileSizeBeforeAnyAllocation) {
  TempDir dir;
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  Write(dir / "huge.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  std::string error = ErrorOf([&] { ReadMesh(dir / "huge.ply"); });
  EXPECT_NE(error.find(dir / "huge.ply" + ":3: PLY header: declares 1000000000 'vertex'"),
            std::string::npos)
      << error;
  // Binary: 12 bytes a vertex.
  Write(dir / "bin.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n" +
            std::string(12 * 99, '\0'));
  error = ErrorOf([&] { ReadMesh(dir / "bin.ply"); });
  EXPECT_NE(error.find("bin.ply:3: PLY header: declares 100 'vertex' elements (at least 12 bytes"),
            std::string::npos)
      << error;
  Write(dir / "count.ply", "ply\nformat ascii 1.0\nelement vertex -5\nend_header\n");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "count.ply"); }).find("count.ply:3:"), std::string::npos);
  Write(dir / "noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir / "noend.ply"); }).find("no 'end_header'"),
            std::string::npos);
  // A good PLY still reads.
  Write(dir / "tet.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  EXPECT_EQ(ReadMesh(dir / "tet.ply").triangles.size(), 4u);
}

class PropChecks : public urlab::testing::MujocoTest {};

TEST_F(PropChecks, AFlatMeshIsRefusedBeforeTheDecompositionRuns) {
  TempDir dir;
  // A flat square: MuJoCo cannot compute its volume.
  Write(dir / "flat.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  PropSpec spec;
  spec.name = "flat";
  spec.mesh = dir / "flat.obj";
  bool decomposition_started = false;
  spec.decompose.progress = [&](double, std::string_view) { decomposition_started = true; };
  const std::string error = ErrorOf([&] { BuildPropDocument(spec, dir / "cache"); });
  EXPECT_NE(error.find(dir / "flat.obj"), std::string::npos) << error;
  EXPECT_NE(error.find("cannot use this mesh as the visual mesh"), std::string::npos) << error;
  EXPECT_FALSE(decomposition_started);
  EXPECT_EQ(CachedDecompositions(dir / "cache"), 0) << error;
}

TEST_F(PropChecks, GeneratedElementsAreLocatedAtTheMeshFile) {
  TempDir dir;
  Write(dir / "box.stl", StlBytes(Box({0, 0, 0}, {1, 1, 1})));
  PropSpec spec;
  spec.mesh = dir / "box.stl";
  const PropDocument prop = BuildPropDocument(spec, dir / "cache");
  prop.doc.root().Visit(
      [&](const document::Element& e) { EXPECT_EQ(e.location().file, spec.mesh) << e.tag(); });
}

TEST(CancelDecomposition, StopsEveryWorkerWithinAUnitOfWorkAndCachesNothing) {
  TempDir dir;
  const TriMesh torus = Torus(0.05, 0.015, 96, 48);
  DecomposeOptions o;
  o.threshold = 0.005;
  o.threads = 4;
  // Baseline: the whole decomposition, timed in this process.
  const auto t0 = std::chrono::steady_clock::now();
  Decompose(torus, o);
  const auto full = std::chrono::steady_clock::now() - t0;
  // Cancelled from another thread once it is under way.
  std::atomic<bool> cancel{false};
  std::atomic<int> polls{0};
  o.cancelled = [&] {
    ++polls;
    return cancel.load();
  };
  std::atomic<bool> started{false};
  o.progress = [&](double f, std::string_view) {
    if (f > 0.05) started = true;
  };
  std::atomic<std::chrono::steady_clock::rep> sent{0};
  std::thread canceller([&] {
    while (!started) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    sent = std::chrono::steady_clock::now().time_since_epoch().count();
    cancel = true;
  });
  bool thrown = false;
  try {
    DecomposeCached(torus, o, dir / "cache");
  } catch (const Cancelled&) {
    thrown = true;
  }
  const auto stopped =
      std::chrono::steady_clock::now() -
      std::chrono::steady_clock::time_point(std::chrono::steady_clock::duration(sent.load()));
  canceller.join();
  EXPECT_TRUE(thrown);
  EXPECT_GT(polls.load(), 10);
  // Well before the whole decomposition would have ended.
  EXPECT_LT(stopped * 4, full) << std::chrono::duration<double>(stopped).count() << " s vs "
                               << std::chrono::duration<double>(full).count() << " s";
  // Nothing cached: the next call decomposes.
  EXPECT_EQ(CachedDecompositions(dir / "cache"), 0);
  o.cancelled = nullptr;
  bool hit = true;
  DecomposeCached(torus, o, dir / "cache", &hit);
  EXPECT_FALSE(hit);
}

}  // namespace
}  // namespace urlab::convert
