#pragma once
// Convex hulls through Qhull (reentrant libqhull_r; internal: no Qhull type leaves this file's
// .cc). Thread: any; every call has its own Qhull state.
#include <optional>
#include <vector>

#include "urlab/convert/mesh.h"

namespace urlab::convert::internal {

struct HullPlane {
  Vec3 normal;    // outward, unit length
  double offset;  // points inside satisfy Dot(normal, p) <= offset
};

struct Hull {
  std::vector<HullPlane> planes;
  double volume = 0;
  double area = 0;
  TriMesh mesh;  // triangulated, outward; filled when asked for
  // Distance from p to the hull's boundary when inside (>= 0), negative (a lower bound of the
  // distance) when outside.
  double Depth(const Vec3& p) const;
};

// Hull of `points`; nullopt when Qhull cannot build one (fewer than 4 points, or all of them
// on a plane or a line). `with_mesh` fills Hull::mesh.
std::optional<Hull> ComputeHull(const std::vector<Vec3>& points, bool with_mesh);

}  // namespace urlab::convert::internal
