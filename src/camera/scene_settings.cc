// The cameras' scene section (urlab/camera/scene_settings.h): what each key takes is data (the
// tables below); the reader's checks report a bad value at its file:line; the stream names are
// checked against the scene's entries when parsed and against the compiled model after it.
#include "urlab/camera/scene_settings.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <any>
#include <set>

#include "urlab/world/scene.h"
#include "world/scene_section.h"

namespace urlab::camera {

namespace {

using world::NumberRange;
using world::SectionReader;

constexpr NumberRange kRate{0, 1000, true};  // frames per second

int Pixels(const SectionReader& r, const YAML::Node& n, const std::string& what) {
  return r.Whole(n, what, 1, 8192);
}

std::vector<std::string> Modes(const SectionReader& r, const YAML::Node& n,
                               const std::string& what) {
  std::vector<std::string> modes =
      n.IsScalar() ? std::vector<std::string>{r.String(n, what)} : r.Names(n, what);
  if (modes.empty()) r.Fail(n, what + " must name at least one mode");
  std::set<std::string> seen;
  for (const auto& m : modes) {
    if (std::find_if(std::begin(kCameraModes), std::end(kCameraModes),
                     [&](const char* k) { return m == k; }) == std::end(kCameraModes)) {
      r.Fail(n, what + ": unknown mode '" + m + "' (expected rgb, depth, segmentation, instance)");
    }
    if (!seen.insert(m).second) r.Fail(n, what + ": mode '" + m + "' is listed twice");
  }
  return modes;
}

// One entry of `cameras.streams`: {width, height, rate, modes, latency}, or nothing.
CameraSettings Stream(const SectionReader& r, const YAML::Node& v, const std::string& what) {
  CameraSettings cs;
  cs.where = r.At(v);
  if (v.IsNull()) return cs;
  if (!v.IsMap()) r.Fail(v, what + " must be a mapping (width, height, rate, modes, latency)");
  r.CheckKeys(v, what, {"width", "height", "rate", "modes", "latency"});
  if (v["width"]) cs.width = Pixels(r, v["width"], what + ".width");
  if (v["height"]) cs.height = Pixels(r, v["height"], what + ".height");
  if (v["rate"]) cs.rate = r.Number(v["rate"], what + ".rate", kRate);
  if (v["modes"]) cs.modes = Modes(r, v["modes"], what + ".modes");
  if (v["latency"]) cs.latency = r.LatencyEntry(v["latency"], what + ".latency");
  return cs;
}

// cameras: {enabled, width, height, rate, modes, shadows, reflections, samples, gl, streams}.
std::any Parse(const SectionReader& r, const YAML::Node& n, const world::SceneConfig& scene) {
  struct Flag {
    const char* key;
    bool CamerasConfig::*field;
  };
  static constexpr Flag kFlags[] = {{"enabled", &CamerasConfig::enabled},
                                    {"shadows", &CamerasConfig::shadows},
                                    {"reflections", &CamerasConfig::reflections}};
  struct Size {
    const char* key;
    int CamerasConfig::*field;
  };
  static constexpr Size kSizes[] = {{"width", &CamerasConfig::width},
                                    {"height", &CamerasConfig::height}};
  static constexpr const char* kGl[] = {"auto", "egl", "osmesa"};
  CamerasConfig c;
  c.where = r.At(n);
  if (!n.IsMap()) r.Fail(n, "cameras must be a mapping");
  r.CheckKeys(n, "cameras",
              {"enabled", "width", "height", "rate", "modes", "shadows", "reflections", "samples",
               "gl", "streams"});
  for (const Flag& f : kFlags) {
    if (n[f.key]) c.*f.field = r.Bool(n[f.key], std::string("cameras.") + f.key);
  }
  for (const Size& f : kSizes) {
    if (n[f.key]) c.*f.field = Pixels(r, n[f.key], std::string("cameras.") + f.key);
  }
  if (n["rate"]) c.rate = r.Number(n["rate"], "cameras.rate", kRate);
  if (n["modes"]) c.modes = Modes(r, n["modes"], "cameras.modes");
  if (n["samples"]) c.samples = r.Whole(n["samples"], "cameras.samples", 0, 16);
  if (n["gl"]) {
    c.gl = r.String(n["gl"], "cameras.gl");
    if (std::none_of(std::begin(kGl), std::end(kGl), [&](const char* g) { return c.gl == g; })) {
      r.Fail(n["gl"], "cameras.gl must be auto, egl or osmesa");
    }
  }
  if (const auto streams = n["streams"]) {
    if (!streams.IsMap()) {
      r.Fail(streams, "cameras.streams must map \"articulation/camera\" to settings");
    }
    for (const auto& [key, v] : r.Entries(streams, "cameras.streams")) {
      const std::string what = "cameras.streams." + key;
      if (std::count(key.begin(), key.end(), '/') != 1 || key.front() == '/' || key.back() == '/') {
        r.Fail(v, what + ": the key must be \"articulation/camera\"");
      }
      c.cameras[key] = Stream(r, v, what);
    }
  }
  // Each stream names an entry of the scene (articulations, props, terrain and launchers share
  // one namespace).
  std::set<std::string> names;
  for (const auto& a : scene.articulations) names.insert(a.name);
  for (const auto& p : scene.props) names.insert(p.spec.name);
  for (const auto& t : scene.terrain) names.insert(t.spec.name);
  for (const auto& l : scene.launchers) names.insert(l.spec.name);
  for (const auto& [key, settings] : c.cameras) {
    const std::string art = key.substr(0, key.find('/'));
    if (!names.count(art)) {
      throw InputError(settings.where,
                       "cameras.streams." + key + ": no articulation '" + art + "' in the scene");
    }
  }
  return c;
}

// Each stream's camera exists in its articulation's compiled MJCF.
void CheckCompiled(const std::any& settings, const world::SceneConfig& scene,
                   const world::CompiledScene& compiled, Diagnostics& sink) {
  const mjModel* m = compiled.model.get();
  const auto* c = std::any_cast<CamerasConfig>(&settings);
  if (!m || !c) return;
  for (const auto& [key, stream] : c->cameras) {
    const auto slash = key.find('/');
    const std::string art = key.substr(0, slash), cam = key.substr(slash + 1);
    for (std::size_t i = 0; i < scene.articulations.size() && i < compiled.articulations.size();
         ++i) {
      const world::ArticulationConfig& a = scene.articulations[i];
      if (a.name != art) continue;
      const std::string& prefix = compiled.articulations[i].prefix;
      std::vector<std::string> cams;  // its cameras' short names, in id order
      for (int j = 0; j < m->ncam; ++j) {
        const char* name = mj_id2name(m, mjOBJ_CAMERA, j);
        if (name && std::string_view(name).starts_with(prefix)) {
          cams.emplace_back(std::string_view(name).substr(prefix.size()));
        }
      }
      if (std::find(cams.begin(), cams.end(), cam) != cams.end()) continue;
      std::string list;
      for (const std::string& x : cams) list += (list.empty() ? "" : ", ") + x;
      sink.Error(stream.where, "cameras.streams." + key + ": articulation '" + a.name +
                                   "' has no camera '" + cam + "' in its MJCF " + a.mjcf +
                                   " (it has: " + (list.empty() ? "none" : list) + ")");
    }
  }
}

}  // namespace

void RegisterSceneSections() {
  world::RegisterSceneSection({kCamerasSection, &Parse, &CheckCompiled});
}

const CamerasConfig& CamerasOf(const world::SceneConfig& scene) {
  static const CamerasConfig kDefaults;
  const auto* c = scene.sections.Get<CamerasConfig>(kCamerasSection);
  return c ? *c : kDefaults;
}

CamerasConfig& EditCameras(world::SceneConfig& scene) {
  return scene.sections.GetOrAdd<CamerasConfig>(kCamerasSection);
}

}  // namespace urlab::camera
