#pragma once
// The viewer's scene sections: `viewer:` (render quality) and `cinematic:` (the O key's orbit and
// camera path). The viewer owns their settings and their parsers; the scene file parser hands it
// the sections through the registration (src/world/scene_section.h), so a scene file's errors in
// them are InputErrors at their file:line like every other key.
//
// Threading contract: RegisterSceneSections before any scene is parsed (main thread at start);
// the settings are value types.
#include <array>
#include <optional>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/world/scene_file.h"

namespace urlab::viewer {

// viewer: the desktop viewer's render quality (the command line's --shadows, --reflections,
// --skybox and --render-scale win over it); unset fields take the viewer's defaults.
struct QualitySettings {
  std::optional<bool> shadows, reflections, skybox;
  std::optional<double> render_scale;  // 0.25 to 2: the 3D view's resolution per window pixel
  SourceLocation where;
};

// Cinematic cameras (the viewer's O key): an orbit around every articulation's root body, and a
// keyframe camera path (positions and look-at targets at simulation times, interpolated smoothly).
struct CameraKey {
  double time = 0;
  std::array<double, 3> pos{}, look_at{};
};

struct CinematicSettings {
  double orbit_period = 30;      // seconds of simulation time per turn
  double orbit_elevation = -20;  // degrees
  double orbit_distance = 0;     // metres; 0 frames every robot
  std::vector<CameraKey> path;   // strictly increasing times
  bool loop = true;              // the path repeats (else it holds its last pose)
  SourceLocation where;
};

inline constexpr const char* kViewerSection = "viewer";
inline constexpr const char* kCinematicSection = "cinematic";

// Registers the parsers of `viewer:` and `cinematic:` (idempotent).
void RegisterSceneSections();

// The scene's settings, or the defaults when it has no such section.
const QualitySettings& QualityOf(const world::SceneConfig& scene);
const CinematicSettings& CinematicOf(const world::SceneConfig& scene);

}  // namespace urlab::viewer
