#include "mjcf/bridge_attach.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "mjcf/bridge_pass.h"
#include "mjcf/bridge_rules.h"
#include "mjcf/compose_steps.h"
#include "mjcf/trial_compile.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"

namespace urlab::mjcf {

namespace {

namespace fs = std::filesystem;
using document::Document;
using document::Element;
using document::Namespace;

constexpr int kMaxDepth = 8;

void Note(BridgeReport& report, const char* rule, const Element& e, std::string what) {
  const BridgeRule& r = FindBridgeRule(rule);
  report.changes.push_back(BridgeChange{r.kind, e.location(), std::move(what), r.id});
}

using NameSets = std::map<Namespace, std::set<std::string>>;

void DefinedNames(const Element& root, NameSets* out) {
  root.Visit([&](const Element& e) {
    if (!e.spec() || e.spec()->name_space == Namespace::kNone ||
        e.spec()->name_space == Namespace::kClass) {
      return;
    }
    if (const std::string* n = e.Get("name")) (*out)[e.spec()->name_space].insert(*n);
  });
}

bool RefersTo(const Element& root, const NameSets& names) {
  bool found = false;
  root.Visit([&](const Element& e) {
    for (const document::Attribute& a : e.attributes()) {
      auto it = names.find(document::ReferencedNamespace(e, a));
      if (it != names.end() && it->second.count(a.value)) found = true;
    }
  });
  return found;
}

// The top-level sections of `doc` with tag `tag`, in document order.
std::vector<Element*> Sections(Document& doc, const char* tag) {
  std::vector<Element*> out;
  for (const auto& c : doc.root().children()) {
    if (c->tag() == tag) out.push_back(c.get());
  }
  return out;
}

// The childclass `e` inherits from its ancestors in its own document ("" when none).
std::string InheritedChildClass(const Element& e) {
  for (const Element* p = &e; p; p = p->parent()) {
    if (const std::string* c = p->Get("childclass")) return *c;
  }
  return "";
}

// The elements a <frame> holds, through nested frames (which the bridge flattens into them).
void FrameContents(Element& frame, std::vector<Element*>* out) {
  for (const auto& c : frame.children()) {
    if (c->tag() == "frame") {
      FrameContents(*c, out);
    } else {
      out->push_back(c.get());
    }
  }
}

void AppendPrefixed(BridgeReport& into, const BridgeReport& from, const std::string& prefix) {
  for (BridgedSensor s : from.software_sensors) {
    s.name = prefix + s.name;
    if (!s.target.empty()) s.target = prefix + s.target;
    for (const char* n :
         {"site", "objname", "geom1", "geom2", "body1", "body2", "subtree1", "subtree2"}) {
      if (s.params.count(n) && s.params[n] != "world") s.params[n] = prefix + s.params[n];
    }
    into.software_sensors.push_back(std::move(s));
  }
  for (BridgedGravcomp g : from.gravcomp) {
    g.body = prefix + g.body;
    into.gravcomp.push_back(g);
  }
  for (BridgedSiteEquality e : from.site_equalities) {
    e.equality = prefix + e.equality;
    e.site1 = prefix + e.site1;
    e.site2 = prefix + e.site2;
    into.site_equalities.push_back(e);
  }
  for (BridgedDeadbandSpring t : from.deadband_springs) {
    t.tendon = prefix + t.tendon;
    into.deadband_springs.push_back(t);
  }
}

// The child's compiled keyframes, values by element name (not yet prefixed). The child's
// unnamed elements are named first (the composer's own naming), so that every value has an
// element to go to. Empty, with the compiler's message, when the child alone does not compile.
std::vector<AttachedKey> ChildKeys(Document& child, std::string* error) {
  NameUnnamed(child);
  const physics::ModelPtr model = TrialCompile(WriteString(child), error);
  const mjModel* m = model.get();
  if (!m) return {};
  auto name = [&](mjtObj type, int id) {
    const char* n = mj_id2name(m, type, id);
    return std::string(n ? n : "");
  };
  std::vector<AttachedKey> keys(static_cast<size_t>(m->nkey));
  for (int k = 0; k < m->nkey; ++k) {
    AttachedKey& out = keys[static_cast<size_t>(k)];
    out.time = m->key_time[k];
    const mjtNum* qpos = m->key_qpos + static_cast<size_t>(k) * m->nq;
    const mjtNum* qvel = m->key_qvel + static_cast<size_t>(k) * m->nv;
    for (int j = 0; j < m->njnt; ++j) {
      const int t = m->jnt_type[j];
      const int nq = t == mjJNT_FREE ? 7 : t == mjJNT_BALL ? 4 : 1;
      const int nv = t == mjJNT_FREE ? 6 : t == mjJNT_BALL ? 3 : 1;
      const std::string n = name(mjOBJ_JOINT, j);
      out.qpos[n].assign(qpos + m->jnt_qposadr[j], qpos + m->jnt_qposadr[j] + nq);
      out.qvel[n].assign(qvel + m->jnt_dofadr[j], qvel + m->jnt_dofadr[j] + nv);
    }
    for (int a = 0; a < m->nu; ++a) {
      out.ctrl[name(mjOBJ_ACTUATOR, a)] = m->key_ctrl[k * m->nu + a];
      // 2.2.2 keeps stateful actuators last (the child's bridge ordered them).
      if (m->actuator_dyntype[a] != mjDYN_NONE) {
        out.act[name(mjOBJ_ACTUATOR, a)] = m->key_act[k * m->na + a - (m->nu - m->na)];
      }
    }
    for (int b = 0; b < m->nbody; ++b) {
      const int mocap = m->body_mocapid[b];
      if (mocap < 0) continue;
      const mjtNum* p = m->key_mpos + static_cast<size_t>(k) * 3 * m->nmocap + 3 * mocap;
      const mjtNum* q = m->key_mquat + static_cast<size_t>(k) * 4 * m->nmocap + 4 * mocap;
      out.mpos[name(mjOBJ_BODY, b)].assign(p, p + 3);
      out.mquat[name(mjOBJ_BODY, b)].assign(q, q + 4);
    }
  }
  return keys;
}

// `key` with every name prefixed.
AttachedKey Prefixed(const AttachedKey& key, const std::string& prefix) {
  AttachedKey out;
  out.key = key.key;
  out.time = key.time;
  auto each = [&](const auto& from, auto& to) {
    for (const auto& [n, v] : from) to[prefix + n] = v;
  };
  each(key.qpos, out.qpos);
  each(key.qvel, out.qvel);
  each(key.ctrl, out.ctrl);
  each(key.act, out.act);
  each(key.mpos, out.mpos);
  each(key.mquat, out.mquat);
  return out;
}

void Attach(Document& doc, Element& attach, const std::map<std::string, std::string>& models,
            BridgeReport& report, std::vector<AttachedKey>* keys, int depth) {
  const std::string what = "<attach model='" + attach.GetOr("model", "") + "'>";
  const std::string* model = attach.Get("model");
  const std::string* prefix = attach.Get("prefix");
  if (!model || !prefix) {
    Note(report, "attach.refused", attach,
         what +
             " needs model and prefix (self-attachment is not supported; nearest: copy the "
             "subtree, or <replicate>)");
    return;
  }
  if (attach.Has("frame") && attach.Has("body")) {
    Note(report, "attach.refused", attach,
         what + ": body and frame are exclusive (MuJoCo 3.x too); nearest: one of them");
    return;
  }
  auto it = models.find(*model);
  if (it == models.end()) {
    throw InputError(attach.location(), what + ": no <model> asset named '" + *model + "'");
  }
  if (depth >= kMaxDepth) {
    throw InputError(attach.location(), what + ": models attach each other more than " +
                                            std::to_string(kMaxDepth) + " levels deep");
  }
  Document child = ReadFile(it->second);
  // frame=: the frame moves to the child's world body before the child is bridged, so that its
  // flattening composes the frame's own pose (only) into its contents, which are then attached.
  std::vector<Element*> frame_contents;
  if (const std::string* name = attach.Get("frame")) {
    Element* frame = nullptr;
    bool nested_macro = false;
    child.root().Visit([&](Element& e) {
      if (!frame && e.tag() == "frame" && e.Name() == *name) frame = &e;
    });
    if (!frame) {
      throw InputError(attach.location(), what + ": the model has no frame '" + *name + "'");
    }
    frame->Visit([&](const Element& e) {
      nested_macro = nested_macro || e.tag() == "replicate" || e.tag() == "attach";
    });
    if (nested_macro) {
      Note(report, "attach.refused", attach,
           what + " frame='" + *name +
               "': a frame holding <replicate> or <attach> cannot be attached by the bridge; "
               "nearest: body=");
      return;
    }
    const std::string childclass = InheritedChildClass(*frame);
    if (!childclass.empty() && !frame->Has("childclass")) frame->Set("childclass", childclass);
    FrameContents(*frame, &frame_contents);
    Element* world = child.root().FirstChild("worldbody");
    world->InsertChild(world->children().size(), frame->parent()->RemoveChild(frame));
  }
  BridgeOptions keep;
  keep.throw_on_refusal = false;
  BridgeReport child_report = ApplyBridge(child, keep);
  std::vector<AttachedKey> nested;  // the child's own attachments' keys: in its keys already
  ExpandAttachments(child, child_report, &nested, depth + 1);
  for (const BridgeChange& c : child_report.changes) report.changes.push_back(c);
  // The child's keyframes, read from the child compiled alone (its own bridge padded them).
  std::vector<AttachedKey> child_keys;
  std::vector<std::string> key_names;
  const std::vector<Element*> key_sections = Sections(child, "keyframe");
  if (!key_sections.empty()) {
    for (const Element* section : key_sections) {
      for (const auto& k : section->children()) key_names.push_back(k->Name());
    }
    std::string error;
    child_keys = ChildKeys(child, &error);
    if (child_keys.size() < key_names.size()) {
      Note(report, "attach.refused", attach,
           what +
               ": the child model's keyframes cannot be merged: the child does not compile "
               "alone (" +
               error +
               "); nearest: keys written for the whole model in the "
               "parent");
      return;
    }
    for (Element* section : key_sections) child.root().RemoveChild(section);
  }
  ConvertAngleUnits(child, child.Compiler(), doc.Compiler());
  PrefixNames(child, *prefix);
  AppendPrefixed(report, child_report, *prefix);
  std::unique_ptr<Element> defaults = WrapDefaultsAsClass(child, *prefix);

  // The subtree: the named body, or the world body's contents in a frame.
  Element* world = child.root().FirstChild("worldbody");
  std::vector<std::unique_ptr<Element>> moved;
  std::string childclass;
  if (const std::string* body = attach.Get("body")) {
    Element* b = child.FindNamed(Namespace::kBody, *prefix + *body);
    if (!b) {
      throw InputError(attach.location(), what + ": the model has no body '" + *body + "'");
    }
    childclass = InheritedChildClass(*b);
    moved.push_back(b->parent()->RemoveChild(b));
    if (!childclass.empty() && !moved.back()->Has("childclass")) {
      moved.back()->Set("childclass", childclass);
    }
  } else if (attach.Has("frame")) {
    for (Element* e : frame_contents) moved.push_back(e->parent()->RemoveChild(e));
  } else if (world) {
    const document::ElementSpec* frame = attach.parent()->spec()->FindChild("frame");
    auto f = std::make_unique<Element>(frame, "frame");
    f->set_location(attach.location());
    f->set_file_bases(attach.file_bases());
    f->set_edited(true);
    while (!world->children().empty()) {
      f->InsertChild(f->children().size(), world->RemoveChild(world->children()[0].get()));
    }
    moved.push_back(std::move(f));
  }
  NameSets inside;
  for (const auto& m : moved) DefinedNames(*m, &inside);
  Element* parent = attach.parent();
  size_t index = static_cast<size_t>(parent->IndexOf(&attach));
  for (auto& m : moved) parent->InsertChild(index++, std::move(m));

  // Defaults: the child's classes join the parent's top-level <default>.
  if (defaults) {
    Element& top = doc.Section("default");
    top.InsertChild(top.children().size(), std::move(defaults));
  }
  // Assets: all of them (3.x copies every asset of the child, referenced or not).
  int assets = 0;
  // A model may have several sections of a kind (an <asset> for materials, another for meshes):
  // every one of them counts.
  for (Element* a : Sections(child, "asset")) {
    Element& into = doc.Section("asset");
    while (!a->children().empty()) {
      into.InsertChild(into.children().size(), a->RemoveChild(a->children()[0].get()));
      ++assets;
    }
  }
  // Elements outside the tree that refer into it; tendons first (actuators may use them).
  int referring = 0;
  for (const char* section : {"tendon", "equality", "contact", "actuator", "sensor"}) {
    for (Element* s : Sections(child, section)) {
      std::vector<Element*> refs;
      for (const auto& c : s->children()) {
        if (RefersTo(*c, inside)) refs.push_back(c.get());
      }
      if (refs.empty()) continue;
      Element& into = doc.Section(section);
      for (Element* r : refs) {
        DefinedNames(*r, &inside);
        into.InsertChild(into.children().size(), s->RemoveChild(r));
        ++referring;
      }
    }
  }
  // Keyframes: after the parent's own, named "{prefix}{name}" (an unnamed one: the prefix).
  if (!child_keys.empty()) {
    Element& section = doc.Section("keyframe");
    const document::ElementSpec* spec = section.spec()->FindChild("key");
    for (size_t k = 0; k < child_keys.size(); ++k) {
      auto key = std::make_unique<Element>(spec, "key");
      key->set_location(attach.location());
      key->set_edited(true);
      key->Set("name", *prefix + (k < key_names.size() ? key_names[k] : std::string()));
      keys->push_back(Prefixed(child_keys[k], *prefix));
      keys->back().key = key.get();
      section.InsertChild(section.children().size(), std::move(key));
    }
    Note(report, "attach.keyframe", attach,
         what + " prefix='" + *prefix + "': the child's " + std::to_string(child_keys.size()) +
             " keyframe(s) added after the parent's keys as '" + *prefix +
             "<name>': the attached joints', actuators' and mocap bodies' values from the child's "
             "keys, the rest of the model at qpos0 (velocities, controls, activations zero), as "
             "MuJoCo 3.x merges them");
  }
  Note(report, "attach", attach,
       what + " prefix='" + *prefix + "': " +
           (attach.Has("body") ? "body '" + attach.GetOr("body", "") + "' and its subtree"
            : attach.Has("frame")
                ? "frame '" + attach.GetOr("frame", "") + "' (its contents with its pose composed)"
                : std::string("the world body's contents (in a frame)")) +
           " attached with its defaults (class '" + *prefix + "main'), " + std::to_string(assets) +
           " asset(s) and " + std::to_string(referring) +
           " referring element(s), every name prefixed, as MuJoCo 3.x's attach does");
  if (const Element* d = doc.root().FirstChild("default")) {
    for (const auto& c : d->children()) {
      if (c->tag() != "default") {
        Note(report, "attach.defaults", attach,
             what +
                 ": the parent's top-level defaults also apply to the attached elements where "
                 "their own classes are silent (2.2.2 classes all descend from main); 3.x "
                 "keeps the child's defaults apart");
        break;
      }
    }
  }
}

}  // namespace

void ExpandAttachments(Document& doc, BridgeReport& report, std::vector<AttachedKey>* keys,
                       int depth) {
  std::map<std::string, std::string> models;  // name -> file
  std::vector<Element*> model_elements;
  doc.root().Visit([&](Element& e) {
    if (e.tag() != "model" || !e.parent() || e.parent()->tag() != "asset") return;
    const std::optional<std::string> file = e.ResolvedFile("file");
    if (!file) throw InputError(e.location(), "<model> needs a file");
    std::string name = e.GetOr("name", "");
    if (name.empty()) {
      // 3.x: the model's own name.
      Document peek = ReadFile(*file);
      name = peek.root().GetOr("model", "");
    }
    models[name] = *file;
    model_elements.push_back(&e);
  });
  std::vector<Element*> attachments;
  doc.root().Visit([&](Element& e) {
    if (e.tag() == "attach") attachments.push_back(&e);
  });
  for (Element* a : attachments) {
    Attach(doc, *a, models, report, keys, depth);
    a->parent()->RemoveChild(a);
  }
  for (Element* m : model_elements) {
    Note(report, "attach.model", *m,
         "<model name='" + m->GetOr("name", "") + "'> asset removed (used by <attach>)");
    m->parent()->RemoveChild(m);
  }
}

namespace bridge {

// The pass of bridge.cc's table: every <attach> of the document, keys kept for PadKeyframes.
void Attachments(State& s) { ExpandAttachments(s.doc, s.report, &s.attached_keys); }

}  // namespace bridge

}  // namespace urlab::mjcf
