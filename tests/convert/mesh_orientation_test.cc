// PlanConsistentOrientation and ReverseObjFaces: which faces a repair reverses, and the OBJ text
// it writes.
#include <gtest/gtest.h>

#include "test_meshes.h"
#include "urlab/convert/mesh.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"

namespace urlab::convert {
namespace {

using testing::Append;
using testing::Box;

TEST(MeshOrientation, OneReversedTriangleOfABoxIsTurnedBack) {
  TriMesh m = Box({0, 0, 0}, {1, 2, 3});
  std::swap(m.triangles[7][1], m.triangles[7][2]);
  const OrientationPlan p = PlanConsistentOrientation(m, false);
  EXPECT_EQ(p.repeated_edges, 3u);  // each of its edges now runs like its neighbour's
  EXPECT_EQ(p.flipped, 1u);
  EXPECT_TRUE(p.flip[7]);
  EXPECT_EQ(p.repeated_after, 0u);
  EXPECT_EQ(p.pieces, 1u);
  EXPECT_EQ(p.closed_pieces, 1u);
  EXPECT_EQ(p.non_orientable, 0u);
}

TEST(MeshOrientation, ClosedPieceFacingInwardsIsTurnedOutwards) {
  TriMesh m = Box({0, 0, 0}, {1, 1, 1});
  Append(m, Box({3, 0, 0}, {4, 1, 1}));
  for (std::size_t t = 12; t < 24; ++t) std::swap(m.triangles[t][1], m.triangles[t][2]);
  const OrientationPlan p = PlanConsistentOrientation(m, false);
  EXPECT_EQ(p.repeated_edges, 0u);  // consistent, but the second box faces inwards
  EXPECT_EQ(p.pieces, 2u);
  EXPECT_EQ(p.turned_outwards, 1u);
  EXPECT_EQ(p.flipped, 12u);
  for (std::size_t t = 0; t < 24; ++t) EXPECT_EQ(p.flip[t], t >= 12) << t;
}

TEST(MeshOrientation, OpenPieceKeepsTheWayMostOfItsFacesFace) {
  TriMesh m = Box({0, 0, 0}, {1, 1, 1});
  m.triangles.erase(m.triangles.begin(), m.triangles.begin() + 2);  // no bottom
  std::swap(m.triangles[0][1], m.triangles[0][2]);
  const OrientationPlan p = PlanConsistentOrientation(m, false);
  EXPECT_EQ(p.closed_pieces, 0u);
  EXPECT_EQ(p.flipped, 1u);
  EXPECT_TRUE(p.flip[0]);
}

TEST(MeshOrientation, StlCornersAreJoinedByCoordinatesOnlyWhenWelding) {
  const TriMesh box = Box({0, 0, 0}, {1, 1, 1});
  TriMesh soup;  // every triangle with corners of its own, as an STL file stores them
  for (const Triangle& t : box.triangles) {
    const auto b = static_cast<std::int32_t>(soup.vertices.size());
    for (std::int32_t i : t) soup.vertices.push_back(box.vertices[static_cast<std::size_t>(i)]);
    soup.triangles.push_back({b, b + 1, b + 2});
  }
  std::swap(soup.triangles[3][1], soup.triangles[3][2]);
  EXPECT_EQ(PlanConsistentOrientation(soup, false).flipped, 0u);  // twelve separate pieces
  const OrientationPlan welded = PlanConsistentOrientation(soup, true);
  EXPECT_EQ(welded.pieces, 1u);
  EXPECT_EQ(welded.flipped, 1u);
  EXPECT_TRUE(welded.flip[3]);
}

TEST(MeshOrientation, AnEdgeOfThreeFacesCannotBeRepaired) {
  TriMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};  // edge 0-1 in three triangles
  const OrientationPlan p = PlanConsistentOrientation(m, false);
  EXPECT_GT(p.repeated_after, 0u);
}

TEST(MeshOrientation, ReversedObjFacesKeepTheirFirstCornerAndEverythingElse) {
  const std::string obj =
      "# quad and triangle\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nvt 0 0\r\n"
      "f 1/1 2/1 3/1 4/1\r\nf 1 3 2\r\n";
  EXPECT_EQ(ReverseObjFaces(obj, {true, true, false}, "q.obj"),
            "# quad and triangle\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nvt 0 0\r\n"
            "f 1/1 4/1 3/1 2/1\r\nf 1 3 2\r\n");
  // The fanned quad reversed keeps its diagonal 1-3: the same two triangles, both reversed.
  const TriMesh m = ParseObj(ReverseObjFaces(obj, {true, true, false}, "q.obj"), "q.obj");
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 3, 2}));
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 1}));
  EXPECT_THROW(ReverseObjFaces(obj, {true, true}, "q.obj"), InputError);
  EXPECT_THROW(ReverseObjFaces(obj, {true, true, false, false}, "q.obj"), InputError);
}

}  // namespace
}  // namespace urlab::convert
