#pragma once
// The scene's `randomize:` section (docs/scene-format.md): world's own settings (the session
// draws them at every reset, world/randomize.h's policy), parsed through the same registration
// as the subsystems' sections (src/world/scene_section.h), in its table from the start. Its
// names are checked against the scene's articulations and props when parsed, at their file:line.
// Thread: a value type; no synchronisation of its own.
#include "urlab/core/error.h"
#include "urlab/world/randomize.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

struct RandomizeSettings {
  RandomizeConfig config;  // empty: nothing is drawn
  SourceLocation where;    // the section's (for the session's checks against the model)
};

inline constexpr const char* kRandomizeSection = "randomize";

// The scene's settings, or none (empty) when it has no `randomize:` section.
const RandomizeSettings& RandomizeOf(const SceneConfig& scene);

}  // namespace urlab::world
