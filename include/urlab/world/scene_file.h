#pragma once
// The scene file (the "level"): YAML listing articulations with their MJCF, world transform,
// options, control source, controller and initial keyframe, Quick Convert props (a mesh, its
// pose, scale, mode, mass or density, friction and decomposition settings), terrain
// (meshes sampled into a heightfield, or a PNG height map), impulse launchers, plus scene-wide
// option overrides, the seed and the debug-XML switch; the sections a subsystem owns (`viewer:`,
// `cinematic:`, `cameras:`, `network:`) go to the parser it registered, and world's own
// `randomize:` to its parser in the same table (src/world/scene_section.h). Unknown keys,
// duplicate keys, keys that are not
// strings, wrong types and numbers out of range (gains, torque limits, hold/blend times, options
// checked against the MJCF grammar, size fields), fractions where a whole number is meant
// (gamepad indices, pool sizes) and names outside the scene name character set
// (world/scene_names.h) are InputErrors with file and line; sections of features that do not
// exist yet (recording, lights...) are refused as "not supported yet". Thread: any (pure
// parsing).
#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "urlab/control/controller.h"
#include "urlab/control/gait.h"
#include "urlab/control/twist.h"
#include "urlab/convert/heightfield.h"
#include "urlab/convert/prop.h"
#include "urlab/core/error.h"
#include "urlab/physics/latency.h"
#include "urlab/world/launchers.h"
#include "urlab/world/scene_sections.h"

namespace urlab::world {

// Who drives an articulation's actuators (the control layer's enum).
using control::ControlSource;

struct PdGains {
  std::optional<double> kp, kv, torque_limit;
};

struct KeyframeStep {
  std::string keyframe;  // keyframe name in the articulation's MJCF
  double hold = 1.0;     // seconds at the pose
  double blend = 0.5;    // seconds blending into it
};

struct ControllerConfig {
  std::string type = "none";             // none | pd | passthrough | keyframe | gait
  PdGains defaults;                      // pd: gains for every actuator
  std::map<std::string, PdGains> gains;  // pd: per joint or actuator (short name)
  std::vector<KeyframeStep> sequence;    // keyframe controller
  bool loop = false;
  bool autoplay = true;
  double start_delay = 0.0;
  // gait: the trot's period, swing height, stance height and landing gain (control/gait.h;
  // stand_key is resolved from the articulation's keyframe when installed).
  control::GaitSettings gait;
  SourceLocation where;
};

// Input mapping (the description's MjInputMapping): a key or gamepad axis/button drives one
// actuator's target on the `input` control source, as value * scale (a key or button is 1 while
// held, an axis -1..1). Exactly one of key, gamepad_axis, gamepad_button. Loading the scene
// refuses an unknown or empty key name (world/input_keys.h) and begin-play's checks an actuator
// that is not the articulation's own (world::CheckCompiledScene), at the binding's file:line.
struct InputBindingConfig {
  std::string actuator;     // short name in the articulation
  std::string key;          // "J", "7", "Space", "Up", ... ("" when a gamepad drives it)
  int gamepad_axis = -1;    // GLFW gamepad axis 0..5
  int gamepad_button = -1;  // GLFW gamepad button 0..14
  double scale = 1;
  SourceLocation where;
};

struct ArticulationConfig {
  std::string name;
  std::string mjcf;  // absolute path
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};    // from quat, euler (degrees, xyz) or axisangle
  std::map<std::string, std::string> options;   // <option> attributes, "flag.X" for flags
  std::optional<ControlSource> control_source;  // overrides the scene's
  ControllerConfig controller;
  std::string keyframe;  // initial keyframe ("" = none)
  // false drops what the MJCF attaches directly to its world body other than bodies (a floor,
  // lights, world cameras): for composing many copies of a model that brings its own floor.
  bool include_world = true;
  bool hold_keyframe = false;
  // Which of its MJCF cameras stream (the scene's `cameras:` section says how): none by default,
  // `cameras: true` all of them, or a list of camera names (as written in its MJCF).
  bool all_cameras = false;
  std::vector<std::string> cameras;
  // The twist controller's maxima and gains (control/twist.h); every articulation with a free
  // base gets one (detached until possessed or set_twist), with these or the defaults.
  // Its mode (what the twist drives) is resolved when installed: `gait` with a gait controller,
  // else `policy`, unless the block says `mode:` (hover for bodies without legs).
  control::TwistSettings twist;
  bool twist_given = false;       // the scene gave a twist block (refused without a free base)
  bool twist_mode_given = false;  // ... with a mode

  std::vector<InputBindingConfig> input;
  // Emulated latency (`latency:`): control and observation delays (physics/latency.h).
  physics::ArticulationLatency latency;
  SourceLocation where;
};

// A Quick Convert prop (`props:`): a mesh made a body with convex collision parts, composed
// after the articulations like one named `spec.name` (prefix "{name}_", body "{name}_body").
struct PropConfig {
  convert::PropSpec spec;  // mesh path absolute
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};
  SourceLocation where;
};

// A terrain (`terrain:`): meshes sampled into a heightfield by ray casts, or a PNG height map,
// composed after the props like an articulation named `spec.name` (geom "{name}_geom").
struct TerrainConfig {
  convert::TerrainSpec spec;  // paths absolute
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};
  SourceLocation where;
};

// An impulse launcher (`launchers:`, world/launchers.h): composed after the terrain like an
// articulation named `spec.name` (bodies "{name}_projectile{i}").
struct LauncherConfig {
  LauncherSpec spec;
  SourceLocation where;
};

struct SceneConfig {
  std::string path;  // the scene file
  std::vector<ArticulationConfig> articulations;
  std::vector<PropConfig> props;
  std::vector<TerrainConfig> terrain;
  std::vector<LauncherConfig> launchers;
  std::map<std::string, std::string> options;  // manager overrides: only the fields set
  std::map<std::string, std::string> size;     // <size> attributes (nconmax, njmax, nstack...)
  ControlSource control_source = ControlSource::kNetwork;
  // The sections subsystems own (`viewer:`, `cinematic:`, `cameras:`, `network:`; world's own
  // `randomize:`, world/randomize_settings.h), parsed by the parser each registered
  // (src/world/scene_section.h) into its own settings type.
  SceneSections sections;
  std::string save_debug_xml;  // folder for scene_compiled.xml/.mjb ("" = off)
  // The run's seed (`seed:`; `urlab run --seed` overrides): every emulated delay's jitter draws
  // from it.
  std::uint64_t seed = 0;
};

// Parses a scene file. Relative MJCF paths resolve against the scene file's folder.
SceneConfig LoadSceneFile(const std::string& path);
// Parses scene YAML held in memory; `path` names it in messages and anchors relative paths.
SceneConfig ParseScene(const std::string& yaml, const std::string& path);

// The scene every command builds from a path: a scene file (.yaml/.yml), or one MJCF file as a
// scene of one articulation named by ModelArticulationName (world/names.h: the folder for a
// `scene.xml`, else `<mujoco model>`, else the file stem), composed
// with its prefix exactly like an articulation of a scene, so a file that validates is a file
// that runs. Paths are made absolute without resolving symlinks. Throws InputError for a bad or
// missing file, a FIFO or device, or a file larger than kMaxTextInputBytes.
SceneConfig LoadSceneOrModel(const std::string& path);

// True when `path` looks like a scene file (.yaml / .yml).
bool IsSceneFile(const std::string& path);

}  // namespace urlab::world
