#pragma once
// The dialect bridge: MJCF written for MuJoCo 3.x, read with the 3.x additions of the grammar
// (grammar_dialect_table.cc), rewritten in place into MJCF that MuJoCo 2.2.2 compiles to the same
// physics. Every change is reported with the source file and line of the element it concerns:
//
//   translated    exact: the 2.2.2 model behaves as 3.x would (or the difference is stated)
//   approximated  close but not identical; the message says how
//   dropped       no effect on this engine (render-only, removed features, metadata)
//   refused       would silently change the physics; the document is left unusable
//
// Documents that use nothing from the 3.x dialect are not touched (ApplyBridge is a no-op, the
// report is empty and the document stays bit-exact). docs/dialect-bridge.md lists every
// construct, what happens to it and why.
//
// Thread: plain function over a document the caller owns. Translating `dampratio` compiles a
// trial copy of the model with MuJoCo (no global state other than MuJoCo's handlers).
#include <array>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/document/document.h"

namespace urlab::mjcf {

struct BridgeChange {
  enum class Kind { kTranslated, kApproximated, kDropped, kRefused };
  Kind kind = Kind::kTranslated;
  SourceLocation where;
  std::string what;
  std::string rule;  // id of the BridgeRules() row that made this change
};

namespace bridge {
struct State;  // the passes' shared state (src/mjcf/bridge_pass.h)
}
// A pass of the bridge: one function per construct family step (src/mjcf/bridge_pass.h).
using BridgePassFn = void (*)(bridge::State&);

// One rule of the bridge (the rule table, src/mjcf/bridge_rules.cc): a MuJoCo 3.x construct, what
// the bridge does with it and the pass(es) that do it, named by their functions (so a row cannot
// name a pass that does not exist), or `elsewhere` for the one rule applied outside the bridge
// (mesh face orientation, by the mesh preparation).
struct BridgeRule {
  const char* id;
  const char* construct;
  BridgeChange::Kind kind;
  std::array<BridgePassFn, 2> passes;  // unused slots nullptr
  const char* elsewhere = nullptr;     // "FILE Function" of a rule applied outside the bridge
};

// The rule's passes by name ("FlattenFrames", "Compiler, FreeJointAlign"), or `elsewhere`.
std::string BridgeRulePasses(const BridgeRule& rule);
// The same with their files ("src/mjcf/bridge_frames.cc FlattenFrames"), or `elsewhere`.
std::string BridgeRuleFunction(const BridgeRule& rule);

// Every rule, in the order the bridge applies them.
std::span<const BridgeRule> BridgeRules();

// "translated", "approximated", "dropped", "refused".
const char* BridgeKindName(BridgeChange::Kind kind);

// A 3.x sensor the bridge turned into a 2.2.2 <user> sensor of the same name; the runtime must
// compute it (physics/software_sensors.h).
struct BridgedSensor {
  enum class Kind {
    kJointActuatorForce,
    kTendonActuatorForce,
    kKineticEnergy,
    kPotentialEnergy,
    kInsideSite,
    kContact
  };
  std::string name;
  Kind kind = Kind::kJointActuatorForce;
  std::string target;  // joint or tendon name (actuator forces)
  // insidesite/contact: the 3.x attributes (site, objtype, objname, geom1, ..., num, data,
  // reduce); names the runtime resolves are listed in `references`.
  std::map<std::string, std::string> params;
};

// A body with 3.x gravity compensation; the runtime adds the force through mjcb_passive
// (physics/software_sensors.h, GravityCompensationSpec).
struct BridgedGravcomp {
  std::string body;
  double gravcomp = 0;
};

// A 3.x equality constraint on sites (connect/weld with site1/site2), written as the 2.2.2
// body-based constraint `equality`; its anchors and relative pose are set from the compiled
// sites' frames after compilation (physics/software_sensors.h, SiteEqualitySpec).
struct BridgedSiteEquality {
  std::string equality;
  std::string site1, site2;
};

// A tendon spring with a 3.x dead band (springlength="lo hi"); the 2.2.2 tendon gets stiffness 0
// and the runtime adds the force through mjcb_passive (physics/software_sensors.h).
struct BridgedDeadbandSpring {
  std::string tendon;
  double stiffness = 0, lo = 0, hi = 0;
};

struct BridgeReport {
  bool dialect = false;  // the document used 3.x constructs (so 3.x defaults were applied)
  std::vector<BridgeChange> changes;
  std::vector<BridgedSensor> software_sensors;
  std::vector<BridgedGravcomp> gravcomp;
  std::vector<BridgedSiteEquality> site_equalities;
  std::vector<BridgedDeadbandSpring> deadband_springs;

  bool HasRefusals() const;
  // Every refusal as an error (file:line: message).
  std::vector<InputError> Refusals() const;
  // One line per change: "file:line: <kind> [<rule id>]: <what>".
  std::string Format() const;
};

struct BridgeOptions {
  // Throw after the whole document was examined when something was refused: the InputError
  // names the first refusal and counts the others. When false, refusals are only reported.
  bool throw_on_refusal = true;
};

// Rewrites `doc` into MuJoCo 2.2.2 MJCF (see the file comment). Throws InputError for malformed
// values, and for refusals unless options say otherwise.
BridgeReport ApplyBridge(document::Document& doc, const BridgeOptions& options = {});

}  // namespace urlab::mjcf
