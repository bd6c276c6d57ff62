// The key names a scene may bind (checked when the scene loads, world/input_keys.h) are exactly
// the names the viewer maps to keys (viewer/input_mapping.h): a scene that loads never names a
// key the viewer cannot press, and the viewer never knows a key loading would refuse.
#include <gtest/gtest.h>

#include <cctype>
#include <string>
#include <vector>

#include "viewer/input_mapping.h"
#include "world/input_keys.h"

namespace urlab {
namespace {

TEST(KeyNames, TheSceneCheckAndTheViewerAgree) {
  std::vector<std::string> names;
  for (char c = 'a'; c <= 'z'; ++c) names.emplace_back(1, c);
  for (char c = '0'; c <= '9'; ++c) names.emplace_back(1, c);
  for (const char* k : world::kNamedKeys) names.emplace_back(k);
  for (const std::string& n : names) {
    EXPECT_TRUE(world::IsKnownKeyName(n)) << n;
    EXPECT_GE(viewer::internal::KeyCode(n), 0) << n;
    std::string upper = n;
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    EXPECT_TRUE(world::IsKnownKeyName(upper)) << upper;
    EXPECT_GE(viewer::internal::KeyCode(upper), 0) << upper;
  }
  for (const char* bad : {"", "F13", "ctrl", " a", "aa", "-", "escape"}) {
    EXPECT_FALSE(world::IsKnownKeyName(bad)) << bad;
    EXPECT_LT(viewer::internal::KeyCode(bad), 0) << bad;
  }
}

}  // namespace
}  // namespace urlab
