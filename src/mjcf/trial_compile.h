#pragma once
// The dialect bridge's trial compile (internal to the mjcf module): MuJoCo 2.2.2 compiles a
// document's text from an in-memory VFS so that a pass can read what the compiler derives
// (dampratio's reflected inertia, qpos0 for keyframe padding, a child model's keyframes).
//
// Thread: any thread; no state but MuJoCo's handlers.
#include <mujoco/mujoco.h>

#include <string>

namespace urlab::mjcf {

// mj_loadXML of `xml`; nullptr and the compiler's message in `error` on failure. The caller
// frees the model with mj_deleteModel.
mjModel* TrialCompile(const std::string& xml, std::string* error);

}  // namespace urlab::mjcf
