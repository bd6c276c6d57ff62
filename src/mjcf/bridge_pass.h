#pragma once
// The dialect bridge's passes (internal to the mjcf module). ApplyBridge (bridge.cc) runs them in
// the order of its pass table over one `State`; each construct family has its own file:
//   bridge_compiler.cc     <compiler>, <option>, <flag>, <size> (and the stack size)
//   bridge_attach.cc       <attach>/<model> (driven by the `Attachments` pass)
//   bridge_frames.cc       <replicate>, <frame>, free-body alignment
//   bridge_constraints.cc  equalities on sites, polycoef
//   bridge_actuators.cc    actuator armature/damping, actuatorfrcrange, position/intvelocity
//                          shortcuts and dampratio, filterexact, actuator order
//   bridge_passive.cc      gravcomp, dead-band tendon springs, spring/damper flags
//   bridge_assets.cc       discardvisual, render-only elements, mesh inertia
//   bridge_sensors.cc      3.x sensors
//   bridge_keyframes.cc    keyframe padding, attached models' keys
//   bridge_attributes.cc   policy-driven 3.x attributes, leftovers (refused)
// A pass is a function `void(State&)`; the rule table (bridge_rules.cc) names the passes that
// apply each rule by these functions, so a rule cannot name a pass that does not exist.
//
// Thread: a State and the passes over it belong to one thread (the document's owner).
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mjcf/bridge_attach.h"
#include "mjcf/bridge_rules.h"
#include "urlab/core/error.h"
#include "urlab/document/document.h"
#include "urlab/document/grammar.h"
#include "urlab/document/orientation.h"
#include "urlab/mjcf/bridge.h"

namespace urlab::mjcf::bridge {

using document::Attribute;
using document::CompilerSettings;
using document::Document;
using document::Element;
using document::IsActuatorTag;
using document::ParseReals;

// What the passes share: the document, the report, and what one pass leaves for a later one.
struct State {
  State(Document& d, BridgeReport& r) : doc(d), report(r) {}
  Document& doc;
  BridgeReport& report;
  CompilerSettings compiler;               // the document's, read again after the Compiler pass
  bool align_free = false;                 // compiler alignfree="true" (Compiler)
  std::vector<Element*> to_align;          // simple free bodies to align (FreeJointAlign)
  std::vector<AttachedKey> attached_keys;  // keyframes of attached models (Attachments)
  bool springs_off = false;                // flag spring disabled, damper enabled (Options)
  bool dampers_off = false;                // flag damper disabled, spring enabled (Options)
  struct PendingDampRatio {  // position/intvelocity dampratio (PositionShortcuts -> DampRatio)
    Element* actuator;
    double kp;
    double ratio;
  };
  std::vector<PendingDampRatio> pending;
  Element* memory_size = nullptr;  // <size> whose 3.x memory the stack is sized from (Options)
  double memory_bytes = 0;         // -> SizeStack
};

// Every pass, in the order ApplyBridge runs them (bridge.cc's pass table).
void Compiler(State& s);
void Attachments(State& s);
void Replicates(State& s);
void FlattenFrames(State& s);
void FreeJointAlign(State& s);
void SiteEqualities(State& s);
void ActuatorArmatureDamping(State& s);
void GravityCompensation(State& s);
void ActuatorForceRanges(State& s);
void PositionShortcuts(State& s);
void Options(State& s);
void FilterExact(State& s);
void PolyCoef(State& s);
void SpringLength(State& s);
void PassiveFlags(State& s);
void VisualOnly(State& s);
void KeepVisualGeoms(State& s);
void MeshInertia(State& s);
void GenericAttributes(State& s);
void Sensors(State& s);
void ComputedSensors(State& s);
void OrderActuators(State& s);
void Leftovers(State& s);
void AlignFreeBodies(State& s);
void DampRatio(State& s);
void PadKeyframes(State& s);
void SizeStack(State& s);

// One row of the pass table (bridge.cc): the pass's name and file (for the rule listing), the
// function, and whether it runs only when nothing was refused (those need a trial compile).
struct PassEntry {
  const char* name;
  const char* file;
  void (*run)(State&);
  bool only_without_refusals;
};
std::span<const PassEntry> Passes();

constexpr double kPi = 3.14159265358979323846;

inline bool InDefault(const Element& e) {
  for (const Element* p = e.parent(); p; p = p->parent()) {
    if (p->tag() == "default") return true;
  }
  return false;
}

inline bool IsDialect(const Attribute& a) { return a.spec && a.spec->dialect; }

// A 3.x attribute, a 3.x keyword of a 2.2.2 attribute, or a value count only 3.x accepts.
inline bool DialectValue(const Attribute& a) {
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

inline std::string Join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

inline bool AllZero(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return x == 0; });
}

// The helpers every pass uses; a family's passes are the methods of a subclass.
class Pass {
 public:
  explicit Pass(State& s) : state_(s), doc_(s.doc), report_(s.report), compiler_(s.compiler) {}

 protected:
  using PendingDampRatio = State::PendingDampRatio;

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

  double ResolveTimestep() {
    const Element* o = doc_.root().FirstChild("option");
    return o ? std::atof(o->GetOr("timestep", "0.002").c_str()) : 0.002;
  }
  std::string Integrator() {
    const Element* o = doc_.root().FirstChild("option");
    return o ? o->GetOr("integrator", "Euler") : "Euler";
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

  // Every actuator element (outside <default>) and every actuator default template.
  std::vector<Element*> FindActuators() {
    std::vector<Element*> out;
    doc_.root().Visit([&](Element& e) {
      if (IsActuatorTag(e.tag()) && !InDefault(e)) out.push_back(&e);
    });
    return out;
  }
  std::vector<Element*> FindActuatorDefaults() {
    std::vector<Element*> out;
    doc_.root().Visit([&](Element& e) {
      if (IsActuatorTag(e.tag()) && e.parent() && e.parent()->tag() == "default") {
        out.push_back(&e);
      }
    });
    return out;
  }

  State& state_;
  Document& doc_;
  BridgeReport& report_;
  const CompilerSettings& compiler_;
};

}  // namespace urlab::mjcf::bridge
