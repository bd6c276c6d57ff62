#pragma once
// The cameras' scene section `cameras:` (issue 11): the global streaming toggle, the defaults
// every streamed camera takes, the off-screen renderer's settings and per-camera settings. The
// camera module owns the settings and their parser; the scene file parser hands it the section
// through the registration (src/world/scene_section.h), so a bad value is an InputError at its
// file:line, and the cameras `cameras.streams` names are checked against the compiled scene by
// the same registration (`urlab validate` refuses what `run` and `view` would).
//
// Which of its MJCF cameras an articulation streams is its own entry's `cameras:` key
// (world::ArticulationConfig); this section says how they stream.
//
// Threading contract: RegisterSceneSections before any scene is parsed (main thread at start);
// the settings are value types.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/physics/latency.h"
#include "urlab/world/scene_file.h"

namespace urlab::camera {

// How one camera streams; unset fields take the `cameras:` section's defaults.
struct CameraSettings {
  std::optional<int> width, height;
  std::optional<double> rate;                     // frames per second
  std::optional<std::vector<std::string>> modes;  // rgb | depth | segmentation | instance
  // Emulated camera delay (physics/latency.h's keys; world::CameraStreams::SetDelay), drawn
  // from the scene's seed.
  std::optional<physics::LatencySetting> latency;
  SourceLocation where;
};

// The scene's `cameras:` section: per-camera settings are keyed "{articulation}/{camera}"
// (naming a camera there also streams it).
struct CamerasConfig {
  bool enabled = true;  // false: no camera renders or streams, whatever articulations ask
  int width = 640, height = 480;
  double rate = 30;
  std::vector<std::string> modes = {"rgb"};
  // Off-screen rendering (software rendering pays dearly for each: off by default).
  bool shadows = false, reflections = false;
  int samples = 0;
  std::string gl = "auto";  // auto | egl | osmesa
  std::map<std::string, CameraSettings> cameras;
  SourceLocation where;
};

// The camera modes a scene may ask for, in wire order.
inline constexpr const char* kCameraModes[] = {"rgb", "depth", "segmentation", "instance"};

inline constexpr const char* kCamerasSection = "cameras";

// Registers the parser and the compiled-scene check of `cameras:` (idempotent).
void RegisterSceneSections();

// The scene's settings, or the defaults when it has no `cameras:` section.
const CamerasConfig& CamerasOf(const world::SceneConfig& scene);
// The scene's settings to change (made the defaults first when absent), for code that adjusts a
// loaded scene (`--video`, `urlab bench cameras`).
CamerasConfig& EditCameras(world::SceneConfig& scene);

}  // namespace urlab::camera
