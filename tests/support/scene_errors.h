// Test helpers for the scene-section tests: a scene of one arm with more lines after it, and a
// scene text that world::ParseScene must refuse at a given file and line, with a message
// containing a given text (the shape every scene-section test checks its bad input in).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "urlab/core/error.h"
#include "urlab/world/scene_file.h"

namespace urlab::testing {

// The bundled arm: the one articulation of the scenes the section tests parse.
inline const std::string kArm = URLAB_SOURCE_DIR "/examples/models/pendulum_arm.xml";

// "articulations:\n  - name: a\n    mjcf: ARM\n" followed by `extra` (from line 4 on).
inline std::string WithArm(const std::string& extra) {
  return "articulations:\n  - name: a\n    mjcf: " + kArm + "\n" + extra;
}

inline void ExpectSceneRefusedAt(const std::string& yaml, const std::string& path, int line,
                                 const std::string& message) {
  try {
    world::ParseScene(yaml, path);
    ADD_FAILURE() << "accepted:\n" << yaml;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, path) << yaml;
    EXPECT_EQ(e.where().line, line) << yaml << e.what();
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

}  // namespace urlab::testing
