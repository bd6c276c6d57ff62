// The dialect bridge's passive-force passes: body gravcomp, dead-band tendon springs (both
// computed by the runtime through mjcb_passive) and the spring/damper flags 3.x split.
#include <mujoco/mujoco.h>

#include "mjcf/bridge_pass.h"
#include "urlab/document/orientation.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Element;
using document::FormatReal;
using document::FormatReals;
using document::ParseReals;

class PassiveForcesPasses : public Pass {
 public:
  using Pass::Pass;

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
    if (!state_.springs_off && !state_.dampers_off) return;
    const char* attr = state_.springs_off ? "stiffness" : "damping";
    int n = 0;
    for (Element* e : Find({"joint", "fixed", "spatial"})) {
      if (e->tag() == "joint" && (!e->parent() || e->parent()->tag() != "body")) continue;
      if (ResolveReal(*e, attr, 0) == 0) continue;
      e->SetReal(attr, 0);
      ++n;
    }
    if (state_.springs_off && !report_.deadband_springs.empty()) {
      n += static_cast<int>(report_.deadband_springs.size());
      report_.deadband_springs.clear();
    }
    Element* f = doc_.root().FirstChild("option");
    Note("flag.spring_damper.split", f ? *f : doc_.root(),
         std::string(attr) + " set to 0 on " + std::to_string(n) + " joint(s)/tendon(s) (flag " +
             (state_.springs_off ? "spring" : "damper") + " disabled)");
  }
};

}  // namespace

void GravityCompensation(State& s) { PassiveForcesPasses(s).GravityCompensation(); }
void SpringLength(State& s) { PassiveForcesPasses(s).SpringLength(); }
void PassiveFlags(State& s) { PassiveForcesPasses(s).PassiveFlags(); }

}  // namespace urlab::mjcf::bridge
