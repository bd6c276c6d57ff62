#pragma once
// The camera a rendering looks through, chosen by the user (`urlab render --camera`): an MJCF
// camera by name ("rig/top" or its full name "rig_top"), "free" (MuJoCo's default free camera:
// the whole scene framed, looking at the centre of the model's extent from 1.5 extents away), or
// "track:BODY" (a camera following the body at a fixed distance).
//
// Threading contract: none of its own (pure functions of the model).
#include <mujoco/mujoco.h>

#include <string>

namespace urlab::render {

struct ViewCamera {
  int camera = -1;    // the MJCF camera's id, -1 for a free or tracking view
  mjvCamera view{};   // the free or tracking camera (unused for an MJCF camera)
  std::string label;  // what it is, for logs
};

// Throws Error naming `option` and what it accepts (with the model's camera and body names)
// for an unknown camera or body.
ViewCamera ParseViewCamera(const mjModel* m, const std::string& spec, const std::string& option);

}  // namespace urlab::render
