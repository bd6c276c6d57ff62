// Consistent face orientation of triangle meshes (see PlanConsistentOrientation in mesh.h).
#include <algorithm>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "geometry.h"
#include "urlab/convert/mesh.h"

namespace urlab::convert {

namespace {

using EdgePair = std::pair<std::int32_t, std::int32_t>;  // (lower, higher) vertex

struct EdgeUse {
  std::size_t triangle;
  bool forward;  // the triangle runs from the lower to the higher vertex
};

struct EdgePairHash {
  std::size_t operator()(const EdgePair& e) const {
    return std::hash<std::uint64_t>()(
        (static_cast<std::uint64_t>(static_cast<std::uint32_t>(e.first)) << 32) |
        static_cast<std::uint32_t>(e.second));
  }
};

// Corner vertex ids: the mesh's indices, or the first index of each exact coordinate.
std::vector<Triangle> CornerIds(const TriMesh& mesh, bool weld) {
  if (!weld) return mesh.triangles;
  std::map<Vec3, std::int32_t> first;
  std::vector<Triangle> out = mesh.triangles;
  for (Triangle& t : out) {
    for (std::int32_t& i : t) {
      const Vec3& v = mesh.vertices[static_cast<std::size_t>(i)];
      if (!Finite(v)) continue;  // never equal to anything (and no order for the map)
      i = first.emplace(Vec3{v[0] + 0.0, v[1] + 0.0, v[2] + 0.0}, i).first->second;
    }
  }
  return out;
}

std::size_t RepeatedDirectedEdges(const std::vector<Triangle>& tris,
                                  const std::vector<bool>& flip) {
  std::vector<EdgePair> directed;
  directed.reserve(tris.size() * 3);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    Triangle c = tris[t];
    if (flip[t]) std::swap(c[1], c[2]);
    for (int k = 0; k < 3; ++k) directed.emplace_back(c[k], c[(k + 1) % 3]);
  }
  std::sort(directed.begin(), directed.end());
  std::size_t repeated = 0;
  for (std::size_t i = 1; i < directed.size(); ++i) repeated += directed[i] == directed[i - 1];
  return repeated;
}

}  // namespace

OrientationPlan PlanConsistentOrientation(const TriMesh& mesh, bool weld_equal_vertices) {
  OrientationPlan plan;
  const std::vector<Triangle> tris = CornerIds(mesh, weld_equal_vertices);
  const std::size_t n = tris.size();
  plan.flip.assign(n, false);
  plan.repeated_edges = RepeatedDirectedEdges(tris, plan.flip);

  std::unordered_map<EdgePair, std::vector<EdgeUse>, EdgePairHash> edges;
  edges.reserve(n * 2);
  for (std::size_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
      if (a == b) continue;  // a degenerate corner joins nothing
      edges[{std::min(a, b), std::max(a, b)}].push_back({t, a < b});
    }
  }
  // Breadth-first over manifold edges: a neighbour must run the shared edge the other way.
  std::vector<int> piece(n, -1);
  std::vector<std::size_t> queue;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (piece[seed] >= 0) continue;
    const int id = static_cast<int>(plan.pieces++);
    std::vector<std::size_t> members;
    bool orientable = true, closed = true;
    piece[seed] = id;
    queue.assign(1, seed);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::size_t t = queue[q];
      members.push_back(t);
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
        if (a == b) continue;
        const std::vector<EdgeUse>& uses = edges[{std::min(a, b), std::max(a, b)}];
        if (uses.size() == 1) closed = false;
        if (uses.size() != 2) continue;
        const EdgeUse& mine = uses[0].triangle == t ? uses[0] : uses[1];
        const EdgeUse& other = uses[0].triangle == t ? uses[1] : uses[0];
        const bool flip_other = plan.flip[t] != (mine.forward == other.forward);
        if (piece[other.triangle] < 0) {
          piece[other.triangle] = id;
          plan.flip[other.triangle] = flip_other;
          queue.push_back(other.triangle);
        } else if (plan.flip[other.triangle] != flip_other) {
          orientable = false;
        }
      }
    }
    if (!orientable) ++plan.non_orientable;
    // Which way the piece faces: outwards when closed, else as most of its triangles did.
    bool turn = false;
    if (closed) {
      ++plan.closed_pieces;
      const Vec3& o = mesh.vertices[static_cast<std::size_t>(mesh.triangles[seed][0])];
      double volume = 0;
      for (std::size_t t : members) {
        const Triangle& c = mesh.triangles[t];
        const double v = Dot(mesh.vertices[static_cast<std::size_t>(c[0])] - o,
                             Cross(mesh.vertices[static_cast<std::size_t>(c[1])] - o,
                                   mesh.vertices[static_cast<std::size_t>(c[2])] - o));
        volume += plan.flip[t] ? -v : v;
      }
      turn = volume < 0;
      if (turn) ++plan.turned_outwards;
    } else {
      const auto flipped = static_cast<std::size_t>(std::count_if(
          members.begin(), members.end(), [&](std::size_t t) { return plan.flip[t]; }));
      turn = 2 * flipped > members.size();
    }
    if (turn) {
      for (std::size_t t : members) plan.flip[t] = !plan.flip[t];
    }
  }
  plan.flipped = static_cast<std::size_t>(std::count(plan.flip.begin(), plan.flip.end(), true));
  plan.repeated_after = RepeatedDirectedEdges(tris, plan.flip);
  return plan;
}

std::size_t MakeEdgesOrientable(TriMesh& mesh) {
  const OrientationPlan plan = PlanConsistentOrientation(mesh, false);
  std::unordered_set<EdgePair, EdgePairHash> directed;  // (from, to) edges in use
  directed.reserve(mesh.triangles.size() * 3);
  std::vector<Triangle> kept;
  kept.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    Triangle c = mesh.triangles[t];
    if (plan.flip[t]) std::swap(c[1], c[2]);
    bool clash = false;
    for (int k = 0; k < 3 && !clash; ++k) clash = directed.count({c[k], c[(k + 1) % 3]}) > 0;
    if (clash) continue;
    for (int k = 0; k < 3; ++k) directed.emplace(c[k], c[(k + 1) % 3]);
    kept.push_back(c);
  }
  const std::size_t dropped = mesh.triangles.size() - kept.size();
  // Unused vertices out, indices renumbered in first-use order.
  std::vector<std::int32_t> remap(mesh.vertices.size(), -1);
  std::vector<Vec3> vertices;
  for (Triangle& c : kept) {
    for (std::int32_t& i : c) {
      std::int32_t& r = remap[static_cast<std::size_t>(i)];
      if (r < 0) {
        r = static_cast<std::int32_t>(vertices.size());
        vertices.push_back(mesh.vertices[static_cast<std::size_t>(i)]);
      }
      i = r;
    }
  }
  mesh.vertices = std::move(vertices);
  mesh.triangles = std::move(kept);
  return dropped;
}

}  // namespace urlab::convert
