#pragma once
// The default camera: a free camera that frames the whole composed scene (every articulation,
// prop, terrain and launcher), not MuJoCo's model statistics alone: the bounding sphere of
// every geom (planes excepted: a floor is as large as it likes) and body, seen at a three-
// quarter angle across the scene's longer horizontal extent, far enough back that the sphere
// fits the viewport's narrower field of view.
//
// Threading contract: any thread, on a model and data nobody writes meanwhile (the viewer calls
// it on the main thread with its own copy).
#include <mujoco/mujoco.h>

namespace urlab::viewer::internal {

struct SceneBounds {
  mjtNum center[3] = {0, 0, 0};
  mjtNum radius = 0;
  mjtNum extent[3] = {0, 0, 0};  // the box's size along x, y, z
};

// The bounds of the positions in `d` (kinematics must have run).
SceneBounds ComputeSceneBounds(const mjModel* m, const mjData* d);

// Points the free camera `cam` at the scene, for a viewport of `aspect` (width / height).
void FrameScene(const mjModel* m, const mjData* d, double aspect, mjvCamera* cam);

}  // namespace urlab::viewer::internal
