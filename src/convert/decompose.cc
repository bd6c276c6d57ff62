#include "urlab/convert/decompose.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <unordered_map>

#include "geometry.h"
#include "hull.h"
#include "parallel.h"
#include "sampling.h"
#include "urlab/core/error.h"

namespace urlab::convert {

namespace {

using internal::ComputeHull;
using internal::Hull;

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Points used to evaluate a part: hull inputs and surface probes are thinned to these counts
// (the final hulls use every point).
constexpr std::size_t kEvalHullPoints = 3000;
constexpr std::size_t kEvalProbes = 3000;
// Points a cut's score thins to: the cut to make, and the further cuts a blind cut's look ahead
// only ranks (see BestCut).
struct Detail {
  std::size_t hull_points, probes;
};
constexpr Detail kChoose{kEvalHullPoints, kEvalProbes};
constexpr Detail kRank{kEvalHullPoints / 3, kEvalProbes / 3};
// Clipping tolerance in normalised units (the mesh's diagonal is 1).
constexpr double kPlaneEps = 1e-9;

// Points p with Dot(n, p) <= d are kept.
struct Plane {
  Vec3 n;
  double d;
};

using Sample = internal::SurfaceSample;

using Grid = internal::VoxelGrid;

// A piece of the mesh inside a convex cell: the clipped triangles (convex polygons, each from
// one input triangle), the surface samples and interior voxels inside the cell, and the cell.
struct Part {
  std::vector<Vec3> verts;
  std::vector<std::int32_t> idx;    // polygon vertex indices, polygon after polygon
  std::vector<std::uint32_t> offs;  // polygon p is idx[offs[p]..offs[p+1])
  std::vector<std::int32_t> tri;    // input triangle of each polygon
  std::vector<Sample> samples;
  std::vector<std::int32_t> voxels;  // sorted
  std::vector<Plane> cell;
  std::size_t polygons() const { return tri.size(); }
};

// What the merge phase keeps of a part: everything its hull and concavity need.
struct Piece {
  std::vector<Vec3> hull_points;
  std::vector<Vec3> probes;  // surface points
  std::vector<Plane> caps;   // planes of the part's cut faces
  std::size_t voxel_count = 0;
  double concavity = 0;
  Bounds box;
};

struct Context {
  DecomposeOptions options;
  Grid grid;
  bool solid = true;            // closed mesh: the volume term applies
  Bounds box;                   // normalised mesh bounds, slightly enlarged
  Bounds mesh_box;              // normalised mesh bounds
  internal::InsideTest inside;  // exact point-in-mesh test (solid meshes)
  // Per axis, coordinates of flat faces (features of CAD-like meshes): cutting
  // exactly there leaves no sliver of one feature on the other side.
  std::array<std::vector<double>, 3> features;
  int threads = 1;
};

// Thins `points` to about `max` by keeping, per cell of a grid over them, the point farthest
// from their centroid (keeps the extremes a hull needs). Deterministic.
std::vector<Vec3> Thin(const std::vector<Vec3>& points, std::size_t max) {
  if (points.size() <= max) return points;
  Bounds b{points[0], points[0]};
  Vec3 c{0, 0, 0};
  for (const Vec3& p : points) {
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], p[k]);
      b.max[k] = std::max(b.max[k], p[k]);
    }
    c = c + p;
  }
  c = c * (1.0 / static_cast<double>(points.size()));
  const int n = std::max(2, static_cast<int>(std::cbrt(static_cast<double>(max) * 0.5)) * 2);
  const Vec3 size = b.Size();
  std::unordered_map<std::int64_t, std::size_t> best;
  best.reserve(max * 2);
  std::vector<std::int64_t> order;
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::int64_t key = 0;
    for (int k = 0; k < 3; ++k) {
      const double t = size[k] > 0 ? (points[i][k] - b.min[k]) / size[k] : 0;
      key = key * (n + 1) + std::clamp(static_cast<int>(t * n), 0, n);
    }
    auto [it, fresh] = best.emplace(key, i);
    if (fresh) {
      order.push_back(key);
    } else {
      const Vec3 a = points[it->second] - c, q = points[i] - c;
      if (Dot(q, q) > Dot(a, a)) it->second = i;
    }
  }
  std::vector<Vec3> out;
  out.reserve(order.size());
  for (std::int64_t key : order) out.push_back(points[best[key]]);
  return out;
}

// Every `stride`-th element so that at most `max` remain.
template <typename T, typename F>
void Strided(const std::vector<T>& v, std::size_t max, F&& f) {
  const std::size_t stride =
      std::max<std::size_t>(1, (v.size() + max - 1) / std::max<std::size_t>(max, 1));
  for (std::size_t i = 0; i < v.size(); i += stride) f(v[i]);
}

double VolumeTerm(double hull_volume, double part_volume) {
  const double extra = std::max(0.0, hull_volume - part_volume);
  return std::cbrt(3 * extra / (4 * kPi));
}

// Distance from a query to the nearest of a fixed set of points (buckets on a uniform grid,
// searched ring by ring).
class NearestPoint {
 public:
  explicit NearestPoint(const std::vector<Vec3>& points) : points_(points) {
    if (points.empty()) return;
    box_ = {points[0], points[0]};
    for (const Vec3& p : points) {
      for (int k = 0; k < 3; ++k) {
        box_.min[k] = std::min(box_.min[k], p[k]);
        box_.max[k] = std::max(box_.max[k], p[k]);
      }
    }
    const Vec3 size = box_.Size();
    const double longest = std::max({size[0], size[1], size[2], 1e-12});
    const double cells = std::max(1.0, std::cbrt(static_cast<double>(points.size()) / 2));
    cell_ = longest / cells;
    for (int k = 0; k < 3; ++k) n_[k] = std::max(1, static_cast<int>(std::ceil(size[k] / cell_)));
    start_.assign(static_cast<std::size_t>(n_[0] * n_[1] * n_[2]) + 1, 0);
    std::vector<std::int32_t> bucket(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      bucket[i] = Bucket(Cell(points[i]));
      ++start_[static_cast<std::size_t>(bucket[i]) + 1];
    }
    for (std::size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
    order_.resize(points.size());
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < points.size(); ++i) {
      order_[fill[static_cast<std::size_t>(bucket[i])]++] = static_cast<std::uint32_t>(i);
    }
  }

  double Distance(const Vec3& q) const {
    if (points_.empty()) return kInf;
    const std::array<int, 3> c = Cell(q);
    double best2 = kInf;
    const int rings = std::max({n_[0], n_[1], n_[2]});
    for (int r = 0; r <= rings; ++r) {
      for (int i = c[0] - r; i <= c[0] + r; ++i) {
        if (i < 0 || i >= n_[0]) continue;
        for (int j = c[1] - r; j <= c[1] + r; ++j) {
          if (j < 0 || j >= n_[1]) continue;
          for (int k = c[2] - r; k <= c[2] + r; ++k) {
            if (k < 0 || k >= n_[2]) continue;
            if (std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])}) != r)
              continue;
            const auto b = static_cast<std::size_t>(Bucket({i, j, k}));
            for (std::uint32_t s = start_[b]; s < start_[b + 1]; ++s) {
              const Vec3 d = points_[order_[s]] - q;
              best2 = std::min(best2, Dot(d, d));
            }
          }
        }
      }
      // Points in later rings are at least r cells from q's (projected) cell.
      if (best2 <= (r * cell_) * (r * cell_)) break;
    }
    return std::sqrt(best2);
  }

 private:
  std::array<int, 3> Cell(const Vec3& p) const {
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      // Clamped as a double: a far query would overflow int.
      c[k] = static_cast<int>(std::clamp(std::floor((p[k] - box_.min[k]) / cell_), 0.0,
                                         static_cast<double>(n_[k] - 1)));
    }
    return c;
  }
  std::int32_t Bucket(const std::array<int, 3>& c) const {
    return (c[2] * n_[1] + c[1]) * n_[0] + c[0];
  }

  const std::vector<Vec3>& points_;
  Bounds box_;
  double cell_ = 1;
  std::array<int, 3> n_ = {1, 1, 1};
  std::vector<std::uint32_t> start_, order_;
};

// Hull surface points sampled per evaluation (the hull-to-surface term).
constexpr int kHullSamples = 800;
// A cut is blind (see BestCut) when it takes less than this fraction of a part's concavity
// above the threshold away and leaves a side above the threshold; then this many of the best
// candidates, besides the middle plane of each axis, are compared two cuts deep.
constexpr double kBlindGain = 0.25;
constexpr std::size_t kLookaheadBest = 2;

// Concavity of a part given its hull (with its mesh), CoACD's measure: the larger of the
// surface term, a symmetric distance between the part's surface and its hull's (how deep a
// surface point lies inside the hull; how far a hull point lies from the part's surface, a
// hull point on one of the part's cut faces counting as on it), and the volume term.
double Concavity(const Hull& hull, const std::vector<Vec3>& probes, std::size_t voxels,
                 const std::vector<Plane>& caps, const Context& ctx) {
  // The deepest probe. A probe matters only when deeper than the deepest so far, so its scan of
  // the planes stops at the first plane closer than that, starting from the plane that stopped
  // the previous probe (probes come surface patch by surface patch).
  double term = 0;
  std::size_t hint = 0;
  const std::size_t nplanes = hull.planes.size();
  for (const Vec3& p : probes) {
    double depth = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < nplanes; ++k) {
      const std::size_t f = (hint + k) % nplanes;
      const double v = hull.planes[f].offset - Dot(hull.planes[f].normal, p);
      if (v < depth) {
        depth = v;
        if (depth <= term) {
          hint = f;
          break;
        }
      }
    }
    term = std::max(term, depth);
  }
  const NearestPoint nearest(probes);
  for (const internal::SurfaceSample& s : internal::SampleSurface(hull.mesh, kHullSamples)) {
    bool on_cap = false;
    for (const Plane& c : caps) {
      if (std::abs(Dot(c.n, s.p) - c.d) <= 1e-7) {
        on_cap = !ctx.solid || std::binary_search(ctx.grid.interior.begin(),
                                                  ctx.grid.interior.end(), ctx.grid.At(s.p));
        if (on_cap) break;
      }
    }
    if (!on_cap) term = std::max(term, nearest.Distance(s.p));
  }
  if (!ctx.solid) return term;
  const double v = VolumeTerm(hull.volume, static_cast<double>(voxels) * ctx.grid.VoxelVolume());
  return std::max(term, ctx.options.volume_weight * v);
}

double EvaluatePiece(const Piece& piece, const Context& ctx) {
  const std::optional<Hull> hull = ComputeHull(Thin(piece.hull_points, kEvalHullPoints), true);
  if (!hull) return 0;  // flat or tiny: convex for our purpose
  return Concavity(*hull, piece.probes, piece.voxel_count, piece.caps, ctx);
}

// ---- geometry of the cell ----

bool Solve3(const Plane& a, const Plane& b, const Plane& c, Vec3* x) {
  const Vec3 bc = Cross(b.n, c.n);
  const double det = Dot(a.n, bc);
  if (std::abs(det) < 1e-12) return false;
  *x = (bc * a.d + Cross(c.n, a.n) * b.d + Cross(a.n, b.n) * c.d) * (1.0 / det);
  return true;
}

// Corners of the cell (its planes and the mesh box) that lie inside the solid: a part's hull
// needs them where three cuts meet inside the mesh.
std::vector<Vec3> InteriorCellCorners(const Part& part, const Context& ctx) {
  std::vector<Vec3> out;
  if (part.cell.size() < 1 || part.voxels.empty()) return out;
  std::vector<Plane> planes = part.cell;
  for (int k = 0; k < 3; ++k) {
    Vec3 n{0, 0, 0};
    n[k] = 1;
    planes.push_back({n, ctx.mesh_box.max[k]});
    n[k] = -1;
    planes.push_back({n, -ctx.mesh_box.min[k]});
  }
  const std::size_t m = planes.size();
  for (std::size_t a = 0; a < part.cell.size(); ++a) {
    for (std::size_t b = a + 1; b < m; ++b) {
      for (std::size_t c = b + 1; c < m; ++c) {
        Vec3 x;
        if (!Solve3(planes[a], planes[b], planes[c], &x)) continue;
        bool inside = true;
        for (const Plane& p : planes) {
          if (Dot(p.n, x) > p.d + 1e-9) {
            inside = false;
            break;
          }
        }
        if (!inside) continue;
        // In this part's solid: inside the mesh, near one of the part's voxels.
        if (!ctx.inside.Inside(x)) continue;
        bool near = false;
        for (int d = 0; d < 7 && !near; ++d) {
          Vec3 q = x;
          if (d > 0) q[(d - 1) / 2] += ((d - 1) % 2 ? -1.0 : 1.0) * ctx.grid.h;
          const std::int32_t v = ctx.grid.At(q);
          near = v >= 0 && std::binary_search(part.voxels.begin(), part.voxels.end(), v);
        }
        if (near) out.push_back(x);
      }
    }
  }
  return out;
}

Piece ToPiece(const Part& part, const Context& ctx) {
  Piece piece;
  piece.hull_points = part.verts;
  for (const Vec3& c : InteriorCellCorners(part, ctx)) piece.hull_points.push_back(c);
  if (piece.hull_points.size() < 4) {
    // A part made of cut faces only (no input surface): its voxels give its shape.
    for (std::int32_t v : part.voxels) piece.hull_points.push_back(ctx.grid.Centre(v));
  }
  Strided(part.samples, kEvalProbes, [&](const Sample& s) { piece.probes.push_back(s.p); });
  Strided(part.verts, kEvalProbes / 4, [&](const Vec3& v) { piece.probes.push_back(v); });
  piece.voxel_count = part.voxels.size();
  piece.caps = part.cell;
  if (!piece.hull_points.empty()) {
    piece.box = {piece.hull_points[0], piece.hull_points[0]};
    for (const Vec3& p : piece.hull_points) {
      for (int k = 0; k < 3; ++k) {
        piece.box.min[k] = std::min(piece.box.min[k], p[k]);
        piece.box.max[k] = std::max(piece.box.max[k], p[k]);
      }
    }
  }
  piece.concavity = EvaluatePiece(piece, ctx);
  return piece;
}

// ---- clipping ----

std::uint64_t CrossingKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

// Signed distances of the part's vertices to `plane` and their sides (-1 kept, 0 in the plane,
// +1 the other side).
void Classify(const Part& part, const Plane& plane, std::vector<double>* s,
              std::vector<int>* side) {
  s->resize(part.verts.size());
  side->resize(part.verts.size());
  for (std::size_t i = 0; i < part.verts.size(); ++i) {
    const double d = Dot(plane.n, part.verts[i]) - plane.d;
    (*s)[i] = d;
    (*side)[i] = d < -kPlaneEps ? -1 : d > kPlaneEps ? 1 : 0;
  }
}

struct Sides {
  bool lo, hi;    // the polygon reaches the kept side, the other side
  bool in_plane;  // every corner in the plane
};

// Which sides of `plane` polygon `p` reaches, given each vertex's side (-1, 0, +1). A polygon
// in the plane bounds the side its normal faces away from.
Sides PolygonSides(const Part& part, std::size_t p, const std::vector<int>& side,
                   const Plane& plane) {
  const std::uint32_t b = part.offs[p], e = part.offs[p + 1];
  Sides s{false, false, false};
  for (std::uint32_t i = b; i < e; ++i) {
    s.lo |= side[static_cast<std::size_t>(part.idx[i])] < 0;
    s.hi |= side[static_cast<std::size_t>(part.idx[i])] > 0;
  }
  if (!s.lo && !s.hi) {
    const Vec3& a = part.verts[static_cast<std::size_t>(part.idx[b])];
    const Vec3 n = Cross(part.verts[static_cast<std::size_t>(part.idx[b + 1])] - a,
                         part.verts[static_cast<std::size_t>(part.idx[b + 2])] - a);
    s.lo = Dot(n, plane.n) > 0;
    s.hi = !s.lo;
    s.in_plane = true;
  }
  return s;
}

// Splits `part` by `plane` into the kept side (`lo`, Dot(n,p) <= d) and the other (`hi`).
void Split(const Part& part, const Plane& plane, const Context& ctx, Part* lo, Part* hi) {
  const std::size_t nv = part.verts.size();
  std::vector<double> s;
  std::vector<int> side;
  Classify(part, plane, &s, &side);
  std::vector<std::int32_t> map_lo(nv, -1), map_hi(nv, -1);
  auto put = [](Part* out, std::vector<std::int32_t>& map, std::int32_t v, const Part& from) {
    std::int32_t& m = map[static_cast<std::size_t>(v)];
    if (m < 0) {
      m = static_cast<std::int32_t>(out->verts.size());
      out->verts.push_back(from.verts[static_cast<std::size_t>(v)]);
    }
    out->idx.push_back(m);
  };
  std::unordered_map<std::uint64_t, std::pair<std::int32_t, std::int32_t>> crossings;
  auto crossing = [&](std::int32_t a, std::int32_t b) {
    auto [it, fresh] =
        crossings.emplace(CrossingKey(a, b), std::pair<std::int32_t, std::int32_t>{});
    if (fresh) {
      const std::size_t ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
      const double t = s[ua] / (s[ua] - s[ub]);
      const Vec3 x = Lerp(part.verts[ua], part.verts[ub], t);
      it->second = {static_cast<std::int32_t>(lo->verts.size()),
                    static_cast<std::int32_t>(hi->verts.size())};
      lo->verts.push_back(x);
      hi->verts.push_back(x);
    }
    return it->second;
  };
  lo->offs = {0};
  hi->offs = {0};
  for (std::size_t p = 0; p < part.polygons(); ++p) {
    const std::uint32_t b = part.offs[p], e = part.offs[p + 1];
    const auto [any_lo, any_hi, in_plane] = PolygonSides(part, p, side, plane);
    if (in_plane) {
      Part* out = any_lo ? lo : hi;
      std::vector<std::int32_t>& map = any_lo ? map_lo : map_hi;
      for (std::uint32_t i = b; i < e; ++i) put(out, map, part.idx[i], part);
      out->offs.push_back(static_cast<std::uint32_t>(out->idx.size()));
      out->tri.push_back(part.tri[p]);
      continue;
    }
    const std::size_t lo_start = lo->idx.size(), hi_start = hi->idx.size();
    for (std::uint32_t i = b; i < e; ++i) {
      const std::int32_t va = part.idx[i];
      const std::int32_t vb = part.idx[i + 1 < e ? i + 1 : b];
      const int sa = side[static_cast<std::size_t>(va)], sb = side[static_cast<std::size_t>(vb)];
      if (any_lo && sa <= 0) put(lo, map_lo, va, part);
      if (any_hi && sa >= 0) put(hi, map_hi, va, part);
      if ((sa < 0 && sb > 0) || (sa > 0 && sb < 0)) {
        const auto [xl, xh] = crossing(va, vb);
        lo->idx.push_back(xl);
        hi->idx.push_back(xh);
      }
    }
    // A polygon of three corners or more is kept; a sliver that lost its area is dropped.
    auto finish = [&](Part* out, std::size_t start) {
      if (out->idx.size() - start >= 3) {
        out->offs.push_back(static_cast<std::uint32_t>(out->idx.size()));
        out->tri.push_back(part.tri[p]);
      } else {
        out->idx.resize(start);
      }
    };
    if (any_lo) finish(lo, lo_start);
    if (any_hi) finish(hi, hi_start);
  }
  for (const Sample& smp : part.samples) {
    (Dot(plane.n, smp.p) <= plane.d ? lo : hi)->samples.push_back(smp);
  }
  for (std::int32_t v : part.voxels) {
    (Dot(plane.n, ctx.grid.Centre(v)) <= plane.d ? lo : hi)->voxels.push_back(v);
  }
  lo->cell = part.cell;
  lo->cell.push_back(plane);
  hi->cell = part.cell;
  hi->cell.push_back({plane.n * -1.0, -plane.d});
}

// ---- connected pieces ----

struct UnionFind {
  std::vector<std::int32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::int32_t Find(std::int32_t x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      parent[static_cast<std::size_t>(x)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  }
  void Union(std::int32_t a, std::int32_t b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  }
};

// Splits a part into its connected pieces: surface polygons sharing vertices, voxels sharing
// faces, and surface vertices lying in a voxel of the part are connected. Pieces with no
// surface and only a few voxels are dropped.
std::vector<Part> Components(Part part, const Context& ctx) {
  const std::size_t nv = part.verts.size(), nw = part.voxels.size();
  UnionFind uf(nv + nw);
  for (std::size_t p = 0; p < part.polygons(); ++p) {
    for (std::uint32_t i = part.offs[p] + 1; i < part.offs[p + 1]; ++i) {
      uf.Union(part.idx[part.offs[p]], part.idx[i]);
    }
  }
  auto voxel_slot = [&](std::int32_t v) -> std::int32_t {
    auto it = std::lower_bound(part.voxels.begin(), part.voxels.end(), v);
    if (it == part.voxels.end() || *it != v) return -1;
    return static_cast<std::int32_t>(nv + static_cast<std::size_t>(it - part.voxels.begin()));
  };
  const Grid& g = ctx.grid;
  for (std::size_t w = 0; w < nw; ++w) {
    const std::int32_t v = part.voxels[w];
    const int i = v % g.nx, j = (v / g.nx) % g.ny, k = v / (g.nx * g.ny);
    const std::int32_t self = static_cast<std::int32_t>(nv + w);
    if (i + 1 < g.nx) {
      if (const std::int32_t o = voxel_slot(v + 1); o >= 0) uf.Union(self, o);
    }
    if (j + 1 < g.ny) {
      if (const std::int32_t o = voxel_slot(v + g.nx); o >= 0) uf.Union(self, o);
    }
    if (k + 1 < g.nz) {
      if (const std::int32_t o = voxel_slot(v + g.nx * g.ny); o >= 0) uf.Union(self, o);
    }
  }
  if (nw) {
    for (std::size_t i = 0; i < nv; ++i) {
      const Vec3& p = part.verts[i];
      for (int d = 0; d < 7; ++d) {
        Vec3 q = p;
        if (d > 0) q[(d - 1) / 2] += ((d - 1) % 2 ? -0.5 : 0.5) * g.h;
        const std::int32_t v = g.At(q);
        if (v < 0) continue;
        if (const std::int32_t o = voxel_slot(v); o >= 0) uf.Union(static_cast<std::int32_t>(i), o);
      }
    }
  }
  // Component ids in order of first appearance (deterministic).
  std::unordered_map<std::int32_t, int> comp_of_root;
  std::vector<int> comp(nv + nw, -1);
  int ncomp = 0;
  for (std::size_t i = 0; i < nv + nw; ++i) {
    const std::int32_t r = uf.Find(static_cast<std::int32_t>(i));
    auto [it, fresh] = comp_of_root.emplace(r, ncomp);
    if (fresh) ++ncomp;
    comp[i] = it->second;
  }
  if (ncomp <= 1) return {std::move(part)};
  std::vector<Part> out(static_cast<std::size_t>(ncomp));
  std::vector<std::int32_t> remap(nv, -1);
  std::unordered_map<std::int32_t, int> comp_of_tri;
  for (Part& o : out) {
    o.offs = {0};
    o.cell = part.cell;
  }
  for (std::size_t p = 0; p < part.polygons(); ++p) {
    const int c = comp[static_cast<std::size_t>(part.idx[part.offs[p]])];
    Part& o = out[static_cast<std::size_t>(c)];
    for (std::uint32_t i = part.offs[p]; i < part.offs[p + 1]; ++i) {
      std::int32_t& m = remap[static_cast<std::size_t>(part.idx[i])];
      if (m < 0) {
        m = static_cast<std::int32_t>(o.verts.size());
        o.verts.push_back(part.verts[static_cast<std::size_t>(part.idx[i])]);
      }
      o.idx.push_back(m);
    }
    o.offs.push_back(static_cast<std::uint32_t>(o.idx.size()));
    o.tri.push_back(part.tri[p]);
    comp_of_tri[part.tri[p]] = c;
  }
  for (const Sample& s : part.samples) {
    auto it = comp_of_tri.find(s.tri);
    if (it != comp_of_tri.end()) out[static_cast<std::size_t>(it->second)].samples.push_back(s);
  }
  for (std::size_t w = 0; w < nw; ++w) {
    out[static_cast<std::size_t>(comp[nv + w])].voxels.push_back(part.voxels[w]);
  }
  std::vector<Part> kept;
  for (Part& o : out) {
    if (o.polygons() == 0 && o.voxels.size() < 8) continue;
    kept.push_back(std::move(o));
  }
  return kept;
}

// The connected pieces of `part` on either side of `plane` (the kept side's first).
std::vector<Part> CutInto(const Part& part, const Plane& plane, const Context& ctx) {
  Part lo, hi;
  Split(part, plane, ctx, &lo, &hi);
  std::vector<Part> pieces = Components(std::move(lo), ctx);
  for (Part& q : Components(std::move(hi), ctx)) pieces.push_back(std::move(q));
  std::erase_if(pieces, [](const Part& q) { return q.verts.empty() && q.voxels.empty(); });
  return pieces;
}

// ---- choosing a cut ----

// Score of cutting `part` by `plane` (lower is better): the larger concavity of the two sides,
// estimated on thinned points without splitting into pieces. +inf when a side is empty.
double ScoreCut(const Part& part, const Plane& plane, const Detail& detail, const Context& ctx) {
  std::vector<Vec3> pts[2];
  const std::size_t nv = part.verts.size();
  std::vector<double> s;
  std::vector<int> side;
  Classify(part, plane, &s, &side);
  // As Split assigns them: a polygon's vertices go to the sides the polygon reaches (a vertex
  // in the plane belongs to a side only through a polygon on that side).
  std::vector<std::uint8_t> taken(nv, 0);
  auto take = [&](std::size_t v, int k) {
    if (!(taken[v] & (1 << k))) {
      taken[v] |= static_cast<std::uint8_t>(1 << k);
      pts[k].push_back(part.verts[v]);
    }
  };
  for (std::size_t p = 0; p < part.polygons(); ++p) {
    const std::uint32_t b = part.offs[p], e = part.offs[p + 1];
    const auto [any_lo, any_hi, in_plane] = PolygonSides(part, p, side, plane);
    for (std::uint32_t i = b; i < e; ++i) {
      const auto va = static_cast<std::size_t>(part.idx[i]);
      const auto vb = static_cast<std::size_t>(part.idx[i + 1 < e ? i + 1 : b]);
      if (any_lo && side[va] <= 0) take(va, 0);
      if (any_hi && side[va] >= 0) take(va, 1);
      if ((side[va] < 0 && side[vb] > 0) || (side[va] > 0 && side[vb] < 0)) {
        if (va > vb) continue;  // each shared edge once
        const Vec3 x = Lerp(part.verts[va], part.verts[vb], s[va] / (s[va] - s[vb]));
        pts[0].push_back(x);
        pts[1].push_back(x);
      }
    }
  }
  if (pts[0].size() < 3 || pts[1].size() < 3) return kInf;
  std::vector<Vec3> probes[2];
  Strided(part.samples, detail.probes, [&](const Sample& smp) {
    probes[Dot(plane.n, smp.p) <= plane.d ? 0 : 1].push_back(smp.p);
  });
  if (probes[0].empty() || probes[1].empty()) return kInf;
  std::size_t voxels[2] = {0, 0};
  for (std::int32_t v : part.voxels) ++voxels[Dot(plane.n, ctx.grid.Centre(v)) <= plane.d ? 0 : 1];
  double c[2];
  for (int k = 0; k < 2; ++k) {
    std::vector<Plane> caps = part.cell;
    caps.push_back(k == 0 ? plane : Plane{plane.n * -1.0, -plane.d});
    const std::optional<Hull> hull = ComputeHull(Thin(pts[k], detail.hull_points), true);
    c[k] = hull ? Concavity(*hull, probes[k], voxels[k], caps, ctx) : 0;
  }
  return std::max(c[0], c[1]) + 0.01 * (c[0] + c[1]);
}

// Planes to try on `part`: `per_axis` evenly spaced per axis over the part's vertex bounds
// (with the spacing on each axis, for refining), and the feature planes inside those bounds.
struct CutCandidates {
  std::vector<Plane> planes, features;
  std::array<double, 3> step = {0, 0, 0};
  Bounds bounds;
};

CutCandidates CandidatesFor(const Part& part, int per_axis, const Context& ctx) {
  CutCandidates out;
  if (part.verts.size() < 4) return out;  // only cut faces: nothing to cut along
  Bounds& b = out.bounds;
  b = {part.verts[0], part.verts[0]};
  for (const Vec3& v : part.verts) {
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], v[k]);
      b.max[k] = std::max(b.max[k], v[k]);
    }
  }
  const int n = per_axis;
  for (int a = 0; a < 3; ++a) {
    const double e = b.max[a] - b.min[a];
    if (e < 1e-6) continue;
    out.step[static_cast<std::size_t>(a)] = e / (n + 1);
    Vec3 nrm{0, 0, 0};
    nrm[a] = 1;
    for (int i = 1; i <= n; ++i) out.planes.push_back({nrm, b.min[a] + e * i / (n + 1)});
    for (double f : ctx.features[static_cast<std::size_t>(a)]) {
      if (f > b.min[a] + 1e-4 && f < b.max[a] - 1e-4) out.features.push_back({nrm, f});
    }
  }
  return out;
}

// ScoreCut of each of `cands` on `part` (in parallel, into indexed slots).
std::vector<double> Scores(const Part& part, const std::vector<Plane>& cands, const Detail& detail,
                           const Context& ctx) {
  std::vector<double> score(cands.size());
  internal::ParallelFor(static_cast<int>(cands.size()), ctx.threads, [&](int i) {
    ThrowIfCancelled(ctx.options);
    score[static_cast<std::size_t>(i)] =
        ScoreCut(part, cands[static_cast<std::size_t>(i)], detail, ctx);
  });
  return score;
}

// Index of the lowest score (the first of equals); 0 for none.
std::size_t Lowest(const std::vector<double>& score) {
  return static_cast<std::size_t>(std::min_element(score.begin(), score.end()) - score.begin());
}

// Score of cutting `part` by `plane` looking one cut further: the part is split into its
// connected pieces, and each piece above the threshold counts with the best score of its own
// next cut (among half as many evenly spaced candidates: this ranks, it does not choose). The
// larger over the pieces, plus a hundredth of their sum, as ScoreCut; within the threshold,
// every cut counts as the threshold (done either way: the tie-breaks decide).
double LookaheadScore(const Part& part, const Plane& plane, const Context& ctx) {
  const std::vector<Part> pieces = CutInto(part, plane, ctx);
  if (pieces.size() < 2) return kInf;
  double worst = 0, sum = 0;
  for (const Part& q : pieces) {
    double c = ToPiece(q, ctx).concavity;
    if (c > ctx.options.threshold) {
      const int per_axis = std::max(2, ctx.options.candidates / 2);
      const std::vector<double> next =
          Scores(q, CandidatesFor(q, per_axis, ctx).planes, kRank, ctx);
      if (!next.empty()) c = std::min(c, next[Lowest(next)]);
    }
    worst = std::max(worst, c);
    sum += c;
  }
  return std::max(worst, ctx.options.threshold) + 0.01 * sum;
}

// The cut for a part of concavity `concavity`: the plane whose two sides are least concave
// (coarse candidates, refined around the best; a feature plane nearly as good wins). Where no
// single cut lowers the worst side by a quarter of its excess over the threshold, the choice
// among the candidates is blind (a ring: half a torus is as concave as the torus, and which nearly
// equal score wins would follow the sampling, hence the tessellation): then the best few candidates
// and the middle plane of each axis are compared two cuts deep (LookaheadScore).
std::optional<Plane> BestCut(const Part& part, double concavity, const Context& ctx) {
  const CutCandidates cands = CandidatesFor(part, ctx.options.candidates, ctx);
  const std::vector<Plane>& planes = cands.planes;
  if (planes.empty()) return std::nullopt;
  const std::vector<double> score = Scores(part, planes, kChoose, ctx);
  const std::size_t best = Lowest(score);
  double best_score = score[best];
  if (!std::isfinite(best_score)) return std::nullopt;
  Plane chosen = planes[best];
  // Refine around the best position on its axis.
  const int axis = chosen.n[0] != 0 ? 0 : chosen.n[1] != 0 ? 1 : 2;
  const double fine = cands.step[static_cast<std::size_t>(axis)] / 3;
  std::vector<Plane> refine;
  for (int j : {-2, -1, 1, 2}) refine.push_back({chosen.n, chosen.d + j * fine});
  const std::vector<double> rscore = Scores(part, refine, kChoose, ctx);
  if (const std::size_t r = Lowest(rscore); rscore[r] < best_score) {
    chosen = refine[r];
    best_score = rscore[r];
  }
  // A feature plane (many vertices on it) nearly as good wins: it leaves no sliver behind.
  const double feature_slack = 0.1 * ctx.options.threshold;
  std::optional<Plane> feature;  // the best feature plane
  bool feature_chosen = false;
  if (!cands.features.empty()) {
    const std::vector<double> fscore = Scores(part, cands.features, kChoose, ctx);
    const std::size_t f = Lowest(fscore);
    if (std::isfinite(fscore[f])) feature = cands.features[f];
    if (fscore[f] <= best_score + feature_slack) {
      chosen = cands.features[f];
      best_score = fscore[f];
      feature_chosen = true;
    }
  }
  const double excess = concavity - ctx.options.threshold;
  if (best_score <= ctx.options.threshold || concavity - best_score >= kBlindGain * excess) {
    return chosen;
  }
  // Blind: look two cuts ahead. The chosen plane first (it wins ties), then the next best
  // candidates, the middle of each axis, and the best feature plane (which wins when nearly as
  // good, as above).
  std::vector<Plane> shortlist = {chosen};
  std::vector<std::size_t> order(planes.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t y) { return score[x] < score[y]; });
  for (std::size_t i = 0; i < order.size() && shortlist.size() < 1 + kLookaheadBest; ++i) {
    if (std::isfinite(score[order[i]]) && order[i] != best) shortlist.push_back(planes[order[i]]);
  }
  for (int a = 0; a < 3; ++a) {
    if (cands.step[static_cast<std::size_t>(a)] == 0) continue;
    Vec3 nrm{0, 0, 0};
    nrm[a] = 1;
    shortlist.push_back({nrm, 0.5 * (cands.bounds.min[a] + cands.bounds.max[a])});
  }
  double ahead = kInf, feature_ahead = kInf;
  for (std::size_t i = 0; i < shortlist.size(); ++i) {
    const double v = LookaheadScore(part, shortlist[i], ctx);
    if (i == 0 && feature_chosen) feature_ahead = v;
    if (v < ahead) {
      ahead = v;
      chosen = shortlist[i];
    }
  }
  if (feature && !feature_chosen) feature_ahead = LookaheadScore(part, *feature, ctx);
  if (feature && feature_ahead <= ahead + feature_slack) chosen = *feature;
  return chosen;
}

// ---- set-up ----

void CheckOptions(const DecomposeOptions& o) {
  auto bad = [](const std::string& what) { throw Error("decompose: " + what); };
  if (!(o.threshold > 0) || !std::isfinite(o.threshold)) bad("threshold must be > 0");
  if (o.max_parts < 1) bad("max_parts must be at least 1");
  if (o.resolution < 4 || o.resolution > 400) bad("resolution must be 4 to 400");
  if (o.samples < 100 || o.samples > 10000000) bad("samples must be 100 to 10000000");
  if (!(o.volume_weight >= 0) || !std::isfinite(o.volume_weight)) {
    bad("volume_weight must be >= 0");
  }
  if (o.candidates < 2 || o.candidates > 100) bad("candidates must be 2 to 100");
  if (o.max_triangles < 1000) bad("max_triangles must be at least 1000");
}

struct Prepared {
  TriMesh mesh;  // normalised: centred on its box, diagonal 1
  Vec3 centre;
  double scale = 1;  // original = normalised * scale + centre
  Context ctx;
  std::vector<std::string> notes;
};

Prepared Prepare(TriMesh mesh, const DecomposeOptions& options) {
  CheckOptions(options);
  auto progress = [&](double f, std::string_view what) {
    ThrowIfCancelled(options);
    if (options.progress) options.progress(f, what);
  };
  Prepared p;
  progress(0, "cleaning the mesh");
  CleanReport clean = CleanMesh(mesh);
  if (mesh.empty()) {
    throw Error("decompose: the mesh has no usable triangles (" + clean.Summary() + ")");
  }
  if (clean.Summary() != "clean") p.notes.push_back("input: " + clean.Summary());
  if (mesh.triangles.size() > options.max_triangles) {
    progress(0, "simplifying a large mesh");
    const std::size_t before = mesh.triangles.size();
    int cells = 0;
    mesh = SimplifyToAtMost(mesh, options.max_triangles, 400, false, &cells);
    // Clustering folds thin places into faces that disagree or share an edge three ways; the
    // inside test and the concavity measure need a surface that agrees.
    const std::size_t dropped = MakeEdgesOrientable(mesh);
    p.notes.push_back(fmt::format(
        "simplified from {} to {} triangles (vertex clustering, {} cells{})", before,
        mesh.triangles.size(), cells,
        dropped ? fmt::format("; {} triangles on non-manifold edges dropped", dropped) : ""));
    ThrowIfCancelled(options);
    clean = CleanMesh(mesh);  // whether the simplified surface is closed decides the terms
  }
  const Bounds b = ComputeBounds(mesh);
  const Vec3 size = b.Size();
  const double diag = b.Diagonal();
  if (!(diag > 0) || !std::isfinite(diag)) throw Error("decompose: the mesh has no extent");
  if (std::max({size[0], size[1], size[2]}) == diag) {
    // Every vertex on one line: nothing to wrap.
    const int nonzero = (size[0] > 0) + (size[1] > 0) + (size[2] > 0);
    if (nonzero < 2) throw Error("decompose: the mesh is a line (no area)");
  }
  p.centre = b.Center();
  p.scale = diag;
  for (Vec3& v : mesh.vertices) v = (v - p.centre) * (1.0 / diag);
  p.mesh = std::move(mesh);
  p.ctx.options = options;
  p.ctx.threads = options.threads > 0 ? options.threads : internal::HardwareThreads();
  p.ctx.box = ComputeBounds(p.mesh);
  p.ctx.mesh_box = p.ctx.box;
  for (int a = 0; a < 3; ++a) {
    // Flat faces: triangles whose three corners share the coordinate.
    std::map<double, int> count;
    for (const Triangle& t : p.mesh.triangles) {
      const double x = p.mesh.vertices[static_cast<std::size_t>(t[0])][a];
      if (p.mesh.vertices[static_cast<std::size_t>(t[1])][a] == x &&
          p.mesh.vertices[static_cast<std::size_t>(t[2])][a] == x) {
        ++count[x];
      }
    }
    std::vector<std::pair<int, double>> common;
    for (const auto& [x, c] : count) {
      if (c >= 2) common.push_back({-c, x});
    }
    std::sort(common.begin(), common.end());
    if (common.size() > 12) common.resize(12);
    for (const auto& [c, x] : common) p.ctx.features[static_cast<std::size_t>(a)].push_back(x);
    std::sort(p.ctx.features[static_cast<std::size_t>(a)].begin(),
              p.ctx.features[static_cast<std::size_t>(a)].end());
  }
  for (int k = 0; k < 3; ++k) {
    p.ctx.box.min[k] -= 1e-3;
    p.ctx.box.max[k] += 1e-3;
  }
  p.ctx.solid = clean.closed();
  if (!p.ctx.solid) {
    p.notes.push_back("open or non-manifold surface: concavity from the surface term only");
  }
  progress(0.01, "voxelizing");
  p.ctx.grid = internal::Voxelize(p.mesh, p.ctx.box, options.resolution);
  ThrowIfCancelled(options);
  if (p.ctx.solid) p.ctx.inside = internal::InsideTest(p.mesh, options.resolution);
  ThrowIfCancelled(options);
  if (p.ctx.solid && p.ctx.grid.interior.empty()) {
    p.ctx.solid = false;
    p.notes.push_back("thinner than one voxel: concavity from the surface term only");
  }
  return p;
}

Part RootPart(const Prepared& p) {
  Part root;
  root.verts = p.mesh.vertices;
  root.offs = {0};
  for (std::size_t t = 0; t < p.mesh.triangles.size(); ++t) {
    for (std::int32_t i : p.mesh.triangles[t]) root.idx.push_back(i);
    root.offs.push_back(static_cast<std::uint32_t>(root.idx.size()));
    root.tri.push_back(static_cast<std::int32_t>(t));
  }
  root.samples = internal::SampleSurface(p.mesh, p.ctx.options.samples);
  if (p.ctx.solid) root.voxels = p.ctx.grid.interior;
  return root;
}

// Final hull of a piece in the input's frame; a flat piece is thickened a little.
ConvexPart FinishPiece(const Piece& piece, const Prepared& p) {
  std::optional<Hull> hull = ComputeHull(piece.hull_points, true);
  if (!hull) {
    std::vector<Vec3> thick;
    constexpr double kThickness = 1e-3;  // of the diagonal
    for (const Vec3& q : piece.hull_points) {
      thick.push_back(q);
      for (int k = 0; k < 3; ++k) {
        Vec3 d{0, 0, 0};
        d[k] = kThickness;
        thick.push_back(q + d);
        thick.push_back(q - d);
      }
    }
    hull = ComputeHull(thick, true);
    if (!hull) throw Error("decompose: could not build a hull for a part");
  }
  ConvexPart out;
  out.hull = std::move(hull->mesh);
  for (Vec3& v : out.hull.vertices) v = v * p.scale + p.centre;
  out.concavity = piece.concavity;
  out.volume = hull->volume * p.scale * p.scale * p.scale;
  return out;
}

Piece MergePieces(const Piece& a, const Piece& b, const Context& ctx) {
  Piece m;
  m.hull_points = a.hull_points;
  m.hull_points.insert(m.hull_points.end(), b.hull_points.begin(), b.hull_points.end());
  m.probes = a.probes;
  m.probes.insert(m.probes.end(), b.probes.begin(), b.probes.end());
  m.voxel_count = a.voxel_count + b.voxel_count;
  m.caps = a.caps;
  m.caps.insert(m.caps.end(), b.caps.begin(), b.caps.end());
  for (int k = 0; k < 3; ++k) {
    m.box.min[k] = std::min(a.box.min[k], b.box.min[k]);
    m.box.max[k] = std::max(a.box.max[k], b.box.max[k]);
  }
  m.concavity = EvaluatePiece(m, ctx);
  return m;
}

bool Touch(const Bounds& a, const Bounds& b, double margin) {
  for (int k = 0; k < 3; ++k) {
    if (a.max[k] + margin < b.min[k] || b.max[k] + margin < a.min[k]) return false;
  }
  return true;
}

}  // namespace

void ThrowIfCancelled(const DecomposeOptions& options) {
  if (options.cancelled && options.cancelled()) throw Cancelled();
}

void Interruptible(const DecomposeOptions& options, bool on) {
  if (options.interruptible) options.interruptible(on);
}

Decomposition Decompose(TriMesh mesh, const DecomposeOptions& options) {
  Prepared p = Prepare(std::move(mesh), options);
  const Context& ctx = p.ctx;
  auto progress = [&](double f, std::string_view what) {
    ThrowIfCancelled(options);
    if (options.progress) options.progress(std::clamp(f, 0.0, 1.0), what);
  };
  Decomposition out;
  out.notes = p.notes;
  out.mesh_volume = ctx.solid ? SignedVolume(p.mesh) * p.scale * p.scale * p.scale : 0;

  // Cutting: always the most concave part next, until every part is within the threshold or
  // there are enough parts to merge down from.
  const std::size_t cut_limit =
      static_cast<std::size_t>(std::max(2 * options.max_parts, options.max_parts + 8));
  struct Entry {
    Part part;
    Piece piece;
  };
  std::vector<Entry> open, done;
  {
    Part root = RootPart(p);
    Piece piece = ToPiece(root, ctx);
    open.push_back({std::move(root), std::move(piece)});
  }
  const double initial = std::max(open[0].piece.concavity, options.threshold);
  progress(0.05, "cutting");
  while (!open.empty()) {
    // The most concave open part (first of equals: deterministic).
    std::size_t worst = 0;
    for (std::size_t i = 1; i < open.size(); ++i) {
      if (open[i].piece.concavity > open[worst].piece.concavity) worst = i;
    }
    const double c = open[worst].piece.concavity;
    progress(0.05 + 0.75 * std::max(1 - (c - options.threshold) / (initial - options.threshold),
                                    static_cast<double>(open.size() + done.size()) / cut_limit),
             "cutting");
    if (c <= options.threshold || open.size() + done.size() >= cut_limit) break;
    Entry e = std::move(open[worst]);
    open.erase(open.begin() + static_cast<std::ptrdiff_t>(worst));
    const std::optional<Plane> plane = BestCut(e.part, e.piece.concavity, ctx);
    if (!plane) {
      done.push_back(std::move(e));
      continue;
    }
    std::vector<Part> pieces = CutInto(e.part, *plane, ctx);
    if (pieces.size() < 2) {
      done.push_back(std::move(e));
      continue;
    }
    ++out.cuts;
    std::vector<Piece> evaluated(pieces.size());
    internal::ParallelFor(static_cast<int>(pieces.size()), ctx.threads, [&](int i) {
      ThrowIfCancelled(options);
      evaluated[static_cast<std::size_t>(i)] = ToPiece(pieces[static_cast<std::size_t>(i)], ctx);
    });
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      open.push_back({std::move(pieces[i]), std::move(evaluated[i])});
    }
  }
  std::vector<Piece> parts;
  for (Entry& e : done) parts.push_back(std::move(e.piece));
  for (Entry& e : open) parts.push_back(std::move(e.piece));
  done.clear();
  open.clear();

  // Merging: the pair whose merged part is least concave, while it stays within the threshold,
  // then regardless of it while there are more than max_parts parts.
  progress(0.8, "merging");
  const double margin = 0.01;
  struct Pair {
    std::size_t a, b;
    Piece merged;
  };
  auto pairs_of = [&](bool all) {
    std::vector<std::pair<std::size_t, std::size_t>> list;
    for (std::size_t a = 0; a < parts.size(); ++a) {
      for (std::size_t b = a + 1; b < parts.size(); ++b) {
        if (all || Touch(parts[a].box, parts[b].box, margin)) list.emplace_back(a, b);
      }
    }
    return list;
  };
  std::vector<Pair> candidates;
  auto evaluate = [&](const std::vector<std::pair<std::size_t, std::size_t>>& list) {
    std::vector<Pair> result(list.size());
    internal::ParallelFor(static_cast<int>(list.size()), ctx.threads, [&](int i) {
      ThrowIfCancelled(options);
      const auto [a, b] = list[static_cast<std::size_t>(i)];
      result[static_cast<std::size_t>(i)] = {a, b, MergePieces(parts[a], parts[b], ctx)};
    });
    return result;
  };
  candidates = evaluate(pairs_of(false));
  const std::size_t start_parts = parts.size();
  while (parts.size() > 1) {
    if (candidates.empty() && parts.size() > static_cast<std::size_t>(options.max_parts)) {
      candidates = evaluate(pairs_of(true));  // disconnected pieces: any pair
    }
    if (candidates.empty()) break;
    std::size_t best = 0;
    for (std::size_t i = 1; i < candidates.size(); ++i) {
      if (candidates[i].merged.concavity < candidates[best].merged.concavity) best = i;
    }
    const bool within = candidates[best].merged.concavity <= options.threshold;
    if (!within && parts.size() <= static_cast<std::size_t>(options.max_parts)) break;
    const std::size_t a = candidates[best].a, b = candidates[best].b;
    parts[a] = std::move(candidates[best].merged);
    parts.erase(parts.begin() + static_cast<std::ptrdiff_t>(b));
    ++out.merges;
    // Drop the pairs that named a or b; renumber; evaluate the new part's pairs.
    std::vector<Pair> kept;
    for (Pair& c : candidates) {
      if (c.a == a || c.b == a || c.a == b || c.b == b) continue;
      c.a -= c.a > b;
      c.b -= c.b > b;
      kept.push_back(std::move(c));
    }
    std::vector<std::pair<std::size_t, std::size_t>> fresh;
    for (std::size_t o = 0; o < parts.size(); ++o) {
      if (o != a && Touch(parts[a].box, parts[o].box, margin)) {
        fresh.emplace_back(std::min(a, o), std::max(a, o));
      }
    }
    for (Pair& c : evaluate(fresh)) kept.push_back(std::move(c));
    candidates = std::move(kept);
    progress(0.8 + 0.15 * static_cast<double>(out.merges) /
                       static_cast<double>(std::max<std::size_t>(start_parts, 1)),
             "merging");
  }

  progress(0.95, "hulls");
  out.parts.resize(parts.size());
  internal::ParallelFor(static_cast<int>(parts.size()), ctx.threads, [&](int i) {
    ThrowIfCancelled(options);
    out.parts[static_cast<std::size_t>(i)] = FinishPiece(parts[static_cast<std::size_t>(i)], p);
  });
  for (const ConvexPart& part : out.parts) out.concavity = std::max(out.concavity, part.concavity);
  progress(1, "done");
  return out;
}

Decomposition SingleHull(TriMesh mesh, const DecomposeOptions& options) {
  Prepared p = Prepare(std::move(mesh), options);
  Decomposition out;
  out.notes = p.notes;
  out.mesh_volume = p.ctx.solid ? SignedVolume(p.mesh) * p.scale * p.scale * p.scale : 0;
  const Piece piece = ToPiece(RootPart(p), p.ctx);
  out.parts.push_back(FinishPiece(piece, p));
  out.concavity = piece.concavity;
  return out;
}

std::string OptionsKey(const DecomposeOptions& o) {
  return fmt::format(
      "v3 threshold={} max_parts={} resolution={} samples={} k={} candidates={} "
      "max_triangles={}",
      o.threshold, o.max_parts, o.resolution, o.samples, o.volume_weight, o.candidates,
      o.max_triangles);
}

}  // namespace urlab::convert
