#include "viewer/framing.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace urlab::viewer::internal {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kMargin = 1.08;      // a little room around the sphere
constexpr double kElevation = -22;    // degrees: looking down a little
constexpr double kThreeQuarter = 30;  // degrees off the axis across the longer extent
}  // namespace

SceneBounds ComputeSceneBounds(const mjModel* m, const mjData* d) {
  mjtNum lo[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    lo[c] = std::numeric_limits<mjtNum>::max();
    hi[c] = -std::numeric_limits<mjtNum>::max();
  }
  bool any = false;
  const auto add = [&](const mjtNum* p, mjtNum r) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], p[c] - r);
      hi[c] = std::max(hi[c], p[c] + r);
    }
    any = true;
  };
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] == mjGEOM_PLANE) continue;
    // An unusually large geom (a terrain's hfield) still counts: it is part of the scene.
    add(d->geom_xpos + 3 * g, std::max<mjtNum>(m->geom_rbound[g], 0));
  }
  for (int b = 1; b < m->nbody; ++b) add(d->xpos + 3 * b, 0);
  SceneBounds s;
  if (!any) {  // only planes: MuJoCo's statistics
    mju_copy3(s.center, m->stat.center);
    s.radius = std::max<mjtNum>(m->stat.extent, 0.5);
    return s;
  }
  for (int c = 0; c < 3; ++c) {
    s.center[c] = (lo[c] + hi[c]) / 2;
    s.extent[c] = hi[c] - lo[c];
  }
  s.radius = std::max<mjtNum>(0.5 * mju_norm3(s.extent), 0.05);
  return s;
}

void FrameScene(const mjModel* m, const mjData* d, double aspect, mjvCamera* cam) {
  const SceneBounds s = ComputeSceneBounds(m, d);
  cam->type = mjCAMERA_FREE;
  cam->trackbodyid = -1;
  cam->fixedcamid = -1;
  mju_copy3(cam->lookat, s.center);
  // Across the longer horizontal extent (spread along y: look along x), turned a little.
  const double across = s.extent[1] >= s.extent[0] ? 180.0 : 90.0;
  cam->azimuth = across - kThreeQuarter;
  cam->elevation = kElevation;
  const double half_v = 0.5 * m->vis.global.fovy * kPi / 180.0;
  const double half_h = std::atan(std::tan(half_v) * std::max(aspect, 1e-3));
  const double half = std::min(half_v, half_h);
  cam->distance = kMargin * s.radius / std::sin(half);
}

}  // namespace urlab::viewer::internal
