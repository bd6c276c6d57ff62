// Test helper: a scene text that world::ParseScene must refuse at a given file and line, with a
// message containing a given text (the shape every scene-section test checks its bad input in).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "urlab/core/error.h"
#include "urlab/world/scene_file.h"

namespace urlab::testing {

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
