#pragma once
// Model files for parameterised tests over whole folders, and their test names.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace urlab::testing {

// MuJoCo's own model corpus (the model/ and test/ folders of the pinned release, brought by
// tools/corpus_check), when $URLAB_MUJOCO_MODELS names it; "" otherwise (the tests then cover the
// project's own models only).
inline std::string MujocoCorpusDir() {
  const char* dir = std::getenv("URLAB_MUJOCO_MODELS");
  return dir ? dir : "";
}

// Every .xml below `dirs` (missing folders skipped), sorted; files under parts/ are only meant to
// be included and are left out.
inline std::vector<std::string> ModelFilesIn(const std::vector<std::string>& dirs) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  for (const std::string& dir : dirs) {
    if (dir.empty() || !fs::is_directory(dir)) continue;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.path().extension() != ".xml") continue;
      if (e.path().string().find("/parts/") != std::string::npos) continue;
      out.push_back(e.path().string());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// "{folder}_{stem}_{index}" with every other character an underscore.
inline std::string ModelTestName(const ::testing::TestParamInfo<std::string>& info) {
  namespace fs = std::filesystem;
  std::string n = fs::path(info.param).parent_path().filename().string() + "_" +
                  fs::path(info.param).stem().string();
  for (char& c : n) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return n + "_" + std::to_string(info.index);
}

}  // namespace urlab::testing
