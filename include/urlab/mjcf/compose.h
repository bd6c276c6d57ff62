#pragma once
// Composition of several articulations into one scene document (what mjs_attach does in MuJoCo
// 3.x, done on our documents because 2.2.2 has no mjSpec): every articulation is an isolated
// document; each is merged into the scene root at its placement with the prefix "{name}_"
// applied to every element name and to every attribute naming another element (joints,
// bodies, sites, geoms, tendons, actuators, sensors, meshes, materials, textures, hfields,
// skins, default classes, keyframes, custom data).
//
// MuJoCo 2.2.2 has no <frame>: the placement is composed into the articulation's top-level
// elements. Keyframes stay per articulation: each becomes a scene keyframe "{name}_{key}" whose
// other articulations keep their reference configuration; its values are written into the
// compiled model by ApplyArticulationKeyframes (2.2.2 needs full-length keyframes, which only
// the compiled model's sizes tell).
//
// Thread: pure functions over documents; any thread that owns them.
#include <mujoco/mujoco.h>

#include <array>
#include <map>
#include <string>
#include <vector>

#include "urlab/document/document.h"

namespace urlab::mjcf {

// An articulation's pose in the scene (MuJoCo frame: metres, quaternion w x y z).
struct Placement {
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};
  bool IsIdentity() const;
};

struct ArticulationInput {
  std::string name;  // prefix is name + "_"
  document::Document doc;
  Placement placement;
  // <option> attributes of this articulation (all written to its options), e.g. {"timestep",
  // "0.002"}; applied over the MJCF's own <option>.
  std::map<std::string, std::string> options;
  // false: drop the elements attached directly to the world body, other than bodies.
  bool include_world = true;
  // true: the document sets no options or compiler settings and takes the scene's (a converted
  // prop, a launcher, composed after the articulations): it neither sets them nor is warned
  // about differing from them.
  bool takes_scene_options = false;
};

// A keyframe of one articulation, kept for ApplyArticulationKeyframes.
struct ArticulationKeyframe {
  std::string name;        // as in the articulation's MJCF
  std::string scene_name;  // "{art}_{name}" in the composed model
  double time = 0;
  std::vector<double> qpos, qvel, act, ctrl, mocap_pos, mocap_quat;  // empty = not given
};

// What the composer knows about each articulation after merging.
struct ArticulationLayout {
  std::string name;
  std::string prefix;
  Placement placement;
  // Prefixed names in MuJoCo's id order within the articulation.
  std::vector<std::string> joints, bodies, actuators, sensors, mocap_bodies;
  // Top-level bodies that carry a free joint (their keyframe poses get the placement).
  std::vector<std::string> free_joints_at_top;
  std::vector<ArticulationKeyframe> keyframes;
  std::map<std::string, std::string> options;  // effective <option> attributes
};

struct ComposeResult {
  document::Document doc;
  std::vector<ArticulationLayout> articulations;
  std::vector<document::Diagnostic> diagnostics;  // warnings (e.g. disagreeing timesteps)
};

// Merges `inputs` (consumed) into one scene document. `scene_options` (the scene's own <option>
// overrides, same keys as ArticulationInput::options) are applied last; articulations that
// disagree on an option the scene sets are not warned about. Throws InputError naming the
// articulation and element ("g1: <joint 'left_knee'> at file:line: ...") on conflicts that
// cannot be composed.
ComposeResult Compose(std::vector<ArticulationInput> inputs,
                      const std::map<std::string, std::string>& scene_options = {});

// Sets one <option> attribute of `doc` ("timestep", ...; "flag.X" for <option><flag X=>),
// creating the elements as needed.
void SetOptionAttribute(document::Document& doc, const std::string& key, const std::string& value);

// Writes every articulation keyframe into the compiled model's key arrays (the placeholder
// keys Compose added): the articulation's own values where given, the model's reference
// configuration elsewhere. Throws Error when the model does not match the layout.
void ApplyArticulationKeyframes(const std::vector<ArticulationLayout>& layouts, mjModel* m);

}  // namespace urlab::mjcf
