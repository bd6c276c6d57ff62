#include "camera/camera_plan.h"

#include <algorithm>
#include <map>

namespace urlab::camera::internal {

namespace {

// The articulation's cameras in id order: short name -> id.
std::vector<std::pair<std::string, int>> CamerasOf(const world::Session& session,
                                                   const world::Articulation& art) {
  const mjModel* m = session.engine().model();
  std::vector<std::pair<std::string, int>> out;
  for (int i = 0; i < m->ncam; ++i) {
    const char* name = mj_id2name(m, mjOBJ_CAMERA, i);
    if (!name || session.OwnerOf(name) != &art) continue;
    out.emplace_back(std::string(name).substr(art.prefix.size()), i);
  }
  return out;
}

}  // namespace

std::vector<PlannedCamera> PlanCameras(const world::Session& session, const CamerasConfig& config) {
  std::vector<PlannedCamera> plan;
  if (!config.enabled) return plan;
  for (const world::Articulation& art : session.articulations()) {
    const auto cams = CamerasOf(session, art);
    auto settings_of = [&](const std::string& cam) -> const CameraSettings* {
      auto it = config.cameras.find(art.name() + "/" + cam);
      return it == config.cameras.end() ? nullptr : &it->second;
    };
    // Which names stream, each checked against the MJCF.
    std::vector<std::string> wanted;
    if (art.config.all_cameras) {
      for (const auto& c : cams) wanted.push_back(c.first);
    }
    auto require = [&](const std::string& cam, const SourceLocation& where) {
      if (std::none_of(cams.begin(), cams.end(), [&](const auto& c) { return c.first == cam; })) {
        std::string list;
        for (const auto& c : cams) list += (list.empty() ? "" : ", ") + c.first;
        throw InputError(where, "articulation '" + art.name() + "' has no camera '" + cam +
                                    "' in its MJCF (it has: " + (list.empty() ? "none" : list) +
                                    ")");
      }
      if (std::find(wanted.begin(), wanted.end(), cam) == wanted.end()) wanted.push_back(cam);
    };
    for (const auto& cam : art.config.cameras) require(cam, art.config.where);
    for (const auto& [key, s] : config.cameras) {
      if (key.substr(0, key.find('/')) == art.name())
        require(key.substr(key.find('/') + 1), s.where);
    }
    for (const auto& [name, id] : cams) {
      if (std::find(wanted.begin(), wanted.end(), name) == wanted.end()) continue;
      PlannedCamera p;
      p.articulation = art.name();
      p.camera = name;
      p.camera_id = id;
      const CameraSettings* s = settings_of(name);
      p.width = s && s->width ? *s->width : config.width;
      p.height = s && s->height ? *s->height : config.height;
      p.rate = s && s->rate ? *s->rate : config.rate;
      p.modes = s && s->modes ? *s->modes : config.modes;
      if (s) p.latency = s->latency;
      plan.push_back(std::move(p));
    }
  }
  return plan;
}

std::vector<int> GeomArticulations(const world::Session& session) {
  const mjModel* m = session.engine().model();
  std::map<const world::Articulation*, int> index;
  for (std::size_t i = 0; i < session.articulations().size(); ++i) {
    index[&session.articulations()[i]] = static_cast<int>(i);
  }
  std::vector<int> out(static_cast<std::size_t>(m->ngeom), -1);
  for (int g = 0; g < m->ngeom; ++g) {
    const char* body = mj_id2name(m, mjOBJ_BODY, m->geom_bodyid[g]);
    const world::Articulation* owner = body ? session.OwnerOf(body) : nullptr;
    if (!owner) {
      const char* geom = mj_id2name(m, mjOBJ_GEOM, g);
      owner = geom ? session.OwnerOf(geom) : nullptr;  // world geoms an articulation brought
    }
    if (owner) out[static_cast<std::size_t>(g)] = index[owner];
  }
  return out;
}

}  // namespace urlab::camera::internal
