#pragma once
// Triangle meshes as the convert layer sees them (MuJoCo frame, metres): plain vertex and index
// arrays, their measures, a repair pass that reports what it changed, and content hashes used
// as cache keys. Thread: plain values and pure functions; any thread that owns the mesh.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace urlab::convert {

using Vec3 = std::array<double, 3>;
using Triangle = std::array<std::int32_t, 3>;

struct TriMesh {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;  // counter-clockwise seen from outside
  bool empty() const { return triangles.empty(); }
};

struct Bounds {
  Vec3 min{0, 0, 0}, max{0, 0, 0};
  Vec3 Size() const { return {max[0] - min[0], max[1] - min[1], max[2] - min[2]}; }
  Vec3 Center() const;
  double Diagonal() const;
};

// Bounds of the vertices that triangles use (all zero for an empty mesh).
Bounds ComputeBounds(const TriMesh& mesh);
// Enclosed volume by the divergence theorem (negative when the triangles face inwards; only
// meaningful for a closed mesh).
double SignedVolume(const TriMesh& mesh);
double SurfaceArea(const TriMesh& mesh);

// What CleanMesh found and changed.
struct CleanReport {
  std::size_t input_vertices = 0, input_triangles = 0;
  std::size_t non_finite_vertices = 0;   // triangles using them were dropped
  std::size_t bad_indices = 0;           // triangles naming a vertex that does not exist
  std::size_t welded_vertices = 0;       // exact duplicates merged
  std::size_t degenerate_triangles = 0;  // repeated vertex or zero area, dropped
  std::size_t duplicate_triangles = 0;   // same three vertices as another, dropped
  std::size_t boundary_edges = 0;        // edges of one triangle: the mesh is open
  std::size_t non_manifold_edges = 0;    // edges of three or more triangles
  bool flipped = false;                  // closed mesh facing inwards, turned outwards
  // No boundary edge: a solid (possibly several touching or overlapping closed pieces, whose
  // shared edges count as non-manifold).
  bool closed() const { return boundary_edges == 0; }
  // One line: "12 degenerate triangles dropped, open (34 boundary edges)" ("clean" if nothing).
  std::string Summary() const;
};

// Repairs `mesh` in place: drops triangles with non-finite or missing vertices, welds exactly
// equal vertices, drops degenerate and duplicate triangles and unused vertices, and turns a
// mesh without boundary edges and with negative volume outwards. Never throws.
CleanReport CleanMesh(TriMesh& mesh);

// Consistent face orientation (the repair MuJoCo 2.2.2 needs for meshes 3.x loads): two
// triangles sharing an edge must run along it in opposite directions. Triangles are connected
// through edges of exactly two triangles; each connected piece is oriented like its first
// triangle, then turned outwards when it is closed (no boundary edge) and encloses a negative
// volume, or else kept the way most of its triangles already face. Vertices are the mesh's
// indices, or with `weld_equal_vertices` exactly equal coordinates (an STL file's corners).
struct OrientationPlan {
  std::vector<bool> flip;           // per triangle: reverse its winding
  std::size_t flipped = 0;          // triangles to reverse
  std::size_t pieces = 0;           // connected pieces
  std::size_t closed_pieces = 0;    // pieces without boundary edges
  std::size_t turned_outwards = 0;  // closed pieces turned as a whole (they faced inwards)
  std::size_t repeated_edges = 0;   // directed edges used twice before the repair
  std::size_t repeated_after = 0;   // ... and after it (non-manifold or non-orientable)
  std::size_t non_orientable = 0;   // pieces whose triangles cannot all agree (Moebius)
  bool needed() const { return flipped > 0; }
};
OrientationPlan PlanConsistentOrientation(const TriMesh& mesh, bool weld_equal_vertices);

// Vertex clustering on a grid of `cells` cells along the longest side: a bounded-time
// simplification for very large meshes (the result is cleaned).
TriMesh ClusterVertices(const TriMesh& mesh, int cells);

// ClusterVertices on a grid from `start_cells` down (to 16 cells at the coarsest) until at most
// `max_triangles` remain; `cells_used` (optional) gets that grid. Each step shrinks the grid by a
// quarter, or with `aim` by as much as the triangle count says (a surface's count goes about
// with the square of the grid), which ends closer below the limit in fewer passes. A mesh
// already small enough comes back unchanged (cells_used 0).
TriMesh SimplifyToAtMost(const TriMesh& mesh, std::size_t max_triangles, int start_cells, bool aim,
                         int* cells_used = nullptr);

// Makes every directed edge appear at most once, which MuJoCo 2.2.2's orientation check needs:
// faces are oriented consistently where the mesh allows (PlanConsistentOrientation), then each
// triangle that would run an edge the same way as an earlier one (a non-manifold edge, as
// vertex clustering leaves where thin parts collapse) is dropped, and unused vertices removed.
// Returns the number of triangles dropped.
std::size_t MakeEdgesOrientable(TriMesh& mesh);

// 64-bit FNV-1a of bytes, continuing from `seed` (for cache keys, not security).
std::uint64_t HashBytes(std::string_view bytes, std::uint64_t seed = 0xcbf29ce484222325ull);
// Hash of a mesh's vertex and index arrays.
std::uint64_t HashMesh(const TriMesh& mesh);
// 16 lowercase hex digits.
std::string HashHex(std::uint64_t hash);

}  // namespace urlab::convert
