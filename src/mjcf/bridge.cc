#include "urlab/mjcf/bridge.h"

#include <fmt/format.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <type_traits>

#include "mjcf/bridge_attach.h"
#include "mjcf/bridge_rules.h"
#include "mjcf/trial_compile.h"
#include "urlab/document/orientation.h"
#include "urlab/mjcf/writer.h"

namespace urlab::mjcf {

namespace fs = std::filesystem;
using document::Attribute;
using document::CompilerSettings;
using document::Document;
using document::Element;
using document::FormatReal;
using document::FormatReals;
using document::ParseReals;
using document::Quat;
using document::Vec3;
using Kind = BridgeChange::Kind;

namespace {

constexpr double kPi = 3.14159265358979323846;

bool IsActuatorTag(std::string_view t) {
  return t == "general" || t == "motor" || t == "position" || t == "velocity" || t == "cylinder" ||
         t == "muscle" || t == "adhesion" || t == "intvelocity" || t == "damper";
}

bool InDefault(const Element& e) {
  for (const Element* p = e.parent(); p; p = p->parent()) {
    if (p->tag() == "default") return true;
  }
  return false;
}

bool IsDialect(const Attribute& a) { return a.spec && a.spec->dialect; }

// A 3.x attribute, a 3.x keyword of a 2.2.2 attribute, or a value count only 3.x accepts.
bool DialectValue(const Attribute& a) {
  if (!a.spec) return false;
  if (a.spec->dialect) return true;
  const auto& kw = a.spec->dialect_keywords;
  if (std::find(kw.begin(), kw.end(), a.value) != kw.end()) return true;
  if (!a.spec->dialect_count) return false;
  const auto v = ParseReals(a.value);
  const int n = v ? static_cast<int>(v->size()) : 0;
  return n < a.spec->legacy_min_count ||
         (a.spec->legacy_max_count >= 0 && n > a.spec->legacy_max_count);
}

std::string Join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

bool AllZero(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return x == 0; });
}

class Bridge {
 public:
  Bridge(Document& doc, BridgeReport& report) : doc_(doc), report_(report) {}

  void Run() {
    report_.dialect = DetectDialect();
    if (!report_.dialect) return;
    compiler_ = doc_.Compiler();
    Compiler();
    compiler_ = doc_.Compiler();
    ExpandAttachments(doc_, report_, &attached_keys_);
    Replicates();
    FlattenFrames();
    FreeJointAlign();
    SiteEqualities();
    ActuatorArmatureDamping();
    GravityCompensation();
    ActuatorForceRanges();
    PositionShortcuts();
    Options();
    FilterExact();
    PolyCoef();
    SpringLength();
    PassiveFlags();
    VisualOnly();
    KeepVisualGeoms();
    MeshInertia();
    GenericAttributes();
    Sensors();
    ComputedSensors();
    OrderActuators();
    Leftovers();
    if (!report_.HasRefusals()) AlignFreeBodies();
    if (!report_.HasRefusals()) DampRatio();
    if (!report_.HasRefusals()) PadKeyframes();
  }

 private:
  // ---- reporting ----
  // Records a change made by the rule `rule` (a row of the rule table, which gives its kind).
  void Note(std::string_view rule, const Element& e, std::string what) {
    const BridgeRule& r = FindBridgeRule(rule);
    report_.changes.push_back(BridgeChange{r.kind, e.location(), std::move(what), r.id});
  }
  static std::string Tag(const Element& e) {
    std::string s = "<" + e.tag();
    const std::string n = e.Name();
    if (!n.empty())
      s += " " +
           std::string(e.spec() && e.spec()->name_space == document::Namespace::kClass ? "class"
                                                                                       : "name") +
           "='" + n + "'";
    return s + ">";
  }

  // ---- helpers ----
  const std::string* Resolve(const Element& e, std::string_view name) const {
    const std::string* v = document::ResolveAttribute(doc_, e, name);
    if (v || (e.tag() != "fixed" && e.tag() != "spatial")) return v;
    // Tendons take their defaults from the class's <tendon> template.
    const std::string cls = document::EffectiveClass(e);
    const Element* d = nullptr;
    doc_.root().Visit([&](const Element& x) {
      if (d || x.tag() != "default") return;
      const std::string* c = x.Get("class");
      const bool top = !x.parent() || x.parent()->tag() != "default";
      if ((c && *c == cls) || (!c && top && cls == "main")) d = &x;
    });
    for (; d && d->tag() == "default"; d = d->parent()) {
      for (const auto& c : d->children()) {
        if (c->tag() == "tendon" && c->Get(name)) v = c->Get(name);
      }
      if (v) return v;
    }
    return nullptr;
  }
  // Removes `name` from `e` only when it is a 3.x attribute; returns whether it did.
  static bool UnsetDialect(Element& e, std::string_view name) {
    for (const Attribute& a : e.attributes()) {
      if (a.name == name) return IsDialect(a) && e.Unset(name);
    }
    return false;
  }
  std::optional<std::vector<double>> ResolveReals(const Element& e, std::string_view name) const {
    const std::string* t = Resolve(e, name);
    if (!t) return std::nullopt;
    auto v = ParseReals(*t);
    if (!v) {
      throw InputError(e.location(), "<" + e.tag() + "> attribute '" + std::string(name) + "': '" +
                                         *t + "' is not a list of numbers");
    }
    return v;
  }
  double ResolveReal(const Element& e, std::string_view name, double fallback) const {
    auto v = ResolveReals(e, name);
    return v && !v->empty() ? (*v)[0] : fallback;
  }
  // Every element (outside <default>) with tag in `tags`.
  std::vector<Element*> Find(std::initializer_list<std::string_view> tags) {
    std::vector<Element*> out;
    doc_.root().Visit([&](Element& e) {
      if (std::find(tags.begin(), tags.end(), e.tag()) != tags.end() && !InDefault(e)) {
        out.push_back(&e);
      }
    });
    return out;
  }
  // Default-class templates with tag in `tags`.
  std::vector<Element*> FindDefaults(std::initializer_list<std::string_view> tags) {
    std::vector<Element*> out;
    doc_.root().Visit([&](Element& e) {
      if (std::find(tags.begin(), tags.end(), e.tag()) != tags.end() && e.parent() &&
          e.parent()->tag() == "default") {
        out.push_back(&e);
      }
    });
    return out;
  }
  Element* FindNamed(document::Namespace ns, const std::string& name) {
    return doc_.FindNamed(ns, name);
  }
  // Whether a *limited attribute pair is active: explicit true, or auto with autolimits and a
  // range. Refuses the 3.x error case (range without limited while autolimits is false).
  bool LimitActive(const Element& e, const char* limited, const char* range) {
    const std::string* l = Resolve(e, limited);
    const bool has_range = Resolve(e, range) != nullptr;
    if (l && *l == "true") return true;
    if (l && *l == "false") return false;
    return compiler_.autolimits && has_range;
  }
  // Replaces `e` by a new element with tag `tag` (same attributes, location, file bases).
  Element& Retag(Element& e, const std::string& tag) {
    Element* parent = e.parent();
    const int index = parent->IndexOf(&e);
    const document::ElementSpec* spec = parent->spec()->FindChild(tag);
    if (!spec) throw Error("dialect bridge: <" + tag + "> not allowed in <" + parent->tag() + ">");
    auto n = std::make_unique<Element>(spec, tag);
    for (const Attribute& a : e.attributes()) n->AddRawAttribute(a.name, a.value);
    n->set_location(e.location());
    n->set_file_bases(e.file_bases());
    n->set_edited(true);
    parent->RemoveChild(&e);
    return parent->InsertChild(static_cast<size_t>(index), std::move(n));
  }

  // ---- detection ----
  bool DetectDialect() {
    bool dialect = false;
    const CompilerSettings c = doc_.Compiler();
    doc_.root().Visit([&](const Element& e) {
      if (dialect) return;
      if (e.spec() && e.spec()->dialect) dialect = true;
      for (const Attribute& a : e.attributes()) dialect = dialect || DialectValue(a);
      if (dialect || c.autolimits || InDefault(e) || e.tag() == "default") return;
      // A range without its limited attribute only loads with 3.x's autolimits default.
      auto missing = [&](const char* range, const char* limited) {
        return Resolve(e, range) && !Resolve(e, limited);
      };
      if (e.tag() == "joint" || e.tag() == "fixed" || e.tag() == "spatial") {
        dialect = missing("range", "limited");
      } else if (IsActuatorTag(e.tag()) && e.parent() && e.parent()->tag() == "actuator") {
        // damper/adhesion imply ctrllimited and intvelocity implies actlimited in 2.2.2.
        const bool implied_ctrl = e.tag() == "damper" || e.tag() == "adhesion";
        dialect = (!implied_ctrl && missing("ctrlrange", "ctrllimited")) ||
                  missing("forcerange", "forcelimited") ||
                  (e.tag() == "general" && missing("actrange", "actlimited"));
      }
    });
    // 2.2.2 discards a visual geom a <pair> uses and then fails: only 3.x loads it.
    if (!dialect && !VisualPairGeoms().empty()) dialect = true;
    return dialect;
  }

  // ---- compiler ----
  Element& FirstCompiler() {
    Element* found = doc_.root().FirstChild("compiler");
    if (found) return *found;
    auto c = std::make_unique<Element>(doc_.root().spec()->FindChild("compiler"), "compiler");
    c->set_file_bases(doc_.root().file_bases());
    c->set_location(doc_.root().location());
    c->set_edited(true);
    return doc_.root().InsertChild(0, std::move(c));
  }

  void Compiler() {
    bool autolimits_set = false;
    std::string meshdir, texturedir;
    for (const auto& c : doc_.root().children()) {
      if (c->tag() != "compiler") continue;
      autolimits_set = autolimits_set || c->Has("autolimits");
      if (const std::string* v = c->Get("meshdir")) meshdir = *v;
      if (const std::string* v = c->Get("texturedir")) texturedir = *v;
    }
    if (!autolimits_set) {
      Element& c = FirstCompiler();
      c.Set("autolimits", "true");
      Note("compiler.autolimits", c,
           "compiler autolimits=\"true\" written explicitly: the document uses MuJoCo 3.x MJCF, "
           "whose default is true (2.2.2's is false)");
    }
    for (const auto& cp : doc_.root().children()) {
      Element& c = *cp;
      if (c.tag() != "compiler") continue;
      if (const std::string* v = c.Get("assetdir")) {
        // assetdir sets both folders unless meshdir/texturedir are given.
        auto bases = std::make_shared<document::FileBases>(*c.file_bases());
        auto join = [&](const std::string& dir) {
          fs::path p(dir);
          return (p.is_absolute() ? p : fs::path(bases->model_dir) / p).lexically_normal().string();
        };
        if (meshdir.empty()) bases->mesh_dir = join(*v);
        if (texturedir.empty()) bases->texture_dir = join(*v);
        std::shared_ptr<const document::FileBases> shared = bases;
        doc_.root().Visit([&](Element& e) { e.set_file_bases(shared); });
        Note("compiler.assetdir", c,
             "compiler assetdir=\"" + *v +
                 "\" applied as meshdir/texturedir (asset paths are "
                 "written resolved)");
        c.Unset("assetdir");
      }
      if (const std::string* v = c.Get("alignfree")) {
        if (*v == "true") {
          align_free_ = true;
          Note("compiler.alignfree", c,
               "compiler alignfree=\"true\": free bodies without child bodies are aligned with "
               "their inertial frame (see the freejoint align entries)");
        } else {
          Note("compiler.alignfree.false", c, "compiler alignfree=\"false\" is 2.2.2's behaviour");
        }
        c.Unset("alignfree");
      }
      if (c.Has("saveinertial")) {
        Note("compiler.saveinertial", c,
             "compiler saveinertial only affects saving XML; no effect here");
        c.Unset("saveinertial");
      }
      if (c.Has("conflict")) {
        Note("compiler.conflict", c,
             "compiler conflict only concerns model attachment; no effect here");
        c.Unset("conflict");
      }
      for (Element* lr = c.FirstChild("lengthrange"); lr; lr = nullptr) {
        if (const std::string* v = lr->Get("interval")) {
          const std::string value = *v;
          lr->Unset("interval");
          lr->Set("inteval", value);
          Note("compiler.lengthrange.interval", *lr,
               "lengthrange interval renamed to 2.2.2's inteval");
        }
      }
    }
  }

  // ---- <frame> ----
  Vec3 ResolvedVec(const Element& e, const char* name, Vec3 fallback) {
    auto v = ResolveReals(e, name);
    if (!v) return fallback;
    if (v->size() != 3) throw InputError(e.location(), std::string(name) + " needs 3 numbers");
    return {(*v)[0], (*v)[1], (*v)[2]};
  }
  std::optional<Quat> ResolvedQuat(const Element& e) {
    if (auto q = document::OwnOrientation(e, compiler_)) return q;
    if (e.tag() == "geom" || e.tag() == "site" || e.tag() == "camera") {
      const document::InheritedPose p = document::InheritedDefaultPose(doc_, e);
      if (p.any) return p.quat;
    }
    return std::nullopt;
  }
  static void SetQuat(Element& e, const Quat& q) {
    for (const char* o : {"quat", "axisangle", "euler", "xyaxes", "zaxis"}) e.Unset(o);
    e.SetReals("quat", document::QuatNormalize(q));
  }

  void TransformChild(Element& c, const Vec3& fp, const Quat& fq, bool rotated) {
    auto apply = [&](const Vec3& p) {
      const Vec3 r = document::QuatRotate(fq, p);
      return Vec3{fp[0] + r[0], fp[1] + r[1], fp[2] + r[2]};
    };
    const std::string& t = c.tag();
    // 3.x turns a fromto into pos/quat in the frame's own coordinates, then composes the frame's
    // rotation: the roll about the segment follows the frame. Transforming the two points would
    // let 2.2.2 choose another roll (wrong for fromto boxes and ellipsoids), so under a rotation
    // the fromto is written as that pos/quat/size first.
    if ((t == "geom" || t == "site") && rotated && Resolve(c, "fromto")) {
      document::NormalizeFromTo(doc_, c);
    }
    if ((t == "geom" || t == "site") && Resolve(c, "fromto")) {
      auto v = ResolveReals(c, "fromto");
      if (v->size() != 6) throw InputError(c.location(), "fromto needs 6 numbers");
      const Vec3 a = apply({(*v)[0], (*v)[1], (*v)[2]});
      const Vec3 b = apply({(*v)[3], (*v)[4], (*v)[5]});
      const std::vector<double> ft = {a[0], a[1], a[2], b[0], b[1], b[2]};
      c.SetReals("fromto", ft);
      return;
    }
    if (t == "body" || t == "geom" || t == "site" || t == "camera" || t == "frame") {
      const Vec3 p = ResolvedVec(c, "pos", {0, 0, 0});
      c.SetReals("pos", apply(p));
      if (rotated)
        SetQuat(c, document::QuatMul(fq, ResolvedQuat(c).value_or(document::kIdentityQuat)));
    } else if (t == "joint") {
      c.SetReals("pos", apply(ResolvedVec(c, "pos", {0, 0, 0})));
      if (rotated) c.SetReals("axis", document::QuatRotate(fq, ResolvedVec(c, "axis", {0, 0, 1})));
    } else if (t == "light") {
      c.SetReals("pos", apply(ResolvedVec(c, "pos", {0, 0, 0})));
      if (rotated) c.SetReals("dir", document::QuatRotate(fq, ResolvedVec(c, "dir", {0, 0, -1})));
    } else if (t == "freejoint" || t == "inertial") {
      // a free joint has no pose; an inertial cannot be in a frame
    } else {
      Note("frame.child", c,
           Tag(c) + " inside a <frame> with a pose: the bridge cannot move this element");
    }
  }

  // ---- <replicate> ----
  // 3.x expands <replicate count offset euler sep> at compile time: copy i (0..count-1) of the
  // children sits at T^i, T = (offset, euler) relative to the previous copy, and every name
  // inside gets the suffix sep + i (i with as many digits as count has); elements outside that
  // refer to something inside (sensors, actuators, tendons, equalities, contact pairs/excludes)
  // are copied once per replica with the same suffix. Nested replicates: the innermost suffix
  // comes first, so they are expanded innermost first. Each copy becomes a <frame> with T^i,
  // which FlattenFrames then composes into its children.
  using NameSets = std::map<document::Namespace, std::set<std::string>>;

  static void DefinedNames(const Element& root, NameSets* out) {
    root.Visit([&](const Element& e) {
      if (!e.spec() || e.spec()->name_space == document::Namespace::kNone ||
          e.spec()->name_space == document::Namespace::kClass) {
        return;
      }
      if (const std::string* n = e.Get("name")) (*out)[e.spec()->name_space].insert(*n);
    });
  }

  // The namespace an attribute of `e` names, when it is a reference.
  static document::Namespace RefNamespace(const Element& e, const Attribute& a) {
    const document::AttributeSpec* spec = e.spec() ? e.spec()->FindAttribute(a.name) : nullptr;
    if (!spec || !spec->IsReference()) return document::Namespace::kNone;
    if (spec->ref != document::Namespace::kNone) return spec->ref;
    const std::string* sel = e.Get(spec->ref_selector);
    return sel ? document::NamespaceFromObjType(*sel) : document::Namespace::kNone;
  }

  static bool RefersTo(const Element& root, const NameSets& names) {
    bool found = false;
    root.Visit([&](const Element& e) {
      for (const Attribute& a : e.attributes()) {
        auto it = names.find(RefNamespace(e, a));
        if (it != names.end() && it->second.count(a.value)) found = true;
      }
    });
    return found;
  }

  // Appends `suffix` to the names in `root` that are in `names` and to references to them.
  static void Suffix(Element& root, const NameSets& names, const std::string& suffix) {
    root.Visit([&](Element& e) {
      std::vector<std::pair<std::string, std::string>> renamed;
      for (const Attribute& a : e.attributes()) {
        const document::Namespace ns =
            a.name == "name" && e.spec() ? e.spec()->name_space : RefNamespace(e, a);
        auto it = names.find(ns);
        if (it != names.end() && it->second.count(a.value)) {
          renamed.emplace_back(a.name, a.value + suffix);
        }
      }
      for (auto& [k, v] : renamed) e.Set(k, v);
    });
  }

  void Replicates() {
    for (;;) {
      Element* innermost = nullptr;
      doc_.root().Visit([&](Element& e) {
        if (innermost || e.tag() != "replicate") return;
        bool nested = false;
        for (const auto& c : e.children()) {
          c->Visit([&](const Element& x) { nested = nested || x.tag() == "replicate"; });
        }
        if (!nested) innermost = &e;
      });
      if (!innermost) return;
      Replicate(*innermost);
    }
  }

  void Replicate(Element& r) {
    Element* parent = r.parent();
    const int count = r.GetInt("count").value_or(0);
    if (count <= 0) {
      Note("replicate.invalid", r, "<replicate> needs a positive count (MuJoCo 3.x too)");
      parent->RemoveChild(&r);
      return;
    }
    const std::string sep = r.GetOr("sep", "");
    const Vec3 offset = ResolvedVec(r, "offset", {0, 0, 0});
    Element probe(r.spec(), "replicate");  // its euler in the compiler's unit and sequence
    if (const std::string* e = r.Get("euler")) probe.AddRawAttribute("euler", *e);
    const Quat step = document::OwnOrientation(probe, compiler_).value_or(document::kIdentityQuat);
    const int digits = static_cast<int>(std::to_string(count).size());
    auto suffix = [&](int i) {
      std::string n = std::to_string(i);
      return sep + std::string(static_cast<size_t>(digits) - n.size(), '0') + n;
    };
    NameSets inside;
    for (const auto& c : r.children()) DefinedNames(*c, &inside);
    // The copies, each a <frame> at T^i.
    const document::ElementSpec* frame_spec = parent->spec()->FindChild("frame");
    if (!frame_spec) throw Error("dialect bridge: <frame> not allowed in <" + parent->tag() + ">");
    size_t index = static_cast<size_t>(parent->IndexOf(&r));
    Vec3 pos = {0, 0, 0};
    Quat quat = document::kIdentityQuat;
    for (int i = 0; i < count; ++i) {
      auto f = std::make_unique<Element>(frame_spec, "frame");
      f->set_location(r.location());
      f->set_file_bases(r.file_bases());
      f->set_edited(true);
      f->SetReals("pos", pos);
      f->SetReals("quat", quat);
      for (const auto& c : r.children()) {
        std::unique_ptr<Element> copy = c->Clone();
        Suffix(*copy, inside, suffix(i));
        f->InsertChild(f->children().size(), std::move(copy));
      }
      parent->InsertChild(index++, std::move(f));
      const Vec3 d = document::QuatRotate(quat, offset);
      pos = {pos[0] + d[0], pos[1] + d[1], pos[2] + d[2]};
      quat = document::QuatNormalize(document::QuatMul(quat, step));
    }
    Note("replicate", r,
         "<replicate count=" + std::to_string(count) + "> expanded into " + std::to_string(count) +
             " copies of its " + std::to_string(r.children().size()) +
             " child element(s), names suffixed '" + suffix(0) + "'..'" + suffix(count - 1) +
             "' as MuJoCo 3.x names them");
    parent->RemoveChild(&r);
    // Elements outside that refer into the replicated tree are replicated with it. Tendons come
    // first: actuators and sensors may refer to a replicated tendon.
    for (const char* section : {"tendon", "equality", "contact", "actuator", "sensor"}) {
      for (Element* s : Find({section})) {
        std::vector<Element*> refs;
        for (const auto& c : s->children()) {
          if (RefersTo(*c, inside)) refs.push_back(c.get());
        }
        if (refs.empty()) continue;
        NameSets own;  // names of the referring elements themselves (suffixed too)
        for (Element* e : refs) DefinedNames(*e, &own);
        NameSets both = inside;
        for (auto& [ns, set] : own) both[ns].insert(set.begin(), set.end());
        size_t at = static_cast<size_t>(s->IndexOf(refs.front()));
        std::vector<std::unique_ptr<Element>> originals;
        for (Element* e : refs) originals.push_back(s->RemoveChild(e));
        for (int i = 0; i < count; ++i) {
          for (const auto& o : originals) {
            std::unique_ptr<Element> copy = o->Clone();
            Suffix(*copy, both, suffix(i));
            s->InsertChild(at++, std::move(copy));
          }
        }
        for (const auto& o : originals) {
          Note("replicate.reference", *o,
               Tag(*o) + " refers into a <replicate>: copied once per replica, names suffixed");
        }
        for (auto& [ns, set] : own) inside[ns].insert(set.begin(), set.end());
      }
    }
  }

  void FlattenFrames() {
    for (;;) {
      Element* frame = nullptr;
      doc_.root().Visit([&](Element& e) {
        if (!frame && e.tag() == "frame") frame = &e;
      });
      if (!frame) return;
      FlattenFrame(*frame);
    }
  }

  void FlattenFrame(Element& f) {
    Element* parent = f.parent();
    const Vec3 fp = ResolvedVec(f, "pos", {0, 0, 0});
    const std::optional<Quat> own = document::OwnOrientation(f, compiler_);
    const Quat fq = own.value_or(document::kIdentityQuat);
    const bool rotated = own && std::abs(std::abs(document::QuatNormalize(fq)[0]) - 1) > 1e-15;
    const bool moved = fp != Vec3{0, 0, 0} || rotated;
    const std::string* cc = f.Get("childclass");
    const std::string childclass = cc ? *cc : "";
    // Transform first: default-class resolution still sees the frame's childclass.
    std::vector<Element*> kids;
    for (const auto& c : f.children()) kids.push_back(c.get());
    if (moved) {
      for (Element* c : kids) TransformChild(*c, fp, fq, rotated);
    }
    if (!childclass.empty()) {
      for (Element* c : kids) {
        const std::string& t = c->tag();
        if (t == "body" || t == "frame") {
          if (!c->Has("childclass")) c->Set("childclass", childclass);
        } else if (c->spec() && c->spec()->FindAttribute("class") && !c->Has("class")) {
          c->Set("class", childclass);
        }
      }
    }
    size_t index = static_cast<size_t>(parent->IndexOf(&f));
    for (Element* c : kids) parent->InsertChild(index++, f.RemoveChild(c));
    std::string what = "<frame";
    if (const std::string* n = f.Get("name")) what += " name='" + *n + "'";
    what += "> flattened: " + std::to_string(kids.size()) + " child element(s) moved into <" +
            parent->tag() + ">";
    if (moved) what += " with the frame's pose composed into theirs";
    if (!childclass.empty()) what += ", childclass='" + childclass + "' given to them";
    Note("frame", f, what);
    parent->RemoveChild(&f);
  }

  // ---- free joint alignment ----
  // 3.x can align a "simple free body" (a free joint, no child bodies) with its inertial frame
  // at compile time (freejoint align="true", or "auto" under compiler alignfree="true"): the body
  // frame moves to the centre of mass along the principal axes, its children are re-expressed in
  // it, and ipos/iquat become zero/identity. That is a change of the model's description, so
  // 2.2.2 gets the aligned document: FreeJointAlign picks the bodies, AlignFreeBodies (after a
  // trial compile gives the inertial frames) rewrites them. Keyframes keep their numbers, which
  // 3.x also reads as the aligned body's pose.
  void FreeJointAlign() {
    for (Element* j : Find({"freejoint", "joint"})) {
      const std::string* a = j->Get("align");
      if (j->tag() == "joint") {
        const std::string* type = Resolve(*j, "type");
        if (!type || *type != "free") continue;
      }
      const std::string mode = a ? *a : "auto";
      if (mode != "true" && mode != "auto") continue;  // "false": the attribute policy drops it
      const bool align = mode == "true" || align_free_;
      Element* body = j->parent();
      if (a) UnsetDialect(*j, "align");
      if (!align || !body || body->tag() != "body") continue;
      if (body->FirstChild("body")) {
        Note("freejoint.align.nochildren", *j,
             Tag(*j) +
                 " align: no effect on a body with child bodies (MuJoCo 3.x aligns only "
                 "free bodies without children)");
        continue;
      }
      const std::string name = body->Name();
      const Element* anchored = nullptr;
      for (Element* e : Find({"connect", "weld"})) {
        if (!name.empty() && (e->GetOr("body1", "") == name || e->GetOr("body2", "") == name)) {
          anchored = e;
        }
      }
      if (anchored) {
        Note("freejoint.align.refused", *j,
             Tag(*j) + " align: the body's equality " + Tag(*anchored) +
                 " gives anchors in the body frame, which alignment moves; nearest 2.2.2 "
                 "construct: align=\"false\" (or site1/site2 on the equality)");
        continue;
      }
      to_align_.push_back(body);
    }
  }

  void AlignFreeBodies() {
    if (to_align_.empty()) return;
    int unnamed = 0;
    for (Element* b : to_align_) {
      if (b->Name().empty()) b->Set("name", fmt::format("aligned_body{}", unnamed++));
    }
    std::string error;
    mjModel* m = TrialCompile(WriteString(doc_), &error);
    if (!m) {
      for (Element* b : to_align_) {
        Note(
            "freejoint.align.refused", *b,
            Tag(*b) + ": aligning its free joint needs the compiled model, which failed: " + error);
      }
      return;
    }
    for (Element* b : to_align_) {
      const int id = mj_name2id(m, mjOBJ_BODY, b->Name().c_str());
      if (id < 0) continue;
      const Vec3 ip = {m->body_ipos[3 * id], m->body_ipos[3 * id + 1], m->body_ipos[3 * id + 2]};
      const Quat iq = {m->body_iquat[4 * id], m->body_iquat[4 * id + 1], m->body_iquat[4 * id + 2],
                       m->body_iquat[4 * id + 3]};
      // The body moves to its inertial frame: pos + R(quat) ip, quat * iquat.
      const Vec3 p = ResolvedVec(*b, "pos", {0, 0, 0});
      const Quat q = ResolvedQuat(*b).value_or(document::kIdentityQuat);
      const Vec3 d = document::QuatRotate(q, ip);
      b->SetReals("pos", Vec3{p[0] + d[0], p[1] + d[1], p[2] + d[2]});
      SetQuat(*b, document::QuatMul(q, iq));
      // Its children move the other way: (-R(iquat)^T ipos, iquat^-1).
      const Quat inv = {iq[0], -iq[1], -iq[2], -iq[3]};
      const Vec3 r = document::QuatRotate(inv, ip);
      std::vector<Element*> kids;
      for (const auto& c : b->children()) kids.push_back(c.get());
      for (Element* c : kids) {
        if (c->tag() == "inertial") {
          b->RemoveChild(c);
          continue;
        }
        TransformChild(*c, {-r[0], -r[1], -r[2]}, inv, true);
      }
      // The inertia, explicit in the aligned frame (what 3.x compiles: ipos 0, iquat identity).
      const document::ElementSpec* spec = b->spec()->FindChild("inertial");
      auto inertial = std::make_unique<Element>(spec, "inertial");
      inertial->set_location(b->location());
      inertial->set_edited(true);
      inertial->SetReals("pos", Vec3{0, 0, 0});
      inertial->SetReals("quat", document::kIdentityQuat);
      inertial->SetReals("mass", std::vector<double>{m->body_mass[id]});
      inertial->SetReals("diaginertia", std::vector<double>(m->body_inertia + 3 * id,
                                                            m->body_inertia + 3 * id + 3));
      b->InsertChild(0, std::move(inertial));
      Note("freejoint.align", *b,
           Tag(*b) +
               " aligned with its inertial frame as MuJoCo 3.x does (freejoint align): "
               "the body moved by ipos " +
               FormatReals(ip) + " and iquat " + FormatReals(iq) + ", its " +
               std::to_string(kids.size()) +
               " child element(s) re-expressed in the new frame, the inertia written explicitly "
               "(ipos 0, iquat identity); the free joint's qpos is the aligned frame's pose");
    }
    mj_deleteModel(m);
  }

  // ---- equality constraints on sites ----
  // 3.x connect/weld with site1/site2 hold the two sites together (position; weld also the
  // orientation). 2.2.2 knows only bodies, and derives the second anchor (and the weld's relative
  // pose) from qpos0; the body constraint is written here and its data set from the compiled
  // sites after compilation (ApplySiteEqualities), which is exact wherever the sites start.
  // Every weld, on bodies too, differs from 3.x's in two ways 2.2.2 offers no hook for
  // (reference3x_test SiteWeldDiffersOnlyByTwoWeldChangesOfMujoco3 pins both).
  static constexpr const char* kWeldSince3 =
      "MuJoCo 3.x changed the weld after 2.2.2: 2.2.2's efc_diagApprox gives all six rows the "
      "bodies' translational inverse weight (3.0.0: the rotational rows get the rotational "
      "one), so the orientation part is regularised, hence softened, differently; and with "
      "torquescale != 1 2.2.2 scales the rotational Jacobian but not the angular residual "
      "(3.0.1 scales both). Same constraint (same pose held), different stiffness under load "
      "and transient";
  void SiteEqualities() {
    int unnamed = 0;
    for (Element* e : Find({"connect", "weld"})) {
      if (!e->parent() || e->parent()->tag() != "equality") continue;
      const std::string* a = e->Get("site1");
      const std::string* b = e->Get("site2");
      if (!a && !b && e->tag() == "weld") {
        Note("equality.weld", *e, Tag(*e) + " kept as it is: " + kWeldSince3);
      }
      if (!a && !b) continue;
      if (!a || !b) {
        Note("equality.site.refused", *e,
             Tag(*e) +
                 " needs both site1 and site2 (MuJoCo 3.x too); nearest 2.2.2 construct: "
                 "body1/body2 with anchor");
        UnsetDialect(*e, "site1");
        UnsetDialect(*e, "site2");
        continue;
      }
      const std::string s1 = *a, s2 = *b;
      const std::string b1 = SiteBody(s1), b2 = SiteBody(s2);
      if (b1.empty() || b2.empty()) continue;  // dangling site: reported by the reader
      std::string name = e->Name();
      if (name.empty()) {
        name = "site_equality" + std::to_string(unnamed++);
        e->Set("name", name);
      }
      UnsetDialect(*e, "site1");
      UnsetDialect(*e, "site2");
      std::string ignored;
      for (const char* n : {"anchor", "relpose"}) {
        if (e->Unset(n)) ignored += std::string(ignored.empty() ? "; " : ", ") + n;
      }
      if (!ignored.empty()) ignored += " ignored with sites, as in MuJoCo 3.x";
      e->Set("body1", b1);
      e->Set("body2", b2);
      if (e->tag() == "connect") e->Set("anchor", "0 0 0");  // replaced after compilation
      report_.site_equalities.push_back({name, s1, s2});
      Note(e->tag() == "weld" ? "equality.site.weld" : "equality.site", *e,
           Tag(*e) + " site1='" + s1 + "' site2='" + s2 + "' -> body1='" + b1 + "' body2='" + b2 +
               "'; anchors" + (e->tag() == "weld" ? " and relative orientation" : "") +
               " set from the sites' frames after compilation" +
               (e->tag() == "weld" ? std::string("; ") + kWeldSince3 : std::string()) + ignored);
    }
  }

  // The name of the body holding site `site` ("world" for the world body); names an unnamed one.
  std::string SiteBody(const std::string& site) {
    Element* s = FindNamed(document::Namespace::kSite, site);
    if (!s) return "";
    Element* b = s->parent();
    while (b && b->tag() != "body" && b->tag() != "worldbody") b = b->parent();
    if (!b) return "";
    if (b->tag() == "worldbody") return "world";
    if (b->Name().empty()) b->Set("name", "body_of_" + site);
    return b->Name();
  }

  // ---- actuator armature / damping (3.x) move to the transmission target ----
  void ActuatorArmatureDamping() {
    for (Element* a : Find({"general", "motor", "position", "velocity", "cylinder", "muscle",
                            "adhesion", "intvelocity", "damper"})) {
      if (!a->parent() || a->parent()->tag() != "actuator") continue;
      auto arm = ResolveReals(*a, "armature");
      auto damp = ResolveReals(*a, "damping");
      UnsetDialect(*a, "armature");
      UnsetDialect(*a, "damping");
      const double armature = arm && !arm->empty() ? (*arm)[0] : 0;
      std::vector<double> damping = damp ? *damp : std::vector<double>{};
      if (armature == 0 && AllZero(damping)) continue;
      if (damping.size() > 1 && !AllZero({damping.begin() + 1, damping.end()})) {
        Note("actuator.armature_damping.refused", *a,
             Tag(*a) + " polynomial damping (quadratic/cubic terms) has no 2.2.2 equivalent");
        continue;
      }
      const double d = damping.empty() ? 0 : damping[0];
      const double g = ResolveReal(*a, "gear", 1);
      const std::string* joint = a->Get("joint");
      if (!joint) joint = a->Get("jointinparent");
      const std::string* tendon = a->Get("tendon");
      if (joint) {
        Element* j = FindNamed(document::Namespace::kJoint, *joint);
        if (!j) continue;  // dangling reference: reported by the reader
        const std::string type = Resolve(*j, "type") ? *Resolve(*j, "type") : "hinge";
        if (type != "hinge" && type != "slide") {
          Note("actuator.armature_damping.refused", *a,
               Tag(*a) + " armature/damping on a " + type + " joint");
          continue;
        }
        const double ja = ResolveReal(*j, "armature", 0) + armature * g * g;
        const double jd = ResolveReal(*j, "damping", 0) + d * g * g;
        if (armature != 0) j->SetReal("armature", ja);
        if (d != 0) j->SetReal("damping", jd);
        Note("actuator.armature_damping", *a,
             Tag(*a) + " armature/damping moved to joint '" + *joint +
                 "' scaled by gear^2 (armature " + FormatReal(ja) + ", damping " + FormatReal(jd) +
                 "): MuJoCo 3.x adds them there the same way");
      } else if (tendon && armature == 0) {
        Element* t = FindNamed(document::Namespace::kTendon, *tendon);
        if (!t) continue;
        const double td = ResolveReal(*t, "damping", 0) + d * g * g;
        t->SetReal("damping", td);
        Note("actuator.armature_damping", *a,
             Tag(*a) + " damping moved to tendon '" + *tendon + "' scaled by gear^2 (" +
                 FormatReal(td) + ")");
      } else {
        Note("actuator.armature_damping.refused", *a,
             Tag(*a) +
                 " armature/damping: only joint transmissions (and tendon damping) can "
                 "carry them in MuJoCo 2.2.2");
      }
    }
    for (Element* d : FindDefaults({"general", "motor", "position", "velocity", "cylinder",
                                    "muscle", "adhesion", "intvelocity", "damper"})) {
      bool any = UnsetDialect(*d, "armature");
      any = UnsetDialect(*d, "damping") || any;
      if (any) {
        Note("actuator.armature_damping.default", *d,
             "default " + Tag(*d) + " armature/damping resolved into each actuator's target");
      }
    }
  }

  // ---- body gravcomp (computed by the runtime through mjcb_passive) ----
  void GravityCompensation() {
    int unnamed = 0;
    for (Element* b : Find({"body"})) {
      const std::string* v = b->Get("gravcomp");
      if (!v) continue;
      const auto g = ParseReals(*v);
      if (!g || g->size() != 1) throw InputError(b->location(), "<body> gravcomp needs a number");
      const std::string text = *v;
      b->Unset("gravcomp");
      if ((*g)[0] == 0) {
        Note("gravcomp.zero", *b, Tag(*b) + " gravcomp=\"0\" dropped: no compensation");
        continue;
      }
      std::string name = b->Name();
      if (name.empty()) {
        name = "gravcomp_body" + std::to_string(unnamed++);
        b->Set("name", name);
      }
      report_.gravcomp.push_back({name, (*g)[0]});
      Note("gravcomp", *b,
           Tag(*b) + " gravcomp=\"" + text +
               "\": the runtime adds gravcomp * mass * (-gravity) at the body's centre of mass "
               "to qfrc_passive through mjcb_passive, as MuJoCo 3.x's mj_gravcomp does");
    }
    for (Element* j : Find({"joint"})) {
      const std::string* v = Resolve(*j, "actuatorgravcomp");
      if (!v || *v != "true") continue;
      const bool clamped = Resolve(*j, "actuatorfrcrange") != nullptr;
      Note(clamped ? "gravcomp.actuator.clamped" : "gravcomp.actuator", *j,
           Tag(*j) +
               " actuatorgravcomp=\"true\": the compensation is added to qfrc_passive, "
               "not qfrc_actuator (same total force; qfrc_actuator and jointactuatorfrc "
               "read it without the compensation)" +
               (clamped ? std::string("; the joint's actuatorfrcrange does not clamp it") : ""));
      UnsetDialect(*j, "actuatorgravcomp");
    }
    for (Element* d : FindDefaults({"joint"})) UnsetDialect(*d, "actuatorgravcomp");
  }

  // ---- actuatorfrcrange on joints and tendons ----
  struct Driver {
    Element* actuator;
    bool direct;  // joint/jointinparent/tendon transmission on exactly this target
  };

  // Joints on the path from the world to the body holding `e` (ancestors' joints).
  static void AncestorJoints(const Element* e, std::set<const Element*>* out) {
    for (const Element* b = e; b; b = b->parent()) {
      if (b->tag() != "body") continue;
      for (const auto& c : b->children()) {
        if (c->tag() == "joint") out->insert(c.get());
      }
    }
  }

  std::vector<Driver> JointDrivers(const Element& joint) {
    std::vector<Driver> out;
    const std::string name = joint.Name();
    for (Element* a : Find({"general", "motor", "position", "velocity", "cylinder", "muscle",
                            "adhesion", "intvelocity", "damper"})) {
      if (!a->parent() || a->parent()->tag() != "actuator") continue;
      const std::string* j = a->Get("joint");
      if (!j) j = a->Get("jointinparent");
      if (j) {
        if (*j == name) out.push_back({a, true});
        continue;
      }
      std::set<const Element*> reach;
      if (const std::string* t = a->Get("tendon")) {
        const Element* ten = FindNamed(document::Namespace::kTendon, *t);
        if (!ten) continue;
        ten->Visit([&](const Element& x) {
          if (x.tag() == "joint" && x.GetOr("joint", "") == name) reach.insert(&joint);
          if (x.tag() == "site") {
            if (const Element* s = FindNamed(document::Namespace::kSite, x.GetOr("site", ""))) {
              AncestorJoints(s, &reach);
            }
          }
        });
      }
      for (const char* attr : {"site", "cranksite"}) {
        if (const std::string* s = a->Get(attr)) {
          if (const Element* site = FindNamed(document::Namespace::kSite, *s)) {
            AncestorJoints(site, &reach);
          }
        }
      }
      if (const std::string* b = a->Get("body")) {
        if (const Element* body = FindNamed(document::Namespace::kBody, *b)) {
          AncestorJoints(body, &reach);
        }
      }
      if (reach.count(&joint)) out.push_back({a, false});
    }
    return out;
  }

  std::vector<Driver> TendonDrivers(const Element& tendon) {
    std::vector<Driver> out;
    for (Element* a : Find({"general", "motor", "position", "velocity", "cylinder", "muscle",
                            "adhesion", "intvelocity", "damper"})) {
      if (a->parent() && a->parent()->tag() == "actuator" &&
          a->GetOr("tendon", "") == tendon.Name()) {
        out.push_back({a, true});
      }
    }
    return out;
  }

  // The actuator's own force clamp, when active.
  std::optional<std::array<double, 2>> ForceRange(const Element& a) {
    if (!LimitActive(a, "forcelimited", "forcerange")) return std::nullopt;
    auto r = ResolveReals(a, "forcerange");
    if (!r || r->size() != 2) return std::array<double, 2>{0, 0};
    return std::array<double, 2>{(*r)[0], (*r)[1]};
  }

  // Clamps the total actuator force at `target` (a joint or tendon) to `range`. `scale_by_gear`:
  // the clamped quantity is gear * actuator_force (joints) rather than actuator_force (tendons).
  void ClampTarget(Element& target, const std::array<double, 2>& range,
                   const std::vector<Driver>& drivers, bool scale_by_gear) {
    const std::string what = Tag(target) + " actuatorfrcrange=\"" + FormatReal(range[0]) + " " +
                             FormatReal(range[1]) + "\"";
    if (drivers.empty()) {
      Note("actuatorfrcrange.inactive", target,
           what + ": no actuator acts on it, so it has no effect");
      return;
    }
    if (drivers.size() == 1 && drivers[0].direct) {
      Element& a = *drivers[0].actuator;
      const double g = scale_by_gear ? ResolveReal(a, "gear", 1) : 1;
      if (g == 0) {
        Note("actuatorfrcrange.inactive", target, what + ": its actuator has gear 0");
        return;
      }
      std::array<double, 2> r = {range[0] / g, range[1] / g};
      if (g < 0) r = {range[1] / g, range[0] / g};
      std::string how = "exact";
      if (auto own = ForceRange(a)) {
        const std::array<double, 2> both = {std::max(r[0], (*own)[0]), std::min(r[1], (*own)[1])};
        if (both[0] > both[1]) {
          Note("actuatorfrcrange.refused", target,
               what + " and the forcerange of " + Tag(a) +
                   " do not overlap: the total force would be constant");
          return;
        }
        r = both;
        how = "intersected with its own forcerange";
      }
      a.Set("forcelimited", "true");
      a.SetReals("forcerange", r);
      Note("actuatorfrcrange.one", target,
           what + " -> forcerange=\"" + FormatReals(r) + "\" forcelimited=\"true\" on " + Tag(a) +
               (scale_by_gear ? " (scaled by 1/gear, " + how + ")" : " (" + how + ")") +
               ". Exact for the force applied to the " +
               (scale_by_gear ? "joint (qfrc_actuator)" : "tendon") +
               "; the actuator's own actuator_force now also reads the clamped value");
      return;
    }
    // Several actuators: exact only if the clamp can never be active.
    double lo = 0, hi = 0;
    for (const Driver& d : drivers) {
      auto own = d.direct ? ForceRange(*d.actuator) : std::nullopt;
      if (!own) {
        Note("actuatorfrcrange.refused", target,
             what + " is shared by " + std::to_string(drivers.size()) +
                 " actuators; MuJoCo 2.2.2 cannot clamp their sum and " + Tag(*d.actuator) +
                 " has no force range that keeps the sum inside it");
        return;
      }
      const double g = scale_by_gear ? ResolveReal(*d.actuator, "gear", 1) : 1;
      lo += std::min(g * (*own)[0], g * (*own)[1]);
      hi += std::max(g * (*own)[0], g * (*own)[1]);
    }
    if (lo >= range[0] && hi <= range[1]) {
      Note("actuatorfrcrange.inactive", target,
           what + ": the force ranges of its " + std::to_string(drivers.size()) +
               " actuators already keep the total inside it, so it is never active");
      return;
    }
    Note("actuatorfrcrange.refused", target,
         what + " clamps the sum of " + std::to_string(drivers.size()) +
             " actuators, which MuJoCo 2.2.2 cannot express (per-actuator force ranges would "
             "change the physics)");
  }

  void ActuatorForceRanges() {
    for (Element* t : Find({"joint", "fixed", "spatial"})) {
      const bool joint = t->tag() == "joint";
      auto copy = [](const std::string* v) {
        return v ? std::optional<std::string>(*v) : std::nullopt;
      };
      const std::optional<std::string> range_text = copy(Resolve(*t, "actuatorfrcrange"));
      const std::optional<std::string> limited = copy(Resolve(*t, "actuatorfrclimited"));
      if (!range_text && !limited) continue;
      const bool active =
          limited ? *limited == "true" || (*limited == "auto" && compiler_.autolimits && range_text)
                  : compiler_.autolimits && range_text;
      t->Unset("actuatorfrcrange");
      t->Unset("actuatorfrclimited");
      if (!limited && range_text && !compiler_.autolimits) {
        Note("actuatorfrcrange.refused", *t,
             Tag(*t) +
                 " actuatorfrcrange without actuatorfrclimited while autolimits is false "
                 "(MuJoCo 3.x rejects this too)");
        continue;
      }
      if (!active) {
        Note("actuatorfrcrange.inactive", *t,
             Tag(*t) + " actuator force clamp disabled: no effect");
        continue;
      }
      auto r = range_text ? ParseReals(*range_text) : std::optional<std::vector<double>>();
      if (!r || r->size() != 2 || (*r)[0] > (*r)[1]) {
        Note("actuatorfrcrange.refused", *t,
             Tag(*t) + " actuatorfrclimited without a valid actuatorfrcrange");
        continue;
      }
      if (joint) {
        const std::string* type = Resolve(*t, "type");
        if (type && *type != "hinge" && *type != "slide") {
          Note("actuatorfrcrange.inactive", *t,
               Tag(*t) + " actuatorfrcrange on a " + *type + " joint is ignored by MuJoCo 3.x");
          continue;
        }
      }
      ClampTarget(*t, {(*r)[0], (*r)[1]}, joint ? JointDrivers(*t) : TendonDrivers(*t), joint);
    }
    for (Element* d : FindDefaults({"joint", "tendon"})) {
      bool any = d->Unset("actuatorfrcrange");
      any = d->Unset("actuatorfrclimited") || any;
      if (any) {
        Note("actuatorfrcrange.default", *d,
             "default " + Tag(*d) + " actuatorfrcrange resolved into each " + d->tag() +
                 " of the class (see their entries)");
      }
    }
  }

  // ---- position / intvelocity: kv, dampratio, timeconst, inheritrange ----
  struct PendingDampRatio {
    Element* actuator;
    double kp;
    double ratio;
  };

  std::optional<std::array<double, 2>> TargetRange(Element& a, std::string* why) {
    const std::string* j = a.Get("joint");
    if (!j) j = a.Get("jointinparent");
    const std::string* t = a.Get("tendon");
    const Element* target = j   ? FindNamed(document::Namespace::kJoint, *j)
                            : t ? FindNamed(document::Namespace::kTendon, *t)
                                : nullptr;
    if (!target) {
      *why = "inheritrange needs a joint or tendon transmission";
      return std::nullopt;
    }
    auto r = ResolveReals(*target, "range");
    if (!r || r->size() != 2) {
      *why = "inheritrange: " + Tag(*target) + " has no range";
      return std::nullopt;
    }
    double scale = 1;
    if (j) {
      const std::string* type = Resolve(*target, "type");
      const std::string ty = type ? *type : "hinge";
      if (ty == "hinge" && compiler_.degree) scale = kPi / 180;
      if (ty != "hinge" && ty != "slide") {
        *why = "inheritrange on a " + ty + " joint";
        return std::nullopt;
      }
    }
    return std::array<double, 2>{(*r)[0] * scale, (*r)[1] * scale};
  }

  // How specific the element holding `value` (a pointer ResolveAttribute returned for `e`) is:
  // e itself is the most specific, then default classes by nesting depth.
  int SetterDepth(const Element& e, const std::string* value) {
    int depth = -1;
    doc_.root().Visit([&](const Element& x) {
      for (const Attribute& at : x.attributes()) {
        if (&at.value != value) continue;
        if (&x == &e) {
          depth = 1 << 20;
        } else {
          depth = 0;
          for (const Element* p = x.parent(); p; p = p->parent()) ++depth;
        }
      }
    });
    return depth;
  }

  // A 3.x attribute of a position/intvelocity actuator resolved through its classes; a value
  // inherited from another shortcut's template (velocity kv, cylinder timeconst) does not count.
  double DialectReal(const Element& e, std::string_view name) {
    const std::string* v = Resolve(e, name);
    if (!v) return 0;
    bool dialect = false;
    doc_.root().Visit([&](const Element& x) {
      for (const Attribute& at : x.attributes()) {
        if (&at.value == v) dialect = IsDialect(at);
      }
    });
    if (!dialect) return 0;
    auto r = ParseReals(*v);
    if (!r || r->size() != 1) {
      throw InputError(e.location(), "<" + e.tag() + "> " + std::string(name) + " needs a number");
    }
    return (*r)[0];
  }

  // Whether a 3.x attribute of a position/intvelocity actuator is set (on it or its classes).
  bool DialectSet(const Element& e, std::string_view name) {
    const std::string* v = Resolve(e, name);
    bool dialect = false;
    if (v) {
      doc_.root().Visit([&](const Element& x) {
        for (const Attribute& at : x.attributes()) {
          if (&at.value == v) dialect = IsDialect(at);
        }
      });
    }
    return dialect;
  }

  void PositionShortcuts() {
    const double dt = doc_.FindSection("option") && doc_.FindSection("option")->Get("timestep")
                          ? *doc_.FindSection("option")->GetReal("timestep")
                          : 0.002;
    const std::string integrator = doc_.FindSection("option")
                                       ? doc_.FindSection("option")->GetOr("integrator", "Euler")
                                       : "Euler";
    for (Element* a : Find({"position", "intvelocity"})) {
      if (!a->parent() || a->parent()->tag() != "actuator") continue;
      const bool position = a->tag() == "position";
      // kv and dampratio fill the same slot (biasprm[2]): the most specific setter wins, whatever
      // its value (an explicit kv="0" overrides a class's dampratio, as in 3.x). Both on one
      // element (or one default template) is an error in 3.x.
      double kv = DialectReal(*a, "kv");
      double ratio = DialectReal(*a, "dampratio");
      bool both = false;
      if (DialectSet(*a, "kv") && DialectSet(*a, "dampratio")) {
        const int dk = SetterDepth(*a, Resolve(*a, "kv"));
        const int dr = SetterDepth(*a, Resolve(*a, "dampratio"));
        if (dk > dr) ratio = 0;
        if (dr > dk) kv = 0;
        both = dk == dr;
      }
      const double tau = position ? DialectReal(*a, "timeconst") : 0;
      const double inherit = DialectReal(*a, "inheritrange");
      for (const char* n : {"kv", "dampratio", "timeconst", "inheritrange"}) UnsetDialect(*a, n);
      if (both) {
        Note("position.refused", *a,
             Tag(*a) +
                 " kv and dampratio set together (MuJoCo 3.x refuses this too: \"kv and "
                 "dampratio cannot both be defined\")");
        continue;
      }
      if (kv == 0 && ratio == 0 && tau == 0 && inherit == 0) continue;
      if (kv < 0 || ratio < 0 || tau < 0 || inherit < 0) {
        Note("position.refused", *a, Tag(*a) + " kv/dampratio/timeconst/inheritrange must be >= 0");
        continue;
      }
      if (inherit > 0) {
        const char* range_attr = position ? "ctrlrange" : "actrange";
        const char* limited_attr = position ? "ctrllimited" : "actlimited";
        if (a->Has(range_attr)) {
          Note("position.refused", *a,
               Tag(*a) + " inheritrange and " + range_attr + " are exclusive (MuJoCo 3.x too)");
          continue;
        }
        std::string why;
        auto r = TargetRange(*a, &why);
        if (!r) {
          Note("position.refused", *a, Tag(*a) + " " + why);
          continue;
        }
        const double mid = ((*r)[0] + (*r)[1]) / 2, half = ((*r)[1] - (*r)[0]) / 2 * inherit;
        const std::array<double, 2> cr = {mid - half, mid + half};
        a->Set(limited_attr, "true");
        a->SetReals(range_attr, cr);
        Note("position.inheritrange", *a,
             Tag(*a) + " inheritrange=" + FormatReal(inherit) + " -> " + range_attr + "=\"" +
                 FormatReals(cr) + "\" (the target's range scaled about its midpoint)");
      }
      if (kv == 0 && ratio == 0 && tau == 0) continue;
      // Expand into <general> with the 3.x parameters.
      const double kp = ResolveReal(*a, "kp", 1);
      a->Unset("kp");
      Element& g = Retag(*a, "general");
      g.Set("gaintype", "fixed");
      g.Set("biastype", "affine");
      g.SetReals("gainprm", std::array<double, 3>{kp, 0, 0});
      g.SetReals("biasprm", std::array<double, 3>{0, -kp, kv == 0 ? 0 : -kv});
      std::string what = Tag(g) + " (" + (position ? "position" : "intvelocity") +
                         ") written as <general> gainprm=\"" + FormatReal(kp) + "\" biasprm=\"0 " +
                         FormatReal(-kp) + " " + FormatReal(kv == 0 ? 0 : -kv) + "\"";
      const char* rule = "position.shortcut";
      if (position) {
        if (tau > 0) {
          // 3.x filterexact: act += (ctrl - act) (1 - exp(-dt/tau)); 2.2.2's Euler-integrated
          // filter gives act += (ctrl - act) dt/tau', equal for tau' = dt / (1 - exp(-dt/tau)).
          const double tau2 = dt / (1 - std::exp(-dt / tau));
          g.Set("dyntype", "filter");
          g.SetReals("dynprm", std::array<double, 3>{tau2, 0, 0});
          what += " dyntype=\"filter\" dynprm=\"" + FormatReal(tau2) +
                  "\": timeconst=" + FormatReal(tau) +
                  " (filterexact) re-expressed for the model's timestep " + FormatReal(dt);
          if (integrator == "RK4") {
            rule = "position.timeconst.rk4";
            what += "; with the RK4 integrator the filter state differs at O(dt^2)";
          } else {
            what += ", exact while the timestep is unchanged";
          }
        } else {
          g.Set("dyntype", "none");
        }
      } else {
        g.Set("dyntype", "integrator");
        g.SetReals("dynprm", std::array<double, 3>{1, 0, 0});
        if (!Resolve(g, "actlimited")) g.Set("actlimited", "true");
      }
      if (ratio > 0) {
        pending_.push_back({&g, kp, ratio});
        what += "; kv from dampratio=" + FormatReal(ratio) + " is computed below";
      }
      Note(rule, g, what);
    }
    for (Element* d : FindDefaults({"position", "intvelocity", "general", "motor", "velocity",
                                    "cylinder", "muscle", "adhesion", "damper"})) {
      if (DialectSet(*d, "kv") && DialectSet(*d, "dampratio") && d->Has("kv") &&
          d->Has("dampratio")) {
        Note("position.refused", *d,
             "default " + Tag(*d) + " kv and dampratio set together (MuJoCo 3.x refuses this too)");
      }
      std::vector<std::string> gone;
      for (const char* n : {"kv", "dampratio", "timeconst", "inheritrange"}) {
        if (UnsetDialect(*d, n)) gone.push_back(n);
      }
      if (!gone.empty()) {
        Note("position.default", *d,
             "default " + Tag(*d) + " " + Join(gone, "/") +
                 " resolved into each actuator of the class (see their entries)");
      }
    }
  }

  void DampRatio() {
    if (pending_.empty()) return;
    for (PendingDampRatio& p : pending_)
      p.actuator->SetReals("biasprm", std::array<double, 3>{0, -p.kp, 0});
    std::string error;
    mjModel* m = TrialCompile(WriteString(doc_), &error);
    if (!m) {
      for (PendingDampRatio& p : pending_) {
        Note("position.dampratio.refused", *p.actuator,
             Tag(*p.actuator) + " dampratio needs the compiled model, which failed: " + error);
      }
      return;
    }
    mjData* d = mj_makeData(m);
    mj_forward(m, d);                   // qpos = qpos0
    std::vector<const Element*> order;  // actuators in compiled order
    doc_.root().Visit([&](const Element& e) {
      if (e.parent() && e.parent()->tag() == "actuator" && IsActuatorTag(e.tag())) {
        order.push_back(&e);
      }
    });
    for (int index = 0; index < static_cast<int>(order.size()) && index < m->nu; ++index) {
      for (PendingDampRatio& p : pending_) {
        if (p.actuator != order[static_cast<size_t>(index)]) continue;
        double mass = 0;
        for (int j = 0; j < m->nv; ++j) {
          const double moment = d->actuator_moment[index * m->nv + j];
          if (moment != 0) mass += m->dof_M0[j] / (moment * moment);
        }
        const double kv = p.ratio * 2 * std::sqrt(p.kp * mass);
        p.actuator->SetReals("biasprm", std::array<double, 3>{0, -p.kp, -kv});
        Note("position.dampratio", *p.actuator,
             Tag(*p.actuator) + " dampratio=" + FormatReal(p.ratio) + " -> kv=" + FormatReal(kv) +
                 " = dampratio * 2 sqrt(kp * m), m = " + FormatReal(mass) +
                 " the transmission's inertia at qpos0 (dof_M0 / moment^2), as MuJoCo 3.x "
                 "computes it");
      }
    }
    mj_deleteData(d);
    mj_deleteModel(m);
  }

  // ---- option, flags, size ----
  void Options() {
    for (Element* o : Find({"option"})) {
      struct Rule {
        const char* attr;
        const char* rule;
        const char* why;
      };
      static const Rule kRules[] = {
          {"ls_iterations", "option.approximated",
           "line-search iterations of the 3.x CG/Newton solvers; 2.2.2's line search is fixed"},
          {"ls_tolerance", "option.approximated",
           "line-search tolerance of the 3.x CG/Newton solvers; 2.2.2's line search is fixed"},
          {"sdf_initpoints", "option.dropped", "SDF collision (plugins) does not exist in 2.2.2"},
          {"sdf_iterations", "option.dropped", "SDF collision (plugins) does not exist in 2.2.2"},
          {"sleep_tolerance", "option.dropped", "island sleeping does not exist in 2.2.2"},
      };
      for (const Rule& r : kRules) {
        if (const std::string* v = o->Get(r.attr)) {
          Note(r.rule, *o, std::string("option ") + r.attr + "=\"" + *v + "\" dropped: " + r.why);
          o->Unset(r.attr);
        }
      }
      for (const char* n : {"ccd_iterations", "ccd_tolerance"}) {
        if (const std::string* v = o->Get(n)) {
          const std::string mpr = std::string("mpr_") + (n + 4);
          if (!o->Has(mpr)) o->Set(mpr, *v);
          Note("option.ccd", *o,
               std::string("option ") + n + " -> " + mpr +
                   " (2.2.2 uses libccd's MPR; 3.x's native convex collider differs slightly)");
          o->Unset(n);
        }
      }
      if (const std::string* v = o->Get("actuatorgroupdisable")) {
        // A list of group numbers (not a mask): "0" disables group 0, every actuator's default.
        const std::string text = *v;
        const std::vector<double> groups = ParseReals(text).value_or(std::vector<double>{});
        std::vector<std::string> hit;
        for (Element* a : Find({"general", "motor", "position", "velocity", "cylinder", "muscle",
                                "adhesion", "intvelocity", "damper"})) {
          if (!a->parent() || a->parent()->tag() != "actuator") continue;
          const double g = ResolveReal(*a, "group", 0);
          if (std::find(groups.begin(), groups.end(), g) != groups.end()) {
            hit.push_back(a->Name().empty() ? Tag(*a) : a->Name());
          }
        }
        if (hit.empty()) {
          Note("option.actuatorgroupdisable", *o,
               "option actuatorgroupdisable=\"" + text + "\": no actuator is in these groups");
        } else {
          Note("option.actuatorgroupdisable.refused", *o,
               "option actuatorgroupdisable=\"" + text + "\" disables actuator group(s) of " +
                   Join(hit, ", ") + ", which 2.2.2 cannot do");
        }
        o->Unset("actuatorgroupdisable");
      }
      if (const std::string* v = o->Get("o_friction")) {
        const bool override_on =
            o->FirstChild("flag") && o->FirstChild("flag")->GetOr("override", "") == "enable";
        if (override_on) {
          Note("option.o_friction.refused", *o,
               "option o_friction with the override flag: 2.2.2's override has no 5-number "
               "friction");
        } else {
          Note("option.o_friction", *o,
               "option o_friction=\"" + *v + "\" only applies with the override flag: no effect");
        }
        o->Unset("o_friction");
      }
      if (o->GetOr("integrator", "") == "implicitfast") {
        o->Set("integrator", "implicit");
        Note("option.implicitfast", *o,
             "option integrator=\"implicitfast\" -> \"implicit\" (2.2.2's implicit integrator "
             "also treats damping and actuator velocity terms implicitly; implicitfast skips the "
             "Coriolis and centripetal derivatives that 3.x's implicit includes)");
      }
      if (Element* f = o->FirstChild("flag")) Flags(*f);
    }
    for (Element* s : Find({"size"})) {
      if (const std::string* v = s->Get("memory")) {
        const std::string text = *v;
        double bytes = std::atof(text.c_str());
        const char unit = text.empty() ? ' ' : text.back();
        if (unit == 'K' || unit == 'k') bytes *= 1024;
        if (unit == 'M' || unit == 'm') bytes *= 1024 * 1024;
        if (unit == 'G' || unit == 'g') bytes *= 1024.0 * 1024 * 1024;
        s->Unset("memory");
        if (!s->Has("nstack") && bytes > 0) {
          s->SetInt("nstack", static_cast<int>(std::min(bytes / 8, 2e9)));
        }
        Note("size.memory", *s,
             "size memory=\"" + text +
                 "\" -> nstack (2.2.2 sizes its arena in mjtNums; "
                 "njmax/nconmax keep their 2.2.2 defaults)");
      }
    }
  }

  void Flags(Element& f) {
    const std::string* spring = f.Get("spring");
    const std::string* damper = f.Get("damper");
    if (spring || damper) {
      const std::string s = spring ? *spring : "enable", d = damper ? *damper : "enable";
      if (s == d) {
        f.Set("passive", s);
        Note("flag.spring_damper", f,
             "flag spring/damper=\"" + s + "\" -> 2.2.2's single passive=\"" + s + "\"");
      } else {
        // One of the two is off: passive stays on and the disabled forces are zeroed in the
        // model (PassiveFlags, after every translation that sets stiffness or damping).
        springs_off_ = s == "disable";
        dampers_off_ = d == "disable";
        Note("flag.spring_damper.split", f,
             "flag spring=\"" + s + "\" damper=\"" + d +
                 "\": 2.2.2 can only switch both (flag passive), so passive stays enabled and "
                 "every joint and tendon gets " +
                 (springs_off_ ? "stiffness" : "damping") +
                 " 0 instead; exact while the flags are not changed at run time");
      }
      f.Unset("spring");
      f.Unset("damper");
    }
    struct Rule {
      const char* attr;
      const char* dflt;  // 3.x default; other values are noted as approximated
      const char* why;
    };
    static const Rule kRules[] = {
        {"autoreset", "enable", "the runtime handles divergence itself"},
        {"diagexact", "enable", "3.x diagonal approximation setting; 2.2.2 uses its own"},
        {"eulerdamp", "enable", "2.2.2's Euler integrator always integrates damping implicitly"},
        {"invdiscrete", "disable", "discrete-time inverse dynamics is not used by the runtime"},
        {"island", "disable", "constraint islands are a 3.x solver optimisation"},
        {"midphase", "enable", "the BVH midphase is a 3.x collision optimisation"},
        {"nativeccd", "enable", "2.2.2 always uses libccd's MPR for convex collisions"},
        {"sleep", "disable", "island sleeping does not exist in 2.2.2"},
    };
    for (const Rule& r : kRules) {
      if (const std::string* v = f.Get(r.attr)) {
        const bool is_default = *v == r.dflt;
        Note(is_default ? "flag.default" : "flag.other", f,
             std::string("flag ") + r.attr + "=\"" + *v + "\" dropped: " + r.why);
        f.Unset(r.attr);
      }
    }
  }

  // ---- general dyntype="filterexact" ----
  // As position timeconst: 3.x's filterexact act += (ctrl - act)(1 - exp(-dt/tau)) is 2.2.2's
  // Euler-integrated filter with tau' = dt / (1 - exp(-dt/tau)).
  void FilterExact() {
    const double dt = ResolveTimestep();
    const bool rk4 = Integrator() == "RK4";
    for (Element* a : Find({"general"})) {
      if (!a->parent() || a->parent()->tag() != "actuator") continue;
      const std::string* t = Resolve(*a, "dyntype");
      if (!t || *t != "filterexact") continue;
      std::vector<double> prm = ResolveReals(*a, "dynprm").value_or(std::vector<double>{1});
      if (prm.empty() || prm[0] <= 0) {
        Note("actuator.filterexact.refused", *a, Tag(*a) + " filterexact needs dynprm[0] > 0");
        continue;
      }
      const double tau = prm[0];
      prm[0] = dt / (1 - std::exp(-dt / tau));
      a->Set("dyntype", "filter");
      a->SetReals("dynprm", prm);
      Note(rk4 ? "actuator.filterexact.rk4" : "actuator.filterexact", *a,
           Tag(*a) + " dyntype=\"filterexact\" dynprm[0]=" + FormatReal(tau) +
               " -> dyntype=\"filter\" dynprm[0]=" + FormatReal(prm[0]) +
               " (the same update per step for the model's timestep " + FormatReal(dt) + ")" +
               (rk4 ? "; with RK4 the filter state differs at O(dt^2)"
                    : ", exact while the timestep is unchanged"));
    }
    for (Element* d : FindDefaults({"general"})) {
      if (d->GetOr("dyntype", "") == "filterexact") {
        d->Set("dyntype", "filter");
        Note("actuator.filterexact.default", *d,
             "default " + Tag(*d) + " dyntype=\"filterexact\" resolved into each actuator");
      }
    }
  }
  double ResolveTimestep() {
    const Element* o = doc_.root().FirstChild("option");
    return o ? std::atof(o->GetOr("timestep", "0.002").c_str()) : 0.002;
  }
  std::string Integrator() {
    const Element* o = doc_.root().FirstChild("option");
    return o ? o->GetOr("integrator", "Euler") : "Euler";
  }

  // ---- equality polycoef with fewer than 5 numbers ----
  void PolyCoef() {
    for (Element* e : Find({"joint", "tendon"})) {
      if (!e->parent() || e->parent()->tag() != "equality") continue;
      const std::string* v = e->Get("polycoef");
      if (!v) continue;
      std::vector<double> c = ParseReals(*v).value_or(std::vector<double>{});
      if (c.size() >= 5 || c.empty()) continue;
      const double defaults[5] = {0, 1, 0, 0, 0};
      const std::string before = *v;
      for (size_t i = c.size(); i < 5; ++i) c.push_back(defaults[i]);
      e->SetReals("polycoef", c);
      Note("equality.polycoef", *e,
           Tag(*e) + " polycoef=\"" + before + "\" -> \"" + FormatReals(c) +
               "\" (3.x fills the missing coefficients with the defaults 0 1 0 0 0)");
    }
  }

  // ---- tendon springlength with two numbers (a dead band) ----
  void SpringLength() {
    for (Element* t : Find({"fixed", "spatial"})) {
      auto sl = ResolveReals(*t, "springlength");
      if (!sl || sl->size() != 2) continue;
      const double lo = (*sl)[0], hi = (*sl)[1];
      const double k = ResolveReal(*t, "stiffness", 0);
      const std::string desc = Tag(*t) + " springlength=\"" + FormatReals(*sl) + "\"";
      if (lo == hi) {
        t->SetReal("springlength", lo);
        Note("tendon.springlength.single", *t, desc + " -> one value (no dead band)");
        continue;
      }
      if (lo > hi) {
        Note("tendon.springlength.refused", *t, desc + ": the lower bound exceeds the upper");
        continue;
      }
      t->SetReal("springlength", lo);
      if (k == 0) {
        Note("tendon.springlength.nostiffness", *t, desc + ": no stiffness, no spring force");
        continue;
      }
      std::string name = t->Name();
      if (name.empty()) {
        name = "deadband_tendon" + std::to_string(report_.deadband_springs.size());
        t->Set("name", name);
      }
      t->SetReal("stiffness", 0);
      report_.deadband_springs.push_back({name, k, lo, hi});
      Note("tendon.springlength.deadband", *t,
           desc + " (a dead band) with stiffness " + FormatReal(k) +
               ": the tendon gets stiffness 0 and the runtime adds stiffness * (bound - length) "
               "outside [" +
               FormatReal(lo) + ", " + FormatReal(hi) +
               "] through mjcb_passive, as MuJoCo 3.x does");
    }
    for (Element* d : FindDefaults({"tendon"})) {
      auto sl = d->GetReals("springlength");
      if (sl && sl->size() == 2) {
        d->SetReal("springlength", (*sl)[0]);
        Note("tendon.springlength.default", *d,
             "default " + Tag(*d) + " springlength resolved into each tendon");
      }
    }
  }

  // ---- flag spring or damper disabled alone ----
  void PassiveFlags() {
    if (!springs_off_ && !dampers_off_) return;
    const char* attr = springs_off_ ? "stiffness" : "damping";
    int n = 0;
    for (Element* e : Find({"joint", "fixed", "spatial"})) {
      if (e->tag() == "joint" && (!e->parent() || e->parent()->tag() != "body")) continue;
      if (ResolveReal(*e, attr, 0) == 0) continue;
      e->SetReal(attr, 0);
      ++n;
    }
    if (springs_off_ && !report_.deadband_springs.empty()) {
      n += static_cast<int>(report_.deadband_springs.size());
      report_.deadband_springs.clear();
    }
    Element* f = doc_.root().FirstChild("option");
    Note("flag.spring_damper.split", f ? *f : doc_.root(),
         std::string(attr) + " set to 0 on " + std::to_string(n) + " joint(s)/tendon(s) (flag " +
             (springs_off_ ? "spring" : "damper") + " disabled)");
  }

  // ---- compiler discardvisual ----
  // 3.x computes body masses and inertias with the visual geoms, then discards them (and keeps
  // those a <pair> uses); 2.2.2 discards them first, so the bodies lose their mass, and fails on
  // a <pair> naming one. Keeping every geom gives 3.x's physics: visual geoms (contype =
  // conaffinity = 0) do not collide; only the model's geom (and mesh) counts are larger.
  // Visual-only geoms (contype = conaffinity = 0) that a <pair> uses, under discardvisual.
  std::vector<Element*> VisualPairGeoms() {
    std::vector<Element*> out;
    if (!DiscardVisual()) return out;
    std::set<std::string> paired;
    for (Element* p : Find({"pair"})) {
      for (const char* a : {"geom1", "geom2"}) {
        if (const std::string* g = p->Get(a)) paired.insert(*g);
      }
    }
    for (Element* g : Find({"geom"})) {
      if (paired.count(g->Name()) && ResolveReal(*g, "contype", 1) == 0 &&
          ResolveReal(*g, "conaffinity", 1) == 0) {
        out.push_back(g);
      }
    }
    return out;
  }
  bool DiscardVisual() {
    for (const auto& c : doc_.root().children()) {
      if (c->tag() == "compiler" && c->GetOr("discardvisual", "") == "true") return true;
    }
    return false;
  }

  void KeepVisualGeoms() {
    for (const auto& c : doc_.root().children()) {
      if (c->tag() != "compiler" || c->GetOr("discardvisual", "") != "true") continue;
      c->Set("discardvisual", "false");
      Note("compiler.discardvisual", *c,
           "compiler discardvisual=\"true\" -> \"false\": MuJoCo 3.x weighs bodies with their "
           "visual geoms before discarding them (and keeps those contact pairs use), 2.2.2 "
           "discards them first; keeping them gives 3.x's masses and contacts, with more geoms "
           "in the model (visual geoms do not collide)");
    }
  }

  // ---- render-only elements of 3.x ----
  void VisualOnly() {
    for (Element* l : Find({"layer"})) {
      if (!l->parent() || l->parent()->tag() != "material") continue;
      Note("material.layer", *l,
           "<material><layer> (physically based texture layer) dropped: render-only");
      l->parent()->RemoveChild(l);
    }
  }

  // ---- keyframes shorter than the model ----
  // 3.x pads a key's qpos with qpos0, qvel/act/ctrl with zeros, mpos/mquat with the mocap bodies'
  // poses; 2.2.2 refuses a key of the wrong length. The padding needs the compiled sizes and
  // qpos0: a trial compile without the keys.
  // Whether every key already has the document's sizes, counted from its joints and actuators
  // (no trial compile needed). False when unsure (composites, mocap or act values).
  bool KeysFitTheDocument(const Element& section) {
    int nq = 0, nv = 0, nu = 0;
    bool unsure = false;
    doc_.root().Visit([&](const Element& e) {
      if (InDefault(e)) return;
      if (e.tag() == "composite") unsure = true;
      if (e.tag() == "freejoint") {
        nq += 7;
        nv += 6;
      } else if (e.tag() == "joint" && e.parent() && e.parent()->tag() == "body") {
        const std::string* t = Resolve(e, "type");
        const std::string type = t ? *t : "hinge";
        nq += type == "free" ? 7 : type == "ball" ? 4 : 1;
        nv += type == "free" ? 6 : type == "ball" ? 3 : 1;
      } else if (IsActuatorTag(e.tag()) && e.parent() && e.parent()->tag() == "actuator") {
        ++nu;
      }
    });
    if (unsure) return false;
    for (const auto& k : section.children()) {
      if (k->Has("act") || k->Has("mpos") || k->Has("mquat")) return false;
      auto count = [&](const char* a) {
        const std::string* v = k->Get(a);
        return v ? static_cast<int>(ParseReals(*v).value_or(std::vector<double>{}).size()) : -1;
      };
      const int q = count("qpos"), v = count("qvel"), c = count("ctrl");
      if ((q >= 0 && q != nq) || (v >= 0 && v != nv) || (c >= 0 && c != nu)) return false;
    }
    return true;
  }

  // An attached model's keyframe (bridge_attach.h) as a key of the whole model: qpos0, zero
  // velocities, controls and activations, mocap bodies at their poses, then the child's values
  // at its elements' addresses.
  void WriteAttachedKey(const mjModel* m, const AttachedKey& k) {
    std::vector<double> qpos(m->qpos0, m->qpos0 + m->nq), qvel(static_cast<size_t>(m->nv));
    std::vector<double> ctrl(static_cast<size_t>(m->nu)), act(static_cast<size_t>(m->na));
    std::vector<double> mpos(static_cast<size_t>(3 * m->nmocap));
    std::vector<double> mquat(static_cast<size_t>(4 * m->nmocap));
    for (int b = 0; b < m->nbody; ++b) {
      if (const int id = m->body_mocapid[b]; id >= 0) {
        std::copy_n(m->body_pos + 3 * b, 3, mpos.begin() + 3 * id);
        std::copy_n(m->body_quat + 4 * b, 4, mquat.begin() + 4 * id);
      }
    }
    auto place = [&](mjtObj type, const auto& values, auto address, std::vector<double>& into) {
      for (const auto& [name, v] : values) {
        const int id = mj_name2id(m, type, name.c_str());
        const int at = id < 0 ? -1 : address(id);
        if (at < 0) continue;  // not attached (outside the subtree, or stayed in the child)
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, double>) {
          into[static_cast<size_t>(at)] = v;
        } else {
          std::copy(v.begin(), v.end(), into.begin() + at);
        }
      }
    };
    place(
        mjOBJ_JOINT, k.qpos, [&](int j) { return m->jnt_qposadr[j]; }, qpos);
    place(
        mjOBJ_JOINT, k.qvel, [&](int j) { return m->jnt_dofadr[j]; }, qvel);
    place(
        mjOBJ_ACTUATOR, k.ctrl, [](int a) { return a; }, ctrl);
    place(
        mjOBJ_ACTUATOR, k.act,
        [&](int a) { return m->actuator_dyntype[a] == mjDYN_NONE ? -1 : a - (m->nu - m->na); },
        act);
    place(
        mjOBJ_BODY, k.mpos, [&](int b) { return 3 * m->body_mocapid[b]; }, mpos);
    place(
        mjOBJ_BODY, k.mquat, [&](int b) { return 4 * m->body_mocapid[b]; }, mquat);
    if (k.time != 0) k.key->SetReals("time", std::vector<double>{k.time});
    k.key->SetReals("qpos", qpos);
    if (m->nv) k.key->SetReals("qvel", qvel);
    if (m->nu) k.key->SetReals("ctrl", ctrl);
    if (m->na) k.key->SetReals("act", act);
    if (m->nmocap) {
      k.key->SetReals("mpos", mpos);
      k.key->SetReals("mquat", mquat);
    }
  }

  void PadKeyframes() {
    Element* section = nullptr;
    for (Element* k : Find({"keyframe"})) section = k;
    if (!section || section->children().empty()) return;
    if (attached_keys_.empty() && KeysFitTheDocument(*section)) return;
    std::unique_ptr<Element> keys = doc_.root().RemoveChild(section);
    std::string error;
    mjModel* m = TrialCompile(WriteString(doc_), &error);
    doc_.root().InsertChild(doc_.root().children().size(), std::move(keys));
    if (!m) return;  // the real compile reports it
    for (const AttachedKey& k : attached_keys_) WriteAttachedKey(m, k);
    for (const auto& k : section->children()) {
      std::vector<std::string> padded;
      auto pad = [&](const char* attr, int size, const mjtNum* fill) {
        const std::string* v = k->Get(attr);
        if (!v) return;
        std::vector<double> x = ParseReals(*v).value_or(std::vector<double>{});
        if (static_cast<int>(x.size()) >= size) return;
        const size_t had = x.size();
        for (int i = static_cast<int>(had); i < size; ++i) x.push_back(fill ? fill[i] : 0.0);
        k->SetReals(attr, x);
        padded.push_back(std::string(attr) + " " + std::to_string(had) + " -> " +
                         std::to_string(size));
      };
      std::vector<mjtNum> mpos, mquat;
      for (int b = 0; b < m->nbody; ++b) {
        if (m->body_mocapid[b] < 0) continue;
        mpos.insert(mpos.end(), m->body_pos + 3 * b, m->body_pos + 3 * b + 3);
        mquat.insert(mquat.end(), m->body_quat + 4 * b, m->body_quat + 4 * b + 4);
      }
      pad("qpos", m->nq, m->qpos0);
      pad("qvel", m->nv, nullptr);
      pad("act", m->na, nullptr);
      pad("ctrl", m->nu, nullptr);
      pad("mpos", 3 * m->nmocap, mpos.data());
      pad("mquat", 4 * m->nmocap, mquat.data());
      if (!padded.empty()) {
        Note("keyframe.pad", *k,
             Tag(*k) +
                 " shorter than the model, padded as MuJoCo 3.x does (qpos with qpos0, "
                 "mocap with the bodies' poses, the rest with zeros): " +
                 Join(padded, ", "));
      }
    }
    mj_deleteModel(m);
  }

  // ---- mesh inertia ----
  // MuJoCo 3.x (since 3.0.1) takes a mesh's mass from its volume; 2.2.2's default
  // (exactmeshinertia false) from the volume of the mesh's equivalent inertia box, which differs
  // even for a convex mesh (a wedge weighs 2/sqrt(3) of its mass). 3.x's per-mesh modes: legacy
  // (the default; tetrahedra from the mesh centre: exact for convex meshes, overcounts others),
  // convex (the hull), exact, shell. 2.2.2's exactmeshinertia="true" is the exact volume: equal
  // to all of them for convex meshes, and to "exact" always.
  void MeshInertia() {
    std::vector<Element*> meshes = Find({"mesh"});
    int maybe_nonconvex = 0;  // legacy/convex meshes read from files (inline vertices: a hull)
    for (Element* m : meshes) {
      const std::string* v = Resolve(*m, "inertia");
      const std::string mode = v ? *v : "legacy";
      if (mode == "shell") {
        Note("mesh.shell", *m,
             Tag(*m) +
                 " inertia=\"shell\": set shellinertia on the geoms that use this mesh "
                 "instead (the bridge does not know which bodies infer inertia)");
      } else if (mode != "exact" && m->Has("file")) {
        ++maybe_nonconvex;
      }
      if (m->Get("inertia")) {
        Note("mesh.inertia", *m,
             Tag(*m) + " inertia=\"" + mode + "\": see the compiler's exactmeshinertia entry");
        m->Unset("inertia");
      }
    }
    for (Element* d : FindDefaults({"mesh"})) {
      if (d->Unset("inertia")) {
        Note("mesh.inertia", *d, "default " + Tag(*d) + " inertia resolved into each mesh");
      }
    }
    if (meshes.empty()) return;
    std::string before;
    bool set = false;
    for (const auto& c : doc_.root().children()) {
      if (c->tag() != "compiler" || !c->Has("exactmeshinertia")) continue;
      before = *c->Get("exactmeshinertia");
      c->Set("exactmeshinertia", "true");
      set = true;
    }
    if (!set) FirstCompiler().Set("exactmeshinertia", "true");
    if (before == "true") return;
    std::string what =
        "compiler exactmeshinertia=\"true\" written" +
        (before.empty() ? std::string() : " (was \"" + before + "\", 3.0-3.1's legacy volume)") +
        ": MuJoCo 3.x computes mesh masses from the mesh volume, 2.2.2's default from its "
        "inertia box";
    if (maybe_nonconvex == 0) {
      Note("mesh.exactmeshinertia", *doc_.root().FirstChild("compiler"), what);
    } else {
      Note("mesh.exactmeshinertia.nonconvex", *doc_.root().FirstChild("compiler"),
           what + "; exact for convex meshes, but " + std::to_string(maybe_nonconvex) +
               " mesh file(s) with inertia legacy/convex may be non-convex, where 3.x's legacy "
               "algorithm overcounts the volume (convex: takes the hull's) and 2.2.2's exact one "
               "does not");
    }
  }

  // ---- remaining 3.x attributes: drop what has no effect, approximate, refuse ----
  void GenericAttributes() {
    doc_.root().Visit([&](Element& e) {
      std::vector<std::string> names;
      for (const Attribute& a : e.attributes()) {
        if (IsDialect(a)) names.push_back(a.name);
      }
      for (const std::string& n : names) GenericAttribute(e, n);
    });
  }

  // Whether an attribute policy's `elements` list covers `e`.
  static bool PolicyCovers(const AttributePolicy& p, const Element& e) {
    for (std::string_view tag : Words(p.elements)) {
      if (tag == "<sensor>" && e.parent() && e.parent()->tag() == "sensor") return true;
      if (tag == "<actuator>" && IsActuatorTag(e.tag())) return true;
      if (tag == e.tag()) return true;
    }
    return false;
  }
  static std::vector<std::string_view> Words(std::string_view s) {
    std::vector<std::string_view> out;
    while (!s.empty()) {
      const size_t b = s.find_first_not_of(" |");
      if (b == std::string_view::npos) break;
      s.remove_prefix(b);
      const size_t n = s.find_first_of(" |");
      out.push_back(s.substr(0, n));
      s.remove_prefix(n == std::string_view::npos ? s.size() : n);
    }
    return out;
  }

  // A 3.x attribute no translation function consumed: the first attribute policy (bridge_rules.cc)
  // covering it decides; the handful that compute something have their own functions.
  void GenericAttribute(Element& e, const std::string& n) {
    if (!e.Has(n)) return;  // handled together with an earlier attribute
    const std::string value = *e.Get(n);
    const std::string& t = e.tag();
    if (t == "light" && n == "type" && value == "directional") return LightType(e);
    if (t == "camera" && (n == "sensorsize" || n == "focal" || n == "focalpixel" ||
                          n == "resolution" || n == "principal" || n == "principalpixel")) {
      return CameraIntrinsics(e);
    }
    const std::string desc =
        (InDefault(e) ? "default " : "") + Tag(e) + " " + n + "=\"" + value + "\"";
    for (const AttributePolicy& p : AttributePolicies()) {
      if (!PolicyCovers(p, e)) continue;
      const std::vector<std::string_view> attrs = Words(p.attributes);
      if (std::find(attrs.begin(), attrs.end(), n) == attrs.end() &&
          std::find(attrs.begin(), attrs.end(), "*") == attrs.end()) {
        continue;
      }
      bool first = true;
      if (p.condition == AttributeCondition::kZero) {
        first = AllZero(ParseReals(value).value_or(std::vector<double>{1}));
      } else if (p.condition == AttributeCondition::kValueIn) {
        const std::vector<std::string_view> values = Words(p.values);
        first = std::find(values.begin(), values.end(), value) != values.end();
      }
      const char* rule = first ? p.rule_if : p.rule_else;
      const char* why = first ? p.why_if : p.why_else;
      const bool refused = FindBridgeRule(rule).kind == Kind::kRefused;
      Note(rule, e, desc + (refused ? ": " : " dropped: ") + why);
      e.Unset(n);
      return;
    }
    // Everything else is left for Leftovers() to refuse.
  }

  void LightType(Element& e) {
    e.Set("directional", "true");
    Note("light.directional", e,
         (InDefault(e) ? "default " : "") + Tag(e) +
             " type=\"directional\" -> directional=\"true\"");
    e.Unset("type");
  }

  void CameraIntrinsics(Element& c) {
    auto reals = [&](const char* n) { return ResolveReals(c, n); };
    auto ss = reals("sensorsize");
    auto focal = reals("focal");
    auto focalpixel = reals("focalpixel");
    auto res = reals("resolution");
    std::string what = Tag(c) + " sensorsize/focal/resolution/principal";
    if (ss && ss->size() == 2 && (*ss)[1] > 0) {
      double fy = 0;
      if (focal && focal->size() == 2) fy = (*focal)[1];
      if (focalpixel && focalpixel->size() == 2 && res && res->size() == 2 && (*res)[1] > 0) {
        fy = (*focalpixel)[1] * (*ss)[1] / (*res)[1];
      }
      if (fy > 0) {
        const double fovy = 2 * std::atan((*ss)[1] / (2 * fy)) * 180 / kPi;
        c.SetReal("fovy", fovy);
        what += " -> fovy=" + FormatReal(fovy) + " (vertical field of view, as 3.x computes it)";
      }
    }
    const bool principal = c.Has("principal") || c.Has("principalpixel");
    for (const char* n :
         {"sensorsize", "focal", "focalpixel", "resolution", "principal", "principalpixel"}) {
      c.Unset(n);
    }
    Note(principal ? "camera.principal" : "camera.intrinsics", c,
         what + (principal ? "; the principal point offset is dropped (render-only)" : ""));
  }

  // ---- sensors ----
  void Sensors() {
    for (Element* s : Find({"jointactuatorfrc", "tendonactuatorfrc"})) {
      const bool joint = s->tag() == "jointactuatorfrc";
      const std::string* target = s->Get(joint ? "joint" : "tendon");
      if (!target) {
        Note("sensor.refused", *s, Tag(*s) + " needs a " + (joint ? "joint" : "tendon"));
        continue;
      }
      const std::string tname = *target;
      std::string name = s->Name();
      if (name.empty()) {
        name = s->tag() + "_" + tname;
        Note("sensor.unnamed", *s, Tag(*s) + " is unnamed; named '" + name + "'");
      }
      Element& u = Retag(*s, "user");
      u.Unset(joint ? "joint" : "tendon");
      u.Set("name", name);
      u.Set("objtype", joint ? "joint" : "tendon");
      u.Set("objname", tname);
      u.Set("datatype", "real");
      u.Set("needstage", "acc");
      u.Set("dim", "1");
      report_.software_sensors.push_back({name,
                                          joint ? BridgedSensor::Kind::kJointActuatorForce
                                                : BridgedSensor::Kind::kTendonActuatorForce,
                                          tname});
      Note("sensor.actuatorfrc", u,
           "<" + std::string(joint ? "jointactuatorfrc" : "tendonactuatorfrc") + " name='" + name +
               "'> -> <user> sensor of the same name, computed by the runtime from " +
               (joint ? "qfrc_actuator at the joint's dof"
                      : "the actuator forces of the tendon's actuators"));
    }
  }

  // 3.x sensors the runtime computes from 2.2.2's mjData (physics/software_sensors.h): energies,
  // insidesite and contact, as <user> sensors with the 3.x layout and stage.
  void ComputedSensors() {
    int unnamed = 0;
    for (Element* s : Find({"e_kinetic", "e_potential", "insidesite", "contact"})) {
      if (!s->parent() || s->parent()->tag() != "sensor") continue;
      const std::string tag = s->tag();
      std::map<std::string, std::string> params;
      for (const char* a : {"site", "objtype", "objname", "geom1", "geom2", "body1", "body2",
                            "subtree1", "subtree2", "num", "data", "reduce"}) {
        if (const std::string* v = s->Get(a)) params[a] = *v;
      }
      int dim = 1;
      const std::string stage = tag == "e_kinetic" ? "vel" : tag == "contact" ? "acc" : "pos";
      const BridgedSensor::Kind kind = tag == "e_kinetic" ? BridgedSensor::Kind::kKineticEnergy
                                       : tag == "e_potential"
                                           ? BridgedSensor::Kind::kPotentialEnergy
                                       : tag == "insidesite" ? BridgedSensor::Kind::kInsideSite
                                                             : BridgedSensor::Kind::kContact;
      if (tag == "insidesite" &&
          (!params.count("site") || !params.count("objtype") || !params.count("objname"))) {
        Note("sensor.refused", *s, Tag(*s) + " needs site, objtype and objname (3.x too)");
        continue;
      }
      if (tag == "contact") {
        if (params.count("reduce") && params["reduce"] == "netforce") {
          Note("sensor.contact.netforce", *s,
               Tag(*s) +
                   " reduce=\"netforce\" (the net wrench of all matched contacts about their "
                   "centroid) is not computed by the runtime; nearest: reduce=\"maxforce\"");
          continue;
        }
        static const std::pair<const char*, int> kFields[] = {
            {"found", 1}, {"force", 3},  {"torque", 3}, {"dist", 1},
            {"pos", 3},   {"normal", 3}, {"tangent", 3}};
        int slot = 0, last = -1;
        bool bad = false;
        std::istringstream words(params.count("data") ? params["data"] : "found");
        for (std::string w; words >> w;) {
          int i = 0;
          while (i < 7 && w != kFields[i].first) ++i;
          bad = bad || i == 7 || i <= last;
          if (i < 7) slot += kFields[i].second;
          last = i;
        }
        const int num = params.count("num") ? std::atoi(params["num"].c_str()) : 1;
        if (bad || num < 1) {
          Note("sensor.refused", *s,
               Tag(*s) +
                   " data/num invalid (3.x refuses it too: fields are found force torque "
                   "dist pos normal tangent, in that order; num >= 1)");
          continue;
        }
        dim = num * slot;
      }
      std::string name = s->Name();
      if (name.empty()) name = tag + "_sensor" + std::to_string(unnamed++);
      Element& u = Retag(*s, "user");
      for (const auto& kv : params) u.Unset(kv.first);
      u.Set("name", name);
      // 2.2.2 requires an object: the site for insidesite, otherwise the world body.
      u.Set("objtype", tag == "insidesite" ? "site" : "body");
      u.Set("objname", tag == "insidesite" ? params["site"] : "world");
      u.Set("datatype", "real");
      u.Set("needstage", stage);
      u.SetInt("dim", dim);
      report_.software_sensors.push_back({name, kind, "", params});
      Note("sensor.computed", u,
           "<" + tag + " name='" + name + "'> -> <user> sensor of the same name (dim " +
               std::to_string(dim) + ", stage " + stage +
               ") computed by the runtime through mjcb_sensor with the 3.x layout");
    }
  }

  // ---- actuator order: 2.2.2 wants stateless actuators before stateful ones ----
  bool Stateful(const Element& a) {
    const std::string& t = a.tag();
    if (t == "intvelocity" || t == "muscle") return true;
    if (t == "general") {
      const std::string* d = Resolve(a, "dyntype");
      return d && *d != "none";
    }
    if (t == "cylinder") return ResolveReal(a, "timeconst", 1) > 0;
    return false;
  }

  void OrderActuators() {
    for (Element* section : Find({"actuator"})) {
      std::vector<Element*> stateless, stateful;
      bool out_of_order = false;
      for (const auto& c : section->children()) {
        if (!IsActuatorTag(c->tag())) continue;
        if (Stateful(*c)) {
          stateful.push_back(c.get());
        } else {
          out_of_order = out_of_order || !stateful.empty();
          stateless.push_back(c.get());
        }
      }
      if (!out_of_order) continue;
      std::vector<std::unique_ptr<Element>> moved;
      for (Element* a : stateful) moved.push_back(section->RemoveChild(a));
      for (auto& a : moved) section->InsertChild(section->children().size(), std::move(a));
      std::vector<std::string> names;
      for (Element* a : stateful) names.push_back(a->Name().empty() ? Tag(*a) : a->Name());
      Note("actuator.order", *section,
           "stateful actuators moved after the stateless ones, as MuJoCo 2.2.2 requires (" +
               Join(names, ", ") +
               "): same physics, but ctrl/act indices follow the new order; address actuators "
               "by name");
    }
  }

  // ---- anything 3.x that is still there cannot be expressed ----
  void Leftovers() {
    for (Element* g : Find({"geom"})) {
      if (g->GetOr("type", "") == "sdf") {
        Note("refused.sdf", *g,
             Tag(*g) +
                 " type=\"sdf\": signed-distance-field geoms need engine plugins, which "
                 "MuJoCo 2.2.2 cannot load; nearest 2.2.2 construct: type=\"mesh\" (its "
                 "convex hull collides)");
        g->Set("type", "sphere");  // keeps the document writable for --bridge-report
      }
    }
    std::vector<Element*> elements;
    doc_.root().Visit([&](Element& e) {
      if (e.spec() && e.spec()->dialect) {
        elements.push_back(&e);
        return;
      }
      std::vector<std::string> names;
      for (const Attribute& a : e.attributes()) {
        if (IsDialect(a)) names.push_back(a.name);
      }
      for (const std::string& n : names) {
        Note("leftover", e,
             (InDefault(e) ? "default " : "") + Tag(e) + " attribute " + n + "=\"" + *e.Get(n) +
                 "\" (MuJoCo 3.x) has no MuJoCo 2.2.2 translation");
        e.Unset(n);
      }
    });
    for (Element* e : elements) {
      bool inside = false;  // a refused ancestor already covers it
      for (const Element* p = e->parent(); p; p = p->parent()) {
        inside = inside || std::find(elements.begin(), elements.end(), p) != elements.end();
      }
      if (inside) continue;
      const auto refused = RefusedElements();
      const auto r = std::find_if(refused.begin(), refused.end(),
                                  [&](const RefusedElement& x) { return e->tag() == x.tag; });
      if (r != refused.end()) {
        Note("refused.element", *e, Tag(*e) + ": " + r->why + "; " + r->nearest);
        continue;
      }
      Note("leftover", *e, Tag(*e) + " (MuJoCo 3.x) has no MuJoCo 2.2.2 translation");
    }
    for (auto it = elements.rbegin(); it != elements.rend(); ++it) {
      if ((*it)->parent()) (*it)->parent()->RemoveChild(*it);
    }
  }

  Document& doc_;
  BridgeReport& report_;
  bool align_free_ = false;                 // compiler alignfree="true"
  std::vector<Element*> to_align_;          // simple free bodies to align (FreeJointAlign)
  std::vector<AttachedKey> attached_keys_;  // keyframes of attached models (ExpandAttachments)
  CompilerSettings compiler_;
  bool springs_off_ = false;  // flag spring disabled, damper enabled
  bool dampers_off_ = false;  // flag damper disabled, spring enabled
  std::vector<PendingDampRatio> pending_;
};

}  // namespace

const char* BridgeKindName(BridgeChange::Kind kind) {
  switch (kind) {
    case Kind::kTranslated:
      return "translated";
    case Kind::kApproximated:
      return "approximated";
    case Kind::kDropped:
      return "dropped";
    case Kind::kRefused:
      return "refused";
  }
  return "?";
}

bool BridgeReport::HasRefusals() const {
  return std::any_of(changes.begin(), changes.end(),
                     [](const BridgeChange& c) { return c.kind == Kind::kRefused; });
}

std::vector<InputError> BridgeReport::Refusals() const {
  std::vector<InputError> out;
  for (const BridgeChange& c : changes) {
    if (c.kind == Kind::kRefused) {
      out.emplace_back(c.where, "MuJoCo 3.x construct refused by the dialect bridge: " + c.what);
    }
  }
  return out;
}

std::string BridgeReport::Format() const {
  std::string s;
  for (const BridgeChange& c : changes) {
    const std::string where = c.where.str();
    s += (where.empty() ? std::string("<model>") : where) + ": " + BridgeKindName(c.kind) + " [" +
         c.rule + "]: " + c.what + "\n";
  }
  return s;
}

BridgeReport ApplyBridge(Document& doc, const BridgeOptions& options) {
  BridgeReport report;
  Bridge(doc, report).Run();
  if (options.throw_on_refusal) {
    const std::vector<InputError> refusals = report.Refusals();
    if (refusals.size() == 1) throw refusals.front();
    if (refusals.size() > 1) {
      throw InputError(refusals.front().where(), refusals.front().message() + " (and " +
                                                     std::to_string(refusals.size() - 1) +
                                                     " more refusal(s); run `urlab "
                                                     "validate --bridge-report` to "
                                                     "list them)");
    }
  }
  return report;
}

}  // namespace urlab::mjcf
