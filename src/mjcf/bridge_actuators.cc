// The dialect bridge's actuator passes: armature/damping moved to the transmission target,
// joint/tendon actuatorfrcrange, the position/intvelocity shortcuts (kv, dampratio, timeconst,
// inheritrange), filterexact, and the order 2.2.2 wants (stateless actuators first).
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
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
using document::FormatReal;
using document::FormatReals;
using document::ParseReals;

class ActuatorsPasses : public Pass {
 public:
  using Pass::Pass;

  // ---- actuator armature / damping (3.x) move to the transmission target ----
  void ActuatorArmatureDamping() {
    for (Element* a : FindActuators()) {
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
    for (Element* d : FindActuatorDefaults()) {
      bool any = UnsetDialect(*d, "armature");
      any = UnsetDialect(*d, "damping") || any;
      if (any) {
        Note("actuator.armature_damping.default", *d,
             "default " + Tag(*d) + " armature/damping resolved into each actuator's target");
      }
    }
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
    for (Element* a : FindActuators()) {
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
    for (Element* a : FindActuators()) {
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
        state_.pending.push_back({&g, kp, ratio});
        what += "; kv from dampratio=" + FormatReal(ratio) + " is computed below";
      }
      Note(rule, g, what);
    }
    for (Element* d : FindActuatorDefaults()) {
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
    if (state_.pending.empty()) return;
    for (PendingDampRatio& p : state_.pending)
      p.actuator->SetReals("biasprm", std::array<double, 3>{0, -p.kp, 0});
    std::string error;
    const physics::ModelPtr model = TrialCompile(WriteString(doc_), &error);
    const mjModel* m = model.get();
    if (!m) {
      for (PendingDampRatio& p : state_.pending) {
        Note("position.dampratio.refused", *p.actuator,
             Tag(*p.actuator) + " dampratio needs the compiled model, which failed: " + error);
      }
      return;
    }
    const physics::DataPtr data = physics::MakeData(m);
    mjData* d = data.get();
    mj_forward(m, d);                   // qpos = qpos0
    std::vector<const Element*> order;  // actuators in compiled order
    doc_.root().Visit([&](const Element& e) {
      if (e.parent() && e.parent()->tag() == "actuator" && IsActuatorTag(e.tag())) {
        order.push_back(&e);
      }
    });
    for (int index = 0; index < static_cast<int>(order.size()) && index < m->nu; ++index) {
      for (PendingDampRatio& p : state_.pending) {
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
};

}  // namespace

void ActuatorArmatureDamping(State& s) { ActuatorsPasses(s).ActuatorArmatureDamping(); }
void ActuatorForceRanges(State& s) { ActuatorsPasses(s).ActuatorForceRanges(); }
void PositionShortcuts(State& s) { ActuatorsPasses(s).PositionShortcuts(); }
void DampRatio(State& s) { ActuatorsPasses(s).DampRatio(); }
void FilterExact(State& s) { ActuatorsPasses(s).FilterExact(); }
void OrderActuators(State& s) { ActuatorsPasses(s).OrderActuators(); }

}  // namespace urlab::mjcf::bridge
