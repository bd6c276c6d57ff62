#pragma once
// Closed meshes built in C++ for the convert tests: boxes, a cup (a lathe with an opening), a
// torus, an L-bracket and a sinusoidal terrain slab, plus a temporary folder and a file writer.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "urlab/convert/mesh.h"

namespace urlab::convert::testing {

inline TriMesh Box(const Vec3& lo, const Vec3& hi) {
  TriMesh m;
  m.vertices = {{lo[0], lo[1], lo[2]}, {hi[0], lo[1], lo[2]}, {hi[0], hi[1], lo[2]},
                {lo[0], hi[1], lo[2]}, {lo[0], lo[1], hi[2]}, {hi[0], lo[1], hi[2]},
                {hi[0], hi[1], hi[2]}, {lo[0], hi[1], hi[2]}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                 {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  return m;
}

inline void Append(TriMesh& to, const TriMesh& from) {
  const auto base = static_cast<std::int32_t>(to.vertices.size());
  to.vertices.insert(to.vertices.end(), from.vertices.begin(), from.vertices.end());
  for (const Triangle& t : from.triangles)
    to.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

// Surface of revolution about z of a closed profile of (r, z) points, clockwise in the r-z
// plane (outward normals); r == 0 points are on the axis.
inline TriMesh Lathe(const std::vector<std::pair<double, double>>& profile, int segments) {
  TriMesh m;
  std::vector<std::vector<std::int32_t>> ids(profile.size());
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const auto [r, z] = profile[k];
    for (int s = 0; s < (r == 0 ? 1 : segments); ++s) {
      const double t = 2 * M_PI * s / segments;
      ids[k].push_back(static_cast<std::int32_t>(m.vertices.size()));
      m.vertices.push_back({r * std::cos(t), r * std::sin(t), z});
    }
  }
  auto id = [&](std::size_t k, int s) {
    return ids[k][static_cast<std::size_t>(s % static_cast<int>(ids[k].size()))];
  };
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const std::size_t k2 = (k + 1) % profile.size();
    for (int s = 0; s < segments; ++s) {
      const std::int32_t a = id(k, s), b = id(k2, s), c = id(k2, s + 1), d = id(k, s + 1);
      if (a != b && b != c && a != c) m.triangles.push_back({a, c, b});
      if (a != c && c != d && a != d) m.triangles.push_back({a, d, c});
    }
  }
  return m;
}

// A cup: outer radius `radius`, height `height`, walls and floor `wall` thick, open at the top.
inline TriMesh Cup(double radius = 0.05, double height = 0.1, double wall = 0.006,
                   int segments = 48) {
  const double r = radius - wall;
  return Lathe({{0, 0}, {radius, 0}, {radius, height}, {r, height}, {r, wall}, {0, wall}},
               segments);
}

inline TriMesh Torus(double R, double r, int nu, int nv) {
  TriMesh m;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      m.vertices.push_back({(R + r * std::cos(v)) * std::cos(u),
                            (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  }
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const std::int32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j;
      const std::int32_t c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  }
  return m;
}

// A prism over a polygon that is star-shaped from its first corner (counter-clockwise).
inline TriMesh Prism(const std::vector<std::pair<double, double>>& polygon, double z0, double z1) {
  TriMesh m;
  const auto n = static_cast<std::int32_t>(polygon.size());
  for (const auto& [x, y] : polygon) m.vertices.push_back({x, y, z0});
  for (const auto& [x, y] : polygon) m.vertices.push_back({x, y, z1});
  for (std::int32_t k = 1; k + 1 < n; ++k) {
    m.triangles.push_back({0, k + 1, k});
    m.triangles.push_back({n, n + k, n + k + 1});
  }
  for (std::int32_t k = 0; k < n; ++k) {
    const std::int32_t k2 = (k + 1) % n;
    m.triangles.push_back({k, k2, n + k2});
    m.triangles.push_back({k, n + k2, n + k});
  }
  return m;
}

// An L-bracket: 10 x 1 and 1 x 8 (cm) arms, 4 deep, one closed surface.
inline TriMesh LBracket() {
  return Prism({{0.01, 0.01}, {0.01, 0.08}, {0, 0.08}, {0, 0}, {0.1, 0}, {0.1, 0.01}}, 0, 0.04);
}

// A terrain slab: top z = height(x, y) on [0, size]^2 sampled n x n, flat bottom at `base`.
template <typename F>
TriMesh TerrainSlab(F height, double size, int n, double base) {
  TriMesh m;
  auto top = [&](int i, int j) { return static_cast<std::int32_t>(i * (n + 1) + j); };
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double x = size * i / n, y = size * j / n;
      m.vertices.push_back({x, y, height(x, y)});
    }
  }
  const auto bottom0 = static_cast<std::int32_t>(m.vertices.size());
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) m.vertices.push_back({size * i / n, size * j / n, base});
  }
  auto bottom = [&](int i, int j) { return bottom0 + top(i, j); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      m.triangles.push_back({top(i, j), top(i + 1, j), top(i + 1, j + 1)});
      m.triangles.push_back({top(i, j), top(i + 1, j + 1), top(i, j + 1)});
      m.triangles.push_back({bottom(i, j), bottom(i + 1, j + 1), bottom(i + 1, j)});
      m.triangles.push_back({bottom(i, j), bottom(i, j + 1), bottom(i + 1, j + 1)});
    }
  }
  for (int k = 0; k < n; ++k) {
    // Walls: y = 0, y = size, x = 0, x = size.
    m.triangles.push_back({top(k, 0), bottom(k, 0), bottom(k + 1, 0)});
    m.triangles.push_back({top(k, 0), bottom(k + 1, 0), top(k + 1, 0)});
    m.triangles.push_back({top(k, n), top(k + 1, n), bottom(k + 1, n)});
    m.triangles.push_back({top(k, n), bottom(k + 1, n), bottom(k, n)});
    m.triangles.push_back({top(0, k), top(0, k + 1), bottom(0, k + 1)});
    m.triangles.push_back({top(0, k), bottom(0, k + 1), bottom(0, k)});
    m.triangles.push_back({top(n, k), bottom(n, k), bottom(n, k + 1)});
    m.triangles.push_back({top(n, k), bottom(n, k + 1), top(n, k + 1)});
  }
  return m;
}

// A fresh temporary folder, removed when the object dies.
// Writes `bytes` to `path` as they are.
inline void Write(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "urlab-convert-XXXXXX").string();
    path_ = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

}  // namespace urlab::convert::testing
