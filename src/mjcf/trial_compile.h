#pragma once
// The dialect bridge's trial compile (internal to the mjcf module): MuJoCo 2.2.2 compiles a
// document's text through physics::TryCompileXmlString, the project's one in-memory compile, so
// that a pass can read what the compiler derives (dampratio's reflected inertia, qpos0 for
// keyframe padding, a child model's keyframes, free bodies' inertial frames).
//
// Thread: any thread; no state but MuJoCo's handlers.
#include <string>

#include "urlab/physics/model.h"

namespace urlab::mjcf {

// The compiled model of `xml` (owned: freed however the caller leaves its scope), or nullptr and
// the compiler's message in `error`. Compiler warnings are not reported: the bridged model's real
// compile reports them once.
physics::ModelPtr TrialCompile(const std::string& xml, std::string* error);

}  // namespace urlab::mjcf
