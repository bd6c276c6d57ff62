#include "sampling.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry.h"

namespace urlab::convert::internal {

std::int32_t VoxelGrid::At(const Vec3& p) const {
  const double fi = std::floor((p[0] - origin[0]) / h);
  const double fj = std::floor((p[1] - origin[1]) / h);
  const double fk = std::floor((p[2] - origin[2]) / h);
  if (!(fi >= 0 && fj >= 0 && fk >= 0 && fi < nx && fj < ny && fk < nz)) return -1;
  return Index(static_cast<int>(fi), static_cast<int>(fj), static_cast<int>(fk));
}

VoxelGrid Voxelize(const TriMesh& mesh, const Bounds& box, int resolution) {
  VoxelGrid g;
  const Vec3 size = box.Size();
  const double longest = std::max({size[0], size[1], size[2]});
  g.h = longest / resolution;
  g.nx = std::max(1, static_cast<int>(std::ceil(size[0] / g.h)));
  g.ny = std::max(1, static_cast<int>(std::ceil(size[1] / g.h)));
  g.nz = std::max(1, static_cast<int>(std::ceil(size[2] / g.h)));
  const Vec3 span{g.nx * g.h, g.ny * g.h, g.nz * g.h};
  g.origin = box.Center() - span * 0.5;
  // One ray along +z per column; crossings with their direction (winding number).
  std::vector<std::vector<std::pair<double, int>>> hits(static_cast<std::size_t>(g.nx * g.ny));
  // A tiny offset keeps rays off shared edges and vertices of axis-aligned meshes.
  const double jx = 1.234567e-4 * g.h, jy = 2.345678e-4 * g.h;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Vec3& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    const double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if (nz == 0) continue;
    const double x0 = std::min({a[0], b[0], c[0]}), x1 = std::max({a[0], b[0], c[0]});
    const double y0 = std::min({a[1], b[1], c[1]}), y1 = std::max({a[1], b[1], c[1]});
    const int i0 = std::max(0, static_cast<int>(std::ceil((x0 - g.origin[0] - jx) / g.h - 0.5)));
    const int i1 =
        std::min(g.nx - 1, static_cast<int>(std::floor((x1 - g.origin[0] - jx) / g.h - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((y0 - g.origin[1] - jy) / g.h - 0.5)));
    const int j1 =
        std::min(g.ny - 1, static_cast<int>(std::floor((y1 - g.origin[1] - jy) / g.h - 0.5)));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const double px = g.origin[0] + (i + 0.5) * g.h + jx;
        const double py = g.origin[1] + (j + 0.5) * g.h + jy;
        // Barycentric coordinates in the xy projection.
        const double w0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) / nz;
        const double w1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) / nz;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double z = w0 * a[2] + w1 * b[2] + w2 * c[2];
        hits[static_cast<std::size_t>(j * g.nx + i)].push_back({z, nz < 0 ? 1 : -1});
      }
    }
  }
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      auto& h = hits[static_cast<std::size_t>(j * g.nx + i)];
      if (h.empty()) continue;
      std::sort(h.begin(), h.end());
      // A ray through an edge shared by two triangles hits both: count such a crossing once.
      h.erase(std::unique(h.begin(), h.end(),
                          [&](const std::pair<double, int>& a, const std::pair<double, int>& b) {
                            return a.second == b.second &&
                                   std::abs(a.first - b.first) <= 1e-9 * g.h;
                          }),
              h.end());
      std::size_t next = 0;
      int winding = 0;
      for (int k = 0; k < g.nz; ++k) {
        const double z = g.origin[2] + (k + 0.5) * g.h;
        while (next < h.size() && h[next].first < z) winding += h[next++].second;
        if (winding > 0) g.interior.push_back(g.Index(i, j, k));
      }
    }
  }
  std::sort(g.interior.begin(), g.interior.end());
  return g;
}

// Surface samples spread by area with a low-discrepancy pattern (deterministic).
std::vector<SurfaceSample> SampleSurface(const TriMesh& mesh, int count) {
  const double total = SurfaceArea(mesh);
  std::vector<SurfaceSample> out;
  if (!(total > 0)) return out;
  out.reserve(static_cast<std::size_t>(count) + mesh.triangles.size());
  double carry = 0;
  std::uint64_t n = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(mesh.triangles[t][0])];
    const Vec3& b = mesh.vertices[static_cast<std::size_t>(mesh.triangles[t][1])];
    const Vec3& c = mesh.vertices[static_cast<std::size_t>(mesh.triangles[t][2])];
    carry += 0.5 * Norm(Cross(b - a, c - a)) / total * count;
    const int k = static_cast<int>(carry);
    carry -= k;
    for (int i = 0; i < k; ++i, ++n) {
      double u = std::fmod(0.5 + static_cast<double>(n) * 0.7548776662466927, 1.0);
      double v = std::fmod(0.5 + static_cast<double>(n) * 0.5698402909980532, 1.0);
      if (u + v > 1) {
        u = 1 - u;
        v = 1 - v;
      }
      out.push_back({a + (b - a) * u + (c - a) * v, static_cast<std::int32_t>(t)});
    }
  }
  return out;
}

// ---- inside test ----

InsideTest::InsideTest(const TriMesh& mesh, int cells)
    : mesh_(std::make_shared<const TriMesh>(mesh)) {
  const Bounds b = ComputeBounds(mesh);
  const Vec3 size = b.Size();
  h_ = std::max({size[0], size[1], 1e-12}) / std::max(cells, 1);
  nx_ = std::max(1, static_cast<int>(std::ceil(size[0] / h_)) + 1);
  ny_ = std::max(1, static_cast<int>(std::ceil(size[1] / h_)) + 1);
  origin_ = b.min;
  std::vector<std::vector<std::int32_t>> lists(static_cast<std::size_t>(nx_ * ny_));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (std::int32_t v : mesh.triangles[t]) {
      const Vec3& p = mesh.vertices[static_cast<std::size_t>(v)];
      x0 = std::min(x0, p[0]);
      x1 = std::max(x1, p[0]);
      y0 = std::min(y0, p[1]);
      y1 = std::max(y1, p[1]);
    }
    const int i0 = static_cast<int>(
        std::clamp(std::floor((x0 - origin_[0]) / h_), 0.0, static_cast<double>(nx_ - 1)));
    const int i1 = static_cast<int>(
        std::clamp(std::floor((x1 - origin_[0]) / h_), 0.0, static_cast<double>(nx_ - 1)));
    const int j0 = static_cast<int>(
        std::clamp(std::floor((y0 - origin_[1]) / h_), 0.0, static_cast<double>(ny_ - 1)));
    const int j1 = static_cast<int>(
        std::clamp(std::floor((y1 - origin_[1]) / h_), 0.0, static_cast<double>(ny_ - 1)));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        lists[static_cast<std::size_t>(j * nx_ + i)].push_back(static_cast<std::int32_t>(t));
      }
    }
  }
  start_.push_back(0);
  for (const auto& l : lists) {
    tris_.insert(tris_.end(), l.begin(), l.end());
    start_.push_back(static_cast<std::uint32_t>(tris_.size()));
  }
}

bool InsideTest::Inside(const Vec3& p) const {
  if (!mesh_) return false;
  const double fi = std::floor((p[0] - origin_[0]) / h_);
  const double fj = std::floor((p[1] - origin_[1]) / h_);
  if (!(fi >= 0 && fj >= 0 && fi < nx_ && fj < ny_)) return false;
  const auto cell = static_cast<std::size_t>(static_cast<int>(fj) * nx_ + static_cast<int>(fi));
  std::vector<std::pair<double, int>> hits;
  for (std::uint32_t k = start_[cell]; k < start_[cell + 1]; ++k) {
    const Triangle& t = mesh_->triangles[static_cast<std::size_t>(tris_[k])];
    const Vec3& a = mesh_->vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = mesh_->vertices[static_cast<std::size_t>(t[1])];
    const Vec3& c = mesh_->vertices[static_cast<std::size_t>(t[2])];
    const double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if (nz == 0) continue;
    const double w0 = ((b[0] - p[0]) * (c[1] - p[1]) - (b[1] - p[1]) * (c[0] - p[0])) / nz;
    const double w1 = ((c[0] - p[0]) * (a[1] - p[1]) - (c[1] - p[1]) * (a[0] - p[0])) / nz;
    const double w2 = 1 - w0 - w1;
    if (w0 < 0 || w1 < 0 || w2 < 0) continue;
    const double z = w0 * a[2] + w1 * b[2] + w2 * c[2];
    if (z > p[2]) hits.push_back({z, nz < 0 ? 1 : -1});
  }
  std::sort(hits.begin(), hits.end());
  hits.erase(std::unique(hits.begin(), hits.end(),
                         [](const std::pair<double, int>& x, const std::pair<double, int>& y) {
                           return x.second == y.second && std::abs(x.first - y.first) <= 1e-12;
                         }),
             hits.end());
  // Crossings above p: leaving through a face facing up (-1) means p was inside.
  int winding = 0;
  for (const auto& hit : hits) winding -= hit.second;
  return winding > 0;
}

// ---- distance to a surface ----

struct SurfaceDistance::Tree {
  struct Node {
    Bounds box;
    std::int32_t left = -1, right = -1;  // children, or -1 for a leaf
    std::uint32_t begin = 0, end = 0;    // leaf: triangles order[begin..end)
  };
  const TriMesh* mesh = nullptr;
  std::vector<Node> nodes;
  std::vector<std::int32_t> order;
  std::vector<Vec3> centre;

  Bounds BoxOf(std::uint32_t b, std::uint32_t e) const {
    Bounds box;
    bool any = false;
    for (std::uint32_t i = b; i < e; ++i) {
      for (std::int32_t v : mesh->triangles[static_cast<std::size_t>(order[i])]) {
        const Vec3& p = mesh->vertices[static_cast<std::size_t>(v)];
        for (int k = 0; k < 3; ++k) {
          box.min[k] = any ? std::min(box.min[k], p[k]) : p[k];
          box.max[k] = any ? std::max(box.max[k], p[k]) : p[k];
        }
        any = true;
      }
    }
    return box;
  }

  std::int32_t Build(std::uint32_t b, std::uint32_t e) {
    const auto id = static_cast<std::int32_t>(nodes.size());
    nodes.push_back({BoxOf(b, e), -1, -1, b, e});
    if (e - b <= 8) return id;
    const Vec3 size = nodes[static_cast<std::size_t>(id)].box.Size();
    const int axis = size[0] >= size[1] && size[0] >= size[2] ? 0 : size[1] >= size[2] ? 1 : 2;
    const std::uint32_t mid = b + (e - b) / 2;
    std::nth_element(order.begin() + b, order.begin() + mid, order.begin() + e,
                     [&](std::int32_t x, std::int32_t y) {
                       return centre[static_cast<std::size_t>(x)][axis] <
                              centre[static_cast<std::size_t>(y)][axis];
                     });
    const std::int32_t l = Build(b, mid);
    const std::int32_t r = Build(mid, e);
    nodes[static_cast<std::size_t>(id)].left = l;
    nodes[static_cast<std::size_t>(id)].right = r;
    return id;
  }

  static double BoxDistance2(const Bounds& b, const Vec3& p) {
    double d = 0;
    for (int k = 0; k < 3; ++k) {
      const double e = std::max({b.min[k] - p[k], 0.0, p[k] - b.max[k]});
      d += e * e;
    }
    return d;
  }

  void Query(std::int32_t id, const Vec3& p, double* best) const {
    const Node& n = nodes[static_cast<std::size_t>(id)];
    if (BoxDistance2(n.box, p) >= *best) return;
    if (n.left < 0) {
      for (std::uint32_t i = n.begin; i < n.end; ++i) {
        const Triangle& t = mesh->triangles[static_cast<std::size_t>(order[i])];
        *best = std::min(*best,
                         PointTriangleDistance2(p, mesh->vertices[static_cast<std::size_t>(t[0])],
                                                mesh->vertices[static_cast<std::size_t>(t[1])],
                                                mesh->vertices[static_cast<std::size_t>(t[2])]));
      }
      return;
    }
    const double dl = BoxDistance2(nodes[static_cast<std::size_t>(n.left)].box, p);
    const double dr = BoxDistance2(nodes[static_cast<std::size_t>(n.right)].box, p);
    if (dl < dr) {
      Query(n.left, p, best);
      Query(n.right, p, best);
    } else {
      Query(n.right, p, best);
      Query(n.left, p, best);
    }
  }
};

SurfaceDistance::SurfaceDistance(const TriMesh& mesh) : tree_(std::make_unique<Tree>()) {
  tree_->mesh = &mesh;
  tree_->order.resize(mesh.triangles.size());
  tree_->centre.resize(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    tree_->order[i] = static_cast<std::int32_t>(i);
    const Triangle& t = mesh.triangles[i];
    tree_->centre[i] = (mesh.vertices[static_cast<std::size_t>(t[0])] +
                        mesh.vertices[static_cast<std::size_t>(t[1])] +
                        mesh.vertices[static_cast<std::size_t>(t[2])]) *
                       (1.0 / 3);
  }
  if (!mesh.triangles.empty()) {
    tree_->Build(0, static_cast<std::uint32_t>(mesh.triangles.size()));
  }
}

SurfaceDistance::~SurfaceDistance() = default;

double SurfaceDistance::Distance(const Vec3& p) const {
  if (tree_->nodes.empty()) return std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  tree_->Query(0, p, &best);
  return std::sqrt(best);
}

}  // namespace urlab::convert::internal
