// The dialect bridge's compiler and option passes: <compiler> settings whose 3.x meaning differs
// (autolimits, assetdir, alignfree, ...), <option>/<flag>/<size> (see docs/dialect-bridge.md).
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "mjcf/bridge_pass.h"
#include "mjcf/trial_compile.h"
#include "urlab/document/orientation.h"
#include "urlab/mjcf/writer.h"

namespace urlab::mjcf::bridge {

namespace {

namespace fs = std::filesystem;
using document::Element;
using document::ParseReals;

class CompilerOptionsPasses : public Pass {
 public:
  using Pass::Pass;

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
          state_.align_free = true;
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
        for (Element* a : FindActuators()) {
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
        // The stack is sized after a trial compile (SizeStack): 3.x's arena also holds the
        // contacts and constraints and its sparse solver needs less, so a memory sized for 3.x
        // can be too small a stack for 2.2.2, whose own estimate then applies.
        if (!s->Has("nstack") && bytes > 0) {
          state_.memory_size = s;
          state_.memory_bytes = bytes;
        }
        Note("size.memory", *s,
             "size memory=\"" + text +
                 "\" -> nstack: memory / 8 (2.2.2 sizes its stack in mjtNums) when that is more "
                 "than MuJoCo 2.2.2's own estimate for the model, otherwise 2.2.2's estimate (3.x "
                 "sizes its arena for its own solver and contacts); njmax/nconmax keep their 2.2.2 "
                 "defaults");
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
        state_.springs_off = s == "disable";
        state_.dampers_off = d == "disable";
        Note("flag.spring_damper.split", f,
             "flag spring=\"" + s + "\" damper=\"" + d +
                 "\": 2.2.2 can only switch both (flag passive), so passive stays enabled and "
                 "every joint and tendon gets " +
                 (state_.springs_off ? "stiffness" : "damping") +
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

  // ---- the stack of a model that gave 3.x a memory size ----
  void SizeStack() {
    Element* s = state_.memory_size;
    if (!s) return;
    const double words = std::min(state_.memory_bytes / 8, 2e9);
    std::string error;
    const physics::ModelPtr model = TrialCompile(WriteString(doc_), &error);
    // 2.2.2's estimate (nstack unset) holds what the model needs; a larger memory is kept.
    if (model && model->nstack >= words) return;
    s->SetInt("nstack", static_cast<int>(words));
  }
};

}  // namespace

void Compiler(State& s) {
  CompilerOptionsPasses(s).Compiler();
  s.compiler = s.doc.Compiler();  // the passes after see the settings as written
}
void SizeStack(State& s) { CompilerOptionsPasses(s).SizeStack(); }
void Options(State& s) { CompilerOptionsPasses(s).Options(); }

}  // namespace urlab::mjcf::bridge
