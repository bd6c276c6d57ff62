// The MJCF grammar table (src/document/grammar_table.cc) checked against MuJoCo 2.2.2 itself.
//
// MuJoCo validates a document against its schema (elements and attribute names per context)
// before it reads any value, and its reader maps keyword values and enforces value counts while
// parsing, before compiling. So for every row of the grammar the tests below build small MJCF
// documents and let mj_loadXML judge them:
//   - every listed child and attribute passes the schema in that context;
//   - an invented attribute / child is a schema violation (the probe is not vacuous), and so is
//     every attribute name and element tag the grammar knows elsewhere but not in that context
//     (the table is complete with respect to its own vocabulary);
//   - keyword attributes accept every listed keyword and refuse a bogus one and every other
//     keyword the grammar knows (the sets are exact); objtype/reftype keywords compile;
//   - in models that compile: every geom/joint/site type and every value of the boolean-like
//     attributes;
//   - numeric attributes accept their counts, refuse one value too many (and one too few), and
//     int attributes refuse non-integers;
//   - include works as a child of every element that has children;
//   - every attribute used by the models under /usr/share/mujoco/model is in the grammar, in the
//     right context.
#include "urlab/document/grammar.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "support/mujoco_test.h"
#include "urlab/core/mujoco_handlers.h"

namespace urlab::document {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Running MuJoCo

struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};

// The error text mj_loadXML reports for `xml` (loaded from an in-memory file); empty when the
// model compiled without complaint.
std::string LoadError(const std::string& xml) {
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  constexpr const char* kName = "grammar_probe.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(xml.size())) != 0) {
    return "test harness: VFS allocation failed";
  }
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), kName)], xml.data(), xml.size());
  char error[1024] = "";
  try {
    mjModel* m = mj_loadXML(kName, vfs.get(), error, sizeof(error));
    if (m) {
      mj_deleteModel(m);
      return "";
    }
  } catch (const std::exception& e) {  // mju_error, turned into an exception by URLab
    return e.what();
  }
  return error[0] ? error : "load failed without a message";
}

std::string LoadFileError(const std::string& path) {
  char error[1024] = "";
  try {
    mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (m) {
      mj_deleteModel(m);
      return "";
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  return error[0] ? error : "load failed without a message";
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

bool IsSchemaViolation(const std::string& error) {
  return Contains(error, "Schema violation") || Contains(error, "unrecognized attribute") ||
         Contains(error, "unrecognized element");
}

// MuJoCo's schema shares the body children with <worldbody>; its reader then refuses attributes,
// joints and inertia on the world body.
bool IsWorldBodyRefusal(const std::string& error) { return Contains(error, "World body cannot"); }

// ---------------------------------------------------------------------------------------------
// Building probe documents

using Attributes = std::vector<std::pair<std::string, std::string>>;

// A model that compiles, with one object of each kind the probes refer to.
constexpr const char* kBaseHead = R"(<mujoco model="grammar probe">
  <compiler autolimits="true"/>
  <asset>
    <texture name="tex" type="2d" builtin="checker" width="8" height="8"/>
    <material name="mat" texture="tex"/>
    <mesh name="mesh" vertex="0 0 0  1 0 0  0 1 0  0 0 1"/>
    <hfield name="hf" nrow="2" ncol="2" size="1 1 1 1"/>
  </asset>
  <worldbody>
    <body name="b1" pos="0 0 1">
      <joint name="j1"/><geom name="g1" size="0.1"/><site name="s1"/><camera name="c1"/>
    </body>
    <body name="b2" pos="1 0 1">
      <joint name="j2" type="ball"/><geom name="g2" size="0.1"/><site name="s2"/>
    </body>
  </worldbody>
  <tendon><fixed name="t1"><joint joint="j1" coef="1"/></fixed></tendon>
  <actuator><motor name="a1" joint="j1"/></actuator>
  <!-- One object named "o" in every namespace, for objtype/objname probes. -->
  <asset>
    <texture name="o" builtin="flat" width="8" height="8"/>
    <material name="o"/>
    <mesh name="o" vertex="0 0 0  1 0 0  0 1 0  0 0 1"/>
    <hfield name="o" nrow="2" ncol="2" size="1 1 1 1"/>
    <skin name="o" vertex="0 0 0  1 0 0  0 1 0" face="0 1 2">
      <bone body="o" bindpos="0 0 0" bindquat="1 0 0 0" vertid="0 1 2" vertweight="1 1 1"/>
    </skin>
  </asset>
  <worldbody>
    <body name="o" pos="0 2 1">
      <joint name="o"/><geom name="o" size="0.1"/><site name="o"/><camera name="o"/><light name="o"/>
    </body>
  </worldbody>
  <tendon><fixed name="o"><joint joint="o" coef="1"/></fixed></tendon>
  <actuator><motor name="o" joint="o"/></actuator>
  <equality><joint name="o" joint1="o"/></equality>
  <contact><pair name="o" geom1="o" geom2="g1"/><exclude name="o" body1="o" body2="b1"/></contact>
  <custom>
    <numeric name="o" data="1"/><text name="o" data="x"/>
    <tuple name="o"><element objtype="body" objname="o"/></tuple>
  </custom>
  <sensor><jointpos name="o" joint="o"/></sensor>
)";
constexpr const char* kBaseTail = "</mujoco>\n";

// Attributes an element needs for MuJoCo's reader to get through it (naming kBase's objects).
Attributes Required(const std::string& id) {
  static const std::map<std::string, Attributes> kRequired = {
      {"default", {{"class", "probe_class"}}},
      {"custom.numeric", {{"name", "probe_numeric"}, {"data", "1"}}},
      {"custom.text", {{"name", "probe_text"}, {"data", "x"}}},
      {"custom.tuple", {{"name", "probe_tuple"}}},
      {"tuple.element", {{"objtype", "body"}, {"objname", "o"}}},
      {"hfield", {{"nrow", "2"}, {"ncol", "2"}, {"size", "1 1 1 1"}}},
      {"material", {{"name", "probe_material"}}},
      {"skin.bone",
       {{"body", "b1"},
        {"bindpos", "0 0 0"},
        {"bindquat", "1 0 0 0"},
        {"vertid", "0"},
        {"vertweight", "1"}}},
      {"inertial", {{"pos", "0 0 0"}, {"mass", "1"}}},
      {"composite", {{"type", "grid"}, {"count", "2 2 1"}, {"spacing", "0.1"}}},
      {"composite.joint", {{"kind", "main"}}},
      {"composite.tendon", {{"kind", "main"}}},
      {"composite.pin", {{"coord", "0 0"}}},
      {"contact.pair", {{"geom1", "g1"}, {"geom2", "g2"}}},
      {"contact.exclude", {{"body1", "b1"}, {"body2", "b2"}}},
      {"equality.connect", {{"body1", "b1"}, {"anchor", "0 0 0"}}},
      {"equality.weld", {{"body1", "b1"}}},
      {"equality.joint", {{"joint1", "j1"}}},
      {"equality.tendon", {{"tendon1", "t1"}}},
      {"equality.distance", {{"geom1", "g1"}, {"geom2", "g2"}}},
      {"spatial.site", {{"site", "s1"}}},
      {"spatial.geom", {{"geom", "g1"}}},
      {"spatial.pulley", {{"divisor", "1"}}},
      {"fixed.joint", {{"joint", "j1"}, {"coef", "1"}}},
      {"damper", {{"joint", "j1"}, {"ctrlrange", "0 1"}}},
      {"default.damper", {{"ctrlrange", "0 1"}}},  // 2.2.2 wants it even in a default
      {"adhesion", {{"body", "b1"}, {"ctrlrange", "0 1"}}},
      {"sensor.user",
       {{"objtype", "body"},
        {"objname", "o"},
        {"datatype", "real"},
        {"needstage", "pos"},
        {"dim", "1"}}},
  };
  if (auto it = kRequired.find(id); it != kRequired.end()) return it->second;
  static const std::set<std::string> kActuators = {
      "general", "motor", "position", "velocity", "intvelocity", "cylinder", "muscle"};
  if (kActuators.contains(id)) return {{"joint", "j1"}};
  if (id.starts_with("sensor.frame")) return {{"objtype", "body"}, {"objname", "o"}};
  if (id.starts_with("sensor.subtree")) return {{"body", "b1"}};
  if (id.starts_with("sensor.joint") || id.starts_with("sensor.ball")) return {{"joint", "j2"}};
  if (id.starts_with("sensor.tendon")) return {{"tendon", "t1"}};
  if (id.starts_with("sensor.actuator")) return {{"actuator", "a1"}};
  if (id.starts_with("sensor.") && id != "sensor.clock") return {{"site", "s1"}};
  return {};
}

// Children an element needs besides the probed one (a moving body needs mass).
std::string RequiredInner(const std::string& id) {
  if (id == "body") return R"(<geom size="0.1"/>)";
  if (id == "custom.tuple") return R"(<element objtype="body" objname="b1"/>)";
  return "";
}

std::string Quote(const std::string& v) { return "\"" + v + "\""; }

std::string StartTag(const std::string& tag, const Attributes& attrs, bool empty) {
  std::string s = "<" + tag;
  for (const auto& [k, v] : attrs) s += " " + k + "=" + Quote(v);
  return s + (empty ? "/>" : ">");
}

// `attrs` over `base`: same names are replaced.
Attributes Merge(Attributes base, const Attributes& attrs) {
  for (const auto& [k, v] : attrs) {
    bool replaced = false;
    for (auto& [bk, bv] : base) {
      if (bk == k) {
        bv = v;
        replaced = true;
      }
    }
    if (!replaced) base.emplace_back(k, v);
  }
  return base;
}

// The 2.2.2 table alone, without the MuJoCo 3.x dialect rows Grammar::Get() adds.
const Grammar& Table() {
  static const Grammar grammar(GrammarTable());
  return grammar;
}

class Probe {
 public:
  Probe() {
    // Shortest path from the root to every row, so each row can be placed in a valid context.
    const Grammar& g = Table();
    std::deque<const ElementSpec*> queue = {&g.Root()};
    paths_[&g.Root()] = {&g.Root()};
    while (!queue.empty()) {
      const ElementSpec* e = queue.front();
      queue.pop_front();
      for (const ElementSpec* c : e->children) {
        if (paths_.contains(c)) continue;
        paths_[c] = paths_[e];
        paths_[c].push_back(c);
        queue.push_back(c);
      }
    }
  }

  bool Reachable(const ElementSpec& e) const { return paths_.contains(&e); }

  // `<mujoco>...<e attrs/>...</mujoco>`: `e` in its context, parents with what they need. With
  // `base`, inside kBase (a compiling model) and with `e`'s required attributes; `inner` goes
  // inside `e`.
  std::string Document(const ElementSpec& e, const Attributes& attrs, bool base,
                       const std::string& inner = "") const {
    const std::vector<const ElementSpec*>& path = paths_.at(&e);
    if (&e == path.front()) {  // <mujoco> itself
      return StartTag("mujoco", attrs, false) + inner + "</mujoco>";
    }
    std::string open, close;
    for (size_t i = 1; i + 1 < path.size(); ++i) {
      const ElementSpec* p = path[i];
      if (base && p->id == "default" && i == 1) {
        // The top-level default is the main class, which kBase uses: probe a class of its own.
        open += "<default>" + StartTag("default", Required("default"), false);
        close = "</default></default>" + close;
        continue;
      }
      open += StartTag(p->tag, Required(p->id), false) + RequiredInner(p->id);
      close = "</" + p->tag + ">" + close;
    }
    const Attributes own = base ? Merge(Required(e.id), attrs) : attrs;
    std::string element;
    if (inner.empty()) {
      element = StartTag(e.tag, own, true);
    } else {
      element = StartTag(e.tag, own, false) + inner + "</" + e.tag + ">";
    }
    if (base) return std::string(kBaseHead) + open + element + close + kBaseTail;
    return "<mujoco>" + open + element + close + "</mujoco>";
  }

 private:
  std::map<const ElementSpec*, std::vector<const ElementSpec*>> paths_;
};

// A value of `a`'s type with `n` numbers (or the first keyword, or a plain string).
std::string Value(const AttributeSpec& a, int n) {
  if (a.type == ValueType::kKeyword) return a.keywords.front();
  if (a.type != ValueType::kReal && a.type != ValueType::kInt) return "probe";
  std::string v;
  for (int i = 0; i < n; ++i) v += i ? " 1" : "1";
  return v;
}

std::string Placeholder(const AttributeSpec& a) {
  return Value(a, a.min_count > 0 ? a.min_count : 1);
}

// Quirks of MuJoCo 2.2.2 where the schema accepts an attribute that the reader never reads, so
// its values cannot be checked: <default><adhesion> and composite joint/tendon `limited`.
bool NeverRead(const ElementSpec& e, const AttributeSpec& a) {
  return e.id == "default.adhesion" ||
         ((e.id == "composite.joint" || e.id == "composite.tendon") && a.name == "limited");
}

// Variable-length arrays MuJoCo reads leniently (it stops at the first non-number, no error).
bool LenientArray(const ElementSpec& e, const AttributeSpec& a) {
  return a.max_count < 0 && (e.id == "mesh" || e.id == "skin" || e.id == "skin.bone");
}

// The reader refuses <equality><distance> outright in 2.2.2, before reading any value.
bool RefusedElement(const ElementSpec& e) { return e.id == "equality.distance"; }

class GrammarTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    InstallMujocoHandlers();
    SetLogLevel("error");  // probes make MuJoCo warn; nothing to see
  }
  const Grammar& g_ = Table();
  Probe probe_;
  WarningCapture warnings_;  // swallowed: the probes are expected to provoke warnings
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
    EXPECT_TRUE(probe_.Reachable(e)) << e.id << " cannot be reached from <mujoco>";
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

// ---------------------------------------------------------------------------------------------
// 2. + 3. The schema: what is listed passes, what is not is refused.

TEST_F(GrammarTest, EveryAttributeAndChildPassesTheSchema) {
  int probes = 0;
  for (const ElementSpec& e : g_.Elements()) {
    if (e.id == "include") continue;  // expanded before the schema check, see IncludeAnywhere
    const std::string bare = LoadError(probe_.Document(e, {}, false));
    EXPECT_FALSE(IsSchemaViolation(bare)) << e.id << ": " << bare;
    for (const AttributeSpec& a : e.attributes) {
      const std::string error = LoadError(probe_.Document(e, {{a.name, Placeholder(a)}}, false));
      EXPECT_FALSE(IsSchemaViolation(error)) << e.id << " " << a.name << ": " << error;
      ++probes;
    }
    for (const ElementSpec* c : e.children) {
      if (c->id == "include") continue;
      const std::string error = LoadError(probe_.Document(e, {}, false, "<" + c->tag + "/>"));
      EXPECT_FALSE(IsSchemaViolation(error)) << e.id << " > " << c->tag << ": " << error;
      if (e.id == "worldbody") {
        EXPECT_FALSE(IsWorldBodyRefusal(error)) << c->tag;
      }
      ++probes;
    }
  }
  EXPECT_GT(probes, 1200);
}

TEST_F(GrammarTest, InventedAttributesAndChildrenAreSchemaViolations) {
  for (const ElementSpec& e : g_.Elements()) {
    if (e.id == "include") continue;
    const std::string attr = LoadError(probe_.Document(e, {{"urlab_bogus", "1"}}, false));
    EXPECT_TRUE(Contains(attr, "Schema violation") && Contains(attr, "unrecognized attribute"))
        << e.id << ": " << attr;
    const std::string child = LoadError(probe_.Document(e, {}, false, "<urlab_bogus/>"));
    EXPECT_TRUE(Contains(child, "Schema violation") && Contains(child, "unrecognized element"))
        << e.id << ": " << child;
  }
}

// Completeness: every attribute name and tag the grammar knows anywhere, tried in every context
// where the grammar does not list it, is refused by MuJoCo.
TEST_F(GrammarTest, NothingMissingFromAnyContext) {
  std::set<std::string> all_attributes, all_tags;
  for (const ElementSpec& e : g_.Elements()) {
    all_tags.insert(e.tag);
    for (const AttributeSpec& a : e.attributes) all_attributes.insert(a.name);
  }
  all_tags.erase("include");
  for (const ElementSpec& e : g_.Elements()) {
    if (e.id == "include") continue;
    for (const std::string& name : all_attributes) {
      if (e.FindAttribute(name)) continue;
      const std::string error = LoadError(probe_.Document(e, {{name, "1"}}, false));
      const bool refused =
          IsSchemaViolation(error) || (e.id == "worldbody" && IsWorldBodyRefusal(error));
      EXPECT_TRUE(refused) << e.id << " accepts attribute " << name << ": " << error;
    }
    for (const std::string& tag : all_tags) {
      if (e.FindChild(tag)) continue;
      const std::string error = LoadError(probe_.Document(e, {}, false, "<" + tag + "/>"));
      const bool refused =
          IsSchemaViolation(error) || (e.id == "worldbody" && IsWorldBodyRefusal(error));
      EXPECT_TRUE(refused) << e.id << " accepts child " << tag << ": " << error;
    }
  }
}

// include is expanded before validation, wherever it stands; MuJoCo reads only its `file`.
TEST_F(GrammarTest, IncludeAnywhere) {
  const std::string dir = testing::MakeTempDir("grammar_include");
  int n = 0;
  for (const ElementSpec& e : g_.Elements()) {
    const ElementSpec* child = nullptr;
    for (const ElementSpec* c : e.children) {
      if (c->id != "include") {
        child = c;
        break;
      }
    }
    if (!child) continue;
    // A fragment holding one `child`, included into `e`.
    const std::string fragment = "fragment" + std::to_string(n++) + ".xml";
    std::ofstream(dir + "/" + fragment)
        << "<mujoco>" << StartTag(child->tag, Required(child->id), true) << "</mujoco>\n";
    const std::string main = dir + "/main" + std::to_string(n) + ".xml";
    std::ofstream(main) << probe_.Document(e, {}, true, R"(<include file=")" + fragment + R"("/>)");
    const std::string error = LoadFileError(main);
    EXPECT_FALSE(IsSchemaViolation(error) || Contains(error, "nclude")) << e.id << ": " << error;
  }
  EXPECT_GE(n, 20);

  std::ofstream(dir + "/geom.xml") << R"(<mujoco><geom size="1"/></mujoco>)";
  std::ofstream(dir + "/bogus.xml")
      << R"(<mujoco><worldbody><include file="geom.xml" urlab_bogus="1"/></worldbody></mujoco>)";
  EXPECT_EQ(LoadFileError(dir + "/bogus.xml"), "");
}

// ---------------------------------------------------------------------------------------------
// Values: keyword sets, counts, int vs real (all enforced by MuJoCo's reader, before compiling).

bool KeywordRefused(const std::string& error) {
  return Contains(error, "invalid keyword") || Contains(error, "unknown object type") ||
         Contains(error, "invalid type") || Contains(error, "must be attached to") ||
         Contains(error, "not allowed in site");
}

TEST_F(GrammarTest, KeywordSetsAreExact) {
  // Every keyword the grammar knows, for trying the ones an attribute does not list.
  std::set<std::string> vocabulary;
  for (const ElementSpec& e : g_.Elements()) {
    for (const AttributeSpec& a : e.attributes) {
      vocabulary.insert(a.keywords.begin(), a.keywords.end());
    }
  }
  int checked = 0;
  for (const ElementSpec& e : g_.Elements()) {
    if (RefusedElement(e)) continue;
    for (const AttributeSpec& a : e.attributes) {
      if (a.type != ValueType::kKeyword) continue;
      // objtype/reftype are looked up when compiling: probe them naming kBase's "o" objects.
      const auto attrs = [&](const std::string& k) {
        Attributes out = {{a.name, k}};
        if (a.name == "reftype") out.emplace_back("refname", "o");
        return out;
      };
      for (const std::string& k : a.keywords) {
        const std::string error = LoadError(probe_.Document(e, attrs(k), true));
        EXPECT_FALSE(KeywordRefused(error)) << e.id << " " << a.name << "=" << k << ": " << error;
        if (a.name == "objtype" || a.name == "reftype") {
          EXPECT_EQ(error, "") << e.id << " " << a.name << "=" << k;
        }
        ++checked;
      }
      // 2.2.2 silently ignores an unknown frame sensor reftype (and drops the reference frame).
      const bool ignored = NeverRead(e, a) || a.name == "reftype";
      const std::string bogus = LoadError(probe_.Document(e, attrs("urlab_bogus"), true));
      EXPECT_EQ(KeywordRefused(bogus), !ignored) << e.id << " " << a.name << ": " << bogus;
      if (ignored) continue;
      for (const std::string& k : vocabulary) {
        if (std::find(a.keywords.begin(), a.keywords.end(), k) != a.keywords.end()) continue;
        // The reader maps every geom type for sites; only a compiled site refuses the others.
        if (e.id == "default.site" && a.name == "type") continue;
        const std::string error = LoadError(probe_.Document(e, attrs(k), true));
        EXPECT_TRUE(KeywordRefused(error))
            << e.id << " " << a.name << " accepts " << k << ": " << error;
      }
    }
  }
  EXPECT_GT(checked, 400);
}

TEST_F(GrammarTest, CountsAndNumberTypesAreExact) {
  int checked = 0;
  for (const ElementSpec& e : g_.Elements()) {
    if (RefusedElement(e)) continue;
    for (const AttributeSpec& a : e.attributes) {
      if ((a.type != ValueType::kReal && a.type != ValueType::kInt) || NeverRead(e, a)) continue;
      const std::string quoted = "'" + a.name + "'";
      auto count_error = [&](const std::string& value) {
        const std::string error = LoadError(probe_.Document(e, {{a.name, value}}, true));
        const bool bad = Contains(error, "enough data") || Contains(error, "too much data") ||
                         Contains(error, "problem reading");
        return bad && Contains(error, quoted) ? error : std::string();
      };
      const std::string where = e.id + " " + a.name;
      if (a.max_count < 0) {
        for (int n : {1, 7}) EXPECT_EQ(count_error(Value(a, n)), "") << where << " x" << n;
      } else {
        for (int n = a.min_count; n <= a.max_count; ++n) {
          EXPECT_EQ(count_error(Value(a, n)), "") << where << " x" << n;
        }
        // A scalar int is read with sscanf("%d"): trailing values are ignored, not refused.
        if (a.type == ValueType::kReal || a.max_count > 1) {
          EXPECT_TRUE(Contains(count_error(Value(a, a.max_count + 1)), "too much data")) << where;
        }
        if (a.min_count > 1) {
          EXPECT_TRUE(Contains(count_error(Value(a, a.min_count - 1)), "enough data")) << where;
        }
      }
      // Type: a word is never a number; an int array refuses a fraction; a scalar int says so.
      ++checked;
      if (LenientArray(e, a)) continue;
      const std::string word = LoadError(probe_.Document(e, {{a.name, "abc"}}, true));
      if (a.type == ValueType::kInt && a.max_count == 1) {
        EXPECT_TRUE(Contains(word, "single int expected")) << where << ": " << word;
      } else {
        EXPECT_TRUE(Contains(word, "problem reading") && Contains(word, quoted))
            << where << ": " << word;
      }
      if (a.max_count > 1 || (a.type == ValueType::kReal && a.max_count == 1)) {
        std::string fractions;
        for (int i = 0; i < std::max(a.min_count, 1); ++i) fractions += i ? " 1.5" : "1.5";
        const std::string error = LoadError(probe_.Document(e, {{a.name, fractions}}, true));
        const bool refused = Contains(error, "problem reading") && Contains(error, quoted);
        EXPECT_EQ(refused, a.type == ValueType::kInt) << where << ": " << error;
      }
    }
  }
  EXPECT_GT(checked, 600);
}

// ---------------------------------------------------------------------------------------------
// Keywords in models that compile: all geom and joint types, and the boolean-like attributes.

TEST_F(GrammarTest, KeywordsCompile) {
  ASSERT_EQ(LoadError(std::string(kBaseHead) + kBaseTail), "");
  const auto compile = [&](const std::string& id, const Attributes& attrs,
                           const std::string& contents = "") {
    return LoadError(probe_.Document(*g_.Find(id), attrs, true, contents));
  };

  const std::map<std::string, Attributes> geom_extra = {
      {"plane", {{"size", "1 1 1"}}},
      {"hfield", {{"hfield", "hf"}}},
      {"mesh", {{"mesh", "mesh"}}},
  };
  for (const std::string& type : g_.Find("geom")->FindAttribute("type")->keywords) {
    Attributes attrs = {{"type", type}, {"size", "0.1 0.1 0.1"}};
    if (geom_extra.contains(type)) attrs = Merge(attrs, geom_extra.at(type));
    EXPECT_EQ(LoadError(std::string(kBaseHead) + "<worldbody>" + StartTag("geom", attrs, true) +
                        "</worldbody>" + kBaseTail),
              "")
        << type;
  }
  EXPECT_TRUE(Contains(compile("geom", {{"type", "urlab_bogus"}}), "invalid keyword"));
  for (const std::string& type : g_.Find("joint")->FindAttribute("type")->keywords) {
    EXPECT_EQ(compile("joint", {{"type", type}}), "") << type;
  }
  EXPECT_TRUE(Contains(compile("joint", {{"type", "urlab_bogus"}}), "invalid keyword"));
  for (const std::string& type : g_.Find("site")->FindAttribute("type")->keywords) {
    EXPECT_EQ(compile("site", {{"type", type}}), "") << type;
  }

  // Boolean-like attributes (false/true[/auto], disable/enable): every value compiles in rows
  // where the attribute can be set on its own; `extra` makes every value meaningful.
  const std::map<std::string, Attributes> extra = {
      {"texture",
       {{"name", "probe_texture"}, {"builtin", "checker"}, {"width", "8"}, {"height", "8"}}},
      {"mesh", {{"name", "probe_mesh"}, {"vertex", "0 0 0  1 0 0  0 1 0  0 0 1"}}},
      {"geom", {{"type", "mesh"}, {"mesh", "mesh"}}},  // shellinertia needs a mesh
      {"general", {{"dyntype", "integrator"}}},        // actlimited needs an activation
      {"intvelocity", {{"actrange", "-1 1"}}},         // its activation needs a range
      {"muscle", {{"lengthrange", "0.5 1.5"}}},        // no length range computation
  };
  // What some elements must contain to compile.
  const std::map<std::string, std::string> inner = {
      {"tendon.fixed", R"(<joint joint="j1" coef="1"/>)"},
      {"tendon.spatial", R"(<site site="s1"/><site site="s2"/>)"},
  };
  // Composites are left to the reader-level checks above; inertiafromgeom="false" leaves the
  // probe model's bodies without inertia; default adhesion and distance equality are not read.
  const std::set<std::string> skip = {"composite",      "composite.joint",  "composite.tendon",
                                      "composite.skin", "default.adhesion", "equality.distance"};
  int compiled = 0;
  for (const ElementSpec& e : g_.Elements()) {
    if (skip.contains(e.id)) continue;
    const std::string contents = inner.contains(e.id) ? inner.at(e.id) : "";
    for (const AttributeSpec& a : e.attributes) {
      if (a.type != ValueType::kKeyword || a.name == "inertiafromgeom") continue;
      const bool boolean = a.keywords.front() == "false" || a.keywords.front() == "disable";
      if (!boolean) continue;
      Attributes base = extra.contains(e.id) ? extra.at(e.id) : Attributes{};
      if (a.name.ends_with("limited")) {
        // A range for the limit this flag controls.
        const std::string range = a.name.substr(0, a.name.size() - 7) + "range";
        if (e.FindAttribute(range)) base = Merge(base, {{range, "0 1"}});
      }
      for (const std::string& k : a.keywords) {
        EXPECT_EQ(compile(e.id, Merge(base, {{a.name, k}}), contents), "")
            << e.id << " " << a.name << "=" << k;
        ++compiled;
      }
      EXPECT_NE(compile(e.id, Merge(base, {{a.name, "urlab_bogus"}}), contents), "")
          << e.id << " " << a.name;
    }
  }
  EXPECT_GT(compiled, 100);
}

// ---------------------------------------------------------------------------------------------
// 4. The models shipped with MuJoCo use nothing outside the grammar.

struct XmlElement {
  std::string tag;
  Attributes attributes;
  std::vector<XmlElement> children;
  int line = 0;
};

// A small XML reader, enough for MJCF files: elements, attributes, comments, declarations,
// text (ignored). Throws std::runtime_error on malformed input.
class XmlReader {
 public:
  explicit XmlReader(std::string text) : s_(std::move(text)) {}

  XmlElement Root() {
    SkipMisc();
    XmlElement root = Element();
    SkipMisc();
    if (i_ != s_.size()) Fail("content after the root element");
    return root;
  }

 private:
  [[noreturn]] void Fail(const std::string& why) const {
    throw std::runtime_error("line " + std::to_string(Line()) + ": " + why);
  }
  int Line() const { return 1 + static_cast<int>(std::count(s_.begin(), s_.begin() + i_, '\n')); }
  bool At(const char* p) const { return s_.compare(i_, std::strlen(p), p) == 0; }
  void SkipTo(const char* end) {
    const size_t j = s_.find(end, i_);
    if (j == std::string::npos) Fail(std::string("missing ") + end);
    i_ = j + std::strlen(end);
  }
  void SkipSpace() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  // Whitespace, comments, processing instructions, DOCTYPE.
  void SkipMisc() {
    for (;;) {
      SkipSpace();
      if (At("<!--")) {
        SkipTo("-->");
      } else if (At("<?")) {
        SkipTo("?>");
      } else if (At("<!")) {
        SkipTo(">");
      } else {
        return;
      }
    }
  }
  std::string Name() {
    const size_t start = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_' ||
                              s_[i_] == '-' || s_[i_] == ':' || s_[i_] == '.')) {
      ++i_;
    }
    if (i_ == start) Fail("expected a name");
    return s_.substr(start, i_ - start);
  }
  XmlElement Element() {
    if (!At("<")) Fail("expected an element");
    ++i_;
    XmlElement e;
    e.line = Line();
    e.tag = Name();
    for (;;) {
      SkipSpace();
      if (At("/>")) {
        i_ += 2;
        return e;
      }
      if (At(">")) {
        ++i_;
        break;
      }
      std::string name = Name();
      SkipSpace();
      if (!At("=")) Fail("expected '=' after " + name);
      ++i_;
      SkipSpace();
      const char quote = i_ < s_.size() ? s_[i_] : '\0';
      if (quote != '"' && quote != '\'') Fail("expected a quoted value");
      const size_t end = s_.find(quote, i_ + 1);
      if (end == std::string::npos) Fail("unterminated value");
      e.attributes.emplace_back(std::move(name), s_.substr(i_ + 1, end - i_ - 1));
      i_ = end + 1;
    }
    for (;;) {
      const size_t lt = s_.find('<', i_);
      if (lt == std::string::npos) Fail("unterminated <" + e.tag + ">");
      i_ = lt;
      if (At("<!--")) {
        SkipTo("-->");
      } else if (At("<![CDATA[")) {
        SkipTo("]]>");
      } else if (At("<?")) {
        SkipTo("?>");
      } else if (At("</")) {
        i_ += 2;
        if (Name() != e.tag) Fail("mismatched end tag for <" + e.tag + ">");
        SkipSpace();
        if (!At(">")) Fail("expected '>'");
        ++i_;
        return e;
      } else {
        e.children.push_back(Element());
      }
    }
  }

  std::string s_;
  size_t i_ = 0;
};

XmlElement ReadXmlFile(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return XmlReader(text.str()).Root();
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  }
}

struct ModelWalk {
  const fs::path model_dir;  // includes are relative to the main file's folder
  int elements = 0;
  int attributes = 0;
  std::vector<std::string> problems;

  void Walk(const XmlElement& x, const ElementSpec& spec, const std::string& where) {
    ++elements;
    for (const auto& [name, value] : x.attributes) {
      ++attributes;
      if (!spec.FindAttribute(name)) {
        problems.push_back(where + ":" + std::to_string(x.line) + ": <" + x.tag + "> (" + spec.id +
                           ") has no attribute '" + name + "'");
      }
    }
    for (const XmlElement& c : x.children) Child(c, spec, where);
  }

  // `x` as a child of an element of kind `parent`; include splices the included file's content.
  void Child(const XmlElement& x, const ElementSpec& parent, const std::string& where) {
    const ElementSpec* spec = parent.FindChild(x.tag);
    if (!spec) {
      problems.push_back(where + ":" + std::to_string(x.line) + ": <" + x.tag +
                         "> not allowed in " + parent.id);
      return;
    }
    if (spec->id != "include") {
      Walk(x, *spec, where);
      return;
    }
    Walk(x, *spec, where);  // its own attributes (file)
    for (const auto& [name, value] : x.attributes) {
      if (name != "file") continue;
      const XmlElement included = ReadXmlFile(model_dir / value);
      for (const XmlElement& c : included.children) Child(c, parent, value);
    }
  }
};

TEST_F(GrammarTest, SampleModelsUseOnlyGrammar) {
  const fs::path root = "/usr/share/mujoco/model";
  if (!fs::is_directory(root)) GTEST_SKIP() << root << " not installed";
  int files = 0, includes = 0;
  int elements = 0, attributes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.path().extension() != ".xml") continue;
    ++files;
    const XmlElement doc = ReadXmlFile(entry.path());
    ASSERT_EQ(doc.tag, "mujoco") << entry.path();
    ModelWalk walk{entry.path().parent_path()};
    walk.Walk(doc, g_.Root(), entry.path().filename().string());
    for (const std::string& p : walk.problems) ADD_FAILURE() << entry.path() << ": " << p;
    elements += walk.elements;
    attributes += walk.attributes;
    std::function<void(const XmlElement&)> count = [&](const XmlElement& x) {
      includes += x.tag == "include";
      for (const XmlElement& c : x.children) count(c);
    };
    count(doc);
    // And MuJoCo agrees these files are valid MJCF (fragments too: all have a <mujoco> root).
    const std::string error = LoadFileError(entry.path().string());
    EXPECT_FALSE(IsSchemaViolation(error)) << entry.path() << ": " << error;
  }
  EXPECT_GE(files, 15);
  EXPECT_GE(includes, 5);
  EXPECT_GT(elements, 1000);
  EXPECT_GT(attributes, 3000);
}

}  // namespace
}  // namespace urlab::document
