// The viewer's scene sections (urlab/viewer/scene_settings.h): what each key takes is data (the
// tables below); the reader's checks report a bad value at its file:line.
#include "urlab/viewer/scene_settings.h"

#include "world/scene_section.h"

namespace urlab::viewer {

namespace {

// viewer: {shadows, reflections, skybox, render_scale}.
std::any ParseQuality(const world::SectionReader& r, const YAML::Node& n,
                      const world::SceneConfig&) {
  if (!n.IsMap()) r.Fail(n, "viewer must be a map {shadows, reflections, skybox, render_scale}");
  struct Flag {
    const char* key;
    std::optional<bool> QualitySettings::*field;
  };
  static constexpr Flag kFlags[] = {{"shadows", &QualitySettings::shadows},
                                    {"reflections", &QualitySettings::reflections},
                                    {"skybox", &QualitySettings::skybox}};
  r.CheckKeys(n, "viewer", {"shadows", "reflections", "skybox", "render_scale"});
  QualitySettings v;
  v.where = r.At(n);
  for (const Flag& f : kFlags) {
    if (n[f.key]) v.*f.field = r.Bool(n[f.key], std::string("viewer.") + f.key);
  }
  if (n["render_scale"]) {
    v.render_scale =
        r.Number(n["render_scale"], "viewer.render_scale", world::NumberRange{0.25, 2});
  }
  return v;
}

// cinematic: {orbit_period, orbit_elevation, orbit_distance, loop, path: [{t, pos, look_at}]}.
std::any ParseCinematic(const world::SectionReader& r, const YAML::Node& n,
                        const world::SceneConfig&) {
  if (!n.IsMap()) r.Fail(n, "cinematic must be a map");
  struct Number {
    const char* key;
    double CinematicSettings::*field;
    world::NumberRange range;
  };
  static constexpr Number kNumbers[] = {
      {"orbit_period", &CinematicSettings::orbit_period,
       world::NumberRange{0, std::numeric_limits<double>::max(), true}},
      {"orbit_elevation", &CinematicSettings::orbit_elevation, world::NumberRange{-90, 90}},
      {"orbit_distance", &CinematicSettings::orbit_distance, world::kNonNegativeFiniteNumber}};
  r.CheckKeys(n, "cinematic",
              {"orbit_period", "orbit_elevation", "orbit_distance", "loop", "path"});
  CinematicSettings c;
  c.where = r.At(n);
  for (const Number& f : kNumbers) {
    if (n[f.key]) c.*f.field = r.Number(n[f.key], std::string("cinematic.") + f.key, f.range);
  }
  if (n["loop"]) c.loop = r.Bool(n["loop"], "cinematic.loop");
  if (const auto path = n["path"]) {
    if (!path.IsSequence()) r.Fail(path, "cinematic.path must be a list of keys {t, pos, look_at}");
    for (const auto& k : path) {
      if (!k.IsMap()) r.Fail(k, "cinematic.path keys must be maps {t, pos, look_at}");
      r.CheckKeys(k, "cinematic.path key", {"t", "pos", "look_at"});
      if (!k["t"] || !k["pos"] || !k["look_at"]) {
        r.Fail(k, "a cinematic.path key needs t, pos and look_at");
      }
      CameraKey key;
      key.time = r.Number(k["t"], "cinematic.path.t", world::kNonNegativeFiniteNumber);
      const auto p = r.Numbers(k["pos"], "cinematic.path.pos", 3);
      const auto l = r.Numbers(k["look_at"], "cinematic.path.look_at", 3);
      key.pos = {p[0], p[1], p[2]};
      key.look_at = {l[0], l[1], l[2]};
      if (!c.path.empty() && key.time <= c.path.back().time) {
        r.Fail(k["t"], "cinematic.path times must increase");
      }
      if (key.pos == key.look_at) r.Fail(k, "cinematic.path: pos and look_at must differ");
      c.path.push_back(key);
    }
  }
  return c;
}

}  // namespace

void RegisterSceneSections() {
  world::RegisterSceneSection({kViewerSection, &ParseQuality});
  world::RegisterSceneSection({kCinematicSection, &ParseCinematic});
}

const QualitySettings& QualityOf(const world::SceneConfig& scene) {
  static const QualitySettings kDefaults;
  const auto* s = scene.sections.Get<QualitySettings>(kViewerSection);
  return s ? *s : kDefaults;
}

const CinematicSettings& CinematicOf(const world::SceneConfig& scene) {
  static const CinematicSettings kDefaults;
  const auto* s = scene.sections.Get<CinematicSettings>(kCinematicSection);
  return s ? *s : kDefaults;
}

}  // namespace urlab::viewer
