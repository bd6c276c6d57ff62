#include "urlab/convert/decompose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include "test_meshes.h"
#include "urlab/convert/evaluate.h"
#include "urlab/core/error.h"

namespace urlab::convert {
namespace {

using testing::Cup;
using testing::LBracket;
using testing::TempDir;
using testing::Torus;

std::vector<TriMesh> Hulls(const Decomposition& d) {
  std::vector<TriMesh> out;
  for (const ConvexPart& p : d.parts) out.push_back(p.hull);
  return out;
}

TEST(Decompose, LBracketBecomesTwoExactParts) {
  DecomposeOptions o;
  o.threads = 1;
  const Decomposition d = Decompose(LBracket(), o);
  EXPECT_EQ(d.parts.size(), 2u);
  EXPECT_LE(d.concavity, o.threshold);
  const HullSetMetrics m = EvaluateHulls(LBracket(), Hulls(d));
  EXPECT_LT(m.volume_error, 0.02);
  EXPECT_LT(m.concavity, 0.01);
  // The single hull fills the corner.
  const Decomposition single = SingleHull(LBracket(), o);
  EXPECT_GT(single.concavity, o.threshold);
  EXPECT_GT(EvaluateHulls(LBracket(), Hulls(single)).volume_error, 1.0);
}

TEST(Decompose, CupKeepsItsOpening) {
  DecomposeOptions o;
  const TriMesh cup = Cup();
  const Decomposition d = Decompose(cup, o);
  EXPECT_GE(d.parts.size(), 4u);
  EXPECT_LE(d.concavity, o.threshold);
  const HullSetMetrics ours = EvaluateHulls(cup, Hulls(d));
  const HullSetMetrics single = EvaluateHulls(cup, Hulls(SingleHull(cup, o)));
  EXPECT_LT(ours.concavity, single.concavity / 2);
  // No hull covers the middle of the opening.
  for (const ConvexPart& p : d.parts) {
    const Bounds b = ComputeBounds(p.hull);
    const bool covers_axis = b.min[0] < 0 && b.max[0] > 0 && b.min[1] < 0 && b.max[1] > 0;
    EXPECT_FALSE(covers_axis && b.max[2] > 0.05) << "a part spans the cup's opening";
  }
}

TEST(Decompose, SameInputSameParts_WhateverTheThreads) {
  DecomposeOptions o;
  o.threads = 1;
  const Decomposition a = Decompose(Torus(0.05, 0.015, 32, 12), o);
  o.threads = 3;
  const Decomposition b = Decompose(Torus(0.05, 0.015, 32, 12), o);
  ASSERT_EQ(a.parts.size(), b.parts.size());
  for (std::size_t i = 0; i < a.parts.size(); ++i) {
    EXPECT_EQ(a.parts[i].hull.vertices, b.parts[i].hull.vertices) << "part " << i;
    EXPECT_EQ(a.parts[i].hull.triangles, b.parts[i].hull.triangles) << "part " << i;
  }
  EXPECT_GT(a.parts.size(), 2u);  // a torus is not convex
}

// The same torus tessellated coarsely and finely: the parts follow the shape. (A greedy cut
// choice among nearly equal scores followed the sampling of each tessellation: 32 parts at
// 48x16 and 28 at 128x40, above the threshold, where 64x28 gave 5.)
TEST(Decompose, PartsFollowTheShapeNotItsTessellation) {
  DecomposeOptions o;
  std::vector<Decomposition> runs;
  for (const auto& [nu, nv] : {std::pair{48, 16}, std::pair{128, 40}}) {
    runs.push_back(Decompose(Torus(0.05, 0.015, nu, nv), o));
    const Decomposition& d = runs.back();
    SCOPED_TRACE(::testing::Message() << nu << "x" << nv);
    EXPECT_LE(d.concavity, o.threshold);
    EXPECT_GE(d.parts.size(), 5u);
    EXPECT_LE(d.parts.size(), 9u);
  }
  const auto volume = [](const Decomposition& d) {
    double v = 0;
    for (const ConvexPart& p : d.parts) v += p.volume;
    return v;
  };
  EXPECT_LE(
      std::abs(static_cast<int>(runs[0].parts.size()) - static_cast<int>(runs[1].parts.size())), 1);
  EXPECT_NEAR(volume(runs[0]) / volume(runs[1]), 1.0, 0.1);
}

TEST(Decompose, MaxPartsIsAHardLimit) {
  DecomposeOptions o;
  o.max_parts = 3;
  o.threshold = 0.01;
  const Decomposition d = Decompose(Torus(0.05, 0.015, 32, 12), o);
  EXPECT_LE(d.parts.size(), 3u);
  EXPECT_GE(d.parts.size(), 1u);
}

TEST(Decompose, ProgressGoesFromZeroToOne) {
  DecomposeOptions o;
  std::vector<double> seen;
  o.progress = [&](double f, std::string_view) { seen.push_back(f); };
  Decompose(Cup(), o);
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.front(), 0.0);
  EXPECT_EQ(seen.back(), 1.0);
  for (double f : seen) EXPECT_TRUE(f >= 0 && f <= 1);
}

TEST(Decompose, BadInputIsAnError) {
  EXPECT_THROW(Decompose(TriMesh{}), Error);
  TriMesh degenerate;
  degenerate.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  degenerate.triangles = {{0, 1, 2}, {0, 0, 1}};
  try {
    Decompose(degenerate);
    FAIL() << "decomposed a mesh with only degenerate triangles";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no usable triangles"), std::string::npos) << e.what();
  }
  DecomposeOptions o;
  o.threshold = 0;
  EXPECT_THROW(Decompose(LBracket(), o), Error);
  o = {};
  o.max_parts = 0;
  EXPECT_THROW(Decompose(LBracket(), o), Error);
}

TEST(Decompose, OpenAndNonManifoldMeshesStillDecompose) {
  // A cup without its floor (open), plus a triangle hanging off an edge (non-manifold).
  TriMesh m = Cup();
  m.triangles.erase(m.triangles.begin(), m.triangles.begin() + 48);
  m.vertices.push_back({0.2, 0.2, 0.2});
  m.triangles.push_back(
      {m.triangles[100][0], m.triangles[100][1], static_cast<std::int32_t>(m.vertices.size() - 1)});
  const Decomposition d = Decompose(m);
  EXPECT_FALSE(d.parts.empty());
  bool noted = false;
  for (const std::string& n : d.notes) noted |= n.find("open") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(DecomposeCache, MissThenHitGivesTheSameParts_DamagedFileIsRedone) {
  TempDir dir;
  DecomposeOptions o;
  bool hit = true;
  const Decomposition a = DecomposeCached(LBracket(), o, dir.path(), &hit);
  EXPECT_FALSE(hit);
  const Decomposition b = DecomposeCached(LBracket(), o, dir.path(), &hit);
  EXPECT_TRUE(hit);
  ASSERT_EQ(a.parts.size(), b.parts.size());
  for (std::size_t i = 0; i < a.parts.size(); ++i) {
    EXPECT_EQ(a.parts[i].hull.vertices, b.parts[i].hull.vertices);
  }
  // Other options: another entry.
  o.max_parts = 1;
  DecomposeCached(LBracket(), o, dir.path(), &hit);
  EXPECT_FALSE(hit);
  // Damage every cache file: read as a miss and rewritten.
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    std::filesystem::resize_file(e.path(), std::filesystem::file_size(e.path()) / 2);
  }
  DecomposeCached(LBracket(), o, dir.path(), &hit);
  EXPECT_FALSE(hit);
  DecomposeCached(LBracket(), o, dir.path(), &hit);
  EXPECT_TRUE(hit);
}

TEST(DecomposeCache, ParseRefusesEveryTruncationAndAnotherKey) {
  const Decomposition d = Decompose(LBracket());
  const std::string bytes = SerializeDecomposition(d, 42);
  EXPECT_EQ(ParseDecomposition(bytes, 42).parts.size(), d.parts.size());
  EXPECT_THROW(ParseDecomposition(bytes, 43), Error);
  for (std::size_t n = 0; n < bytes.size(); n += 7) {
    EXPECT_THROW(ParseDecomposition(bytes.substr(0, n), 42), Error) << n;
  }
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x40;
  EXPECT_THROW(ParseDecomposition(flipped, 42), Error);
}

}  // namespace
}  // namespace urlab::convert
