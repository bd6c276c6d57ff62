#include "urlab/mjcf/compose.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "mjcf/compose_steps.h"
#include "skin_file.h"
#include "urlab/document/orientation.h"

namespace urlab::mjcf {

using document::Diagnostic;
using document::Document;
using document::Element;
using document::Namespace;

bool Placement::IsIdentity() const {
  return pos == std::array<double, 3>{0, 0, 0} && quat == std::array<double, 4>{1, 0, 0, 0};
}

namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void Fail(const std::string& art, const Element& e, const std::string& what) {
  throw InputError(e.location(), art + ": " + e.Describe() + ": " + what);
}

bool InWorldbody(const Element& e) {
  for (const Element* p = e.parent(); p; p = p->parent()) {
    if (p->tag() == "worldbody") return true;
  }
  return false;
}

std::vector<double> RealsOr(const Element& e, std::string_view name, std::vector<double> fallback) {
  auto v = e.GetReals(name);
  return v ? *v : fallback;
}

// ---- naming ----

}  // namespace

// Gives unnamed bodies, joints, sites, tendons, actuators and sensors a stable generated name
// "{tag}{index}" (index = MuJoCo id order of that kind within the articulation), made unique with
// _1, _2 when a real name already uses it.
void NameUnnamed(Document& doc) {
  std::unordered_map<int, std::unordered_set<std::string>> used;
  doc.root().Visit([&](const Element& e) {
    if (e.spec() && e.spec()->name_space != Namespace::kNone) {
      used[static_cast<int>(e.spec()->name_space)].insert(document::DefinedName(e));
    }
  });
  std::unordered_map<int, int> counter;
  auto name_it = [&](Element& e, const std::string& base) {
    const Namespace ns = e.spec()->name_space;
    const int index = counter[static_cast<int>(ns)]++;
    if (!e.Name().empty()) return;
    auto& u = used[static_cast<int>(ns)];
    std::string n = base + std::to_string(index);
    for (int k = 1; u.count(n); ++k) n = base + std::to_string(index) + "_" + std::to_string(k);
    u.insert(n);
    e.Set("name", n);
  };
  doc.root().Visit([&](Element& e) {
    if (!e.spec() || e.parent() == nullptr) return;
    const std::string& pt = e.parent()->tag();
    const Namespace ns = e.spec()->name_space;
    if (pt == "default" || e.tag() == "composite") return;
    if (e.parent()->parent() && e.parent()->tag() == "composite") return;
    switch (ns) {
      case Namespace::kBody:
        name_it(e, "body");
        break;
      case Namespace::kSite:
        name_it(e, "site");
        break;
      case Namespace::kTendon:
        name_it(e, "tendon");
        break;
      case Namespace::kActuator:
        name_it(e, "actuator");
        break;
      case Namespace::kSensor:
        name_it(e, "sensor");
        break;
      default:
        break;
    }
  });
  // Joints in MuJoCo's order: a body's own joints, then its child bodies depth first.
  std::function<void(Element&)> joints = [&](Element& body) {
    for (auto& c : body.children()) {
      if (c->tag() == "joint" || c->tag() == "freejoint") name_it(*c, "joint");
    }
    for (auto& c : body.children()) {
      if (c->tag() == "body") joints(*c);
    }
  };
  for (auto& s : doc.root().children()) {
    if (s->tag() == "worldbody") joints(*s);
  }
}

namespace {

// Skins from SKN files name their bone bodies inside the binary file, where the prefix cannot
// reach: they are written inline (the same data) so that their bones get prefixed.
void InlineSkinFiles(Document& doc) {
  for (auto& s : doc.root().children()) {
    if (s->tag() != "asset") continue;
    for (auto& a : s->children()) {
      if (a->tag() == "skin" && a->Has("file")) internal::InlineSkinFile(*a);
    }
  }
}

// Prefixes every defined name and every reference in the articulation.
void ApplyPrefix(Document& doc, const std::string& prefix) {
  doc.root().Visit([&](Element& e) {
    if (!e.spec()) return;
    const Namespace own = e.spec()->name_space;
    // Assets named implicitly after their file get that name explicitly; the loop below
    // prefixes it like every other name (once).
    if (own != Namespace::kNone && own != Namespace::kClass && e.Name().empty()) {
      const std::string implicit = document::DefinedName(e);
      if (!implicit.empty()) e.Set("name", implicit);
    }
    if (e.tag() == "composite") e.Set("prefix", prefix + e.GetOr("prefix", ""));
    std::vector<std::pair<std::string, std::string>> updates;
    for (const document::Attribute& a : e.attributes()) {
      if (!a.spec || a.value.empty()) continue;
      const bool defines =
          (a.name == "name" && own != Namespace::kNone && own != Namespace::kClass) ||
          (a.name == "class" && own == Namespace::kClass);
      if (defines) {
        updates.emplace_back(a.name, prefix + a.value);
        continue;
      }
      const Namespace ns = document::ReferencedNamespace(e, a);
      if (ns == Namespace::kNone) continue;
      if (ns == Namespace::kBody && a.value == "world") continue;
      updates.emplace_back(a.name, prefix + a.value);
    }
    for (auto& [n, v] : updates) e.Set(n, v);
  });
}

// ---- default classes ----

// Turns the articulation's top-level <default> into class "{prefix}main" and makes every element
// that used the implicit main class use it explicitly. Returns the class element (detached), or
// nullptr when the articulation has no defaults.
// True when default class `d` (not its children classes) has a template for elements `tag`.
bool HasTemplate(const Element& d, const std::string& tag) {
  using document::IsActuatorTag;
  for (const auto& c : d.children()) {
    if (c->tag() == tag || (IsActuatorTag(tag) && IsActuatorTag(c->tag()))) return true;
  }
  return false;
}

std::unique_ptr<Element> WrapDefaults(Document& doc, const std::string& prefix) {
  Element* top = doc.root().FirstChild("default");
  if (!top) return nullptr;
  std::unique_ptr<Element> wrapped = doc.root().RemoveChild(top);
  // Further top-level <default> sections (rare) are merged into the first.
  while (Element* more = doc.root().FirstChild("default")) {
    std::unique_ptr<Element> m = doc.root().RemoveChild(more);
    while (!m->children().empty()) {
      wrapped->InsertChild(wrapped->children().size(), m->RemoveChild(m->children()[0].get()));
    }
  }
  const std::string main = prefix + "main";
  wrapped->Unset("class");
  wrapped->Set("class", main);
  // Elements that used the implicit main class now name it, but only where main has a template
  // for them (elsewhere the class changes nothing, and leaving it out keeps identical assets of
  // several articulations identical, so they can be shared).
  doc.root().Visit([&](Element& e) {
    if (!e.spec() || !e.spec()->FindAttribute("class") || e.Has("class")) return;
    if (e.parent() && e.parent()->tag() == "default") return;
    if (e.tag() == "default") return;
    // Inside the world body, elements of bodies inherit through childclass (set below).
    if (InWorldbody(e) && e.parent()->tag() != "worldbody") return;
    if (HasTemplate(*wrapped, e.tag())) e.Set("class", main);
  });
  bool body_templates = false;
  for (const char* t : {"geom", "joint", "site", "camera", "light"}) {
    body_templates = body_templates || HasTemplate(*wrapped, t);
  }
  for (auto& s : doc.root().children()) {
    if (s->tag() != "worldbody" || !body_templates) continue;
    for (auto& c : s->children()) {
      if (c->tag() == "body" && !c->Has("childclass")) c->Set("childclass", main);
    }
  }
  return wrapped;
}

// Shares assets that several articulations define identically (same kind, same attributes but
// the name, same files): the later copy is dropped and its references renamed to the first. A
// scene of many copies of one robot then holds one set of textures, as a hand-written scene
// would, which keeps compilation as fast as MuJoCo's own multi-robot files.
void ShareIdenticalAssets(Document& doc, Element* defaults,
                          std::unordered_map<std::string, std::string>& seen) {
  Element* assets = doc.root().FirstChild("asset");
  if (!assets) return;
  // In dependency order: materials name textures, skins name materials.
  for (Namespace ns : {Namespace::kTexture, Namespace::kHField, Namespace::kMesh,
                       Namespace::kMaterial, Namespace::kSkin}) {
    std::unordered_map<std::string, std::string> renames;
    for (size_t i = 0; i < assets->children().size();) {
      const Element& a = *assets->children()[i];
      if (!a.spec() || a.spec()->name_space != ns) {
        ++i;
        continue;
      }
      std::vector<std::string> parts;
      for (const document::Attribute& at : a.attributes()) {
        if (at.name == "name") continue;
        const bool file = at.spec && at.spec->type == document::ValueType::kFile;
        parts.push_back(at.name + "=" + (file ? *a.ResolvedFile(at.name) : at.value));
      }
      std::sort(parts.begin(), parts.end());
      std::string key = a.tag();
      for (const std::string& p : parts) key += '\n' + p;
      const std::string name = a.Name();
      auto [it, fresh] = seen.emplace(key, name);
      if (fresh || !a.children().empty()) {
        ++i;
        continue;
      }
      if (!name.empty()) renames[name] = it->second;
      assets->RemoveChild(&a);
    }
    if (renames.empty()) continue;
    auto rename = [&](Element& e) {
      std::vector<std::pair<std::string, std::string>> updates;
      for (const document::Attribute& at : e.attributes()) {
        if (!at.spec || at.spec->ref != ns) continue;
        auto r = renames.find(at.value);
        if (r != renames.end()) updates.emplace_back(at.name, r->second);
      }
      for (auto& [n, v] : updates) e.Set(n, v);
    };
    doc.root().Visit(rename);
    if (defaults) defaults->Visit(rename);
  }
}

// ---- compiler unit normalization ----

// Rewrites angle-dependent values so the articulation means the same under the scene's
// compiler angle unit and eulerseq.
void ConvertAngles(Document& doc, const document::CompilerSettings& from,
                   const document::CompilerSettings& to) {
  const bool unit_differs = from.degree != to.degree;
  const bool seq_differs = from.eulerseq != to.eulerseq;
  if (!unit_differs && !seq_differs) return;
  doc.root().Visit([&](Element& e) {
    const bool has_angle_form = e.Has("euler") || (unit_differs && e.Has("axisangle"));
    if (has_angle_form && e.tag() != "compiler") {
      const document::Quat q = *document::OwnOrientation(e, from);
      for (const char* a : {"euler", "axisangle"}) e.Unset(a);
      e.SetReals("quat", q);
    }
  });
  if (!unit_differs) return;
  const double factor = from.degree ? kPi / 180.0 : 180.0 / kPi;
  doc.root().Visit([&](Element& e) {
    if (e.tag() != "joint" || (e.parent() && e.parent()->tag() == "default")) return;
    const std::string* type = document::ResolveAttribute(doc, e, "type");
    const std::string t = type ? *type : "hinge";
    if (t != "hinge" && t != "ball") return;
    for (const char* a : {"range", "ref", "springref"}) {
      const std::string* v = document::ResolveAttribute(doc, e, a);
      if (!v) continue;
      std::vector<double> vals = *document::ParseReals(*v);
      for (double& x : vals) x *= factor;
      e.SetReals(a, vals);
    }
  });
}

// ---- placement ----

void PlaceTopLevel(const Document& doc, Element& e, const Placement& p) {
  const document::Quat Q = p.quat;
  auto transform_point = [&](const document::Vec3& v) {
    const document::Vec3 r = document::QuatRotate(Q, v);
    return document::Vec3{p.pos[0] + r[0], p.pos[1] + r[1], p.pos[2] + r[2]};
  };
  if ((e.tag() == "geom" || e.tag() == "site") && document::ResolveAttribute(doc, e, "fromto")) {
    const std::vector<double> f =
        *document::ParseReals(*document::ResolveAttribute(doc, e, "fromto"));
    const document::Vec3 a = transform_point({f[0], f[1], f[2]});
    const document::Vec3 b = transform_point({f[3], f[4], f[5]});
    e.SetReals("fromto", std::vector<double>{a[0], a[1], a[2], b[0], b[1], b[2]});
    return;
  }
  const std::string* pos_text = document::ResolveAttribute(doc, e, "pos");
  std::vector<double> pos =
      pos_text ? *document::ParseReals(*pos_text) : std::vector<double>{0, 0, 0};
  pos.resize(3, 0);
  e.SetReals("pos", transform_point({pos[0], pos[1], pos[2]}));
  if (e.tag() == "light") {
    const std::string* d = document::ResolveAttribute(doc, e, "dir");
    std::vector<double> dir = d ? *document::ParseReals(*d) : std::vector<double>{0, 0, -1};
    dir.resize(3, 0);
    e.SetReals("dir", document::QuatRotate(Q, {dir[0], dir[1], dir[2]}));
    return;
  }
  std::optional<document::Quat> own = document::OwnOrientation(e, doc.Compiler());
  document::Quat q = own ? *own : document::InheritedDefaultPose(doc, e).quat;
  for (const char* a : {"quat", "axisangle", "euler", "xyaxes", "zaxis"}) e.Unset(a);
  e.SetReals("quat", document::QuatMul(Q, q));
}

// ---- layout and keyframes ----

void CollectLayout(const Document& doc, ArticulationLayout& out) {
  std::function<void(const Element&, bool)> walk = [&](const Element& body, bool top) {
    if (body.tag() == "body") {
      out.bodies.push_back(body.Name());
      if (body.GetOr("mocap", "false") == "true") out.mocap_bodies.push_back(body.Name());
    }
    for (const auto& c : body.children()) {
      if (c->tag() == "joint" || c->tag() == "freejoint") {
        out.joints.push_back(c->Name());
        const std::string* type = document::ResolveAttribute(doc, *c, "type");
        const bool free = c->tag() == "freejoint" || (type && *type == "free");
        if (free && top) out.free_joints_at_top.push_back(c->Name());
      }
    }
    for (const auto& c : body.children()) {
      if (c->tag() == "body") walk(*c, body.tag() == "worldbody");
    }
  };
  if (const Element* wb = doc.FindSection("worldbody")) walk(*wb, true);
  for (const auto& s : doc.root().children()) {
    if (s->tag() == "actuator") {
      for (const auto& a : s->children()) out.actuators.push_back(a->Name());
    }
    if (s->tag() == "sensor") {
      for (const auto& a : s->children()) out.sensors.push_back(a->Name());
    }
  }
}

// Moves the articulation's keys into the layout, leaving placeholder keys (name and time only).
// A <size nkey> larger than the keys written adds unnamed keys at the reference configuration,
// as MuJoCo does (named "key{index}" in the scene).
void ExtractKeyframes(Document& doc, const std::string& prefix, ArticulationLayout& out) {
  int index = 0;
  std::unordered_set<std::string> used;
  for (auto& s : doc.root().children()) {
    if (s->tag() != "keyframe") continue;
    for (auto& k : s->children()) {
      if (!k->Name().empty()) used.insert(k->Name().substr(prefix.size()));
    }
  }
  auto unnamed = [&](int i) {
    std::string n = "key" + std::to_string(i);
    for (int k = 1; used.count(n); ++k) n = "key" + std::to_string(i) + "_" + std::to_string(k);
    used.insert(n);
    return n;
  };
  for (auto& s : doc.root().children()) {
    if (s->tag() != "keyframe") continue;
    for (auto& k : s->children()) {
      ArticulationKeyframe key;
      key.name = k->Name().empty() ? unnamed(index) : k->Name().substr(prefix.size());
      ++index;
      key.scene_name = prefix + key.name;
      key.time = k->GetReal("time").value_or(0.0);
      key.qpos = RealsOr(*k, "qpos", {});
      key.qvel = RealsOr(*k, "qvel", {});
      key.act = RealsOr(*k, "act", {});
      key.ctrl = RealsOr(*k, "ctrl", {});
      key.mocap_pos = RealsOr(*k, "mpos", {});
      key.mocap_quat = RealsOr(*k, "mquat", {});
      for (const char* a : {"qpos", "qvel", "act", "ctrl", "mpos", "mquat"}) k->Unset(a);
      k->Set("name", key.scene_name);
      out.keyframes.push_back(std::move(key));
    }
  }
  int nkey = 0;
  for (const auto& s : doc.root().children()) {
    if (s->tag() == "size" && s->Has("nkey")) nkey = s->GetInt("nkey").value_or(0);
  }
  for (; index < nkey; ++index) {
    ArticulationKeyframe key;
    key.name = unnamed(index);
    key.scene_name = prefix + key.name;
    doc.Section("keyframe").AddChild("key").Set("name", key.scene_name);
    out.keyframes.push_back(std::move(key));
  }
}

std::map<std::string, std::string> OptionAttributes(const Document& doc) {
  std::map<std::string, std::string> out;
  for (const auto& s : doc.root().children()) {
    if (s->tag() != "option") continue;
    for (const auto& a : s->attributes()) out[a.name] = a.value;
    for (const auto& f : s->children()) {
      for (const auto& a : f->attributes()) out["flag." + a.name] = a.value;
    }
  }
  return out;
}

}  // namespace

void PrefixNames(Document& doc, const std::string& prefix) { ApplyPrefix(doc, prefix); }

std::unique_ptr<Element> WrapDefaultsAsClass(Document& doc, const std::string& prefix) {
  return WrapDefaults(doc, prefix);
}

void ConvertAngleUnits(Document& doc, const document::CompilerSettings& from,
                       const document::CompilerSettings& to) {
  ConvertAngles(doc, from, to);
}

void SetOptionAttribute(Document& doc, const std::string& key, const std::string& value) {
  Element& option = doc.Section("option");
  if (key.rfind("flag.", 0) == 0) {
    Element* flag = option.FirstChild("flag");
    if (!flag) flag = &option.AddChild("flag");
    flag->Set(key.substr(5), value);
  } else {
    option.Set(key, value);
  }
}

namespace {

// Sections merged child by child into the scene, in MuJoCo's processing order.
constexpr const char* kMergedSections[] = {"custom", "asset",    "worldbody", "contact", "equality",
                                           "tendon", "actuator", "sensor",    "keyframe"};

}  // namespace

ComposeResult Compose(std::vector<ArticulationInput> inputs,
                      const std::map<std::string, std::string>& overrides) {
  ComposeResult result;
  if (inputs.empty()) throw Error("a scene needs at least one articulation");
  std::unordered_set<std::string> names;
  for (const auto& in : inputs) {
    if (in.name.empty()) throw Error("an articulation needs a name");
    if (!names.insert(in.name).second) {
      throw Error("two articulations are named '" + in.name + "'");
    }
  }
  Document& scene = result.doc;
  scene.root().Set("model", "urlab_scene");
  const document::CompilerSettings scene_compiler = inputs[0].doc.Compiler();
  Element* scene_default = nullptr;
  std::map<std::string, std::string> scene_options;
  std::unordered_map<std::string, std::string> shared_assets;

  for (size_t i = 0; i < inputs.size(); ++i) {
    ArticulationInput& in = inputs[i];
    Document& doc = in.doc;
    const std::string prefix = in.name + "_";
    ArticulationLayout layout;
    layout.name = in.name;
    layout.prefix = prefix;
    layout.placement = in.placement;

    for (const auto& s : doc.root().children()) {
      if (s->tag() != "compiler") continue;
      if (s->GetOr("coordinate", "local") == "global") {
        Fail(in.name, *s, "compiler coordinate=\"global\" cannot be composed; use local");
      }
      if (s->Has("settotalmass") && inputs.size() > 1) {
        Fail(in.name, *s,
             "compiler settotalmass rescales the whole model, so in a scene it would change every "
             "articulation's mass; remove it or set the masses in the MJCF");
      }
    }
    if (i > 0 && !in.takes_scene_options) {
      // Compiler settings are scene-wide: the first articulation's apply (paths and angle units
      // are normalised per articulation, so those may differ). A generated document (a prop, a
      // launcher) takes the scene's, like its options.
      static const std::set<std::string> kPerArticulation = {"meshdir",   "texturedir", "assetdir",
                                                             "strippath", "angle",      "eulerseq"};
      std::map<std::string, std::string> mine, first;
      for (const auto* d : {&doc, &inputs[0].doc}) {
        auto& out = d == &doc ? mine : first;
        for (const auto& s : d->root().children()) {
          if (s->tag() != "compiler") continue;
          for (const auto& a : s->attributes()) {
            if (!kPerArticulation.count(a.name)) out[a.name] = a.value;
          }
        }
      }
      if (mine != first) {
        // Built as a named value: a braced temporary here makes GCC 12 at -O3 report a false
        // -Wmaybe-uninitialized on its strings.
        Diagnostic d;
        d.severity = Diagnostic::Severity::kWarning;
        d.where = {doc.source_path(), 0};
        d.message = in.name + ": its <compiler> settings differ from the first articulation's ('" +
                    inputs[0].name + "'), whose settings the scene uses";
        result.diagnostics.push_back(std::move(d));
      }
    }
    if (!in.include_world) {
      if (Element* wb = doc.root().FirstChild("worldbody")) {
        for (size_t c = wb->children().size(); c-- > 0;) {
          if (wb->children()[c]->tag() != "body") wb->RemoveChild(wb->children()[c].get());
        }
      }
    }
    ConvertAngles(doc, doc.Compiler(), scene_compiler);
    NameUnnamed(doc);
    InlineSkinFiles(doc);
    ApplyPrefix(doc, prefix);
    std::unique_ptr<Element> defaults = WrapDefaults(doc, prefix);
    ShareIdenticalAssets(doc, defaults.get(), shared_assets);
    if (!in.placement.IsIdentity()) {
      if (Element* wb = doc.root().FirstChild("worldbody")) {
        for (auto& c : wb->children()) {
          if (c->tag() == "body" || c->tag() == "geom" || c->tag() == "site" ||
              c->tag() == "camera" || c->tag() == "light") {
            PlaceTopLevel(doc, *c, in.placement);
          }
        }
      }
    }
    CollectLayout(doc, layout);
    ExtractKeyframes(doc, prefix, layout);

    // Options: MuJoCo defaults, then the MJCF's <option>, then the articulation's own settings.
    std::map<std::string, std::string> options = OptionAttributes(doc);
    for (const auto& [k, v] : in.options) options[k] = v;
    layout.options = options;
    if (in.takes_scene_options) {
      // No options of its own (a converted prop): nothing to resolve or warn about.
    } else if (i == 0) {
      scene_options = options;
    } else {
      std::set<std::string> keys;
      for (const auto& [k, v] : options) keys.insert(k);
      for (const auto& [k, v] : scene_options) keys.insert(k);
      for (const std::string& k : keys) {
        auto a = options.find(k), b = scene_options.find(k);
        const std::string mine = a == options.end() ? "(default)" : a->second;
        const std::string theirs = b == scene_options.end() ? "(default)" : b->second;
        if (mine != theirs && !overrides.count(k)) {
          Diagnostic d;  // a named value, as above
          d.severity = Diagnostic::Severity::kWarning;
          d.where = {doc.source_path(), 0};
          d.message = in.name + ": option " + k + "=" + mine + " differs from the scene's " +
                      theirs + " (taken from the first articulation, '" + inputs[0].name +
                      "'; set it in the scene's options to choose)";
          result.diagnostics.push_back(std::move(d));
        }
      }
    }

    // Scene-wide sections come from the first articulation.
    for (auto& s : doc.root().children()) {
      const std::string& t = s->tag();
      if (i == 0 && (t == "compiler" || t == "visual" || t == "statistic")) {
        scene.root().InsertChild(scene.root().children().size(), s->Clone());
      }
      if (t == "size") {
        Element& size = scene.Section("size");
        for (const auto& a : s->attributes()) {
          if (a.name == "nkey") continue;  // counted from the keyframes
          const bool additive = a.name == "njmax" || a.name == "nconmax" || a.name == "nstack";
          const auto mine = document::ParseReals(a.value);
          const auto cur = size.GetReals(a.name);
          if (!mine || mine->empty()) continue;
          double v = (*mine)[0];
          if (cur && !cur->empty()) v = additive ? v + (*cur)[0] : std::max(v, (*cur)[0]);
          // <size> values are integers: 2.2.2 reads "1e+06" as 1 (an nstack of 1).
          size.Set(a.name, std::to_string(static_cast<long long>(v)));
        }
      }
    }
    if (defaults) {
      if (!scene_default) scene_default = &scene.Section("default");
      scene_default->InsertChild(scene_default->children().size(), std::move(defaults));
    }
    for (const char* section : kMergedSections) {
      for (auto& s : doc.root().children()) {
        if (s->tag() != section) continue;
        Element& target = scene.Section(section);
        while (!s->children().empty()) {
          target.InsertChild(target.children().size(), s->RemoveChild(s->children()[0].get()));
        }
      }
    }
    for (const auto& d : doc.diagnostics()) result.diagnostics.push_back(d);
    result.articulations.push_back(std::move(layout));
  }
  for (const auto& [k, v] : overrides) scene_options[k] = v;
  for (const auto& [k, v] : scene_options) SetOptionAttribute(scene, k, v);
  return result;
}

namespace {

// MuJoCo 2.2.2 normalizes the quaternions of keyframes when it compiles them; applying
// mju_normalize4 twice reproduces its values bit for bit (checked on 200 random quaternions).
void NormalizeLikeCompiler(mjtNum* q) {
  mju_normalize4(q);
  mju_normalize4(q);
}

}  // namespace

void ApplyArticulationKeyframes(const std::vector<ArticulationLayout>& layouts, mjModel* m) {
  for (const ArticulationLayout& art : layouts) {
    for (const ArticulationKeyframe& key : art.keyframes) {
      const int k = mj_name2id(m, mjOBJ_KEY, key.scene_name.c_str());
      if (k < 0) throw Error(art.name + ": keyframe '" + key.name + "' missing in compiled model");
      m->key_time[k] = key.time;
      // qpos/qvel: the articulation's joints, in its own order.
      size_t qi = 0, vi = 0;
      for (const std::string& jn : art.joints) {
        const int j = mj_name2id(m, mjOBJ_JOINT, jn.c_str());
        if (j < 0) throw Error(art.name + ": joint '" + jn + "' missing in compiled model");
        const int nq = m->jnt_type[j] == mjJNT_FREE ? 7 : m->jnt_type[j] == mjJNT_BALL ? 4 : 1;
        const int nv = m->jnt_type[j] == mjJNT_FREE ? 6 : m->jnt_type[j] == mjJNT_BALL ? 3 : 1;
        mjtNum* qpos = m->key_qpos + static_cast<size_t>(k) * m->nq + m->jnt_qposadr[j];
        if (qi + nq <= key.qpos.size()) {
          for (int c = 0; c < nq; ++c) qpos[c] = key.qpos[qi + c];
          const bool top_free =
              std::find(art.free_joints_at_top.begin(), art.free_joints_at_top.end(), jn) !=
              art.free_joints_at_top.end();
          if (top_free && !art.placement.IsIdentity()) {
            const document::Vec3 r =
                document::QuatRotate(art.placement.quat, {qpos[0], qpos[1], qpos[2]});
            for (int c = 0; c < 3; ++c) qpos[c] = art.placement.pos[c] + r[c];
            const document::Quat q =
                document::QuatMul(art.placement.quat, {qpos[3], qpos[4], qpos[5], qpos[6]});
            for (int c = 0; c < 4; ++c) qpos[3 + c] = q[c];
          }
          if (nq > 1) NormalizeLikeCompiler(qpos + nq - 4);
        }
        mjtNum* qvel = m->key_qvel + static_cast<size_t>(k) * m->nv + m->jnt_dofadr[j];
        if (vi + nv <= key.qvel.size()) {
          for (int c = 0; c < nv; ++c) qvel[c] = key.qvel[vi + c];
        }
        qi += nq;
        vi += nv;
      }
      // ctrl by actuator; act by stateful actuators in order.
      size_t ai = 0;
      for (size_t a = 0; a < art.actuators.size(); ++a) {
        const int id = mj_name2id(m, mjOBJ_ACTUATOR, art.actuators[a].c_str());
        if (id < 0) continue;
        if (a < key.ctrl.size()) m->key_ctrl[static_cast<size_t>(k) * m->nu + id] = key.ctrl[a];
        if (m->actuator_dyntype[id] != mjDYN_NONE) {
          int act_adr = 0;
          for (int b = 0; b < id; ++b) act_adr += m->actuator_dyntype[b] != mjDYN_NONE;
          if (ai < key.act.size())
            m->key_act[static_cast<size_t>(k) * m->na + act_adr] = key.act[ai];
          ++ai;
        }
      }
      for (size_t b = 0; b < art.mocap_bodies.size(); ++b) {
        const int body = mj_name2id(m, mjOBJ_BODY, art.mocap_bodies[b].c_str());
        if (body < 0 || m->body_mocapid[body] < 0) continue;
        const int mid = m->body_mocapid[body];
        // Mocap bodies are always children of the world: their key poses get the placement.
        if (3 * b + 3 <= key.mocap_pos.size()) {
          const document::Vec3 r = document::QuatRotate(
              art.placement.quat,
              {key.mocap_pos[3 * b], key.mocap_pos[3 * b + 1], key.mocap_pos[3 * b + 2]});
          for (int c = 0; c < 3; ++c) {
            m->key_mpos[static_cast<size_t>(k) * 3 * m->nmocap + 3 * mid + c] =
                art.placement.IsIdentity() ? key.mocap_pos[3 * b + c] : art.placement.pos[c] + r[c];
          }
        }
        if (4 * b + 4 <= key.mocap_quat.size()) {
          const document::Quat q = document::QuatMul(
              art.placement.quat, {key.mocap_quat[4 * b], key.mocap_quat[4 * b + 1],
                                   key.mocap_quat[4 * b + 2], key.mocap_quat[4 * b + 3]});
          mjtNum* mquat = m->key_mquat + static_cast<size_t>(k) * 4 * m->nmocap + 4 * mid;
          for (int c = 0; c < 4; ++c) {
            mquat[c] = art.placement.IsIdentity() ? key.mocap_quat[4 * b + c] : q[c];
          }
          NormalizeLikeCompiler(mquat);
        }
      }
    }
  }
}

}  // namespace urlab::mjcf
