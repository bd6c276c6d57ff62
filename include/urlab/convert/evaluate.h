#pragma once
// Quality of a set of convex hulls standing for a mesh, independent of how they were made (our
// decomposition, Bullet's HACD, a single hull), all as fractions of the mesh's bounding-box
// diagonal or volume:
//  - concavity: the deepest mesh surface point inside a hull (how far a hull fills what the
//    mesh leaves open: a mug's opening under a single hull), or the volume term
//    volume_weight * cbrt(3 |V(union) - V(mesh)| / 4 pi) when larger;
//  - volume_error: |union of hulls XOR mesh| / V(mesh) on a voxel grid;
//  - hausdorff: the larger of the farthest union-boundary point from the mesh surface and the
//    farthest mesh surface point outside every hull from the hulls.
// Thread: any; pure.
#include <vector>

#include "urlab/convert/mesh.h"

namespace urlab::convert {

struct HullSetMetrics {
  double concavity = 0;
  double volume_error = 0;
  double hausdorff = 0;
  double union_volume = 0;  // m^3 (voxel estimate)
  double mesh_volume = 0;   // m^3 (exact, closed meshes)
};

struct EvaluateOptions {
  int samples = 20000;  // surface samples on the mesh and on the hulls
  int resolution = 80;  // voxels along the longest side for the volumes
  double volume_weight = 0.3;
};

// Metrics of `hulls` against `mesh` (cleaned first). Hulls with fewer than four points are
// ignored.
HullSetMetrics EvaluateHulls(TriMesh mesh, const std::vector<TriMesh>& hulls,
                             const EvaluateOptions& options = {});

}  // namespace urlab::convert
