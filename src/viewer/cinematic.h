#pragma once
// Cinematic cameras (the description's Cinematic Tools), toggled with O: an orbit camera that
// circles the detected robots (the mean of every articulation's root body, at a distance that
// frames them all), and a keyframe camera path from the scene file (positions and look-at targets
// at times, interpolated with Catmull-Rom splines so the camera moves smoothly through every
// key). Both follow the simulation's time (a paused simulation holds the shot).
//
// Threading contract: main thread only.
#include <mujoco/mujoco.h>

#include <array>
#include <vector>

#include "urlab/viewer/scene_settings.h"

namespace urlab::viewer::internal {

enum class CinematicMode { kOff, kOrbit, kPath };
const char* ToString(CinematicMode mode);

struct CameraPose {
  std::array<double, 3> pos{}, look_at{};
};

// The path's pose at time t (keys sorted by time, at least one): before the first key the first
// pose, after the last the last one, or with `loop` t wraps over the path's duration.
CameraPose SamplePath(const std::vector<CameraKey>& keys, double t, bool loop);
// Points a free camera from pose.pos at pose.look_at.
void PoseToCamera(const CameraPose& pose, mjvCamera* camera);

class Cinematic {
 public:
  void Configure(const CinematicSettings& config, std::vector<int> root_bodies);
  // O: off -> orbit -> path (when the scene has one) -> off. Returns the new mode.
  CinematicMode Next();
  CinematicMode mode() const { return mode_; }
  // Back to off (possession or the free-camera key take the camera).
  void Stop() { mode_ = CinematicMode::kOff; }
  // Sets `camera` for simulation time t from the viewer's copy of the state.
  void Apply(const mjModel* m, const mjData* d, double t, mjvCamera* camera) const;

 private:
  CinematicSettings config_;
  std::vector<int> roots_;
  CinematicMode mode_ = CinematicMode::kOff;
};

}  // namespace urlab::viewer::internal
