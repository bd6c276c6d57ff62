// The dialect bridge checked against MuJoCo 3.x itself. Every model of the 3.x corpus
// (tests/data/mjcf/dialect3x and the robot-style models in tests/data/mjcf/robots) is loaded
//  - here as `urlab compile FILE.xml` loads a single file (reader, ApplyBridge, writer, compile
//    from the in-memory VFS: world::BuildModel's steps) on MuJoCo 2.2.2, and
//  - by the official MuJoCo 3.x WebAssembly build (npm package mujoco-js, run by Node.js through
//    tests/mjcf/reference3x/dump3x.mjs; one node process for the whole corpus) from the original
//    file,
// and what both compile (masses, inertias, ranges, gains, friction, options, keyframes...), the
// joint forces of an actuation probe, the activations after 20 probe steps and a 500-step
// zero-control trajectory are compared entity by entity, by name, within the tolerances below.
// It prints one table: per quantity, the largest relative difference over the corpus.
//
// The reference is found in $URLAB_MUJOCO_JS or the build's mujoco-js folder; without it (or
// without node) the test is skipped with the command that installs it.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "mujoco_test.h"
#include "urlab/convert/mesh_assets.h"
#include "urlab/mjcf/bridge.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"
#include "urlab/physics/software_sensors.h"
#include "urlab/world/scene.h"

#ifndef URLAB_MUJOCO_JS_DIR
#define URLAB_MUJOCO_JS_DIR ""
#endif

namespace urlab {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kSteps = 500;         // zero-control trajectory length
constexpr int kRecordEvery = 25;    // trajectory samples compared (20 per joint)
constexpr int kProbeActSteps = 20;  // steps of probe control before activations are compared

// ---------------------------------------------------------------------------------------------
// Data: what the comparison allows, and why.

// Attributes of the corpus newer than the reference (mujoco-js 0.0.7 is MuJoCo 3.3.8, whose
// parser rejects them). They are removed from the reference's copy of the files. Those without
// effect on the compiled physics stay in our input (the bridge's handling of them is part of what
// is checked); those with an effect are removed from our input too, so the rest of the model is
// still compared against 3.x, and their translation is checked by bridge_test.cc alone.
struct NewerAttribute {
  const char* element;
  const char* attribute;
  bool affects_physics;
  const char* reason;
};
constexpr NewerAttribute kNewerThanReference[] = {
    {"position", "armature", true,
     "actuator armature (MuJoCo 3.5): the bridge adds gear^2 * armature to the joint "
     "(bridge_test ActuatorArmatureAndDampingMoveToTheJoint)"},
    {"position", "damping", true,
     "actuator damping (MuJoCo 3.5): the bridge adds gear^2 * damping to the joint (same test)"},
    {"gyro", "nsample", false, "sensor delay buffers (3.4+): sensors only, not compared"},
    {"gyro", "interp", false, "sensor delay buffers (3.4+): sensors only, not compared"},
    {"gyro", "delay", false, "sensor delay (3.4+), zero here"},
    {"framequat", "nsample", false, "sensor delay buffers (3.4+): sensors only"},
    {"tendonpos", "interval", false, "sensor interval (3.4+), zero here"},
    {"jointpos", "delay", false, "sensor delay (3.4+), zero here"},
    {"jointpos", "interval", false, "sensor interval (3.4+), zero here"},
    {"motor", "delay", false, "actuator delay (3.4+), zero here"},
    {"motor", "nsample", false, "actuator delay buffer (3.4+), zero here"},
    {"option", "sleep_tolerance", false, "island sleeping (3.4+); sleep is disabled here"},
    {"flag", "sleep", false, "island sleeping (3.4+), disabled here"},
    {"body", "sleep", false, "island sleeping (3.4+) hint; sleep is disabled"},
    {"geom", "adhesion", false, "contact adhesion (3.4+), zero here"},
    {"light", "softness", false, "render-only (3.4+)"},
    {"camera", "projection", false, "render-only (3.4+), perspective here"},
    {"rangefinder", "data", false, "rangefinder outputs (3.4+), the 2.2.2 output here"},
};

// Where MuJoCo 3.3.8 departs from the documented 3.x behaviour the bridge follows, the
// reference's copy of the files spells out the documented value: attribute="value" is added to
// every `element` that has `if_present` and lacks `attribute`.
struct ReferenceFix {
  const char* element;
  const char* attribute;
  const char* value;
  const char* if_present;
  const char* reason;
};
constexpr const char* kTendonAutoLimits =
    "tendon actuatorfrclimited defaults to \"auto\" (clamp when actuatorfrcrange is set under "
    "autolimits, the corpus's setting) as documented; 3.3.8 defaulted it to false "
    "(google-deepmind/mujoco#3573), so its tendon clamps were off";
constexpr ReferenceFix kReferenceFixes[] = {
    {"fixed", "actuatorfrclimited", "true", "actuatorfrcrange", kTendonAutoLimits},
    {"spatial", "actuatorfrclimited", "true", "actuatorfrcrange", kTendonAutoLimits},
    {"tendon", "actuatorfrclimited", "true", "actuatorfrcrange", kTendonAutoLimits},
};

// Constructs newer than the reference (3.3.8's parser rejects them): the reference loads, instead
// of the model, a file next to it that writes out what the 3.x XML reference defines the
// construct to mean, in MJCF 3.3.8 loads.
struct ReferenceInput {
  const char* model;
  const char* file;
  const char* reason;
};
constexpr ReferenceInput kReferenceInputs[] = {
    {"bridge3x/attach/frame_parent", "frame_parent.expanded3x",
     "<attach frame=> (after 3.3.8): the frame with its pose, childclass and contents at the "
     "attachment point, names and classes prefixed, referring elements and keys appended"},
};

// Properties of a reference entity that select a tolerance or a known difference.
enum class When {
  kAlways,
  kTargetHasActuatorFrcRange,  // the actuator's joint/tendon has a 3.x actuatorfrcrange
  kJointHasActuatorFrcRange,   // the actuator's joint has a 3.x actuatorfrcrange
  kFilterExact,                // the 3.x actuator has dyntype filterexact (position timeconst)
  kImplicitFast,               // the 3.x model uses integrator implicitfast
  kMeshGeom,                   // a mesh geom
  kHfieldGeom,                 // a height field geom
  kBodyWithMesh,               // a body with a mesh geom (mass properties may come from it)
  kDofMovesMesh,               // a joint's dofs move a body with a mesh geom (its subtree has one)
};

// Tolerances: the first row whose quantity ("category.field", a category, or "*") matches and
// whose condition holds. A value (the vector of one field of one entity) passes when
// |ours - ref|inf <= atol + rtol * scale; scale is max(|ours|inf, |ref|inf), except for
// trajectories (below). The relative difference reported is |ours - ref|inf / max(scale, atol).
struct Tolerance {
  const char* quantity;
  When when;
  double rtol;
  double atol;
  const char* reason;
};
constexpr const char* kFloatMesh =
    "mesh vertices are single precision in both engines and the compilers sum volume, centroid "
    "and inertia in different orders and frames: agreement to float precision (~1e-7)";
constexpr Tolerance kTolerances[] = {
    {"camera.fovy", When::kAlways, 1e-7, 1e-12,
     "3.x keeps camera sensorsize/focal in single precision, so the fovy it derives from them "
     "carries float rounding (~5e-8 relative); render-only"},
    {"geom", When::kMeshGeom, 1e-6, 1e-9, kFloatMesh},
    {"body", When::kBodyWithMesh, 1e-6, 1e-12, kFloatMesh},
    {"dof.M0", When::kDofMovesMesh, 1e-6, 1e-12, kFloatMesh},
    {"trajectory", When::kAlways, 1e-6, 1e-9,
     "zero-control trajectory without contacts, 500 steps: the same equations of motion "
     "(actuators, limits, passive forces, equalities, integrator) in both engines; round-off "
     "grown over 500 steps (observed: ~1e-11); relative to the joint's largest |value| over the "
     "trajectory"},
    {"contact_trajectory", When::kAlways, 1e-3, 1e-9,
     "the same with contacts: 2.2.2 and 3.x share the contact model, not its code (3.x changed "
     "the contact solver's details, collision pairs' order and warm start), so contact forces "
     "differ near the solver tolerance and the differences grow with the motion; 1e-3 of the "
     "joint's range of motion. Models whose contacts are chaotic or ill-posed are listed in "
     "kContactTrajectoryNotCompared"},
    {"trajectory_sensor", When::kAlways, 1e-6, 1e-9,
     "sensors along the contact-free trajectory (bridge corpus): as the trajectory; relative to "
     "the sensor's largest |value| over the trajectory"},
    {"contact_trajectory_sensor", When::kAlways, 1e-3, 1e-9,
     "sensors along the trajectory with contacts (bridge corpus): as contact_trajectory"},
    {"*", When::kAlways, 1e-9, 1e-12,
     "compiled quantities: both engines evaluate the same double-precision formulas from the "
     "same text (the bridge writes shortest round-trip decimals); 1e-9 is ~1e7 ulp of slack for "
     "a different evaluation order (frame composition, inertia eigen-decomposition, mass-matrix "
     "factorisation), anything larger is a modelling difference"},
};

// Approximations of the bridge corpus: per model and category (trajectory, sensor, ...), the
// tolerance that bounds what the approximation costs (its measured error is in the per-model
// table the test prints). Checked before kTolerances.
struct Approximation {
  const char* model;
  Tolerance tolerance;  // its quantity: a category ("trajectory") or "*trajectory*" for all four
};
constexpr const char* kSiteWeld =
    "weld on sites: the bridge's body weld holds the same two site frames (anchors and relative "
    "orientation from the compiled sites), but MuJoCo changed the weld after 2.2.2 (3.0.0: the "
    "rotational rows' efc_diagApprox; 3.0.1: torquescale also scales the angular residual), so "
    "3.x's orientation constraint is softer and the block turns into alignment along another "
    "path (SiteWeldDiffersOnlyByTwoWeldChangesOfMujoco3 shows nothing else differs)";
constexpr Approximation kApproximations[] = {
    {"bridge3x/site_weld",
     {"trajectory_sensor", When::kAlways, 5e-3, 1e-9,
      "weld on sites, the welded site's position (what the constraint holds): within 5e-3 of "
      "its largest coordinate over 500 steps (measured 2.7e-3)"}},
    {"bridge3x/site_weld",
     {"contact_trajectory_sensor", When::kAlways, 5e-3, 1e-9, "as trajectory_sensor"}},
    {"bridge3x/site_weld", {"*trajectory*", When::kAlways, 1.0, 1e-9, kSiteWeld}},
    {"bridge3x/approx_filter_rk4",
     {"probe.act", When::kAlways, 2e-3, 1e-9,
      "filterexact / position timeconst under RK4: the bridge's re-timed Euler filter "
      "tau' = dt / (1 - exp(-dt/tau)) gives 3.x's exact per-step update only for the Euler and "
      "implicit integrators; RK4 integrates it in four stages. After 20 steps of full control "
      "(dt = 0.004, tau = 0.02 and 0.015) the activations differ by 1.0e-3 and 7.9e-4 of 1 "
      "(measured); the trajectories (zero control) are exact"}},
    {"bridge3x/approx_gravcomp_clamp",
     {"*trajectory*", When::kAlways, 1.0, 1e-9,
      "joint actuatorgravcomp with an actuatorfrcrange below the compensation: 3.x clamps "
      "motor + compensation to the range, so the arm sags (0.32 rad after 500 steps); the "
      "bridge's compensation (mjcb_passive) is not clamped and holds it: the whole motion "
      "(measured: 100% of the range of motion)"}},
    {"bridge3x/approx_gravcomp_clamp",
     {"passive.qfrc_passive_plus_actuator", When::kAlways, 0.1, 1e-9,
      "the same at qpos0: 3.x's total is the clamp (2), the bridge's the full compensation "
      "(2.207): 9.4% (measured)"}},
};

// Known differences: a quantity of a model's entity that is not compared, with the reason (also
// in docs/dialect-bridge.md, "Checked against MuJoCo 3.x"). `model`, `quantity` and `entity` are
// exact or "*"; an entity pattern ending in '*' matches by prefix, one starting with '*' by suffix.
// `when` restricts a row to reference entities with a property.
struct KnownDifference {
  const char* model;
  const char* quantity;
  const char* entity;
  When when;
  const char* reason;
};
constexpr KnownDifference kKnownDifferences[] = {
    {"*", "actuator.forcelimited", "*", When::kTargetHasActuatorFrcRange,
     "3.x clamps the joint/tendon total (actuatorfrcrange); the bridge expresses that clamp as "
     "the single driving actuator's forcerange (divided by gear for joints): compared through "
     "its effect, probe.qfrc_actuator"},
    {"*", "actuator.forcerange", "*", When::kTargetHasActuatorFrcRange, "same as forcelimited"},
    {"*", "probe.actuator_force", "*", When::kJointHasActuatorFrcRange,
     "3.x reports the joint-clamped actuator's force unclamped (only qfrc_actuator is clamped); "
     "the bridge's forcerange clamps actuator_force itself (documented caveat). Tendon clamps "
     "scale actuator_force in 3.x too, so those are compared"},
    {"*", "actuator.dyntype", "*", When::kFilterExact,
     "position timeconst: 3.x filterexact, the bridge an Euler filter with "
     "tau' = dt / (1 - exp(-dt/tau)), the same update per step: compared through its effect, "
     "probe.act"},
    {"*", "actuator.dynprm", "*", When::kFilterExact, "same as dyntype (tau' instead of tau)"},
    {"*", "geom.quat", "*", When::kMeshGeom,
     "a mesh geom's frame is its mesh's principal inertia frame, whose axes are defined only up "
     "to sign and, with equal principal moments, up to any rotation: both engines place the "
     "same vertices, compared through geom.pos (the centroid), geom.rbound and body.inertia"},
    {"*", "geom.size", "*", When::kMeshGeom,
     "a mesh geom's size is its bounding box in that frame (see geom.quat)"},
    {"*", "geom.pos", "*", When::kMeshGeom,
     "a mesh geom's pos is its mesh's centre, which 3.x's legacy algorithm (its default) "
     "computes from overcounted volumes for non-convex meshes; the vertices land at the same "
     "place: compared through geom.mesh_box"},
    {"*", "geom.rbound", "*", When::kMeshGeom, "bounding sphere about that centre (see geom.pos)"},
    {"*", "geom.size", "*", When::kHfieldGeom,
     "a height field geom's size is derived from its asset for bounding boxes (2.2.2: half of "
     "elevation + base, 3.x: another convention); the asset that collides is compared, "
     "hfield.size"},
    {"*", "geom.rbound", "*", When::kHfieldGeom,
     "2.2.2 gives height fields rbound 0 (always tested in the broad phase), 3.x a radius"},
    {"bridge3x/*", "equality.data", "*", When::kAlways,
     "equalities on sites: 3.x keeps site-relative data, the bridge body-relative anchors set "
     "from the sites after compilation; compared through the trajectories"},
    {"bridge3x/small_attributes", "tendon.stiffness", "band", When::kAlways,
     "dead-band spring: the 2.2.2 tendon has stiffness 0 and the runtime adds the spring force "
     "through mjcb_passive; compared through passive.qfrc_passive and the trajectories"},
    {"bridge3x/spring_flag", "joint.stiffness", "*", When::kAlways,
     "flag spring disabled alone: the bridge zeroes the stiffness in the model (2.2.2 can only "
     "switch spring and damper together); compared through its effect, the trajectories"},
    {"bridge3x/spring_flag", "flag.passive", "opt", When::kAlways,
     "the same: 2.2.2's passive flag stays enabled for the dampers"},
    {"bridge3x/discardvisual", "size.ngeom", "model", When::kAlways,
     "discardvisual: the bridge keeps the visual geoms (3.x weighs bodies with them before "
     "discarding them; 2.2.2 would discard them first): one more geom, which does not collide"},
    {"bridge3x/discardvisual", "geom.*", "ball#*", When::kAlways,
     "the kept visual geom 'decor' (unnamed here: keyed by body and rank)"},
    {"bridge3x/gravcomp", "passive.qfrc_passive", "shoulder", When::kAlways,
     "joint actuatorgravcomp: 3.x adds the shoulder's gravity compensation to qfrc_actuator, the "
     "bridge's mjcb_passive to qfrc_passive (documented); compared through their sum, "
     "passive.qfrc_passive_plus_actuator, and the trajectories"},
    {"bridge3x/gravcomp", "probe.qfrc_actuator", "*/shoulder", When::kAlways,
     "same as passive.qfrc_passive (the compensation is in 3.x's qfrc_actuator)"},
    {"bridge3x/approx_gravcomp_clamp", "passive.qfrc_passive", "shoulder", When::kAlways,
     "as for bridge3x/gravcomp: the compensation is in 3.x's qfrc_actuator (clamped there), in "
     "the bridge's qfrc_passive; compared through their sum (an approximation) and the "
     "trajectories"},
    {"bridge3x/approx_gravcomp_clamp", "probe.qfrc_actuator", "*/shoulder", When::kAlways,
     "the same (3.x's qfrc_actuator holds the clamped compensation)"},
    {"*", "option.integrator", "*", When::kImplicitFast,
     "implicitfast (3.x) becomes 2.2.2's implicit, which also includes the Coriolis/centripetal "
     "derivatives (the bridge's documented approximation)"},
};

// Models whose trajectory with contacts is not compared (their contact-free trajectory is).
struct ChaoticTrajectory {
  const char* model;
  const char* reason;
};
constexpr ChaoticTrajectory kContactTrajectoryNotCompared[] = {
    {"dialect3x/arm_servos",
     "the upper arm's capsule starts 25 mm (its full radius) inside the base cylinder, a body "
     "welded to the world, so the contact is not filtered; the two engines resolve that "
     "ill-posed penetration with different normals, which turns the shoulder"},
    {"dialect3x/g1_like",
     "the humanoid falls from its initial pose: foot and body contacts with the floor make the "
     "motion chaotic"},
    {"robots/arm/arm",
     "both finger boxes start at the same place (fully overlapping), an ill-posed contact "
     "resolved differently"},
};

// ---------------------------------------------------------------------------------------------
// MuJoCo 2.2.2 side: the same dump dump3x.mjs writes for 3.x.

const char* Name(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "";
}

std::string JointTypeName(int t) {
  static const char* k[] = {"free", "ball", "slide", "hinge"};
  return t >= 0 && t < 4 ? k[t] : "?";
}
std::string GeomTypeName(int t) {
  static const char* k[] = {"plane",     "hfield",   "sphere", "capsule",
                            "ellipsoid", "cylinder", "box",    "mesh"};
  return t >= 0 && t < 8 ? k[t] : "?";
}
std::string TrnName(int t) {
  static const char* k[] = {"joint", "jointinparent", "slidercrank", "tendon", "site", "body"};
  return t >= 0 && t < 6 ? k[t] : "?";
}
std::string DynName(int t) {
  static const char* k[] = {"none", "integrator", "filter", "muscle", "user"};
  return t >= 0 && t < 5 ? k[t] : "?";
}
std::string GainBiasName(int t, bool gain) {
  static const char* g[] = {"fixed", "affine", "muscle", "user"};
  static const char* b[] = {"none", "affine", "muscle", "user"};
  return t >= 0 && t < 4 ? (gain ? g[t] : b[t]) : "?";
}

int JointQposSize(int type) { return type == mjJNT_FREE ? 7 : type == mjJNT_BALL ? 4 : 1; }
int JointDofSize(int type) { return type == mjJNT_FREE ? 6 : type == mjJNT_BALL ? 3 : 1; }

std::vector<double> Slice(const mjtNum* a, int i, int n) {
  return std::vector<double>(a + static_cast<size_t>(i) * n, a + static_cast<size_t>(i + 1) * n);
}

std::vector<double> InertiaTensor(const mjtNum* diag, const mjtNum* quat) {
  mjtNum r[9];
  mju_quat2Mat(r, quat);
  auto at = [&](int a, int b) {
    return r[3 * a] * diag[0] * r[3 * b] + r[3 * a + 1] * diag[1] * r[3 * b + 1] +
           r[3 * a + 2] * diag[2] * r[3 * b + 2];
  };
  return {at(0, 0), at(1, 1), at(2, 2), at(0, 1), at(0, 2), at(1, 2)};
}

// Body-frame bounding box (min xyz, max xyz) of a mesh geom's vertices (see dump3x.mjs).
std::vector<double> MeshBox(const mjModel* m, int g) {
  const int mesh = m->geom_dataid[g];
  mjtNum r[9];
  mju_quat2Mat(r, m->geom_quat + 4 * g);
  std::vector<double> box = {mjMAXVAL, mjMAXVAL, mjMAXVAL, -mjMAXVAL, -mjMAXVAL, -mjMAXVAL};
  for (int i = m->mesh_vertadr[mesh]; i < m->mesh_vertadr[mesh] + m->mesh_vertnum[mesh]; ++i) {
    const float* v = m->mesh_vert + 3 * i;
    for (int a = 0; a < 3; ++a) {
      const double c =
          m->geom_pos[3 * g + a] + r[3 * a] * v[0] + r[3 * a + 1] * v[1] + r[3 * a + 2] * v[2];
      box[static_cast<size_t>(a)] = std::min(box[static_cast<size_t>(a)], c);
      box[static_cast<size_t>(a) + 3] = std::max(box[static_cast<size_t>(a) + 3], c);
    }
  }
  return box;
}

// `extended`: also the nsensordata size, the passive forces at qpos0 and every sensor along the
// trajectories (the bridge corpus, tests/data/mjcf/bridge3x).
json Dump222(const mjModel* m, mjData* d, bool extended) {
  json out;
  auto put = [&](const std::string& cat, const std::string& ent, const std::string& field,
                 const json& v) { out[cat][ent][field] = v; };
  auto body_name = [&](int b) -> std::string {
    if (b == 0) return "world";
    const std::string n = Name(m, mjOBJ_BODY, b);
    return n.empty() ? "body#" + std::to_string(b) : n;
  };
  auto keyed = [&](mjtObj type, int count, const int* bodyid) {
    std::map<int, int> rank;
    std::vector<std::string> keys;
    for (int i = 0; i < count; ++i) {
      const int r = rank[bodyid[i]]++;
      const std::string n = Name(m, type, i);
      keys.push_back(n.empty() ? body_name(bodyid[i]) + "#" + std::to_string(r) : n);
    }
    return keys;
  };

  const std::pair<const char*, int> sizes[] = {
      {"nq", m->nq},       {"nv", m->nv},         {"nu", m->nu},           {"na", m->na},
      {"nbody", m->nbody}, {"njnt", m->njnt},     {"ngeom", m->ngeom},     {"nsite", m->nsite},
      {"ncam", m->ncam},   {"nlight", m->nlight}, {"ntendon", m->ntendon}, {"neq", m->neq},
      {"nkey", m->nkey},   {"nmesh", m->nmesh},   {"nhfield", m->nhfield}};
  for (const auto& [k, v] : sizes) put("size", "model", k, std::vector<double>{double(v)});
  if (extended) put("size", "model", "nsensordata", std::vector<double>{double(m->nsensordata)});

  const mjOption& o = m->opt;
  put("option", "opt", "timestep", std::vector<double>{o.timestep});
  put("option", "opt", "impratio", std::vector<double>{o.impratio});
  put("option", "opt", "tolerance", std::vector<double>{o.tolerance});
  put("option", "opt", "noslip_tolerance", std::vector<double>{o.noslip_tolerance});
  put("option", "opt", "density", std::vector<double>{o.density});
  put("option", "opt", "viscosity", std::vector<double>{o.viscosity});
  put("option", "opt", "o_margin", std::vector<double>{o.o_margin});
  put("option", "opt", "iterations", std::vector<double>{double(o.iterations)});
  put("option", "opt", "noslip_iterations", std::vector<double>{double(o.noslip_iterations)});
  put("option", "opt", "gravity", Slice(o.gravity, 0, 3));
  put("option", "opt", "wind", Slice(o.wind, 0, 3));
  put("option", "opt", "magnetic", Slice(o.magnetic, 0, 3));
  put("option", "opt", "o_solref", Slice(o.o_solref, 0, 2));
  put("option", "opt", "o_solimp", Slice(o.o_solimp, 0, 5));
  static const char* integrators[] = {"euler", "rk4", "implicit"};
  static const char* cones[] = {"pyramidal", "elliptic"};
  static const char* solvers[] = {"pgs", "cg", "newton"};
  put("option", "opt", "integrator", integrators[o.integrator]);
  put("option", "opt", "cone", cones[o.cone]);
  put("option", "opt", "solver", solvers[o.solver]);
  const std::pair<const char*, int> disable[] = {{"constraint", mjDSBL_CONSTRAINT},
                                                 {"equality", mjDSBL_EQUALITY},
                                                 {"frictionloss", mjDSBL_FRICTIONLOSS},
                                                 {"limit", mjDSBL_LIMIT},
                                                 {"contact", mjDSBL_CONTACT},
                                                 {"gravity", mjDSBL_GRAVITY},
                                                 {"clampctrl", mjDSBL_CLAMPCTRL},
                                                 {"warmstart", mjDSBL_WARMSTART},
                                                 {"filterparent", mjDSBL_FILTERPARENT},
                                                 {"actuation", mjDSBL_ACTUATION},
                                                 {"refsafe", mjDSBL_REFSAFE},
                                                 {"sensor", mjDSBL_SENSOR},
                                                 {"passive", mjDSBL_PASSIVE}};
  for (const auto& [k, bit] : disable) {
    put("flag", "opt", k, (o.disableflags & bit) ? "disable" : "enable");
  }
  const std::pair<const char*, int> enable[] = {{"override", mjENBL_OVERRIDE},
                                                {"energy", mjENBL_ENERGY},
                                                {"fwdinv", mjENBL_FWDINV},
                                                {"multiccd", mjENBL_MULTICCD}};
  for (const auto& [k, bit] : enable) {
    put("flag", "opt", k, (o.enableflags & bit) ? "enable" : "disable");
  }

  for (int b = 0; b < m->nbody; ++b) {
    const std::string k = body_name(b);
    put("body", k, "parent", body_name(m->body_parentid[b]));
    put("body", k, "pos", Slice(m->body_pos, b, 3));
    put("body", k, "quat", Slice(m->body_quat, b, 4));
    put("body", k, "mass", std::vector<double>{m->body_mass[b]});
    put("body", k, "ipos", Slice(m->body_ipos, b, 3));
    put("body", k, "inertia", InertiaTensor(m->body_inertia + 3 * b, m->body_iquat + 4 * b));
  }

  std::vector<std::string> joint_keys;
  for (int j = 0; j < m->njnt; ++j) {
    std::string k = Name(m, mjOBJ_JOINT, j);
    if (k.empty()) k = body_name(m->jnt_bodyid[j]) + ":joint#" + std::to_string(j);
    joint_keys.push_back(k);
    const int nq = JointQposSize(m->jnt_type[j]), nv = JointDofSize(m->jnt_type[j]);
    const int qa = m->jnt_qposadr[j], da = m->jnt_dofadr[j];
    put("joint", k, "type", JointTypeName(m->jnt_type[j]));
    put("joint", k, "body", body_name(m->jnt_bodyid[j]));
    put("joint", k, "limited", std::vector<double>{double(m->jnt_limited[j])});
    if (m->jnt_limited[j]) put("joint", k, "range", Slice(m->jnt_range, j, 2));
    put("joint", k, "pos", Slice(m->jnt_pos, j, 3));
    put("joint", k, "axis", Slice(m->jnt_axis, j, 3));
    put("joint", k, "stiffness", std::vector<double>{m->jnt_stiffness[j]});
    put("joint", k, "margin", std::vector<double>{m->jnt_margin[j]});
    put("joint", k, "solref", Slice(m->jnt_solref, j, 2));
    put("joint", k, "solimp", Slice(m->jnt_solimp, j, 5));
    put("joint", k, "qpos0", std::vector<double>(m->qpos0 + qa, m->qpos0 + qa + nq));
    put("joint", k, "qpos_spring",
        std::vector<double>(m->qpos_spring + qa, m->qpos_spring + qa + nq));
    put("dof", k, "armature", std::vector<double>(m->dof_armature + da, m->dof_armature + da + nv));
    put("dof", k, "damping", std::vector<double>(m->dof_damping + da, m->dof_damping + da + nv));
    put("dof", k, "frictionloss",
        std::vector<double>(m->dof_frictionloss + da, m->dof_frictionloss + da + nv));
    put("dof", k, "M0", std::vector<double>(m->dof_M0 + da, m->dof_M0 + da + nv));
  }
  auto per_joint = [&](const mjtNum* a, bool qpos, auto&& f) {
    for (int j = 0; j < m->njnt; ++j) {
      const int adr = qpos ? m->jnt_qposadr[j] : m->jnt_dofadr[j];
      const int n = qpos ? JointQposSize(m->jnt_type[j]) : JointDofSize(m->jnt_type[j]);
      f(joint_keys[static_cast<size_t>(j)], std::vector<double>(a + adr, a + adr + n));
    }
  };

  const std::vector<std::string> geoms = keyed(mjOBJ_GEOM, m->ngeom, m->geom_bodyid);
  for (int g = 0; g < m->ngeom; ++g) {
    const std::string& k = geoms[static_cast<size_t>(g)];
    put("geom", k, "type", GeomTypeName(m->geom_type[g]));
    put("geom", k, "body", body_name(m->geom_bodyid[g]));
    put("geom", k, "size", Slice(m->geom_size, g, 3));
    put("geom", k, "pos", Slice(m->geom_pos, g, 3));
    put("geom", k, "quat", Slice(m->geom_quat, g, 4));
    put("geom", k, "friction", Slice(m->geom_friction, g, 3));
    put("geom", k, "solref", Slice(m->geom_solref, g, 2));
    put("geom", k, "solimp", Slice(m->geom_solimp, g, 5));
    put("geom", k, "solmix", std::vector<double>{m->geom_solmix[g]});
    put("geom", k, "margin", std::vector<double>{m->geom_margin[g]});
    put("geom", k, "gap", std::vector<double>{m->geom_gap[g]});
    put("geom", k, "contype", std::vector<double>{double(m->geom_contype[g])});
    put("geom", k, "conaffinity", std::vector<double>{double(m->geom_conaffinity[g])});
    put("geom", k, "condim", std::vector<double>{double(m->geom_condim[g])});
    put("geom", k, "priority", std::vector<double>{double(m->geom_priority[g])});
    put("geom", k, "rbound", std::vector<double>{m->geom_rbound[g]});
    if (m->geom_type[g] == mjGEOM_MESH) put("geom", k, "mesh_box", MeshBox(m, g));
  }
  for (int h = 0; h < m->nhfield; ++h) {
    std::string k = Name(m, mjOBJ_HFIELD, h);
    if (k.empty()) k = "hfield#" + std::to_string(h);
    put("hfield", k, "size", Slice(m->hfield_size, h, 4));
    put("hfield", k, "grid",
        std::vector<double>{double(m->hfield_nrow[h]), double(m->hfield_ncol[h])});
  }
  const std::vector<std::string> sites = keyed(mjOBJ_SITE, m->nsite, m->site_bodyid);
  for (int s = 0; s < m->nsite; ++s) {
    const std::string& k = sites[static_cast<size_t>(s)];
    put("site", k, "body", body_name(m->site_bodyid[s]));
    put("site", k, "pos", Slice(m->site_pos, s, 3));
    put("site", k, "quat", Slice(m->site_quat, s, 4));
  }
  const std::vector<std::string> cams = keyed(mjOBJ_CAMERA, m->ncam, m->cam_bodyid);
  for (int c = 0; c < m->ncam; ++c) {
    const std::string& k = cams[static_cast<size_t>(c)];
    put("camera", k, "pos", Slice(m->cam_pos, c, 3));
    put("camera", k, "quat", Slice(m->cam_quat, c, 4));
    put("camera", k, "fovy", std::vector<double>{m->cam_fovy[c]});
  }
  const std::vector<std::string> lights = keyed(mjOBJ_LIGHT, m->nlight, m->light_bodyid);
  for (int l = 0; l < m->nlight; ++l) {
    const std::string& k = lights[static_cast<size_t>(l)];
    put("light", k, "pos", Slice(m->light_pos, l, 3));
    put("light", k, "dir", Slice(m->light_dir, l, 3));
    put("light", k, "directional", std::vector<double>{double(m->light_directional[l])});
  }

  for (int t = 0; t < m->ntendon; ++t) {
    std::string k = Name(m, mjOBJ_TENDON, t);
    if (k.empty()) k = "tendon#" + std::to_string(t);
    put("tendon", k, "limited", std::vector<double>{double(m->tendon_limited[t])});
    if (m->tendon_limited[t]) put("tendon", k, "range", Slice(m->tendon_range, t, 2));
    put("tendon", k, "stiffness", std::vector<double>{m->tendon_stiffness[t]});
    put("tendon", k, "damping", std::vector<double>{m->tendon_damping[t]});
    put("tendon", k, "frictionloss", std::vector<double>{m->tendon_frictionloss[t]});
    put("tendon", k, "margin", std::vector<double>{m->tendon_margin[t]});
    put("tendon", k, "length0", std::vector<double>{m->tendon_length0[t]});
  }

  static const char* eq_types[] = {"connect", "weld", "joint", "tendon", "distance"};
  for (int e = 0; e < m->neq; ++e) {
    std::string k = Name(m, mjOBJ_EQUALITY, e);
    if (k.empty()) k = "equality#" + std::to_string(e);
    const std::string type = eq_types[m->eq_type[e]];
    put("equality", k, "type", type);
    put("equality", k, "active", std::vector<double>{double(m->eq_active[e])});
    put("equality", k, "solref", Slice(m->eq_solref, e, 2));
    put("equality", k, "solimp", Slice(m->eq_solimp, e, 5));
    std::vector<double> data = Slice(m->eq_data, e, mjNEQDATA);
    data.resize(type == "connect" ? 6 : 5);
    put("equality", k, "data", data);
  }

  std::vector<std::string> act_keys;
  for (int a = 0; a < m->nu; ++a) {
    std::string k = Name(m, mjOBJ_ACTUATOR, a);
    if (k.empty()) k = "actuator#" + std::to_string(a);
    act_keys.push_back(k);
    put("actuator", k, "trntype", TrnName(m->actuator_trntype[a]));
    put("actuator", k, "dyntype", DynName(m->actuator_dyntype[a]));
    put("actuator", k, "gaintype", GainBiasName(m->actuator_gaintype[a], true));
    put("actuator", k, "biastype", GainBiasName(m->actuator_biastype[a], false));
    if (m->actuator_dyntype[a] != mjDYN_NONE) {
      put("actuator", k, "dynprm", Slice(m->actuator_dynprm, a, mjNDYN));
    }
    put("actuator", k, "gainprm", Slice(m->actuator_gainprm, a, mjNGAIN));
    if (m->actuator_biastype[a] != mjBIAS_NONE) {
      put("actuator", k, "biasprm", Slice(m->actuator_biasprm, a, mjNBIAS));
    }
    put("actuator", k, "gear", Slice(m->actuator_gear, a, 6));
    put("actuator", k, "ctrllimited", std::vector<double>{double(m->actuator_ctrllimited[a])});
    put("actuator", k, "forcelimited", std::vector<double>{double(m->actuator_forcelimited[a])});
    put("actuator", k, "actlimited", std::vector<double>{double(m->actuator_actlimited[a])});
    if (m->actuator_ctrllimited[a])
      put("actuator", k, "ctrlrange", Slice(m->actuator_ctrlrange, a, 2));
    if (m->actuator_forcelimited[a]) {
      put("actuator", k, "forcerange", Slice(m->actuator_forcerange, a, 2));
    }
    if (m->actuator_actlimited[a])
      put("actuator", k, "actrange", Slice(m->actuator_actrange, a, 2));
  }

  for (int i = 0; i < m->nkey; ++i) {
    std::string k = Name(m, mjOBJ_KEY, i);
    if (k.empty()) k = "key#" + std::to_string(i);
    put("key", k, "time", std::vector<double>{m->key_time[i]});
    per_joint(m->key_qpos + static_cast<size_t>(i) * m->nq, true,
              [&](const std::string& j, const std::vector<double>& v) {
                put("key", k + "/" + j, "qpos", v);
              });
    per_joint(m->key_qvel + static_cast<size_t>(i) * m->nv, false,
              [&](const std::string& j, const std::vector<double>& v) {
                put("key", k + "/" + j, "qvel", v);
              });
    for (int a = 0; a < m->nu; ++a) {
      const std::string ak = k + "/" + act_keys[static_cast<size_t>(a)];
      put("key", ak, "ctrl", std::vector<double>{m->key_ctrl[i * m->nu + a]});
      if (m->actuator_dyntype[a] != mjDYN_NONE) {
        put("key", ak, "act", std::vector<double>{m->key_act[i * m->na + (a - (m->nu - m->na))]});
      }
    }
  }

  // Actuation probe (see dump3x.mjs).
  if (m->nu > 0) {
    for (const auto& probe : {std::pair<const char*, int>{"hi", 1}, {"lo", 0}}) {
      // Plain copies: clang 14 cannot capture structured bindings in the lambdas below.
      const char* label = probe.first;
      const int side = probe.second;
      mj_resetData(m, d);
      for (int a = 0; a < m->nu; ++a) {
        d->ctrl[a] =
            m->actuator_ctrllimited[a] ? m->actuator_ctrlrange[2 * a + side] : (side ? 1.0 : -1.0);
      }
      mj_forward(m, d);
      per_joint(d->qfrc_actuator, false, [&](const std::string& j, const std::vector<double>& v) {
        put("probe", std::string(label) + "/" + j, "qfrc_actuator", v);
      });
      for (int a = 0; a < m->nu; ++a) {
        put("probe", std::string(label) + "/" + act_keys[static_cast<size_t>(a)], "actuator_force",
            std::vector<double>{d->actuator_force[a]});
      }
      if (side == 1 && m->na > 0) {
        for (int s = 0; s < kProbeActSteps; ++s) mj_step(m, d);
        for (int a = m->nu - m->na; a < m->nu; ++a) {
          put("probe", std::string(label) + "/" + act_keys[static_cast<size_t>(a)], "act",
              std::vector<double>{d->act[a - (m->nu - m->na)]});
        }
      }
    }
  }

  std::vector<std::string> sensor_keys;
  if (extended) {
    mj_resetData(m, d);
    mj_forward(m, d);
    per_joint(d->qfrc_passive, false, [&](const std::string& j, const std::vector<double>& v) {
      put("passive", j, "qfrc_passive", v);
    });
    std::vector<mjtNum> total(static_cast<size_t>(m->nv));
    mju_add(total.data(), d->qfrc_passive, d->qfrc_actuator, m->nv);
    per_joint(total.data(), false, [&](const std::string& j, const std::vector<double>& v) {
      put("passive", j, "qfrc_passive_plus_actuator", v);
    });
    for (int i = 0; i < m->nsensor; ++i) {
      const std::string n = Name(m, mjOBJ_SENSOR, i);
      sensor_keys.push_back(n.empty() ? "sensor#" + std::to_string(i) : n);
    }
  }

  // Zero-control trajectories (see dump3x.mjs): without contacts, then the full physics.
  mjModel* mm = const_cast<mjModel*>(m);  // the flag is restored below
  const int flags = m->opt.disableflags;
  for (const auto& run :
       {std::pair<std::string, int>{"trajectory", mjDSBL_CONTACT}, {"contact_trajectory", 0}}) {
    const std::string& cat = run.first;  // a plain reference: see the probe loop above
    mm->opt.disableflags = flags | run.second;
    mj_resetData(m, d);
    mj_forward(m, d);
    for (int s = 1; s <= kSteps; ++s) {
      mj_step(m, d);
      if (s % kRecordEvery != 0 && s != kSteps) continue;
      const std::string at = "@" + std::to_string(s);
      per_joint(d->qpos, true, [&](const std::string& j, const std::vector<double>& v) {
        put(cat, j + at, "qpos", v);
      });
      per_joint(d->qvel, false, [&](const std::string& j, const std::vector<double>& v) {
        put(cat, j + at, "qvel", v);
      });
      for (size_t i = 0; i < sensor_keys.size(); ++i) {
        const int id = static_cast<int>(i);
        put(cat + "_sensor", sensor_keys[i] + at, "value",
            Slice(d->sensordata + m->sensor_adr[id], 0, m->sensor_dim[id]));
      }
    }
    put(cat, "final", "time", std::vector<double>{d->time});
  }
  mm->opt.disableflags = flags;
  return out;
}

// ---------------------------------------------------------------------------------------------
// The comparison.

bool Matches(const char* pattern, const std::string& s) {
  const std::string p = pattern;
  if (p == "*") return true;
  if (!p.empty() && p.back() == '*') return s.compare(0, p.size() - 1, p, 0, p.size() - 1) == 0;
  if (p.size() > 1 && p.front() == '*') {
    return s.size() >= p.size() - 1 &&
           s.compare(s.size() - (p.size() - 1), p.size() - 1, p, 1) == 0;
  }
  return p == s;
}

struct Stat {
  std::set<const Tolerance*> tolerances;  // the rows that applied
  int compared = 0, excluded = 0, failed = 0;
  double max_rel = 0, max_abs = 0;
  std::string worst;
};

class Comparison {
 public:
  Comparison(std::string model, const json& ours, const json& ref,
             std::map<std::string, Stat>* stats)
      : model_(std::move(model)), ours_(ours), ref_(ref), stats_(*stats) {
    TrajectoryScales();
  }

  void Run() {
    for (const auto& [cat, entities] : ref_.items()) {
      for (const auto& [ent, fields] : entities.items()) {
        for (const auto& [field, value] : fields.items()) Compare(cat, ent, field, value);
      }
    }
    // Entities we have that 3.x does not (the bridge must not invent any).
    for (const auto& [cat, entities] : ours_.items()) {
      for (const auto& [ent, fields] : entities.items()) {
        if (!ref_.contains(cat) || !ref_[cat].contains(ent)) {
          if (Chaotic() && cat.starts_with("contact_trajectory")) continue;
          if (KnownExtra(cat, ent)) continue;
          ADD_FAILURE() << model_ << ": " << cat << " '" << ent << "' exists only on 2.2.2";
        }
      }
    }
  }

  std::set<std::string> compared;         // "quantity|entity" actually compared
  std::map<std::string, Stat> per_model;  // this model's largest differences per quantity

 private:
  bool Chaotic() const {
    for (const ChaoticTrajectory& c : kContactTrajectoryNotCompared) {
      if (model_ == c.model) return true;
    }
    return false;
  }

  // Largest |ref| of each joint's qpos/qvel over the trajectory (per joint, per field).
  void TrajectoryScales() {
    for (const char* cat :
         {"trajectory", "contact_trajectory", "trajectory_sensor", "contact_trajectory_sensor"}) {
      if (!ref_.contains(cat)) continue;
      for (const auto& [ent, fields] : ref_[cat].items()) {
        const std::string joint = ent.substr(0, ent.rfind('@'));
        for (const auto& [field, value] : fields.items()) {
          double& s = scales_[std::string(cat) + "|" + joint + "|" + field];
          for (const auto& x : value) s = std::max(s, std::abs(x.get<double>()));
        }
      }
    }
  }

  const Tolerance& ToleranceFor(const std::string& cat, const std::string& ent,
                                const std::string& quantity) const {
    for (const Approximation& a : kApproximations) {
      const std::string q = a.tolerance.quantity;
      const bool all = q == "*trajectory*" && cat.find("trajectory") != std::string::npos;
      if (model_ == a.model && (all || q == cat || q == quantity)) return a.tolerance;
    }
    for (const Tolerance& t : kTolerances) {
      const std::string q = t.quantity;
      if ((q == quantity || q == cat || q == "*") && Holds(t.when, cat, ent)) return t;
    }
    return kTolerances[std::size(kTolerances) - 1];
  }

  bool Holds(When when, const std::string& cat, const std::string& ent) const {
    switch (when) {
      case urlab::When::kAlways:
        return true;
      case urlab::When::kFilterExact:
        return cat == "actuator" && ref_["actuator"][ent].value("dyntype", "") == "filterexact";
      case urlab::When::kTargetHasActuatorFrcRange:
      case urlab::When::kJointHasActuatorFrcRange: {
        const std::string name = cat == "probe" ? ent.substr(ent.find('/') + 1) : ent;
        if (!ref_.contains("meta") || !ref_["meta"].contains(name)) return false;
        const std::string target = ref_["meta"][name].value("target_actfrclimited", "none");
        return when == urlab::When::kJointHasActuatorFrcRange ? target == "joint"
                                                              : target != "none";
      }
      case urlab::When::kMeshGeom:
        return cat == "geom" && ref_["geom"][ent].value("type", "") == "mesh";
      case urlab::When::kHfieldGeom:
        return cat == "geom" && ref_["geom"][ent].value("type", "") == "hfield";
      case urlab::When::kImplicitFast:
        return ref_["option"]["opt"].value("integrator", "") == "implicitfast";
      case urlab::When::kDofMovesMesh: {
        if (cat != "dof" || !ref_.contains("geom") || !ref_["joint"].contains(ent)) return false;
        const std::string body = ref_["joint"][ent].value("body", "");
        for (const auto& [g, fields] : ref_["geom"].items()) {
          if (fields.value("type", "") != "mesh") continue;
          // Up from the mesh's body: is the joint's body one of its ancestors (or itself)?
          for (std::string b = fields.value("body", "world"); b != "world";
               b = ref_["body"][b].value("parent", "world")) {
            if (b == body) return true;
          }
        }
        return false;
      }
      case urlab::When::kBodyWithMesh:
        if (cat != "body" || !ref_.contains("geom")) return false;
        for (const auto& [g, fields] : ref_["geom"].items()) {
          if (fields.value("body", "") == ent && fields.value("type", "") == "mesh") return true;
        }
        return false;
    }
    return false;
  }

  // An entity only 2.2.2 has, listed as quantity "<category>.*".
  bool KnownExtra(const std::string& cat, const std::string& ent) const {
    for (const KnownDifference& k : kKnownDifferences) {
      if (Matches(k.model, model_) && std::string(k.quantity) == cat + ".*" &&
          Matches(k.entity, ent)) {
        return true;
      }
    }
    return false;
  }

  const KnownDifference* Known(const std::string& cat, const std::string& ent,
                               const std::string& quantity) const {
    for (const KnownDifference& k : kKnownDifferences) {
      if (Matches(k.model, model_) && Matches(k.quantity, quantity) && Matches(k.entity, ent) &&
          Holds(k.when, cat, ent)) {
        return &k;
      }
    }
    return nullptr;
  }

  void Compare(const std::string& cat, const std::string& ent, const std::string& field,
               const json& ref) {
    if (cat == "meta") return;  // reference-side facts used by the tables above
    const std::string quantity = cat + "." + field;
    Stat& stat = stats_[quantity];
    if ((cat.starts_with("contact_trajectory") && Chaotic()) || Known(cat, ent, quantity)) {
      ++stat.excluded;
      return;
    }
    const std::string where = model_ + ": " + cat + " '" + ent + "' " + field;
    if (!ours_.contains(cat) || !ours_[cat].contains(ent) || !ours_[cat][ent].contains(field)) {
      ++stat.failed;
      ADD_FAILURE() << where << ": missing on 2.2.2 (3.x: " << ref.dump() << ")";
      return;
    }
    const json& mine = ours_[cat][ent][field];
    ++stat.compared;
    compared.insert(quantity + "|" + ent);
    if (ref.is_string() || mine.is_string()) {
      if (ref != mine) {
        ++stat.failed;
        stat.max_rel = std::max(stat.max_rel, 1.0);
        stat.worst = where;
        ADD_FAILURE() << where << ": 2.2.2 " << mine.dump() << ", 3.x " << ref.dump();
      }
      return;
    }
    const std::vector<double> a = mine.get<std::vector<double>>();
    const std::vector<double> b = ref.get<std::vector<double>>();
    if (a.size() != b.size()) {
      ++stat.failed;
      ADD_FAILURE() << where << ": 2.2.2 " << mine.dump() << ", 3.x " << ref.dump();
      return;
    }
    const bool quat = field == "quat";
    double diff = 0, diff_neg = 0, scale = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      diff = std::max(diff, std::abs(a[i] - b[i]));
      diff_neg = std::max(diff_neg, std::abs(a[i] + b[i]));
      scale = std::max({scale, std::abs(a[i]), std::abs(b[i])});
    }
    if (quat) diff = std::min(diff, diff_neg);  // q and -q are the same rotation
    if (cat.find("trajectory") != std::string::npos) {
      const std::string key = cat + "|" + ent.substr(0, ent.rfind('@')) + "|" + field;
      scale = scales_.count(key) ? scales_[key] : scale;
    }
    const Tolerance& tol = ToleranceFor(cat, ent, quantity);
    stat.tolerances.insert(&tol);
    const double rel = diff / std::max(scale, tol.atol);
    if (rel > stat.max_rel || (stat.worst.empty() && diff > 0)) {
      stat.max_rel = std::max(stat.max_rel, rel);
      stat.worst = where;
    }
    stat.max_abs = std::max(stat.max_abs, diff);
    Stat& mine_stat = per_model[quantity];
    ++mine_stat.compared;
    mine_stat.max_abs = std::max(mine_stat.max_abs, diff);
    if (rel >= mine_stat.max_rel) {
      mine_stat.max_rel = rel;
      mine_stat.worst = ent;
    }
    if (diff > tol.atol + tol.rtol * scale) {
      ++stat.failed;
      ADD_FAILURE() << where << ": 2.2.2 " << mine.dump() << ", 3.x " << ref.dump() << " (|diff| "
                    << diff << " > " << tol.atol << " + " << tol.rtol << " * " << scale << ")";
    }
  }

  std::string model_;
  const json& ours_;
  const json& ref_;
  std::map<std::string, Stat>& stats_;
  std::map<std::string, double> scales_;
};

// ---------------------------------------------------------------------------------------------

std::string MujocoJsDir() {
  const char* env = std::getenv("URLAB_MUJOCO_JS");
  return env && *env ? env : URLAB_MUJOCO_JS_DIR;
}

std::vector<std::pair<std::string, std::string>> Corpus() {
  std::vector<std::pair<std::string, std::string>> models;  // id, path
  for (const char* dir : {"mjcf/dialect3x", "mjcf/robots", "mjcf/bridge3x"}) {
    const fs::path root = testing::TestData(dir);
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
      if (e.path().extension() == ".xml") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      std::string id = fs::path(dir).filename().string() + "/" +
                       fs::relative(f, root).replace_extension().string();
      models.emplace_back(id, f.string());
    }
  }
  return models;
}

// The bridge corpus (one small model per 3.x construct) also compares passive forces and sensors.
bool Extended(const std::string& id) { return id.starts_with("bridge3x/"); }

// Our side of a model: the single-file path of `urlab compile` (world::BuildModel's steps:
// reader, bridge, mesh preparation with the face orientation repair, writer, compile) and the
// runtime's share of the bridge (software sensors, gravity compensation, site equalities), then
// the dump. Attributes newer than the reference that affect physics are removed first.
json DumpBridged(const std::string& path, bool extended, const std::string& mesh_cache) {
  document::Document doc = mjcf::ReadFile(path);
  doc.root().Visit([](document::Element& e) {
    for (const NewerAttribute& n : kNewerThanReference) {
      if (n.affects_physics && e.tag() == n.element) e.Unset(n.attribute);
    }
  });
  mjcf::BridgeReport report = mjcf::ApplyBridge(doc);
  const convert::MeshAssetReport meshes = convert::PrepareMeshAssets(doc, mesh_cache);
  report.changes.insert(report.changes.end(), meshes.bridge_changes.begin(),
                        meshes.bridge_changes.end());
  physics::ModelPtr model = physics::CompileXmlString(mjcf::WriteString(doc));
  physics::DataPtr data = physics::MakeData(model.get());
  physics::SoftwareModelSpec runtime;
  world::AddBridgeRuntime(report, "", &runtime);
  physics::ApplySiteEqualities(model.get(), runtime);
  const physics::SoftwareSensorRegistration registered =
      physics::RegisterSoftwareModel(model.get(), runtime);
  return Dump222(model.get(), data.get(), extended);
}

// Runs dump3x.mjs on `job` (one node process) and returns its output.
json RunDump3x(const json& job, const std::string& tag, int timeout_seconds) {
  const std::string dir = testing::MakeTempDir(tag);
  const std::string job_file = testing::WriteTextFile(dir, "job.json", job.dump());
  const std::string out_file = dir + "/out.json";
  std::string log;
  const int rc =
      testing::RunCommand(std::string("timeout ") + std::to_string(timeout_seconds) + " node '" +
                              testing::SourcePath("tests/mjcf/reference3x/dump3x.mjs") + "' '" +
                              job_file + "' > '" + out_file + "'",
                          &log);
  if (rc != 0) {
    ADD_FAILURE() << "dump3x.mjs failed: " << log;
    return json::object();
  }
  std::ifstream in(out_file);
  return json::parse(in);
}

class Reference3xTest : public testing::MujocoTest {};

TEST_F(Reference3xTest, BridgedCorpusMatchesMujoco3) {
  const std::string js_dir = MujocoJsDir();
  const std::string module = js_dir + "/node_modules/mujoco-js/dist/mujoco_wasm.js";
  if (testing::RunCommand("node --version") != 0) {
    GTEST_SKIP() << "node (Node.js) is not installed; the MuJoCo 3.x reference needs it "
                    "(apt-get install nodejs npm), then: bash tools/install-mujoco-js.sh "
                    "build/mujoco-js";
  }
  if (js_dir.empty() || !fs::is_regular_file(module)) {
    GTEST_SKIP() << "MuJoCo 3.x reference (npm mujoco-js) not found in '" << js_dir
                 << "'; install it with: bash tools/install-mujoco-js.sh build/mujoco-js (or set "
                    "URLAB_MUJOCO_JS to its folder)";
  }

  // One node process for the whole corpus (the wasm module loads once).
  const auto corpus = Corpus();
  ASSERT_GE(corpus.size(), 8u);
  json job = {{"module", module},
              {"steps", kSteps},
              {"record_every", kRecordEvery},
              {"probe_act_steps", kProbeActSteps},
              {"probe", true},
              {"strip", json::array()},
              {"models", json::array()}};
  for (const NewerAttribute& n : kNewerThanReference) {
    job["strip"].push_back({{"element", n.element}, {"attribute", n.attribute}});
  }
  job["disable"] = {"NATIVECCD"};
  job["add"] = json::array();
  for (const ReferenceFix& f : kReferenceFixes) {
    job["add"].push_back({{"element", f.element},
                          {"attribute", f.attribute},
                          {"value", f.value},
                          {"if_present", f.if_present}});
  }
  for (const auto& [id, path] : corpus) {
    std::string reference_file = path;
    for (const ReferenceInput& r : kReferenceInputs) {
      if (id == r.model) reference_file = (fs::path(path).parent_path() / r.file).string();
    }
    job["models"].push_back({{"id", id}, {"file", reference_file}, {"extended", Extended(id)}});
  }
  const json ref = RunDump3x(job, "reference3x", 300);
  ASSERT_TRUE(ref.contains("models"));
  std::cout << "MuJoCo 3.x reference: " << ref["version"].get<std::string>() << " (mujoco-js in "
            << js_dir << "); MuJoCo " << mj_versionString() << " here\n";

  const std::string mesh_cache = testing::MakeTempDir("reference3x_meshes");
  std::map<std::string, Stat> stats;
  std::map<std::string, std::map<std::string, Stat>> per_model;  // bridge corpus: model -> quantity
  std::set<std::string> compared;
  for (const auto& [id, path] : corpus) {
    SCOPED_TRACE(id);
    const json& r = ref["models"][id];
    ASSERT_FALSE(r.contains("error")) << id << ": MuJoCo 3.x could not load it: " << r["error"];
    const json ours = DumpBridged(path, Extended(id), mesh_cache);
    Comparison c(id, ours, r["data"], &stats);
    c.Run();
    for (const std::string& q : c.compared) compared.insert(id + "|" + q);
    if (Extended(id)) per_model[id] = c.per_model;
  }

  // The checks this test exists for were made (not excluded, not vacuous).
  for (const char* must : {
           "dialect3x/arm_servos|actuator.biasprm|wrist",        // dampratio through a class
           "dialect3x/g1_like|actuator.biasprm|left_wrist",      // dampratio inline
           "robots/arm/arm|actuator.biasprm|joint1",             // dampratio, implicitfast arm
           "robots/arm/arm|probe.qfrc_actuator|hi/finger_left",  // tendon clamp with gear 2
           "dialect3x/arm_servos|probe.qfrc_actuator|hi/finger_left",  // tendon clamp, gear 1
           "robots/arm/arm|probe.qfrc_actuator|hi/joint4",             // joint clamp with gear 2
           "dialect3x/arm_servos|probe.act|hi/elbow",                  // timeconst filter
           "bridge3x/replicate|body.pos|driven-3",                     // replicate offset
           "bridge3x/replicate|body.quat|arm1_2",                      // nested euler
           "bridge3x/gravcomp|passive.qfrc_passive_plus_actuator|shoulder",  // actuatorgravcomp
           "bridge3x/small_attributes|probe.act|hi/drive",                   // filterexact
           "bridge3x/small_attributes|key.qpos|bent/slide",                 // key padded with qpos0
           "bridge3x/small_attributes|passive.qfrc_passive|slide",          // dead-band spring
           "bridge3x/small_attributes|trajectory.qpos|follower@500",        // polycoef "0 2"
           "bridge3x/spring_flag|trajectory.qpos|h1@500",                   // spring off, damper on
           "bridge3x/site_equality|trajectory.qpos|hinge2@500",             // connect on sites
           "bridge3x/discardvisual|body.mass|ball",                         // visual geoms weigh
           "bridge3x/discardvisual|contact_trajectory.qpos|ball_free@500",  // pair on a visual geom
           "bridge3x/attach/parent|body.pos|right_base",                    // attach in a frame
           "bridge3x/attach/parent|actuator.biasprm|left_elbow_servo",      // attached actuator
           "bridge3x/attach/parent|trajectory_sensor.value|right_tip_pos@500",  // and sensor
           "bridge3x/attach/parent|key.qpos|left_bent/left_shoulder",  // attached keyframes
           "bridge3x/attach/parent|key.qpos|left_bent/right_elbow",    // the rest at qpos0
           "bridge3x/attach/parent|key.qvel|right_/right_elbow",       // unnamed: the prefix
           "bridge3x/attach/parent|key.time|right_",
           "bridge3x/attach/parent|key.ctrl|right_bent/right_elbow_servo",
           "bridge3x/attach/parent|key.qpos|home/left_shoulder",  // parent's key first
           "bridge3x/freejoint_align|body.pos|tray",              // alignfree (auto)
           "bridge3x/freejoint_align|body.quat|crate",            // align="true"
           "bridge3x/freejoint_align|body.ipos|tray",             // now zero
           "bridge3x/freejoint_align|geom.pos|weight",            // children moved
           "bridge3x/freejoint_align|body.pos|plate",             // align="false"
           "bridge3x/freejoint_align|contact_trajectory.qpos|tray_free@500",
           "bridge3x/freejoint_align|key.qpos|lifted/tray_free",
           "bridge3x/attach/frame_parent|body.pos|b_finger_b",  // attach frame=, nested frame
           "bridge3x/attach/frame_parent|site.pos|a_tcp",
           "bridge3x/attach/frame_parent|key.qpos|b_open/b_slide_b",
           "bridge3x/approx_filter_rk4|probe.act|hi/filtered",  // filterexact, RK4
           "bridge3x/approx_filter_rk4|probe.act|hi/servo",     // timeconst, RK4
           "bridge3x/approx_gravcomp_clamp|trajectory.qpos|shoulder@500",
           "bridge3x/approx_gravcomp_clamp|passive.qfrc_passive_plus_actuator|shoulder",
           "bridge3x/sensors|contact_trajectory_sensor.value|ball_any@100",   // contact, data
           "bridge3x/sensors|contact_trajectory_sensor.value|floor_box@100",  // body1/body2
           "bridge3x/sensors|contact_trajectory_sensor.value|in_zone@100",    // insidesite
           "bridge3x/sensors|contact_trajectory_sensor.value|kinetic@100",    // e_kinetic
           "bridge3x/sensors|contact_trajectory_sensor.value|potential@100",  // e_potential
           "bridge3x/gravcomp|trajectory.qpos|ball_free@500",                 // over-compensated
           "bridge3x/mesh_orientation|body.mass|crate",     // OBJ with disagreeing faces
           "bridge3x/mesh_orientation|body.inertia|wedge",  // STL with a facet turned inwards
           "bridge3x/mesh_orientation|trajectory.qpos|swing@500",
           "bridge3x/mesh_orientation|contact_trajectory.qpos|crate_free@500",
       }) {
    EXPECT_TRUE(compared.count(must)) << "not compared: " << must;
  }

  // The table: per quantity, the largest relative difference over the corpus.
  std::ostringstream t;
  t << "\n| quantity | compared | excluded | max rel diff | max abs diff | tolerance (rtol/atol) "
       "| largest at |\n|---|---|---|---|---|---|---|\n";
  for (const auto& [q, s] : stats) {
    std::string tols;
    for (const Tolerance* tol : s.tolerances) {
      std::ostringstream one;
      one << std::setprecision(0) << std::scientific << tol->rtol << "/" << tol->atol;
      if (tols.find(one.str()) == std::string::npos) tols += (tols.empty() ? "" : ", ") + one.str();
    }
    t << "| " << q << " | " << s.compared << " | " << s.excluded << " | " << std::setprecision(2)
      << std::scientific << s.max_rel << " | " << s.max_abs << std::defaultfloat << " | "
      << (tols.empty() ? "-" : tols) << " | " << (s.max_rel > 0 ? s.worst : "") << " |\n";
  }
  std::cout << t.str() << std::endl;

  // The bridge corpus, model by model: the largest relative difference of every quantity that
  // is not exactly equal (what each construct's translation or approximation costs).
  std::ostringstream pm;
  pm << "\n| bridge corpus model | quantity | compared | max rel diff | max abs diff | at |\n"
        "|---|---|---|---|---|---|\n";
  for (const auto& [model, quantities] : per_model) {
    bool any = false;
    for (const auto& [q, st] : quantities) {
      if (st.max_rel == 0) continue;
      any = true;
      pm << "| " << model << " | " << q << " | " << st.compared << " | " << std::setprecision(2)
         << std::scientific << st.max_rel << " | " << st.max_abs << std::defaultfloat << " | "
         << st.worst << " |\n";
    }
    if (!any)
      pm << "| " << model << " | (all " << quantities.size() << " quantities) | | 0 | 0 | |\n";
  }
  std::cout << pm.str() << std::endl;
}

// The models the bridge refuses (tests/data/mjcf/bridge3x_refused) are valid MuJoCo 3.x: the
// reference loads them (bridge_test checks the refusals). The WebAssembly build has no engine
// plugins, so the SDF model is only read by the bridge.
TEST_F(Reference3xTest, RefusedCorpusLoadsInMujoco3) {
  const std::string js_dir = MujocoJsDir();
  const std::string module = js_dir + "/node_modules/mujoco-js/dist/mujoco_wasm.js";
  if (testing::RunCommand("node --version") != 0 || !fs::is_regular_file(module)) {
    GTEST_SKIP() << "MuJoCo 3.x reference not installed (see BridgedCorpusMatchesMujoco3)";
  }
  json job = {{"module", module}, {"steps", 1},           {"record_every", 1},
              {"probe", false},   {"probe_act_steps", 0}, {"models", json::array()}};
  for (const char* f : {"flexcomp.xml", "tendon_armature.xml"}) {
    job["models"].push_back(
        {{"id", f}, {"file", testing::TestData("mjcf/bridge3x_refused") + "/" + f}});
  }
  const std::string dir = testing::MakeTempDir("refused3x");
  const std::string job_file = testing::WriteTextFile(dir, "job.json", job.dump());
  std::string out;
  ASSERT_EQ(testing::RunCommand("timeout 120 node '" +
                                    testing::SourcePath("tests/mjcf/reference3x/dump3x.mjs") +
                                    "' '" + job_file + "'",
                                &out),
            0)
      << out;
  const json ref = json::parse(out.substr(out.find('{')));
  for (const auto& [id, r] : ref["models"].items()) {
    EXPECT_FALSE(r.contains("error")) << id << ": " << r.dump().substr(0, 300);
  }
}

// Why the site weld is approximated (docs/dialect-bridge.md, rule equality.site.weld): the body
// weld the bridge writes holds the same site frames (anchors and relative orientation from the
// compiled sites; 3.x's site-frame residual is the body-frame one rotated, which the solver does
// not see). What remains are two changes MuJoCo made to every weld after 2.2.2:
//  1. 2.2.2's efc_diagApprox gives all six rows of a weld the bodies' translational inverse
//     weight (its row counter is reset on every equality row); 3.0.0 gives the rotational rows
//     the rotational weight. The regularisation, hence the softness of the orientation part,
//     differs by their ratio (566 / 1.04 for the block here).
//  2. 2.2.2 scales the rotational Jacobian by torquescale but not the angular residual; 3.0.1
//     scales both.
// Neither is reachable from 2.2.2's callbacks (and body_invweight0 also weighs contacts), so the
// bridge cannot make the weld exact. This test pins the cause: with torquescale 1 and 3.x's
// rotational weights set to the translational ones (dump3x.mjs weld_diag_as_222), MuJoCo 3.3.8
// reproduces the bridged model to round-off; without that (or with torquescale 0.5) it does not.
TEST_F(Reference3xTest, SiteWeldDiffersOnlyByTwoWeldChangesOfMujoco3) {
  const std::string js_dir = MujocoJsDir();
  const std::string module = js_dir + "/node_modules/mujoco-js/dist/mujoco_wasm.js";
  if (testing::RunCommand("node --version") != 0 || !fs::is_regular_file(module)) {
    GTEST_SKIP() << "MuJoCo 3.x reference not installed (see BridgedCorpusMatchesMujoco3)";
  }
  std::string source;
  {
    std::ifstream in(testing::TestData("mjcf/bridge3x/site_weld.xml"));
    source.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string scale = "torquescale=\"0.5\"";
  ASSERT_NE(source.find(scale), std::string::npos);
  const std::string dir = testing::MakeTempDir("site_weld_cause");
  std::map<std::string, std::string> files;  // torquescale -> variant file (a folder each)
  for (const char* ts : {"1", "0.5"}) {
    std::string text = source;
    text.replace(text.find(scale), scale.size(), std::string("torquescale=\"") + ts + "\"");
    fs::create_directories(dir + "/ts" + ts);
    files[ts] = testing::WriteTextFile(dir + "/ts" + ts, "site_weld.xml", text);
  }
  json job = {{"module", module}, {"steps", kSteps},      {"record_every", kRecordEvery},
              {"probe", false},   {"probe_act_steps", 0}, {"models", json::array()}};
  job["models"].push_back(
      {{"id", "ts1 emulated"}, {"file", files["1"]}, {"weld_diag_as_222", true}});
  job["models"].push_back({{"id", "ts1"}, {"file", files["1"]}});
  job["models"].push_back(
      {{"id", "ts0.5 emulated"}, {"file", files["0.5"]}, {"weld_diag_as_222", true}});
  const json ref = RunDump3x(job, "site_weld_cause3x", 120);
  ASSERT_TRUE(ref.contains("models"));
  const std::string cache = testing::MakeTempDir("site_weld_cause_meshes");
  std::map<std::string, json> ours;
  for (const auto& [ts, file] : files) ours[ts] = DumpBridged(file, false, cache);
  // Largest |2.2.2 - 3.x| over the contact-free trajectory's qpos and qvel.
  auto largest = [&](const std::string& id, const std::string& ts) {
    const json& r = ref["models"][id]["data"]["trajectory"];
    double diff = 0;
    for (const auto& [ent, fields] : r.items()) {
      for (const char* f : {"qpos", "qvel"}) {
        if (!fields.contains(f)) continue;
        const auto a = fields[f].get<std::vector<double>>();
        const auto b = ours[ts]["trajectory"][ent][f].get<std::vector<double>>();
        for (size_t i = 0; i < a.size(); ++i) diff = std::max(diff, std::abs(a[i] - b[i]));
      }
    }
    return diff;
  };
  const double emulated = largest("ts1 emulated", "1");
  const double plain = largest("ts1", "1");
  const double scaled = largest("ts0.5 emulated", "0.5");
  std::cout << "site weld, largest |2.2.2 - 3.x| over qpos/qvel (500 steps): torquescale 1 with "
               "2.2.2's weld weights in 3.x "
            << emulated << "; torquescale 1 " << plain << "; torquescale 0.5 with 2.2.2's weld "
            << "weights " << scaled << "\n";
  EXPECT_LT(emulated, 1e-9);  // nothing else differs
  EXPECT_GT(plain, 1e-3);     // cause 1 alone is visible
  EXPECT_GT(scaled, 1e-3);    // cause 2 alone is visible
}

}  // namespace
}  // namespace urlab
