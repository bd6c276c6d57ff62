#include "render/view_camera.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::render {

namespace {

// Up to `limit` names of objects of `type`, for error messages.
std::string NamesOf(const mjModel* m, mjtObj type, int count, int first, int limit = 12) {
  std::vector<std::string> names;
  for (int i = first; i < count && static_cast<int>(names.size()) < limit; ++i) {
    if (const char* n = mj_id2name(m, type, i)) names.emplace_back(n);
  }
  if (names.empty()) return "none";
  std::string out = fmt::format("{}", fmt::join(names, ", "));
  if (count - first > limit) out += ", ...";
  return out;
}

// An id by full name, or by "articulation/name" (the scene's prefix "{articulation}_").
int Find(const mjModel* m, mjtObj type, std::string name) {
  int id = mj_name2id(m, type, name.c_str());
  if (id < 0) {
    std::replace(name.begin(), name.end(), '/', '_');
    id = mj_name2id(m, type, name.c_str());
  }
  return id;
}

// The radius of body `id`'s subtree in the reference configuration: the farthest geom's reach
// from the body's origin (body offsets summed down the tree, each geom's bounding sphere).
double SubtreeRadius(const mjModel* m, int id) {
  double radius = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    mjtNum offset[3] = {m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]};
    int b = m->geom_bodyid[g];
    while (b > id) {
      for (int k = 0; k < 3; ++k) offset[k] += m->body_pos[3 * b + k];
      b = m->body_parentid[b];
    }
    if (b == id) radius = std::max(radius, mju_norm3(offset) + m->geom_rbound[g]);
  }
  return radius;
}

}  // namespace

ViewCamera ParseViewCamera(const mjModel* m, const std::string& spec, const std::string& option) {
  ViewCamera out;
  mjv_defaultFreeCamera(m, &out.view);
  if (spec.empty() || spec == "free") {
    out.label = "free camera framing the scene";
    return out;
  }
  constexpr std::string_view kTrack = "track:";
  if (spec.starts_with(kTrack)) {
    const std::string body = spec.substr(kTrack.size());
    const int id = Find(m, mjOBJ_BODY, body);
    if (id <= 0) {
      throw Error(fmt::format("{} {}: no body '{}' to track (bodies: {})", option, spec, body,
                              NamesOf(m, mjOBJ_BODY, m->nbody, 1)));
    }
    out.view.type = mjCAMERA_TRACKING;
    out.view.trackbodyid = id;
    // A chase view: the tracked body's whole subtree (a robot) a third of the frame's height.
    const double radius = SubtreeRadius(m, id);
    out.view.distance = radius > 0 ? 4 * radius : 0.6 * m->stat.extent;
    out.view.elevation = -20;
    out.label = fmt::format("tracking body '{}'", mj_id2name(m, mjOBJ_BODY, id));
    return out;
  }
  const int id = Find(m, mjOBJ_CAMERA, spec);
  if (id < 0) {
    throw Error(fmt::format(
        "{} {}: no camera '{}' (use free, track:BODY or one of the model's cameras: {})", option,
        spec, spec, NamesOf(m, mjOBJ_CAMERA, m->ncam, 0)));
  }
  out.camera = id;
  out.label = fmt::format("camera '{}'", mj_id2name(m, mjOBJ_CAMERA, id));
  return out;
}

}  // namespace urlab::render
