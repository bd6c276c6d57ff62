// The viewer's scene sections (urlab/viewer/scene_settings.h): registered with the scene parser,
// `viewer:` and `cinematic:` are parsed by the viewer into its own settings, and bad input is an
// InputError at its file:line as before the sections moved out of world/scene_file.
#include "urlab/viewer/scene_settings.h"

#include <gtest/gtest.h>

#include <string>

#include "scene_errors.h"
#include "urlab/world/scene_file.h"

namespace urlab {
namespace {

using testing::WithArm;

class ViewerSceneSections : public ::testing::Test {
 protected:
  void SetUp() override { viewer::RegisterSceneSections(); }
};

TEST_F(ViewerSceneSections, BadInputIsRefusedAtItsLine) {
  struct Case {
    std::string yaml;
    int line;
    const char* message;
  };
  const Case cases[] = {
      // cinematic cameras (the viewer's O)
      {WithArm("cinematic: []\n"), 4, "cinematic must be a map"},
      {WithArm("cinematic: {orbit_period: 0}\n"), 4, "cinematic.orbit_period must be > 0"},
      {WithArm("cinematic: {orbit_elevation: 95}\n"), 4,
       "cinematic.orbit_elevation must be -90 to 90, not 95"},
      {WithArm("cinematic: {zoom: 2}\n"), 4, "unknown key 'zoom' in cinematic"},
      {WithArm("cinematic:\n  path:\n    - {t: 0, pos: [1, 0, 0]}\n"), 6,
       "needs t, pos and look_at"},
      {WithArm("cinematic:\n  path:\n    - {t: 1, pos: [1, 0, 0], look_at: [0, 0, 0]}\n"
               "    - {t: 1, pos: [2, 0, 0], look_at: [0, 0, 0]}\n"),
       7, "times must increase"},
      {WithArm("cinematic:\n  path:\n    - {t: 0, pos: [1, 0, 0], look_at: [1, 0, 0]}\n"), 6,
       "pos and look_at must differ"},
      // the viewer's render quality
      {WithArm("viewer: true\n"), 4, "viewer must be a map"},
      {WithArm("viewer: {shadows: maybe}\n"), 4, "viewer.shadows must be true or false"},
      {WithArm("viewer: {render_scale: 3}\n"), 4, "viewer.render_scale must be 0.25 to 2"},
      {WithArm("viewer: {fog: true}\n"), 4, "unknown key 'fog' in viewer"},
      {WithArm("viewer: {}\nviewer: {}\n"), 5, "duplicate key 'viewer' in the scene"},
      // still an unknown key beside them
      {WithArm("viewr: {}\n"), 4, "unknown key 'viewr' in the scene"},
  };
  for (const Case& c : cases)
    testing::ExpectSceneRefusedAt(c.yaml, "/tmp/s.yaml", c.line, c.message);
}

TEST_F(ViewerSceneSections, GoodValuesReachTheViewersSettings) {
  const world::SceneConfig v =
      world::ParseScene(WithArm("viewer: {shadows: false, skybox: true, render_scale: 0.5}\n"
                                "cinematic:\n  orbit_period: 12\n  loop: false\n"
                                "  path:\n    - {t: 0, pos: [1, 0, 0], look_at: [0, 0, 0]}\n"
                                "    - {t: 2, pos: [0, 1, 0], look_at: [0, 0, 0.5]}\n"),
                        "/tmp/v.yaml");
  const viewer::QualitySettings& q = viewer::QualityOf(v);
  EXPECT_EQ(q.shadows, false);
  EXPECT_EQ(q.skybox, true);
  EXPECT_FALSE(q.reflections.has_value());
  EXPECT_EQ(q.render_scale, 0.5);
  EXPECT_EQ(q.where.line, 4);
  const viewer::CinematicSettings& c = viewer::CinematicOf(v);
  EXPECT_EQ(c.orbit_period, 12);
  EXPECT_FALSE(c.loop);
  ASSERT_EQ(c.path.size(), 2u);
  EXPECT_EQ(c.path[1].look_at[2], 0.5);
  EXPECT_EQ(c.where.line, 6);  // (the mapping under the key starts on the next line)
  // Without the sections: the defaults.
  const world::SceneConfig plain = world::ParseScene(WithArm(""), "/tmp/p.yaml");
  EXPECT_FALSE(plain.sections.Has(viewer::kViewerSection));
  EXPECT_FALSE(viewer::QualityOf(plain).shadows.has_value());
  EXPECT_EQ(viewer::CinematicOf(plain).orbit_period, 30);
}

}  // namespace
}  // namespace urlab
