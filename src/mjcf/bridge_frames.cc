// The dialect bridge's body-structure passes: <replicate> expansion, <frame> flattening and the
// alignment of simple free bodies with their inertial frame (3.x compile-time rewrites).
#include <fmt/format.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "mjcf/bridge_pass.h"
#include "mjcf/trial_compile.h"
#include "urlab/document/orientation.h"
#include "urlab/mjcf/writer.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Attribute;
using document::Element;
using document::FormatReals;
using document::Quat;
using document::Vec3;

class FramesPasses : public Pass {
 public:
  using Pass::Pass;

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
      const bool align = mode == "true" || state_.align_free;
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
      state_.to_align.push_back(body);
    }
  }

  void AlignFreeBodies() {
    if (state_.to_align.empty()) return;
    int unnamed = 0;
    for (Element* b : state_.to_align) {
      if (b->Name().empty()) b->Set("name", fmt::format("aligned_body{}", unnamed++));
    }
    std::string error;
    const physics::ModelPtr model = TrialCompile(WriteString(doc_), &error);
    const mjModel* m = model.get();
    if (!m) {
      for (Element* b : state_.to_align) {
        Note(
            "freejoint.align.refused", *b,
            Tag(*b) + ": aligning its free joint needs the compiled model, which failed: " + error);
      }
      return;
    }
    for (Element* b : state_.to_align) {
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
  }
};

}  // namespace

void Replicates(State& s) { FramesPasses(s).Replicates(); }
void FlattenFrames(State& s) { FramesPasses(s).FlattenFrames(); }
void FreeJointAlign(State& s) { FramesPasses(s).FreeJointAlign(); }
void AlignFreeBodies(State& s) { FramesPasses(s).AlignFreeBodies(); }

}  // namespace urlab::mjcf::bridge
