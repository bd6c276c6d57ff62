// The dialect bridge's rule table and attribute policies (see bridge_rules.h). One row per rule:
// id, the MuJoCo 3.x construct, what the bridge does with it (kind), and the pass(es) applying it
// (functions of bridge_pass.h, so the compiler checks them; "elsewhere" for the one rule applied
// outside the bridge). docs/dialect-bridge.md explains each construct; `urlab validate
// --bridge-report` names the rule of every change it lists.
#include "mjcf/bridge_rules.h"

#include <algorithm>
#include <string>

#include "mjcf/bridge_pass.h"
#include "urlab/core/error.h"

namespace urlab::mjcf {

namespace {

using K = BridgeChange::Kind;
constexpr K kT = K::kTranslated;
constexpr K kA = K::kApproximated;
constexpr K kD = K::kDropped;
constexpr K kR = K::kRefused;

// clang-format off
constexpr BridgeRule kRules[] = {
    // id                                construct                                            kind  passes
    {"compiler.autolimits",             "compiler autolimits (3.x default true)",            kT, {&bridge::Compiler}},
    {"compiler.assetdir",               "compiler assetdir",                                 kT, {&bridge::Compiler}},
    {"compiler.alignfree",              "compiler alignfree=\"true\"",                       kT, {&bridge::Compiler, &bridge::FreeJointAlign}},
    {"compiler.alignfree.false",        "compiler alignfree=\"false\"",                      kD, {&bridge::Compiler}},
    {"compiler.saveinertial",           "compiler saveinertial",                             kD, {&bridge::Compiler}},
    {"compiler.conflict",               "compiler conflict",                                 kD, {&bridge::Compiler}},
    {"compiler.discardvisual",          "compiler discardvisual=\"true\"",                   kT, {&bridge::KeepVisualGeoms}},
    {"compiler.lengthrange.interval",   "lengthrange interval",                              kT, {&bridge::Compiler}},
    {"attach",                          "<attach model body|frame prefix> of a <model>",    kT, {&bridge::Attachments}},
    {"attach.model",                    "<model> asset",                                     kT, {&bridge::Attachments}},
    {"attach.defaults",                 "<attach> under a parent with top-level defaults",   kA, {&bridge::Attachments}},
    {"attach.keyframe",                 "keyframes of an attached model",                    kT, {&bridge::Attachments, &bridge::PadKeyframes}},
    {"attach.refused",                  "self-attachment, keys of a child that fails alone", kR, {&bridge::Attachments}},
    {"replicate",                       "<replicate> count/offset/euler/sep",                kT, {&bridge::Replicates}},
    {"replicate.reference",             "element referring into a <replicate>",              kT, {&bridge::Replicates}},
    {"replicate.invalid",               "<replicate> without a positive count",              kR, {&bridge::Replicates}},
    {"frame",                           "<frame>",                                           kT, {&bridge::FlattenFrames}},
    {"frame.child",                     "element that cannot move inside a posed <frame>",   kR, {&bridge::FlattenFrames}},
    {"equality.site",                   "equality connect site1/site2",                      kT, {&bridge::SiteEqualities}},
    {"equality.site.weld",              "equality weld site1/site2",                         kA, {&bridge::SiteEqualities}},
    {"freejoint.align",                 "freejoint align (simple free body)",                kT, {&bridge::FreeJointAlign, &bridge::AlignFreeBodies}},
    {"freejoint.align.nochildren",      "freejoint align on a body with child bodies",       kD, {&bridge::FreeJointAlign}},
    {"freejoint.align.refused",         "freejoint align with body-frame equality anchors",  kR, {&bridge::FreeJointAlign, &bridge::AlignFreeBodies}},
    {"equality.weld",                   "equality weld on bodies (3.x's weld rows)",         kA, {&bridge::SiteEqualities}},
    {"equality.site.refused",           "equality with only one of site1/site2",             kR, {&bridge::SiteEqualities}},
    {"actuator.armature_damping",       "actuator armature/damping on a joint or tendon",    kT, {&bridge::ActuatorArmatureDamping}},
    {"actuator.armature_damping.default", "default actuator armature/damping",               kT, {&bridge::ActuatorArmatureDamping}},
    {"actuator.armature_damping.refused", "actuator polynomial damping, other transmissions", kR, {&bridge::ActuatorArmatureDamping}},
    {"gravcomp",                        "body gravcomp",                                     kT, {&bridge::GravityCompensation}},
    {"gravcomp.zero",                   "body gravcomp=\"0\"",                               kD, {&bridge::GravityCompensation}},
    {"gravcomp.actuator",               "joint actuatorgravcomp=\"true\"",                   kT, {&bridge::GravityCompensation}},
    {"gravcomp.actuator.clamped",       "joint actuatorgravcomp with actuatorfrcrange",      kA, {&bridge::GravityCompensation}},
    {"actuatorfrcrange.one",            "joint/tendon actuatorfrcrange, one actuator",       kT, {&bridge::ActuatorForceRanges}},
    {"actuatorfrcrange.inactive",       "actuatorfrcrange never active or disabled",         kD, {&bridge::ActuatorForceRanges}},
    {"actuatorfrcrange.refused",        "actuatorfrcrange shared by actuators, invalid",     kR, {&bridge::ActuatorForceRanges}},
    {"actuatorfrcrange.default",        "default actuatorfrcrange",                          kT, {&bridge::ActuatorForceRanges}},
    {"position.shortcut",               "position/intvelocity kv, timeconst",                kT, {&bridge::PositionShortcuts}},
    {"position.timeconst.rk4",          "position timeconst with RK4",                       kA, {&bridge::PositionShortcuts}},
    {"position.inheritrange",           "position/intvelocity inheritrange",                 kT, {&bridge::PositionShortcuts}},
    {"position.refused",                "kv with dampratio, negative values, bad inheritrange", kR, {&bridge::PositionShortcuts}},
    {"position.default",                "default kv/dampratio/timeconst/inheritrange",       kT, {&bridge::PositionShortcuts}},
    {"position.dampratio",              "position/intvelocity dampratio",                    kT, {&bridge::DampRatio}},
    {"position.dampratio.refused",      "dampratio when the trial compile fails",            kR, {&bridge::DampRatio}},
    {"option.approximated",             "option ls_iterations/ls_tolerance",                 kA, {&bridge::Options}},
    {"option.dropped",                  "option sdf_*, sleep_tolerance",                     kD, {&bridge::Options}},
    {"option.ccd",                      "option ccd_iterations/ccd_tolerance",               kA, {&bridge::Options}},
    {"option.actuatorgroupdisable",     "option actuatorgroupdisable (no actuator hit)",     kD, {&bridge::Options}},
    {"option.actuatorgroupdisable.refused", "option actuatorgroupdisable",                   kR, {&bridge::Options}},
    {"option.o_friction",               "option o_friction without override",                kD, {&bridge::Options}},
    {"option.o_friction.refused",       "option o_friction with override",                   kR, {&bridge::Options}},
    {"option.implicitfast",             "option integrator=\"implicitfast\"",                kA, {&bridge::Options}},
    {"size.memory",                     "size memory",                                       kA, {&bridge::Options, &bridge::SizeStack}},
    {"flag.spring_damper",              "flag spring/damper equal",                          kT, {&bridge::Options}},
    {"flag.spring_damper.split",        "flag spring/damper different",                      kT, {&bridge::Options, &bridge::PassiveFlags}},
    {"actuator.filterexact",            "general dyntype=\"filterexact\"",                   kT, {&bridge::FilterExact}},
    {"actuator.filterexact.rk4",        "general dyntype=\"filterexact\" with RK4",          kA, {&bridge::FilterExact}},
    {"actuator.filterexact.default",    "default general dyntype=\"filterexact\"",           kT, {&bridge::FilterExact}},
    {"actuator.filterexact.refused",    "filterexact without a positive time constant",      kR, {&bridge::FilterExact}},
    {"equality.polycoef",               "equality joint/tendon polycoef with < 5 numbers",   kT, {&bridge::PolyCoef}},
    {"tendon.springlength.deadband",    "tendon springlength=\"lo hi\" (dead band)",         kT, {&bridge::SpringLength}},
    {"tendon.springlength.single",      "tendon springlength=\"x x\"",                       kT, {&bridge::SpringLength}},
    {"tendon.springlength.nostiffness", "tendon springlength=\"lo hi\" without stiffness",   kD, {&bridge::SpringLength}},
    {"tendon.springlength.refused",     "tendon springlength with lo > hi",                  kR, {&bridge::SpringLength}},
    {"tendon.springlength.default",     "default tendon springlength=\"lo hi\"",             kT, {&bridge::SpringLength}},
    {"material.layer",                  "<material><layer>",                                 kD, {&bridge::VisualOnly}},
    {"flag.default",                    "flag autoreset/diagexact/.../sleep at 3.x default", kD, {&bridge::Options}},
    {"flag.other",                      "flag autoreset/diagexact/.../sleep otherwise",      kA, {&bridge::Options}},
    {"mesh.shell",                      "mesh inertia=\"shell\"",                            kR, {&bridge::MeshInertia}},
    {"mesh.inertia",                    "mesh inertia legacy/convex/exact",                  kT, {&bridge::MeshInertia}},
    {"mesh.exactmeshinertia",           "mesh volumes (all exact or inline)",                kT, {&bridge::MeshInertia}},
    {"mesh.exactmeshinertia.nonconvex", "mesh volumes (files that may be non-convex)",       kA, {&bridge::MeshInertia}},
    {"mesh.orientation",                "mesh file whose faces disagree (or face inwards)",  kT, {}, "src/convert/mesh_assets.cc OrientedFile"},
    {"light.directional",               "light type=\"directional\"",                        kT, {&bridge::GenericAttributes}},
    {"camera.intrinsics",               "camera sensorsize/focal/focalpixel/resolution",     kT, {&bridge::GenericAttributes}},
    {"camera.principal",                "camera principal/principalpixel",                   kA, {&bridge::GenericAttributes}},
    {"sensor.actuatorfrc",              "sensor jointactuatorfrc/tendonactuatorfrc",         kT, {&bridge::Sensors}},
    {"sensor.unnamed",                  "unnamed software sensor",                           kT, {&bridge::Sensors}},
    {"sensor.refused",                  "sensor without its target, invalid data/num",       kR, {&bridge::Sensors, &bridge::ComputedSensors}},
    {"sensor.computed",                 "sensor e_kinetic/e_potential/insidesite/contact",   kT, {&bridge::ComputedSensors}},
    {"sensor.contact.netforce",         "contact sensor reduce=\"netforce\"",                kR, {&bridge::ComputedSensors}},
    {"actuator.order",                  "stateful actuators before stateless ones",          kT, {&bridge::OrderActuators}},
    {"keyframe.pad",                    "<key> shorter than the model",                      kT, {&bridge::PadKeyframes}},
    {"leftover",                        "any other 3.x element or attribute",                kR, {&bridge::Leftovers}},
    {"refused.element",                 "flexcomp, deformable, extension, plugin",           kR, {&bridge::Leftovers}},
    {"refused.sdf",                     "geom type=\"sdf\"",                                 kR, {&bridge::Leftovers}},
    // attribute policies (AttributePolicies below), applied by GenericAttribute
    {"attr.dropped",                    "3.x attribute without effect here",                 kD, {&bridge::GenericAttributes}},
    {"attr.approximated",               "3.x attribute approximated",                        kA, {&bridge::GenericAttributes}},
    {"attr.refused",                    "3.x attribute changing the physics",                kR, {&bridge::GenericAttributes}},
};

constexpr AttributePolicy kPolicies[] = {
    // elements                      attributes        condition                       values        rule_if             why_if                                           rule_else             why_else
    {"<sensor>",                     "nsample interp", AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "only used with delay",                          nullptr,              nullptr},
    {"<sensor>",                     "delay interval", AttributeCondition::kZero,      nullptr,      "attr.dropped",     "zero",                                          "attr.approximated",  "the sensor reads the current value every step (no delay or interval in 2.2.2)"},
    {"<actuator>",                   "nsample interp", AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "only used with delay",                          nullptr,              nullptr},
    {"<actuator>",                   "delay",          AttributeCondition::kZero,      nullptr,      "attr.dropped",     "zero",                                          "attr.refused",       "actuator delay changes the physics"},
    {"<actuator>",                   "actearly",       AttributeCondition::kValueIn,   "false",      "attr.dropped",     "2.2.2's behaviour",                             "attr.approximated",  "forces use the current activation (one step later than actearly)"},
    {"<actuator>",                   "actdim",         AttributeCondition::kValueIn,   "0|1",        "attr.dropped",     "implied by dyntype",                            "attr.refused",       "vector activations"},
    {"intvelocity",                  "actlimited",     AttributeCondition::kValueIn,   "true",       "attr.dropped",     "intvelocity is always activation-limited in 2.2.2", "attr.refused",   "an unlimited intvelocity"},
    {"muscle",                       "tausmooth",      AttributeCondition::kZero,      nullptr,      "attr.dropped",     "zero",                                          "attr.refused",       "muscle tausmooth"},
    {"<actuator>",                   "*",              AttributeCondition::kAlways,    nullptr,      "attr.refused",     "no 2.2.2 equivalent for this actuator attribute", nullptr,            nullptr},
    {"material",                     "metallic roughness", AttributeCondition::kAlways, nullptr,     "attr.dropped",     "physically based rendering parameter; render-only", nullptr,          nullptr},
    {"texture",                      "colorspace nchannel content_type", AttributeCondition::kAlways, nullptr, "attr.dropped", "texture decoding hint; render-only", nullptr,              nullptr},
    {"mesh hfield",                  "content_type",   AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "the file extension gives the format",           nullptr,              nullptr},
    {"mesh",                         "maxhullvert",    AttributeCondition::kAlways,    nullptr,      "attr.approximated", "2.2.2 uses the full convex hull for collisions", nullptr,             nullptr},
    {"mesh",                         "material",       AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "default material for geoms; render-only",       nullptr,              nullptr},
    {"light",                        "type",           AttributeCondition::kValueIn,   "spot",       "attr.dropped",     "2.2.2 lights are spot lights unless directional", "attr.approximated", "2.2.2 has no such light type; rendered as a spot light (render-only)"},
    {"light",                        "*",              AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "physically based lighting parameter; render-only", nullptr,           nullptr},
    {"camera",                       "output",         AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "camera output channels; render-only",           nullptr,              nullptr},
    {"camera",                       "projection",     AttributeCondition::kValueIn,   "perspective", "attr.dropped",    "2.2.2 cameras are perspective",                 "attr.approximated",  "orthographic cameras render in perspective"},
    {"global rgba scale",            "*",              AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "visualisation only",                            nullptr,              nullptr},
    {"body",                         "sleep simple",   AttributeCondition::kAlways,    nullptr,      "attr.dropped",     "a 3.x simulation optimisation hint",            nullptr,              nullptr},
    {"joint",                        "actuatorgravcomp", AttributeCondition::kValueIn, "false",      "attr.dropped",     "2.2.2's behaviour",                             "attr.dropped",       "without body gravcomp it has no effect"},
    {"fixed spatial tendon",         "armature",       AttributeCondition::kZero,      nullptr,      "attr.dropped",     "zero",                                          "attr.refused",       "tendon armature (3.3+: inertia on the tendon's length) does not exist in 2.2.2; nearest 2.2.2 construct: armature on the tendon's joints (a fixed tendon over one joint with coef c: c^2 x armature)"},
    {"geom",                         "adhesion surfacevel", AttributeCondition::kZero, nullptr,      "attr.dropped",     "zero",                                          "attr.refused",       "this contact feature does not exist in 2.2.2"},
    {"pair",                         "solreffriction adhesion", AttributeCondition::kZero, nullptr,  "attr.dropped",     "zero means the 2.2.2 behaviour",                "attr.refused",       "no 2.2.2 equivalent"},
    {"freejoint joint",              "align",          AttributeCondition::kValueIn,   "false",      "attr.dropped",     "2.2.2's behaviour",                             "attr.refused",       "not a value of align (true, false, auto)"},
    {"rangefinder",                  "data",           AttributeCondition::kValueIn,   "dist",       "attr.dropped",     "the 2.2.2 output",                              "attr.refused",       "rangefinder outputs"},
    {"rangefinder",                  "camera",         AttributeCondition::kAlways,    nullptr,      "attr.refused",     "rangefinders mounted on cameras do not exist in 2.2.2", nullptr,       nullptr},
};
constexpr RefusedElement kRefused[] = {
    {"flexcomp", "deformable bodies (flex objects with elasticity, 3.0+) do not exist in MuJoCo 2.2.2",
     "nearest 2.2.2 construct: <composite> (grid, cloth, box or particle) of rigid bodies joined by tendons or joints"},
    {"deformable", "flex objects (3.0+) do not exist in MuJoCo 2.2.2",
     "nearest 2.2.2 construct: <composite> of rigid bodies; a plain <skin> for rendering"},
    {"extension", "engine plugins (SDF colliders, elasticity, actuators, sensors; 2.3+) cannot be loaded by MuJoCo 2.2.2",
     "nearest 2.2.2 construct: a mesh geom (its convex hull collides) for an SDF shape"},
    {"plugin", "engine plugins (2.3+) cannot be loaded by MuJoCo 2.2.2",
     "nearest 2.2.2 construct: a mesh geom for an SDF shape, a <user> sensor or actuator for the rest"},
};
// clang-format on

}  // namespace

std::span<const RefusedElement> RefusedElements() { return kRefused; }

std::span<const BridgeRule> BridgeRules() { return kRules; }

namespace {

// The names of the rule's passes, with their files when `files` ("" when a pass is missing from
// the pass table: bridge_test checks that none is).
std::string PassNames(const BridgeRule& rule, bool files) {
  if (rule.elsewhere) return rule.elsewhere;
  std::string out;
  for (BridgePassFn fn : rule.passes) {
    if (!fn) continue;
    const auto passes = bridge::Passes();
    const auto p = std::find_if(passes.begin(), passes.end(),
                                [&](const bridge::PassEntry& e) { return e.run == fn; });
    if (p == passes.end()) continue;
    if (!out.empty()) out += ", ";
    if (files) {
      out += p->file;
      out += " ";
    }
    out += p->name;
  }
  return out;
}

}  // namespace

std::string BridgeRulePasses(const BridgeRule& rule) { return PassNames(rule, false); }

std::string BridgeRuleFunction(const BridgeRule& rule) { return PassNames(rule, true); }

std::span<const AttributePolicy> AttributePolicies() { return kPolicies; }

const BridgeRule& FindBridgeRule(std::string_view id) {
  const auto* it = std::find_if(std::begin(kRules), std::end(kRules),
                                [&](const BridgeRule& r) { return id == r.id; });
  if (it == std::end(kRules)) {
    throw Error("dialect bridge: no rule '" + std::string(id) + "' in the rule table");
  }
  return *it;
}

}  // namespace urlab::mjcf
