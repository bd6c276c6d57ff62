// The dialect bridge's driver: detection of MuJoCo 3.x documents and the pass table, which runs
// the construct families' passes (bridge_pass.h) in one documented order.
#include "urlab/mjcf/bridge.h"

#include <algorithm>

#include "mjcf/bridge_pass.h"

namespace urlab::mjcf {

using document::Attribute;
using document::CompilerSettings;
using document::Document;
using document::Element;
using Kind = BridgeChange::Kind;

namespace bridge {

namespace {

class Detection : public Pass {
 public:
  using Pass::Pass;

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
};

// The passes in the order they run. Constructs are rewritten before what reads them: the compiler
// settings first (autolimits, assetdir, angle units), then the passes that change the body tree
// (attach, replicate, frame: everything after sees plain bodies), then per construct family; the
// generic attribute policies and the leftovers come after every pass that consumes 3.x
// attributes. The last four need a trial compile of the bridged model, so they run only when
// nothing was refused.
// clang-format off
constexpr PassEntry kPasses[] = {
    // name                      file                              function                     after refusals
    {"Compiler",                 "src/mjcf/bridge_compiler.cc",    &Compiler,                   false},
    {"Attachments",              "src/mjcf/bridge_attach.cc",      &Attachments,                false},
    {"Replicates",               "src/mjcf/bridge_frames.cc",      &Replicates,                 false},
    {"FlattenFrames",            "src/mjcf/bridge_frames.cc",      &FlattenFrames,              false},
    {"FreeJointAlign",           "src/mjcf/bridge_frames.cc",      &FreeJointAlign,             false},
    {"SiteEqualities",           "src/mjcf/bridge_constraints.cc", &SiteEqualities,             false},
    {"ActuatorArmatureDamping",  "src/mjcf/bridge_actuators.cc",   &ActuatorArmatureDamping,    false},
    {"GravityCompensation",      "src/mjcf/bridge_passive.cc",     &GravityCompensation,        false},
    {"ActuatorForceRanges",      "src/mjcf/bridge_actuators.cc",   &ActuatorForceRanges,        false},
    {"PositionShortcuts",        "src/mjcf/bridge_actuators.cc",   &PositionShortcuts,          false},
    {"Options",                  "src/mjcf/bridge_compiler.cc",    &Options,                    false},
    {"FilterExact",              "src/mjcf/bridge_actuators.cc",   &FilterExact,                false},
    {"PolyCoef",                 "src/mjcf/bridge_constraints.cc", &PolyCoef,                   false},
    {"SpringLength",             "src/mjcf/bridge_passive.cc",     &SpringLength,               false},
    {"PassiveFlags",             "src/mjcf/bridge_passive.cc",     &PassiveFlags,               false},
    {"VisualOnly",               "src/mjcf/bridge_assets.cc",      &VisualOnly,                 false},
    {"KeepVisualGeoms",          "src/mjcf/bridge_assets.cc",      &KeepVisualGeoms,            false},
    {"MeshInertia",              "src/mjcf/bridge_assets.cc",      &MeshInertia,                false},
    {"GenericAttributes",        "src/mjcf/bridge_attributes.cc",  &GenericAttributes,          false},
    {"Sensors",                  "src/mjcf/bridge_sensors.cc",     &Sensors,                    false},
    {"ComputedSensors",          "src/mjcf/bridge_sensors.cc",     &ComputedSensors,            false},
    {"OrderActuators",           "src/mjcf/bridge_actuators.cc",   &OrderActuators,             false},
    {"Leftovers",                "src/mjcf/bridge_attributes.cc",  &Leftovers,                  false},
    {"AlignFreeBodies",          "src/mjcf/bridge_frames.cc",      &AlignFreeBodies,            true},
    {"DampRatio",                "src/mjcf/bridge_actuators.cc",   &DampRatio,                  true},
    {"PadKeyframes",             "src/mjcf/bridge_keyframes.cc",   &PadKeyframes,               true},
    {"SizeStack",                "src/mjcf/bridge_compiler.cc",    &SizeStack,                  true},
};
// clang-format on

void Run(Document& doc, BridgeReport& report) {
  State state(doc, report);
  report.dialect = Detection(state).DetectDialect();
  if (!report.dialect) return;
  state.compiler = doc.Compiler();
  for (const PassEntry& pass : kPasses) {
    if (pass.only_without_refusals && report.HasRefusals()) continue;
    pass.run(state);
  }
}

}  // namespace

std::span<const PassEntry> Passes() { return kPasses; }

}  // namespace bridge

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
  bridge::Run(doc, report);
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
