#pragma once
// Composition of several articulations into one scene, as the URLab architecture does it with
// MuJoCo's model editing: every articulation is its own spec (parsed from its MJCF); the scene is
// a root spec; each articulation is attached (mjs_attach) to a frame of the root's world body at
// its placement with the prefix "{name}_", which MuJoCo applies to every name and every reference
// (defaults, assets, keyframes included). Options follow the description's resolution order:
// MuJoCo's defaults, then the first articulation's MJCF and `options:`, then the scene's own.
//
// After MuJoCo compiled the root spec, LayoutOf tells each articulation's elements and
// PlaceKeyframes puts the free bases of the articulations' own keyframes at their placements
// (MuJoCo keeps a keyframe's free-joint pose as written in the articulation's file).
//
// Thread: pure functions over specs and models; the thread that owns them (main).
#include <mujoco/mujoco.h>

#include <array>
#include <map>
#include <string>
#include <vector>

#include "urlab/core/diagnostics.h"
#include "urlab/mjcf/spec.h"

namespace urlab::mjcf {

// An articulation's pose in the scene (MuJoCo frame: metres, quaternion w x y z).
struct Placement {
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};
  bool IsIdentity() const;
};

struct ArticulationInput {
  std::string name;  // prefix is name + "_"
  SpecPtr spec;      // consumed by Compose
  std::string file;  // where it was read from (a generated one: the scene file), for messages
  int line = 0;      // a generated one: the line of its scene entry, which messages name
  Placement placement;
  // <option> attributes of this articulation (SetOption's keys), applied over its MJCF's own.
  std::map<std::string, std::string> options;
  // false: drop the elements attached directly to the world body, other than bodies and frames.
  bool include_world = true;
  // true: it sets no options and takes the scene's (a converted prop, a terrain, a launcher,
  // composed after the articulations): it is neither the source of the options nor warned about.
  bool takes_scene_options = false;
};

// A keyframe of one articulation as its MJCF gives it.
struct ArticulationKeyframe {
  std::string name;        // as in the articulation's MJCF
  std::string scene_name;  // "{art}_{name}" in the composed model
  double time = 0;
  std::vector<double> qpos, qvel, act, ctrl, mocap_pos, mocap_quat;  // empty = not given
};

// What the composition knows about each articulation.
struct ArticulationLayout {
  std::string name;
  std::string prefix;
  std::string file;
  int line = 0;  // ArticulationInput::line
  Placement placement;
  // Prefixed names in MuJoCo's id order within the articulation (filled by LayoutOf).
  std::vector<std::string> joints, bodies, actuators, sensors, mocap_bodies;
  // Free joints of bodies attached to the world (their keyframe poses get the placement).
  std::vector<std::string> free_joints_at_top;
  std::vector<ArticulationKeyframe> keyframes;
  // How many elements of each kind the articulation's own spec held (CheckAttached).
  std::map<int, int> own_counts;  // mjtObj -> count
};

struct ComposeResult {
  SpecPtr spec;  // the root spec, every articulation attached
  std::vector<ArticulationLayout> articulations;
  std::vector<Diagnostic> diagnostics;  // warnings (e.g. options the scene overrides)
};

// Every keyframe of an articulation's own spec (read from `file`, named `name` in the scene) whose
// qpos, qvel, act, ctrl, mpos or mquat is longer than the articulation's own size (MuJoCo refuses
// it when attaching, unlocated; a shorter one it fills from the model's reference configuration,
// as it does for a file alone): an error at the key's line, naming the articulation and the key.
std::vector<Diagnostic> KeyframeLengthProblems(mjSpec* spec, const std::string& file,
                                               const std::string& name);

// Attaches `inputs` (consumed) to a new root spec. `scene_options` (SetOption's keys) are
// applied last; an articulation whose own option differs from the scene's on a field the scene
// does not set is warned about (the scene's value applies). Throws InputError naming the
// articulation for an option MuJoCo would not take, a keyframe of the wrong length
// (KeyframeLengthProblems), a whole-model compiler setting (settotalmass) in a scene of several
// articulations, or an attachment MuJoCo refuses.
ComposeResult Compose(std::vector<ArticulationInput> inputs,
                      const std::map<std::string, std::string>& scene_options = {});

// Sets one <size> attribute of `spec` from its MJCF text ("memory" = "64M", "nuserdata" = "3",
// "njmax", "nconmax", "nstack", "nuser_*"). Throws Error naming it.
void SetSize(mjSpec* spec, const std::string& key, const std::string& value);

// Fills the element names of `layout` (its prefix's) from the compiled model.
void LayoutOf(const mjModel* m, ArticulationLayout* layout);

// Throws InputError when the compiled model lacks an element an articulation's spec held:
// MuJoCo's attach drops an element whose reference names nothing (an actuator on a misspelt
// joint) without a word, where compiling the file alone refuses it. The articulation's file is
// compiled alone then, for MuJoCo's own message and line.
void CheckAttached(const mjModel* m, const std::vector<ArticulationLayout>& layouts);

// Moves the free bases (and mocap bodies) attached to the world in every articulation keyframe
// that gives their poses to the articulation's placement, in the compiled model and in `spec`'s
// keys (so a saved scene holds the same).
void PlaceKeyframes(const std::vector<ArticulationLayout>& layouts, mjModel* m, mjSpec* spec);

}  // namespace urlab::mjcf
