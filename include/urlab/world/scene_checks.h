#pragma once
// Every check begin-play runs on a scene, in one place: `urlab validate` collects them into a
// Diagnostics sink without starting anything, and the manager, `urlab compile`, `urlab run` and
// `urlab bench loop` throw the first (BuildCheckedScene), so a scene that validates is a scene
// that runs. Thread: main (before the physics thread starts); no shared state.
#include "urlab/core/diagnostics.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

// Checks that need only the scene file: articulation names whose prefixes overlap ("a" and
// "a_b": prefix "a_" would also own "a_b_..."), hold_keyframe without an initial keyframe.
void CheckSceneConfig(const SceneConfig& scene, Diagnostics& sink);

// Checks against the composed and compiled scene: each articulation's initial keyframe exists,
// its keyframes have exactly its own number of qpos/qvel/act/ctrl/mocap values (MuJoCo refuses
// a single model's wrong-length key; composition fills keys after compiling, so this is checked
// here), its controller names only joints, actuators and keyframes it has
// (world::CheckController), and what its entry names besides exists in its MJCF: the cameras of
// its `cameras:` list, a free base for `twist:`, its own actuators for `input:` bindings
// (src/world/binding_checks.h); then each registered section's own check (the cameras of
// `cameras.streams`: src/world/scene_section.h).
void CheckCompiledScene(const SceneConfig& scene, const CompiledScene& compiled, Diagnostics& sink);

// CheckSceneConfig (throws the first error), BuildScene, CheckCompiledScene (throws the first
// error, "(and N more)"). What begin-play and every command that builds a scene call.
CompiledScene BuildCheckedScene(const SceneConfig& scene);

}  // namespace urlab::world
