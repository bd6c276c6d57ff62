// The MJCF grammar table (src/document/grammar_table.cc) that URLab's generated documents
// (props, terrain, launchers, the C++ builder) and `urlab mjcf roundtrip` are checked against:
// its structure, references and actuator shortcuts. (MuJoCo's own parser judges every model
// URLab loads; the table describes the MJCF of MuJoCo 2.2.2 plus the 3.x constructs those
// documents use, so it is no longer probed against the engine.)
#include "urlab/document/grammar.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <functional>
#include <set>
#include <string>
#include <vector>

namespace urlab::document {
namespace {

// The 2.2.2 table alone, without the MuJoCo 3.x dialect rows Grammar::Get() adds.
const Grammar& Table() {
  static const Grammar grammar(GrammarTable());
  return grammar;
}

// Every row reachable from <mujoco> (breadth first over the children).
std::set<const ElementSpec*> ReachableRows() {
  const Grammar& g = Table();
  std::set<const ElementSpec*> seen = {&g.Root()};
  std::deque<const ElementSpec*> queue = {&g.Root()};
  while (!queue.empty()) {
    const ElementSpec* e = queue.front();
    queue.pop_front();
    for (const ElementSpec* c : e->children) {
      if (seen.insert(c).second) queue.push_back(c);
    }
  }
  return seen;
}

class GrammarTest : public ::testing::Test {
 protected:
  const Grammar& g_ = Table();
  const std::set<const ElementSpec*> reachable_ = ReachableRows();
};

// ---------------------------------------------------------------------------------------------
// 1. The table parses and says what we know about MJCF 2.2.2.

TEST_F(GrammarTest, ParsesAndKnowsTheBasics) {
  ASSERT_NO_THROW(Grammar::Get());
  EXPECT_EQ(g_.Root().id, "mujoco");
  EXPECT_EQ(g_.Elements().front().tag, "mujoco");
  EXPECT_GT(g_.Elements().size(), 120u);

  const ElementSpec* geom = g_.Find("geom");
  ASSERT_NE(geom, nullptr);
  EXPECT_EQ(geom->name_space, Namespace::kGeom);
  const AttributeSpec* size = geom->FindAttribute("size");
  ASSERT_NE(size, nullptr);
  EXPECT_EQ(size->type, ValueType::kReal);
  EXPECT_EQ(size->min_count, 1);
  EXPECT_EQ(size->max_count, 3);
  EXPECT_EQ(geom->FindAttribute("pos")->min_count, 3);
  EXPECT_EQ(geom->FindAttribute("quat")->max_count, 4);
  EXPECT_EQ(geom->FindAttribute("rgba")->min_count, 4);
  EXPECT_EQ(geom->FindAttribute("user")->max_count, -1);
  EXPECT_EQ(geom->FindAttribute("class")->ref, Namespace::kClass);
  EXPECT_EQ(geom->FindAttribute("material")->ref, Namespace::kMaterial);
  EXPECT_EQ(geom->FindAttribute("mesh")->ref, Namespace::kMesh);
  EXPECT_EQ(geom->FindAttribute("hfield")->ref, Namespace::kHField);
  EXPECT_EQ(geom->FindAttribute("type")->keywords,
            (std::vector<std::string>{"plane", "hfield", "sphere", "capsule", "ellipsoid",
                                      "cylinder", "box", "mesh"}));

  const ElementSpec* default_geom = g_.Find("default.geom");
  ASSERT_NE(default_geom, nullptr);
  EXPECT_EQ(default_geom->FindAttribute("name"), nullptr);
  EXPECT_EQ(default_geom->FindAttribute("class"), nullptr);
  EXPECT_NE(g_.Find("composite.geom"), nullptr);
  EXPECT_EQ(g_.Find("composite.geom")->FindAttribute("pos"), nullptr);

  const ElementSpec* body = g_.Find("body");
  ASSERT_NE(body, nullptr);
  EXPECT_EQ(body->FindChild("body"), body);
  EXPECT_EQ(body->FindAttribute("childclass")->ref, Namespace::kClass);
  const ElementSpec* dflt = g_.Find("default");
  ASSERT_NE(dflt, nullptr);
  EXPECT_EQ(dflt->FindChild("default"), dflt);
  EXPECT_EQ(dflt->name_space, Namespace::kClass);
  EXPECT_EQ(g_.Root().FindChild("worldbody")->attributes.size(), 0u);
  EXPECT_EQ(g_.Root().FindChild("worldbody")->FindChild("joint"), nullptr);

  const ElementSpec* joint = g_.Find("joint");
  ASSERT_NE(joint, nullptr);
  EXPECT_EQ(joint->FindAttribute("limited")->keywords,
            (std::vector<std::string>{"false", "true", "auto"}));
  EXPECT_EQ(g_.Find("freejoint")->name_space, Namespace::kJoint);

  const ElementSpec* general = g_.Find("general");
  ASSERT_NE(general, nullptr);
  EXPECT_EQ(general->name_space, Namespace::kActuator);
  EXPECT_EQ(general->FindAttribute("joint")->ref, Namespace::kJoint);
  EXPECT_EQ(general->FindAttribute("jointinparent")->ref, Namespace::kJoint);
  EXPECT_EQ(general->FindAttribute("tendon")->ref, Namespace::kTendon);
  EXPECT_EQ(general->FindAttribute("refsite")->ref, Namespace::kSite);
  EXPECT_EQ(general->FindAttribute("slidersite")->ref, Namespace::kSite);
  EXPECT_EQ(general->FindAttribute("body")->ref, Namespace::kBody);
  EXPECT_EQ(g_.Find("damper")->FindAttribute("ctrllimited"), nullptr);

  const ElementSpec* framepos = g_.Find("sensor.framepos");
  ASSERT_NE(framepos, nullptr);
  EXPECT_EQ(framepos->name_space, Namespace::kSensor);
  EXPECT_EQ(framepos->FindAttribute("objname")->ref_selector, "objtype");
  EXPECT_EQ(framepos->FindAttribute("refname")->ref_selector, "reftype");
  EXPECT_TRUE(framepos->FindAttribute("objname")->IsReference());

  EXPECT_EQ(g_.Find("mesh")->FindAttribute("file")->file_base, FileBase::kMeshDir);
  EXPECT_EQ(g_.Find("hfield")->FindAttribute("file")->file_base, FileBase::kMeshDir);
  EXPECT_EQ(g_.Find("skin")->FindAttribute("file")->file_base, FileBase::kMeshDir);
  for (const char* f :
       {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"}) {
    EXPECT_EQ(g_.Find("texture")->FindAttribute(f)->file_base, FileBase::kTextureDir) << f;
  }
  const ElementSpec* include = g_.Find("include");
  ASSERT_NE(include, nullptr);
  EXPECT_EQ(include->FindAttribute("file")->file_base, FileBase::kModelDir);
  EXPECT_EQ(g_.Find("key")->FindAttribute("qpos")->max_count, -1);
  EXPECT_EQ(g_.Find("texture")->name_space, Namespace::kTexture);
  EXPECT_EQ(g_.Find("key")->name_space, Namespace::kKey);
}

// Grammar::Get() = this table + the dialect table; the 2.2.2 rows keep what they have here.
TEST_F(GrammarTest, DialectKeepsThe222Rows) {
  const Grammar* full = nullptr;
  ASSERT_NO_THROW(full = &Grammar::Get());
  for (const ElementSpec& e : g_.Elements()) {
    const ElementSpec* f = full->Find(e.id);
    ASSERT_NE(f, nullptr) << e.id;
    EXPECT_FALSE(f->dialect) << e.id;
    EXPECT_EQ(f->tag, e.tag);
    EXPECT_EQ(f->name_space, e.name_space) << e.id;
    for (const AttributeSpec& a : e.attributes) {
      const AttributeSpec* fa = f->FindAttribute(a.name);
      ASSERT_NE(fa, nullptr) << e.id << " " << a.name;
      EXPECT_FALSE(fa->dialect) << e.id << " " << a.name;
      EXPECT_EQ(fa->type, a.type) << e.id << " " << a.name;
      // A dialect row may widen the count (3.x's springlength "lo hi"); 2.2.2's is kept.
      EXPECT_EQ(fa->dialect_count ? fa->legacy_min_count : fa->min_count, a.min_count)
          << e.id << " " << a.name;
      EXPECT_EQ(fa->dialect_count ? fa->legacy_max_count : fa->max_count, a.max_count)
          << e.id << " " << a.name;
      EXPECT_EQ(fa->ref, a.ref) << e.id << " " << a.name;
      for (size_t i = 0; i < a.keywords.size(); ++i) {
        ASSERT_LT(i, fa->keywords.size()) << e.id << " " << a.name;
        EXPECT_EQ(fa->keywords[i], a.keywords[i]) << e.id << " " << a.name;
      }
    }
    for (const ElementSpec* c : e.children) {
      EXPECT_EQ(f->FindChild(c->tag)->id, c->id) << e.id << " > " << c->tag;
    }
  }
}

// The one list of actuator elements (used by the bridge, the composer and default resolution)
// comes from the table: the <actuator> section's children with a default template of their own,
// MuJoCo 2.2.2's nine, in table order; neither <include> nor 3.x additions are actuators.
TEST_F(GrammarTest, ActuatorTagsComeFromTheTable) {
  const auto tags = document::ActuatorTags();
  const std::vector<std::string> expected = {"general",  "motor",       "position",
                                             "velocity", "intvelocity", "damper",
                                             "cylinder", "muscle",      "adhesion"};
  EXPECT_EQ(std::vector<std::string>(tags.begin(), tags.end()), expected);
  for (const std::string& t : expected) EXPECT_TRUE(document::IsActuatorTag(t)) << t;
  for (const char* t : {"include", "plugin", "joint", "actuator", "default"}) {
    EXPECT_FALSE(document::IsActuatorTag(t)) << t;
  }
}

TEST_F(GrammarTest, StructureIsConsistent) {
  const ElementSpec* include = g_.Find("include");
  ASSERT_NE(include, nullptr);
  std::set<std::string> ids;
  for (const ElementSpec& e : g_.Elements()) {
    EXPECT_TRUE(ids.insert(e.id).second) << e.id;
    EXPECT_TRUE(reachable_.contains(&e)) << e.id << " cannot be reached from <mujoco>";
    // include may stand wherever an element is expected: listed by every element with children.
    const bool has_children = std::any_of(e.children.begin(), e.children.end(),
                                          [&](const ElementSpec* c) { return c != include; });
    EXPECT_EQ(e.FindChild("include") == include, has_children) << e.id;
    std::set<std::string> tags, names;
    for (const ElementSpec* c : e.children) {
      EXPECT_TRUE(tags.insert(c->tag).second) << e.id << ": two children with tag " << c->tag;
    }
    for (const AttributeSpec& a : e.attributes) {
      EXPECT_TRUE(names.insert(a.name).second) << e.id << ": duplicate " << a.name;
      if (!a.ref_selector.empty()) {
        const AttributeSpec* selector = e.FindAttribute(a.ref_selector);
        ASSERT_NE(selector, nullptr) << e.id << "." << a.name;
        for (const std::string& k : selector->keywords) {
          EXPECT_NE(NamespaceFromObjType(k), Namespace::kNone) << e.id << " " << k;
        }
      }
      if (a.name == "class" || a.name == "childclass") {
        if (e.id != "default") {
          EXPECT_EQ(a.ref, Namespace::kClass) << e.id;
        }
      }
    }
    // An element whose `name` enters a namespace has a `name` attribute, and vice versa (default
    // defines classes with `class`).
    if (e.id == "default") continue;
    EXPECT_EQ(e.name_space != Namespace::kNone, e.FindAttribute("name") != nullptr) << e.id;
  }
}

}  // namespace
}  // namespace urlab::document
