// Composition through MuJoCo's mjs_attach: file assets named implicitly by their file (how
// Unitree and MuJoCo Menagerie models name their meshes) are named "{prefix}{file stem}" once and
// every reference finds them; options follow the scene's resolution order.
#include "urlab/mjcf/compose.h"

#include <algorithm>
#include <filesystem>

#include "core/gcc_workarounds.h"
#include "mujoco_test.h"
#include "urlab/mjcf/spec.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

class ComposeTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("compose");
    // Real asset files of every kind MuJoCo names after their file.
    const std::string corpus = testing::TestData("mjcf/corpus/assets");
    fs::create_directories(dir_ + "/meshes/sub");
    fs::create_directories(dir_ + "/textures");
    fs::copy_file(corpus + "/meshes/tetra.stl", dir_ + "/meshes/pelvis.STL");
    fs::copy_file(corpus + "/meshes/octa.obj", dir_ + "/meshes/sub/foot.v2.obj");
    fs::copy_file(corpus + "/meshes/wedge.stl", dir_ + "/meshes/knee.stl");
    fs::copy_file(corpus + "/meshes/strip.skn", dir_ + "/meshes/strip.skn");
    fs::copy_file(corpus + "/hfields/terrain.png", dir_ + "/meshes/terrain.png");
    fs::copy_file(corpus + "/textures/checker.png", dir_ + "/textures/checker.png");
    fs::copy_file(corpus + "/textures/sky.png", dir_ + "/textures/sky.png");
  }

  // Composes `xml` (written to the temporary folder) as the single articulation `name`.
  mjcf::ComposeResult ComposeOne(const std::string& xml, const std::string& name = "r") {
    std::vector<mjcf::ArticulationInput> in(1);
    in[0].name = name;
    in[0].file = testing::WriteTextFile(dir_, "robot.xml", xml);
    in[0].spec = mjcf::ParseFile(in[0].file);
    return mjcf::Compose(std::move(in));
  }

  // MuJoCo's compilation of the composed root spec; Error with MuJoCo's message.
  static physics::ModelPtr Compile(const mjcf::ComposeResult& composed) {
    mjModel* m = mj_compile(composed.spec.get(), nullptr);
    if (!m) throw Error(mjs_getError(composed.spec.get()));
    return physics::ModelPtr(m);
  }

  std::string dir_;
};

// Every kind of implicitly named file asset: MuJoCo strips the folder and the extension.
constexpr const char* kImplicitAssets = R"(<mujoco model="implicit">
  <compiler meshdir="meshes" texturedir="textures"/>
  <asset>
    <mesh file="pelvis.STL"/>
    <mesh file="sub/foot.v2.obj"/>
    <mesh file="knee.stl"/>
    <skin file="strip.skn"/>
    <hfield file="terrain.png" size="1 1 .1 .1"/>
    <texture type="2d" file="checker.png"/>
    <texture type="skybox" file="sky.png"/>
    <material name="paint" texture="checker"/>
  </asset>
  <worldbody>
    <geom type="hfield" hfield="terrain" material="paint"/>
    <body name="skin_a" pos="0 0 1">
      <freejoint/>
      <geom type="mesh" mesh="pelvis"/>
      <geom type="mesh" mesh="foot.v2" pos="0 0 -.1"/>
      <geom type="mesh" mesh="knee" pos="0 0 -.2"/>
      <body name="skin_b" pos=".2 0 0">
        <joint axis="0 1 0"/>
        <geom type="box" size=".1 .04 .04"/>
      </body>
    </body>
  </worldbody>
</mujoco>)";

TEST_F(ComposeTest, ImplicitFileAssetNamesArePrefixedOnce) {
  // The same file, loaded by MuJoCo itself, gives the unprefixed names.
  const std::string path = testing::WriteTextFile(dir_, "plain.xml", kImplicitAssets);
  physics::ModelPtr plain = physics::LoadXmlFile(path);
  ASSERT_GE(mj_name2id(plain.get(), mjOBJ_MESH, "pelvis"), 0);
  ASSERT_GE(mj_name2id(plain.get(), mjOBJ_MESH, "foot.v2"), 0);
  ASSERT_GE(mj_name2id(plain.get(), mjOBJ_MESH, "knee"), 0);

  mjcf::ComposeResult composed = ComposeOne(kImplicitAssets);
  physics::ModelPtr m = Compile(composed);
  const std::string xml = mjcf::SaveXml(composed.spec.get());
  for (auto [type, name] : std::vector<std::pair<mjtObj, const char*>>{{mjOBJ_MESH, "r_pelvis"},
                                                                       {mjOBJ_MESH, "r_foot.v2"},
                                                                       {mjOBJ_MESH, "r_knee"},
                                                                       {mjOBJ_SKIN, "r_strip"},
                                                                       {mjOBJ_HFIELD, "r_terrain"},
                                                                       {mjOBJ_TEXTURE, "r_checker"},
                                                                       {mjOBJ_TEXTURE, "r_sky"}}) {
    EXPECT_GE(mj_name2id(m.get(), type, name), 0) << name << "\n" << xml;
  }
  EXPECT_EQ(xml.find("r_r_"), std::string::npos) << xml;
  // The composed model is the original one under new names.
  EXPECT_EQ(m->nmesh, plain->nmesh);
  EXPECT_EQ(m->nskin, plain->nskin);
  EXPECT_EQ(m->ntex, plain->ntex);
  EXPECT_EQ(m->nhfield, plain->nhfield);
  EXPECT_EQ(m->nmeshvert, plain->nmeshvert);
  // The SKN skin holds the file's numbers, its bones the prefixed bodies.
  ASSERT_EQ(m->nskinvert, plain->nskinvert);
  ASSERT_EQ(m->nskinface, plain->nskinface);
  ASSERT_EQ(m->nskinbone, plain->nskinbone);
  ASSERT_EQ(m->nskinbonevert, plain->nskinbonevert);
  auto same = [](const auto* a, const auto* b, int n) { return std::equal(a, a + n, b); };
  EXPECT_TRUE(same(m->skin_vert, plain->skin_vert, 3 * m->nskinvert));
  EXPECT_TRUE(same(m->skin_face, plain->skin_face, 3 * m->nskinface));
  EXPECT_TRUE(same(m->skin_bonebindpos, plain->skin_bonebindpos, 3 * m->nskinbone));
  EXPECT_TRUE(same(m->skin_bonebindquat, plain->skin_bonebindquat, 4 * m->nskinbone));
  EXPECT_TRUE(same(m->skin_bonevertid, plain->skin_bonevertid, m->nskinbonevert));
  EXPECT_TRUE(same(m->skin_bonevertweight, plain->skin_bonevertweight, m->nskinbonevert));
  for (int b = 0; b < m->nskinbone; ++b) {
    const int body = m->skin_bonebodyid[b];
    EXPECT_EQ(std::string(m->names + m->name_bodyadr[body]),
              "r_" + std::string(plain->names + plain->name_bodyadr[plain->skin_bonebodyid[b]]));
  }
}

// A truncated SKN file is refused by MuJoCo naming the skin's file.
TEST_F(ComposeTest, TruncatedSkinFileIsRefused) {
  const std::string skn = dir_ + "/meshes/strip.skn";
  fs::resize_file(skn, fs::file_size(skn) - 4);
  try {
    Compile(ComposeOne(kImplicitAssets));
    FAIL() << "compiled a truncated skin file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("strip.skn"), std::string::npos) << e.what();
  }
}

// Two copies of a robot with implicit mesh names: each copy's geoms find its own prefixed mesh.
TEST_F(ComposeTest, TwoCopiesShareImplicitlyNamedMeshes) {
  const std::string path = testing::WriteTextFile(dir_, "robot.xml", kImplicitAssets);
  std::vector<mjcf::ArticulationInput> in(2);
  for (int i = 0; i < 2; ++i) {
    // -O3: a false -Wrestrict inside std::string's assignment (GCC PR 105329 / 105651).
    URLAB_GCC_IGNORE("-Wrestrict")
    in[i].name = i ? "b" : "a";
    URLAB_GCC_RESTORE
    in[i].spec = mjcf::ParseFile(path);
    in[i].placement.pos = {0, 3.0 * i, 0};
  }
  mjcf::ComposeResult composed = mjcf::Compose(std::move(in));
  physics::ModelPtr m = Compile(composed);
  EXPECT_EQ(m->nmesh, 6);
  EXPECT_EQ(m->nbody, 5);
  for (const char* prefix : {"a_", "b_"}) {
    const int mesh = mj_name2id(m.get(), mjOBJ_MESH, (std::string(prefix) + "pelvis").c_str());
    ASSERT_GE(mesh, 0) << prefix;
    const int body = mj_name2id(m.get(), mjOBJ_BODY, (std::string(prefix) + "skin_a").c_str());
    int users = 0;
    for (int g = 0; g < m->ngeom; ++g) {
      users +=
          m->geom_type[g] == mjGEOM_MESH && m->geom_dataid[g] == mesh && m->geom_bodyid[g] == body;
    }
    EXPECT_EQ(users, 1) << prefix;
  }
}

// A name given explicitly keeps winning over the file name, and a skybox without a file stays
// unnamed.
TEST_F(ComposeTest, ExplicitNamesAndUnnamedSkyboxAreUnchanged) {
  mjcf::ComposeResult composed = ComposeOne(R"(<mujoco>
  <compiler meshdir="meshes"/>
  <asset>
    <mesh name="base" file="pelvis.STL"/>
    <texture type="skybox" builtin="gradient" width="8" height="8" rgb1="1 1 1" rgb2="0 0 0"/>
  </asset>
  <worldbody><body><freejoint/><geom type="mesh" mesh="base"/></body></worldbody>
</mujoco>)");
  physics::ModelPtr m = Compile(composed);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_MESH, "r_base"), 0);
  ASSERT_EQ(m->ntex, 1);
  EXPECT_STREQ(m->names + m->name_texadr[0], "");
}

}  // namespace
}  // namespace urlab

namespace urlab {
namespace {

// Articulations that disagree on an option get a warning, unless the scene sets that option.
TEST_F(ComposeTest, SceneOptionsSettleDisagreements) {
  auto inputs = [&] {
    std::vector<mjcf::ArticulationInput> in(2);
    in[0].name = "a";
    in[0].spec = mjcf::ParseFile(testing::WriteTextFile(
        dir_, "a.xml", R"(<mujoco><option timestep="0.001" cone="elliptic"/></mujoco>)"));
    in[1].name = "b";
    in[1].spec = mjcf::ParseFile(testing::WriteTextFile(dir_, "b.xml", "<mujoco/>"));
    return in;
  };
  auto warned = [](const mjcf::ComposeResult& r, const std::string& key) {
    for (const auto& d : r.diagnostics) {
      if (d.message.find("option " + key + "=") != std::string::npos) return true;
    }
    return false;
  };
  const mjcf::ComposeResult plain = mjcf::Compose(inputs());
  EXPECT_TRUE(warned(plain, "timestep"));
  EXPECT_TRUE(warned(plain, "cone"));
  const mjcf::ComposeResult settled = mjcf::Compose(inputs(), {{"timestep", "0.004"}});
  EXPECT_FALSE(warned(settled, "timestep"));
  EXPECT_TRUE(warned(settled, "cone"));
  physics::ModelPtr m = Compile(settled);
  EXPECT_EQ(m->opt.timestep, 0.004);
  EXPECT_EQ(m->opt.cone, mjCONE_ELLIPTIC);
}

// What MuJoCo 3.17's attach loses and Compose puts back (found on MuJoCo's own test corpus): two
// unnamed keys, a weld to body2="world", a light aimed at the world; a flex in a body keeps its
// edge equality.
TEST_F(ComposeTest, WorldReferencesUnnamedKeysAndFlexEqualitiesSurviveTheAttach) {
  const mjcf::ComposeResult composed = ComposeOne(R"(<mujoco>
  <worldbody>
    <light name="spot" mode="targetbodycom" target="world" pos="0 0 4"/>
    <body name="box" pos="0 0 1">
      <freejoint/>
      <geom type="box" size=".1 .1 .1"/>
    </body>
    <body name="cloth" pos="0 0 2">
      <flexcomp name="sheet" type="grid" count="3 3 1" spacing=".1 .1 .1" mass="1" dim="2">
        <edge equality="true"/>
      </flexcomp>
    </body>
  </worldbody>
  <equality><weld name="hold" body1="box" body2="world"/></equality>
  <keyframe><key time="1"/><key time="2"/></keyframe>
</mujoco>)");
  const physics::ModelPtr model = Compile(composed);
  const mjModel* m = model.get();
  const int hold = mj_name2id(m, mjOBJ_EQUALITY, "r_hold");
  ASSERT_GE(hold, 0);
  EXPECT_EQ(m->eq_obj2id[hold], 0);  // the world
  const int spot = mj_name2id(m, mjOBJ_LIGHT, "r_spot");
  ASSERT_GE(spot, 0);
  EXPECT_EQ(m->light_targetbodyid[spot], 0);
  EXPECT_EQ(m->nkey, 2);
  EXPECT_GE(mj_name2id(m, mjOBJ_KEY, "r_key0"), 0);
  EXPECT_GE(mj_name2id(m, mjOBJ_KEY, "r_key1"), 0);
  ASSERT_EQ(m->nflex, 1);
  int flex_equalities = 0;
  for (int e = 0; e < m->neq; ++e) flex_equalities += m->eq_type[e] == mjEQ_FLEX;
  EXPECT_EQ(flex_equalities, 1);
}

}  // namespace
}  // namespace urlab
