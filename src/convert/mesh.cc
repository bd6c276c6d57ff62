#include "urlab/convert/mesh.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

#include "geometry.h"

namespace urlab::convert {

namespace {

struct VecHash {
  std::size_t operator()(const Vec3& v) const {
    return static_cast<std::size_t>(
        HashBytes({reinterpret_cast<const char*>(v.data()), sizeof(double) * 3}));
  }
};

std::uint64_t EdgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

}  // namespace

Vec3 Bounds::Center() const { return (min + max) * 0.5; }

double Bounds::Diagonal() const { return Norm(max - min); }

Bounds ComputeBounds(const TriMesh& mesh) {
  Bounds b;
  bool any = false;
  for (const Triangle& t : mesh.triangles) {
    for (std::int32_t i : t) {
      const Vec3& v = mesh.vertices[static_cast<std::size_t>(i)];
      for (int k = 0; k < 3; ++k) {
        b.min[k] = any ? std::min(b.min[k], v[k]) : v[k];
        b.max[k] = any ? std::max(b.max[k], v[k]) : v[k];
      }
      any = true;
    }
  }
  return b;
}

double SignedVolume(const TriMesh& mesh) {
  // Relative to the first vertex, which keeps the terms small for meshes far from the origin.
  if (mesh.triangles.empty()) return 0;
  const Vec3 o = mesh.vertices[static_cast<std::size_t>(mesh.triangles[0][0])];
  double v = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[static_cast<std::size_t>(t[0])] - o;
    const Vec3 b = mesh.vertices[static_cast<std::size_t>(t[1])] - o;
    const Vec3 c = mesh.vertices[static_cast<std::size_t>(t[2])] - o;
    v += Dot(a, Cross(b, c));
  }
  return v / 6;
}

double SurfaceArea(const TriMesh& mesh) {
  double s = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    s += 0.5 * Norm(Cross(mesh.vertices[static_cast<std::size_t>(t[1])] - a,
                          mesh.vertices[static_cast<std::size_t>(t[2])] - a));
  }
  return s;
}

std::string CleanReport::Summary() const {
  std::string s;
  auto add = [&s](std::size_t n, const char* what) {
    if (n) s += fmt::format("{}{} {}", s.empty() ? "" : ", ", n, what);
  };
  add(non_finite_vertices, "non-finite vertices (their triangles dropped)");
  add(bad_indices, "triangles with out-of-range indices dropped");
  add(welded_vertices, "duplicate vertices welded");
  add(degenerate_triangles, "degenerate triangles dropped");
  add(duplicate_triangles, "duplicate triangles dropped");
  if (flipped) s += std::string(s.empty() ? "" : ", ") + "turned outwards";
  if (boundary_edges) {
    s += fmt::format("{}open ({} boundary edges)", s.empty() ? "" : ", ", boundary_edges);
  }
  if (non_manifold_edges) {
    s += fmt::format("{}{} non-manifold edges", s.empty() ? "" : ", ", non_manifold_edges);
  }
  return s.empty() ? "clean" : s;
}

CleanReport CleanMesh(TriMesh& mesh) {
  CleanReport r;
  r.input_vertices = mesh.vertices.size();
  r.input_triangles = mesh.triangles.size();
  // Weld exact duplicates (non-finite vertices are never used).
  std::vector<std::int32_t> remap(mesh.vertices.size(), -1);
  std::vector<Vec3> verts;
  std::unordered_map<Vec3, std::int32_t, VecHash> seen;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& v = mesh.vertices[i];
    if (!Finite(v)) {
      ++r.non_finite_vertices;
      continue;
    }
    // -0.0 and 0.0 are the same point.
    const Vec3 key = {v[0] + 0.0, v[1] + 0.0, v[2] + 0.0};
    auto [it, fresh] = seen.emplace(key, static_cast<std::int32_t>(verts.size()));
    if (fresh) {
      verts.push_back(key);
    } else {
      ++r.welded_vertices;
    }
    remap[i] = it->second;
  }
  std::vector<Triangle> tris;
  tris.reserve(mesh.triangles.size());
  std::map<std::array<std::int32_t, 3>, int> exact;
  for (const Triangle& t : mesh.triangles) {
    Triangle m{};
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= remap.size()) {
        ok = false;
        ++r.bad_indices;
        break;
      }
      m[k] = remap[static_cast<std::size_t>(t[k])];
      if (m[k] < 0) ok = false;
    }
    if (!ok) continue;
    if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2]) {
      ++r.degenerate_triangles;
      continue;
    }
    const Vec3& a = verts[static_cast<std::size_t>(m[0])];
    const Vec3 n =
        Cross(verts[static_cast<std::size_t>(m[1])] - a, verts[static_cast<std::size_t>(m[2])] - a);
    if (!(Dot(n, n) > 0)) {
      ++r.degenerate_triangles;
      continue;
    }
    std::array<std::int32_t, 3> key = m;
    std::sort(key.begin(), key.end());
    if (!exact.emplace(key, 1).second) {
      ++r.duplicate_triangles;
      continue;
    }
    tris.push_back(m);
  }
  // Drop unused vertices.
  std::vector<std::int32_t> used(verts.size(), -1);
  std::vector<Vec3> compact;
  for (Triangle& t : tris) {
    for (std::int32_t& i : t) {
      if (used[static_cast<std::size_t>(i)] < 0) {
        used[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(compact.size());
        compact.push_back(verts[static_cast<std::size_t>(i)]);
      }
      i = used[static_cast<std::size_t>(i)];
    }
  }
  mesh.vertices = std::move(compact);
  mesh.triangles = std::move(tris);
  // Edge use counts.
  std::unordered_map<std::uint64_t, int> edges;
  edges.reserve(mesh.triangles.size() * 2);
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++edges[EdgeKey(t[k], t[(k + 1) % 3])];
  }
  for (const auto& [key, count] : edges) {
    if (count == 1) ++r.boundary_edges;
    if (count > 2) ++r.non_manifold_edges;
  }
  if (r.boundary_edges == 0 && SignedVolume(mesh) < 0) {
    for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
    r.flipped = true;
  }
  return r;
}

TriMesh ClusterVertices(const TriMesh& mesh, int cells) {
  const Bounds b = ComputeBounds(mesh);
  const Vec3 size = b.Size();
  const double longest = std::max({size[0], size[1], size[2], 1e-300});
  const double cell = longest / std::max(cells, 1);
  std::unordered_map<std::uint64_t, std::int32_t> cluster;
  std::vector<Vec3> sum;
  std::vector<int> count;
  std::vector<std::int32_t> map(mesh.vertices.size(), -1);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& v = mesh.vertices[i];
    if (!Finite(v)) continue;
    std::uint64_t key = 0;
    for (int k = 0; k < 3; ++k) {
      const auto c = static_cast<std::uint64_t>(std::clamp((v[k] - b.min[k]) / cell, 0.0, 1e6));
      key = key * 1048583ull + c;
    }
    auto [it, fresh] = cluster.emplace(key, static_cast<std::int32_t>(sum.size()));
    if (fresh) {
      sum.push_back({0, 0, 0});
      count.push_back(0);
    }
    sum[static_cast<std::size_t>(it->second)] = sum[static_cast<std::size_t>(it->second)] + v;
    ++count[static_cast<std::size_t>(it->second)];
    map[i] = it->second;
  }
  TriMesh out;
  out.vertices.resize(sum.size());
  for (std::size_t i = 0; i < sum.size(); ++i) out.vertices[i] = sum[i] * (1.0 / count[i]);
  for (const Triangle& t : mesh.triangles) {
    Triangle m{};
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= map.size() ||
          map[static_cast<std::size_t>(t[k])] < 0) {
        ok = false;
        break;
      }
      m[k] = map[static_cast<std::size_t>(t[k])];
    }
    if (ok) out.triangles.push_back(m);
  }
  CleanMesh(out);
  return out;
}

TriMesh SimplifyToAtMost(const TriMesh& mesh, std::size_t max_triangles, int start_cells, bool aim,
                         int* cells_used) {
  if (cells_used) *cells_used = 0;
  if (mesh.triangles.size() <= max_triangles) return mesh;
  int cells = std::max(start_cells, 16);
  TriMesh small = ClusterVertices(mesh, cells);
  while (small.triangles.size() > max_triangles && cells > 16) {
    // Aimed: just below the limit, shrinking by at least a quarter so that it ends.
    const double factor = 0.95 * std::sqrt(static_cast<double>(max_triangles) /
                                           static_cast<double>(small.triangles.size()));
    const int quarter = cells * 3 / 4;
    cells = std::max(aim ? std::min(quarter, static_cast<int>(cells * factor)) : quarter, 16);
    small = ClusterVertices(mesh, cells);
  }
  if (cells_used) *cells_used = cells;
  return small;
}

std::uint64_t HashBytes(std::string_view bytes, std::uint64_t seed) {
  std::uint64_t h = seed;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::uint64_t HashMesh(const TriMesh& mesh) {
  std::uint64_t h = HashBytes(
      {reinterpret_cast<const char*>(mesh.vertices.data()), mesh.vertices.size() * sizeof(Vec3)});
  return HashBytes({reinterpret_cast<const char*>(mesh.triangles.data()),
                    mesh.triangles.size() * sizeof(Triangle)},
                   h);
}

std::string HashHex(std::uint64_t hash) { return fmt::format("{:016x}", hash); }

double PointTriangleDistance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  auto dist2 = [&p](const Vec3& q) { return Dot(p - q, p - q); };
  if (d1 <= 0 && d2 <= 0) return dist2(a);
  const Vec3 bp = p - b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist2(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return dist2(a + ab * (d1 / (d1 - d3)));
  const Vec3 cp = p - c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist2(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return dist2(a + ac * (d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return dist2(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return std::min({dist2(a), dist2(b), dist2(c)});
  const double v = vb / denom, w = vc / denom;
  return dist2(a + ab * v + ac * w);
}

}  // namespace urlab::convert
