#pragma once
// Surface samples, interior voxels and point-to-surface distance for the convert layer
// (internal). Thread: pure functions / immutable after construction.
#include <memory>
#include <vector>

#include "urlab/convert/mesh.h"

namespace urlab::convert::internal {

struct SurfaceSample {
  Vec3 p;
  std::int32_t tri;
};

// About `count` points spread over the surface by area with a low-discrepancy pattern
// (deterministic).
std::vector<SurfaceSample> SampleSurface(const TriMesh& mesh, int count);

// Voxel centres on a grid of cubes of side h over `box` (origin at its centre minus half the
// grid) whose centre is inside the closed mesh (winding number of one ray along +z).
struct VoxelGrid {
  Vec3 origin{0, 0, 0};
  double h = 1;
  int nx = 0, ny = 0, nz = 0;
  std::vector<std::int32_t> interior;  // sorted indices of voxels whose centre is inside
  std::int32_t Index(int i, int j, int k) const { return (k * ny + j) * nx + i; }
  Vec3 Centre(std::int32_t idx) const {
    const int i = idx % nx, j = (idx / nx) % ny, k = idx / (nx * ny);
    return {origin[0] + (i + 0.5) * h, origin[1] + (j + 0.5) * h, origin[2] + (k + 0.5) * h};
  }
  // The voxel holding p, or -1 outside the grid.
  std::int32_t At(const Vec3& p) const;
  double VoxelVolume() const { return h * h * h; }
};
VoxelGrid Voxelize(const TriMesh& mesh, const Bounds& box, int resolution);

// Exact inside test for a closed mesh: the winding number of a ray along +z, against only the
// triangles whose xy bounds cover the query's cell of an xy grid.
class InsideTest {
 public:
  InsideTest() = default;
  InsideTest(const TriMesh& mesh, int cells);
  bool Inside(const Vec3& p) const;

 private:
  std::shared_ptr<const TriMesh> mesh_;  // a copy: the test may outlive the caller's mesh
  Vec3 origin_{0, 0, 0};
  double h_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> start_;
  std::vector<std::int32_t> tris_;
};

// Closest distance from points to a triangle mesh (an AABB tree over the triangles).
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const TriMesh& mesh);
  ~SurfaceDistance();
  double Distance(const Vec3& p) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace urlab::convert::internal
