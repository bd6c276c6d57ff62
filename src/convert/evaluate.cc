#include "urlab/convert/evaluate.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "geometry.h"
#include "hull.h"
#include "sampling.h"

namespace urlab::convert {

HullSetMetrics EvaluateHulls(TriMesh mesh, const std::vector<TriMesh>& hulls,
                             const EvaluateOptions& options) {
  HullSetMetrics m;
  const CleanReport clean = CleanMesh(mesh);
  if (mesh.empty()) return m;
  const Bounds mb = ComputeBounds(mesh);
  const double diag = mb.Diagonal();
  if (!(diag > 0)) return m;
  std::vector<internal::Hull> hs;
  Bounds box = mb;
  for (const TriMesh& h : hulls) {
    std::optional<internal::Hull> hull = internal::ComputeHull(h.vertices, true);
    if (!hull) continue;
    const Bounds hb = ComputeBounds(hull->mesh);
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], hb.min[k]);
      box.max[k] = std::max(box.max[k], hb.max[k]);
    }
    hs.push_back(std::move(*hull));
  }
  // Volumes on one grid over the mesh and the hulls.
  const internal::VoxelGrid grid = internal::Voxelize(mesh, box, options.resolution);
  std::size_t in_union = 0, xor_count = 0;
  const auto cells = static_cast<std::int32_t>(grid.nx * grid.ny * grid.nz);
  for (std::int32_t v = 0; v < cells; ++v) {
    const Vec3 c = grid.Centre(v);
    bool u = false;
    for (const internal::Hull& h : hs) {
      if (h.Depth(c) >= 0) {
        u = true;
        break;
      }
    }
    const bool in_mesh = std::binary_search(grid.interior.begin(), grid.interior.end(), v);
    in_union += u;
    xor_count += u != in_mesh;
  }
  m.union_volume = static_cast<double>(in_union) * grid.VoxelVolume();
  m.mesh_volume = clean.closed() ? SignedVolume(mesh) : 0;
  const double mesh_vox = static_cast<double>(grid.interior.size()) * grid.VoxelVolume();
  if (mesh_vox > 0) m.volume_error = static_cast<double>(xor_count) * grid.VoxelVolume() / mesh_vox;

  // Mesh surface points: how deep inside a hull (concavity), how far outside all (Hausdorff).
  double depth = 0, outside = 0;
  for (const internal::SurfaceSample& s : internal::SampleSurface(mesh, options.samples)) {
    double deepest = -std::numeric_limits<double>::infinity();
    for (const internal::Hull& h : hs) deepest = std::max(deepest, h.Depth(s.p));
    if (deepest >= 0) {
      depth = std::max(depth, deepest);
    } else {
      outside = std::max(outside, -deepest);
    }
  }
  // Points of the union's boundary: hull surface points inside no other hull.
  const internal::SurfaceDistance to_mesh(mesh);
  double bulge = 0;
  for (std::size_t i = 0; i < hs.size(); ++i) {
    const int count = std::max(200, options.samples / static_cast<int>(hs.size()));
    for (const internal::SurfaceSample& s : internal::SampleSurface(hs[i].mesh, count)) {
      bool covered = false;
      for (std::size_t j = 0; j < hs.size() && !covered; ++j) {
        covered = j != i && hs[j].Depth(s.p) > 1e-6 * diag;
      }
      if (!covered) bulge = std::max(bulge, to_mesh.Distance(s.p));
    }
  }
  const double volume_term =
      options.volume_weight *
      std::cbrt(3 * std::abs(m.union_volume - mesh_vox) / (4 * std::numbers::pi));
  m.concavity = std::max(depth, clean.closed() ? volume_term : 0) / diag;
  m.hausdorff = std::max(bulge, outside) / diag;
  return m;
}

}  // namespace urlab::convert
