#pragma once
// Which cameras of a running scene stream, and how: the scene's articulations that ask
// (`cameras: true` or a list) plus the cameras named in `cameras.streams`, each with its
// settings resolved against the section's defaults. Thread: main (reads the session's registry).
#include <string>
#include <vector>

#include "urlab/camera/scene_settings.h"
#include "urlab/world/session.h"

namespace urlab::camera::internal {

struct PlannedCamera {
  std::string articulation;
  std::string camera;  // the name in the articulation's MJCF
  int camera_id = -1;  // in the compiled scene
  int width = 0, height = 0;
  double rate = 0;
  std::vector<std::string> modes;
  std::optional<physics::LatencySetting> latency;  // the scene's camera delay
};

// Throws InputError (the scene file's line) for a camera the articulation's MJCF lacks.
std::vector<PlannedCamera> PlanCameras(const world::Session& session, const CamerasConfig& config);

// Per geom of the compiled scene, the index of the articulation owning its body (-1: none).
std::vector<int> GeomArticulations(const world::Session& session);

}  // namespace urlab::camera::internal
