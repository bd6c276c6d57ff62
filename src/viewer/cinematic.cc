#include "viewer/cinematic.h"

#include <algorithm>
#include <cmath>

namespace urlab::viewer::internal {

namespace {

// Uniform Catmull-Rom between p1 and p2 (p0, p3 their neighbours), u in [0, 1], with the
// tangents scaled for uneven key spacing (dt01, dt12, dt23: the segments' durations).
double CatmullRom(double p0, double p1, double p2, double p3, double dt01, double dt12, double dt23,
                  double u) {
  const double m1 = dt12 * ((p1 - p0) / dt01 + (p2 - p1) / dt12) / 2;
  const double m2 = dt12 * ((p2 - p1) / dt12 + (p3 - p2) / dt23) / 2;
  const double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * p1 + (u3 - 2 * u2 + u) * m1 + (-2 * u3 + 3 * u2) * p2 +
         (u3 - u2) * m2;
}

}  // namespace

const char* ToString(CinematicMode mode) {
  switch (mode) {
    case CinematicMode::kOrbit:
      return "orbit";
    case CinematicMode::kPath:
      return "keyframe path";
    default:
      return "off";
  }
}

CameraPose SamplePath(const std::vector<CameraKey>& keys, double t, bool loop) {
  CameraPose pose;
  if (keys.empty()) return pose;
  const double t0 = keys.front().time, t1 = keys.back().time;
  if (loop && t1 > t0) t = t0 + std::fmod(std::fmod(t - t0, t1 - t0) + (t1 - t0), t1 - t0);
  t = std::clamp(t, t0, t1);
  const auto last = static_cast<int>(keys.size()) - 1;
  int i = 0;  // the segment [i, i + 1] holding t
  while (i < last - 1 && t > keys[static_cast<std::size_t>(i + 1)].time) ++i;
  const auto key = [&](int k) -> const CameraKey& {
    return keys[static_cast<std::size_t>(std::clamp(k, 0, last))];
  };
  if (last == 0) return {keys[0].pos, keys[0].look_at};
  const CameraKey &k0 = key(i - 1), &k1 = key(i), &k2 = key(i + 1), &k3 = key(i + 2);
  const double dt12 = std::max(k2.time - k1.time, 1e-9);
  const double dt01 = i > 0 ? std::max(k1.time - k0.time, 1e-9) : dt12;
  const double dt23 = i + 2 <= last ? std::max(k3.time - k2.time, 1e-9) : dt12;
  const double u = (t - k1.time) / dt12;
  for (std::size_t c = 0; c < 3; ++c) {
    // End segments repeat their end key as the missing neighbour (zero slope there).
    pose.pos[c] = CatmullRom(k0.pos[c], k1.pos[c], k2.pos[c], k3.pos[c], dt01, dt12, dt23, u);
    pose.look_at[c] =
        CatmullRom(k0.look_at[c], k1.look_at[c], k2.look_at[c], k3.look_at[c], dt01, dt12, dt23, u);
  }
  return pose;
}

void PoseToCamera(const CameraPose& pose, mjvCamera* camera) {
  const double dx = pose.look_at[0] - pose.pos[0], dy = pose.look_at[1] - pose.pos[1],
               dz = pose.look_at[2] - pose.pos[2];
  const double dist = std::max(std::sqrt(dx * dx + dy * dy + dz * dz), 1e-6);
  camera->type = mjCAMERA_FREE;
  for (int c = 0; c < 3; ++c) camera->lookat[c] = pose.look_at[static_cast<std::size_t>(c)];
  camera->distance = dist;
  camera->azimuth = std::atan2(dy, dx) * 180 / mjPI;
  camera->elevation = std::asin(std::clamp(dz / dist, -1.0, 1.0)) * 180 / mjPI;
}

void Cinematic::Configure(const CinematicSettings& config, std::vector<int> root_bodies) {
  config_ = config;
  roots_ = std::move(root_bodies);
}

CinematicMode Cinematic::Next() {
  switch (mode_) {
    case CinematicMode::kOff:
      mode_ =
          roots_.empty() && !config_.path.empty() ? CinematicMode::kPath : CinematicMode::kOrbit;
      break;
    case CinematicMode::kOrbit:
      mode_ = config_.path.empty() ? CinematicMode::kOff : CinematicMode::kPath;
      break;
    case CinematicMode::kPath:
      mode_ = CinematicMode::kOff;
      break;
  }
  return mode_;
}

void Cinematic::Apply(const mjModel* m, const mjData* d, double t, mjvCamera* camera) const {
  if (mode_ == CinematicMode::kPath) {
    PoseToCamera(SamplePath(config_.path, t, config_.loop), camera);
    return;
  }
  if (mode_ != CinematicMode::kOrbit) return;
  // Orbit: around the mean of the root bodies, far enough to frame the farthest one.
  mjtNum centre[3] = {0, 0, 0};
  for (int b : roots_) mju_addTo3(centre, d->xpos + 3 * b);
  if (!roots_.empty()) mju_scl3(centre, centre, 1.0 / static_cast<double>(roots_.size()));
  mjtNum spread = 0;
  for (int b : roots_) spread = std::max(spread, mju_dist3(centre, d->xpos + 3 * b));
  camera->type = mjCAMERA_FREE;
  mju_copy3(camera->lookat, centre);
  camera->distance = config_.orbit_distance > 0
                         ? config_.orbit_distance
                         : std::max<mjtNum>(2 * spread + 1.5 * m->stat.extent / 4, 1.0);
  camera->elevation = config_.orbit_elevation;
  camera->azimuth = std::fmod(360.0 * t / config_.orbit_period, 360.0);
}

}  // namespace urlab::viewer::internal
