#include "urlab/world/scene_file.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "urlab/convert/mesh_io.h"
#include "urlab/core/files.h"
#include "urlab/document/element.h"
#include "urlab/document/grammar.h"
#include "urlab/document/orientation.h"
#include "urlab/world/names.h"
#include "world/input_keys.h"
#include "world/scene_names.h"
#include "world/scene_section.h"

namespace urlab::world {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Top-level sections a scene does not take, with where the setting lives instead: refused with a
// clear message instead of "unknown key" (and never silently accepted).
constexpr std::pair<const char*, const char*> kNotYetSupported[] = {
    {"recording", "recordings are made with `urlab record` or `urlab run --record`"},
    {"replay", "recordings are played with `urlab replay`"},
    {"input", "input bindings go in an articulation's `input:` list"},
    {"debug", "debug drawing is toggled in the viewer (keys 1-5, `--debug-all`)"},
    {"lights", "scene lights are not supported; put <light> elements in an articulation's MJCF"},
};

// Sections of the `urlab` tool's subsystems, which live above world and register their parsers
// (scene_section.h): a program built on the libraries parses one once it links the module and
// registers it; until then the key is refused naming the registration, not as an unknown key.
constexpr std::pair<const char*, const char*> kSubsystemSections[] = {
    {"network", "urlab::net (call urlab::net::RegisterSceneSections())"},
    {"cameras", "urlab::camera (call urlab::camera::RegisterSceneSections())"},
    {"viewer", "urlab::viewer (call urlab::viewer::RegisterSceneSections())"},
    {"cinematic", "urlab::viewer (call urlab::viewer::RegisterSceneSections())"},
};

using Range = NumberRange;
constexpr Range kNonNegativeFinite{0, std::numeric_limits<double>::max()};
constexpr Range kNonNegative{0, kInf};  // inf allowed (e.g. an unlimited torque)

// The scene's own keys; the reader's checks (world/scene_section.h) are shared with the sections
// subsystems parse.
class Parser : public SectionReader {
 public:
  explicit Parser(std::string path) : SectionReader(std::move(path)) {}
  using SectionReader::Number;

  // A whole number 0..max.
  int Index(const YAML::Node& n, const std::string& what, int max) const {
    const double v = Number(n, what, {0, static_cast<double>(max)});
    if (v != std::floor(v)) Fail(n, what + " must be a whole number, not " + n.Scalar());
    return static_cast<int>(v);
  }

  // `value` checked as the MJCF attribute `attribute` of grammar context `element` (count, type,
  // range, keyword), so a bad scene option is reported at its YAML line.
  void CheckAttribute(const YAML::Node& at, const std::string& element,
                      const std::string& attribute, const std::string& value,
                      const std::string& what) const {
    const document::ElementSpec* spec = document::Grammar::Get().Find(element);
    const document::AttributeSpec* a = spec ? spec->FindAttribute(attribute) : nullptr;
    if (!a) {
      std::string list;
      if (spec) {
        for (const auto& x : spec->attributes) list += (list.empty() ? "" : ", ") + x.name;
      }
      Fail(at,
           "unknown " + what + " '" + attribute + "' (MJCF <" + element + "> has: " + list + ")");
    }
    const std::string problem = document::CheckValue(*a, value);
    if (!problem.empty()) Fail(at, what + " " + attribute + ": " + problem);
  }

  std::map<std::string, std::string> Options(const YAML::Node& n, const std::string& where) const {
    if (!n.IsMap()) Fail(n, where + " must be a mapping of MJCF <option> attributes");
    std::map<std::string, std::string> out;
    for (const auto& [key, value] : Entries(n, where)) {
      if (key == "flag") {
        if (!value.IsMap()) Fail(value, where + ".flag must be a mapping");
        for (const auto& [flag, v] : Entries(value, where + ".flag")) {
          const std::string text = Scalar(v, where + ".flag." + flag);
          CheckAttribute(v, "option.flag", flag, text, where + ".flag");
          out["flag." + flag] = text;
        }
        continue;
      }
      const std::string text = Scalar(value, where + "." + key);
      CheckAttribute(value, "option", key, text, where);
      out[key] = text;
    }
    return out;
  }

  // A scalar or a list of scalars as MJCF attribute text.
  std::string Scalar(const YAML::Node& n, const std::string& what) const {
    if (n.IsScalar()) return n.as<std::string>();
    if (n.IsSequence()) {
      std::string s;
      for (const auto& v : n) {
        if (!s.empty()) s += ' ';
        s += String(v, what);
      }
      return s;
    }
    Fail(n, what + " must be a value or a list of values");
  }

  ControlSource Source(const YAML::Node& n) const {
    const std::string s = String(n, "control_source");
    if (s == "network" || s == "zmq") return ControlSource::kNetwork;
    if (s == "ui") return ControlSource::kUi;
    if (s == "input") return ControlSource::kInput;
    Fail(n, "control_source must be 'network', 'ui' or 'input', not '" + s + "'");
  }

  // kp, kv: >= 0 and finite; torque_limit: >= 0 (.inf for no limit).
  PdGains Gains(const YAML::Node& n, const std::string& where) const {
    CheckKeys(n, where, {"kp", "kv", "torque_limit"});
    return GainFields(n, where);
  }

  PdGains GainFields(const YAML::Node& n, const std::string& where) const {
    PdGains g;
    if (n["kp"]) g.kp = Number(n["kp"], where + ".kp", kNonNegativeFinite);
    if (n["kv"]) g.kv = Number(n["kv"], where + ".kv", kNonNegativeFinite);
    if (n["torque_limit"]) {
      g.torque_limit = Number(n["torque_limit"], where + ".torque_limit", kNonNegative);
    }
    return g;
  }

  ControllerConfig Controller(const YAML::Node& n) const {
    ControllerConfig c;
    c.where = At(n);
    if (n.IsScalar()) {
      c.type = n.as<std::string>();
    } else {
      CheckKeys(n, "controller",
                {"type", "kp", "kv", "torque_limit", "gains", "sequence", "loop", "autoplay",
                 "start_delay", "period", "swing_height", "stance_height", "step_gain"});
      if (!n["type"]) Fail(n, "controller needs a type (pd, passthrough, keyframe, gait)");
      c.type = String(n["type"], "controller.type");
      c.defaults = GainFields(n, "controller");
      if (const auto g = n["gains"]) {
        if (!g.IsMap()) Fail(g, "controller.gains must map joint names to gains");
        for (const auto& [joint, gains] : Entries(g, "controller.gains")) {
          c.gains[joint] = Gains(gains, "controller.gains." + joint);
        }
      }
      if (const auto s = n["sequence"]) {
        if (!s.IsSequence()) Fail(s, "controller.sequence must be a list");
        for (const auto& step : s) {
          CheckKeys(step, "controller.sequence entry", {"keyframe", "hold", "blend"});
          KeyframeStep k;
          if (!step["keyframe"]) Fail(step, "a sequence entry needs a keyframe");
          k.keyframe = String(step["keyframe"], "keyframe");
          if (step["hold"]) k.hold = Number(step["hold"], "hold", kNonNegativeFinite);
          if (step["blend"]) k.blend = Number(step["blend"], "blend", kNonNegativeFinite);
          c.sequence.push_back(k);
        }
      }
      if (n["loop"]) c.loop = Bool(n["loop"], "controller.loop");
      if (n["autoplay"]) c.autoplay = Bool(n["autoplay"], "controller.autoplay");
      if (n["start_delay"]) {
        c.start_delay = Number(n["start_delay"], "controller.start_delay", kNonNegativeFinite);
      }
      // The gait's fields, only on a gait controller.
      struct GaitField {
        const char* key;
        double control::GaitSettings::*value;
        Range range;
      };
      const GaitField gait_fields[] = {
          {"period", &control::GaitSettings::period, Range{0.1, 2}},
          {"swing_height", &control::GaitSettings::swing_height, Range{0, 0.5}},
          {"stance_height", &control::GaitSettings::stance_height, Range{0, 5, true}},
          {"step_gain", &control::GaitSettings::step_gain, Range{0, 1}},
      };
      for (const GaitField& f : gait_fields) {
        if (!n[f.key]) continue;
        if (c.type != "gait") {
          Fail(n[f.key], std::string("controller.") + f.key + " applies to a gait controller");
        }
        c.gait.*f.value = Number(n[f.key], std::string("controller.") + f.key, f.range);
      }
    }
    if (c.type != "none" && c.type != "pd" && c.type != "passthrough" && c.type != "keyframe" &&
        c.type != "gait") {
      throw InputError(
          c.where,
          "controller type must be none, pd, passthrough, keyframe or gait, not '" + c.type + "'");
    }
    if (c.type == "keyframe" && c.sequence.empty()) {
      throw InputError(c.where, "a keyframe controller needs a sequence of keyframes");
    }
    return c;
  }

  // The orientation of an entry: quat, euler (degrees, xyz) or axisangle (degrees), at most one.
  std::array<double, 4> Orientation(const YAML::Node& n, const std::string& name,
                                    std::array<double, 4> quat) const {
    int orientations = 0;
    if (n["quat"]) {
      auto v = Numbers(n["quat"], "quat", 4);
      if (v[0] == 0 && v[1] == 0 && v[2] == 0 && v[3] == 0)
        Fail(n["quat"], "quat must not be zero");
      quat = document::QuatNormalize({v[0], v[1], v[2], v[3]});
      ++orientations;
    }
    if (n["euler"]) {
      auto v = Numbers(n["euler"], "euler (degrees)", 3);
      quat = document::EulerToQuat({v[0] * kPi / 180, v[1] * kPi / 180, v[2] * kPi / 180}, "xyz");
      ++orientations;
    }
    if (n["axisangle"]) {
      auto v = Numbers(n["axisangle"], "axisangle (axis, degrees)", 4);
      const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      if (len < 1e-12) Fail(n["axisangle"], "axisangle axis must not be zero");
      const double h = v[3] * kPi / 360;
      quat = {std::cos(h), std::sin(h) * v[0] / len, std::sin(h) * v[1] / len,
              std::sin(h) * v[2] / len};
      ++orientations;
    }
    if (orientations > 1) Fail(n, name + ": give at most one of quat, euler, axisangle");
    return quat;
  }

  // The name of an articulation, prop, terrain or launcher entry: required, of the scene name
  // character set (world/scene_names.h).
  std::string EntryName(const YAML::Node& n, const std::string& kind) const {
    if (!n["name"])
      Fail(n, "a" + std::string(kind == "articulation" ? "n " : " ") + kind + " needs a name");
    std::string name = String(n["name"], kind + ".name");
    if (const std::string problem = SceneNameProblem(name); !problem.empty()) {
      std::string shown;
      for (char c : name) shown += c == '\n' ? std::string("\\n") : std::string(1, c);
      Fail(n["name"],
           kind + " name '" + shown + "' " + problem + " (names use " + kSceneNameRule + ")");
    }
    return name;
  }

  // A Quick Convert prop.
  PropConfig Prop(const YAML::Node& n) const {
    CheckKeys(n, "prop",
              {"name", "mesh", "pos", "quat", "euler", "axisangle", "scale", "mode", "mass",
               "density", "friction", "rgba", "threshold", "max_parts", "resolution"});
    PropConfig p;
    p.where = At(n);
    p.spec.name = EntryName(n, "prop");
    const std::string& name = p.spec.name;
    if (!n["mesh"]) Fail(n, name + ": a prop needs a mesh file");
    fs::path mesh(String(n["mesh"], "mesh"));
    if (mesh.is_relative()) mesh = fs::path(path()).parent_path() / mesh;
    p.spec.mesh = fs::absolute(mesh).lexically_normal().string();
    CheckInputFile(p.spec.mesh, name + ": mesh file", At(n["mesh"]), convert::kMaxMeshFileBytes);
    if (!convert::IsReadableMeshFormat(p.spec.mesh)) {
      Fail(n["mesh"], name + ": unknown mesh format '" + mesh.extension().string() + "'");
    }
    if (n["pos"]) {
      auto v = Numbers(n["pos"], "pos", 3);
      p.pos = {v[0], v[1], v[2]};
    }
    p.quat = Orientation(n, name, p.quat);
    if (const auto s = n["scale"]) {
      if (s.IsSequence()) {
        auto v = Numbers(s, name + ".scale", 3);
        p.spec.scale = {v[0], v[1], v[2]};
      } else {
        const double k = Number(s, name + ".scale", kNonNegativeFinite);
        p.spec.scale = {k, k, k};
      }
      for (double k : p.spec.scale) {
        if (!(k > 0)) Fail(s, name + ".scale must be > 0");
      }
    }
    if (const auto m = n["mode"]) {
      const std::string word = String(m, name + ".mode");
      const auto mode = convert::ParsePropMode(word);
      if (!mode) Fail(m, name + ".mode must be static, dynamic or mocap, not '" + word + "'");
      p.spec.mode = *mode;
    }
    if (n["mass"] && n["density"]) Fail(n, name + ": give mass or density, not both");
    constexpr Range kPositive{0, std::numeric_limits<double>::max(), true};
    if (n["mass"]) p.spec.mass = Number(n["mass"], name + ".mass", kPositive);
    if (n["density"]) p.spec.density = Number(n["density"], name + ".density", kPositive);
    if (const auto f = n["friction"]) {
      if (f.IsSequence()) {
        if (f.size() < 1 || f.size() > 3) Fail(f, name + ".friction must be 1 to 3 numbers");
        for (std::size_t i = 0; i < f.size(); ++i) {
          p.spec.friction[i] = Number(f[i], name + ".friction", kNonNegativeFinite);
        }
      } else {
        p.spec.friction[0] = Number(f, name + ".friction", kNonNegativeFinite);
      }
    }
    if (n["rgba"]) p.spec.rgba = Rgba(n["rgba"], name + ".rgba");
    if (n["threshold"]) {
      p.spec.decompose.threshold = Number(n["threshold"], name + ".threshold", Range{0, 1, true});
    }
    if (const auto m = n["max_parts"]) {
      const double v = Number(m, name + ".max_parts", Range{1, 1024});
      if (v != std::floor(v)) Fail(m, name + ".max_parts must be an integer");
      p.spec.decompose.max_parts = static_cast<int>(v);
    }
    if (const auto r = n["resolution"]) {
      const double v = Number(r, name + ".resolution", Range{4, 400});
      if (v != std::floor(v)) Fail(r, name + ".resolution must be an integer");
      p.spec.decompose.resolution = static_cast<int>(v);
    }
    return p;
  }

  // A file named in the scene: absolute, relative to the scene file's folder, checked to exist.
  std::string InputPath(const YAML::Node& n, const std::string& what,
                        std::uintmax_t max_bytes = kMaxTextInputBytes) const {
    fs::path p(String(n, what));
    if (p.is_relative()) p = fs::path(path()).parent_path() / p;
    const std::string out = fs::absolute(p).lexically_normal().string();
    CheckInputFile(out, what, At(n), max_bytes);
    return out;
  }

  // A terrain: meshes (file names, or {file, pos, scale}) or a png with its size.
  TerrainConfig Terrain(const YAML::Node& n) const {
    CheckKeys(n, "terrain",
              {"name", "meshes", "png", "size", "resolution", "bounds", "base", "friction", "pos",
               "quat", "euler", "axisangle"});
    TerrainConfig t;
    t.where = At(n);
    t.spec.name = EntryName(n, "terrain");
    const std::string& name = t.spec.name;
    if (!n["meshes"] == !n["png"]) Fail(n, name + ": give meshes or png (one of them)");
    if (const auto ms = n["meshes"]) {
      if (!ms.IsSequence() || ms.size() == 0) Fail(ms, name + ".meshes must be a list of files");
      for (const auto& m : ms) {
        convert::TerrainMesh tm;
        if (m.IsMap()) {
          CheckKeys(m, name + ".meshes entry", {"file", "pos", "scale"});
          if (!m["file"]) Fail(m, name + ": a mesh entry needs a file");
          tm.file = InputPath(m["file"], name + ": mesh file", convert::kMaxMeshFileBytes);
          if (m["pos"]) {
            auto v = Numbers(m["pos"], name + ".pos", 3);
            tm.pos = {v[0], v[1], v[2]};
          }
          if (m["scale"]) {
            const double k = Number(m["scale"], name + ".scale", Range{0, 1e6, true});
            tm.scale = {k, k, k};
          }
        } else {
          tm.file = InputPath(m, name + ": mesh file", convert::kMaxMeshFileBytes);
        }
        if (!convert::IsReadableMeshFormat(tm.file)) {
          Fail(m, name + ": unknown mesh format '" + fs::path(tm.file).extension().string() + "'");
        }
        t.spec.meshes.push_back(tm);
      }
    }
    if (const auto png = n["png"]) {
      t.spec.png = InputPath(png, name + ": png height map");
      if (!n["size"]) Fail(n, name + ": a png terrain needs size: [x, y, height, base] (m)");
    }
    if (n["size"]) {
      if (!n["png"]) Fail(n["size"], name + ".size is for png terrain (meshes give their size)");
      auto v = Numbers(n["size"], name + ".size", 4);
      for (double x : v) {
        if (!(x > 0)) Fail(n["size"], name + ".size values must be > 0");
      }
      t.spec.png_size = {v[0], v[1], v[2], v[3]};
    }
    if (n["resolution"]) {
      t.spec.resolution = Number(n["resolution"], name + ".resolution",
                                 Range{0, std::numeric_limits<double>::max(), true});
    }
    if (n["bounds"]) {
      auto v = Numbers(n["bounds"], name + ".bounds [x min, y min, x max, y max]", 4);
      if (!(v[2] > v[0]) || !(v[3] > v[1])) {
        Fail(n["bounds"], name + ".bounds: x max and y max must exceed x min and y min");
      }
      t.spec.bounds = std::array<double, 4>{v[0], v[1], v[2], v[3]};
    }
    if (n["base"]) {
      t.spec.base =
          Number(n["base"], name + ".base", Range{0, std::numeric_limits<double>::max(), true});
    }
    if (const auto f = n["friction"]) {
      auto v = Numbers(f, name + ".friction", 3);
      for (std::size_t i = 0; i < 3; ++i) {
        if (v[i] < 0) Fail(f, name + ".friction must be >= 0");
        t.spec.friction[i] = v[i];
      }
    }
    if (n["pos"]) {
      auto v = Numbers(n["pos"], "pos", 3);
      t.pos = {v[0], v[1], v[2]};
    }
    t.quat = Orientation(n, name, t.quat);
    return t;
  }

  // A colour: four numbers 0 to 1.
  std::array<double, 4> Rgba(const YAML::Node& n, const std::string& what) const {
    const std::vector<double> v = Numbers(n, what, 4);
    std::array<double, 4> out{};
    for (std::size_t i = 0; i < 4; ++i) {
      if (v[i] < 0 || v[i] > 1) Fail(n, what + " values must be 0 to 1");
      out[i] = v[i];
    }
    return out;
  }

  // An impulse launcher: pose (+x fires), projectile shape, size, mass, speed, pool, colour.
  LauncherConfig Launcher(const YAML::Node& n) const {
    CheckKeys(n, "launcher",
              {"name", "pos", "quat", "euler", "axisangle", "shape", "size", "mass", "speed",
               "pool", "rgba"});
    LauncherConfig l;
    l.where = At(n);
    LauncherSpec& spec = l.spec;
    spec.name = EntryName(n, "launcher");
    const std::string& name = spec.name;
    if (n["pos"]) {
      auto v = Numbers(n["pos"], name + ".pos", 3);
      spec.pos = {v[0], v[1], v[2]};
    }
    spec.quat = Orientation(n, name, spec.quat);
    if (n["shape"]) {
      spec.shape = String(n["shape"], name + ".shape");
      if (!FindProjectileShape(spec.shape)) {
        Fail(n["shape"], name + ".shape must be sphere, box or capsule, not '" + spec.shape + "'");
      }
    }
    const ProjectileShape& shape = *FindProjectileShape(spec.shape);
    constexpr Range kPositive{0, std::numeric_limits<double>::max(), true};
    if (const auto sz = n["size"]) {
      if (sz.IsSequence()) {
        for (const auto& v : sz) spec.size.push_back(Number(v, name + ".size", kPositive));
      } else {
        spec.size.push_back(Number(sz, name + ".size", kPositive));
      }
      if (static_cast<int>(spec.size.size()) != shape.size_count) {
        Fail(sz, name + ".size: a " + shape.name + " needs " + std::to_string(shape.size_count) +
                     " number(s) (" + shape.size_help + "), not " +
                     std::to_string(spec.size.size()));
      }
    }
    if (n["mass"]) spec.mass = Number(n["mass"], name + ".mass", kPositive);
    if (n["speed"]) spec.speed = Number(n["speed"], name + ".speed", Range{0, 1000});
    if (n["pool"]) {
      const double v = Number(n["pool"], name + ".pool", Range{1, kMaxLauncherPool});
      if (v != std::floor(v)) Fail(n["pool"], name + ".pool must be a whole number");
      spec.pool = static_cast<int>(v);
    }
    if (n["rgba"]) spec.rgba = Rgba(n["rgba"], name + ".rgba");
    return l;
  }

  // The twist block: a mode (policy, gait, hover), every other field a positive finite number.
  control::TwistSettings Twist(const YAML::Node& n, const std::string& where) const {
    if (!n.IsMap()) Fail(n, where + " must be a map (mode, max_vx, max_vy, max_yaw_rate, gains)");
    struct Field {
      const char* key;
      double control::TwistSettings::*value;
    };
    static constexpr Field kFields[] = {
        {"max_vx", &control::TwistSettings::max_vx},
        {"max_vy", &control::TwistSettings::max_vy},
        {"max_yaw_rate", &control::TwistSettings::max_yaw_rate},
        {"linear_gain", &control::TwistSettings::linear_gain},
        {"yaw_gain", &control::TwistSettings::yaw_gain},
    };
    std::set<std::string> keys;
    for (const Field& f : kFields) keys.insert(f.key);
    keys.insert("mode");
    CheckKeys(n, where, keys);
    control::TwistSettings t;
    if (n["mode"]) {
      const std::string mode = String(n["mode"], where + ".mode");
      const auto parsed = control::ParseTwistMode(mode);
      if (!parsed) {
        Fail(n["mode"], where + ".mode must be policy, gait or hover, not '" + mode + "'");
      }
      t.mode = *parsed;
    }
    for (const Field& f : kFields) {
      if (n[f.key]) t.*f.value = Number(n[f.key], where + "." + f.key, kNonNegativeFinite);
    }
    return t;
  }

  // {actuator, key | gamepad_axis | gamepad_button, scale}.
  InputBindingConfig InputBinding(const YAML::Node& n, const std::string& where) const {
    if (!n.IsMap()) Fail(n, where + " entries must be maps (actuator, key or gamepad_*, scale)");
    CheckKeys(n, where, {"actuator", "key", "gamepad_axis", "gamepad_button", "scale"});
    InputBindingConfig b;
    b.where = At(n);
    if (!n["actuator"]) Fail(n, where + ": a binding needs an actuator");
    b.actuator = String(n["actuator"], where + ".actuator");
    const int sources =
        (n["key"] ? 1 : 0) + (n["gamepad_axis"] ? 1 : 0) + (n["gamepad_button"] ? 1 : 0);
    if (sources != 1) Fail(n, where + ": give exactly one of key, gamepad_axis, gamepad_button");
    if (n["key"]) {
      b.key = String(n["key"], where + ".key");
      if (!IsKnownKeyName(b.key)) {
        Fail(n["key"], where + ": " +
                           (b.key.empty() ? "an empty key" : "unknown key '" + b.key + "'") +
                           " (keys: " + KnownKeyNamesText() + ")");
      }
    }
    if (n["gamepad_axis"]) b.gamepad_axis = Index(n["gamepad_axis"], where + ".gamepad_axis", 5);
    if (n["gamepad_button"]) {
      b.gamepad_button = Index(n["gamepad_button"], where + ".gamepad_button", 14);
    }
    if (n["scale"]) b.scale = Number(n["scale"], where + ".scale");
    return b;
  }

  ArticulationConfig Articulation(const YAML::Node& n) const {
    CheckKeys(n, "articulation",
              {"name", "mjcf", "pos", "quat", "euler", "axisangle", "options", "control_source",
               "controller", "keyframe", "hold_keyframe", "include_world", "cameras", "twist",
               "input", "latency"});
    ArticulationConfig a;
    a.where = At(n);
    a.name = EntryName(n, "articulation");
    if (!n["mjcf"]) Fail(n, a.name + ": an articulation needs an mjcf file");
    // Relative to the scene file's folder as written (a symlinked folder is not resolved first,
    // so "../models" means the folder next to the link, as users expect).
    fs::path p(String(n["mjcf"], "mjcf"));
    if (p.is_relative()) p = fs::path(path()).parent_path() / p;
    a.mjcf = fs::absolute(p).lexically_normal().string();
    CheckInputFile(a.mjcf, a.name + ": mjcf file", At(n["mjcf"]));
    if (n["pos"]) {
      auto v = Numbers(n["pos"], "pos", 3);
      a.pos = {v[0], v[1], v[2]};
    }
    a.quat = Orientation(n, a.name, a.quat);

    if (n["options"]) a.options = Options(n["options"], a.name + ".options");
    if (n["control_source"]) a.control_source = Source(n["control_source"]);
    if (n["controller"]) a.controller = Controller(n["controller"]);
    if (n["keyframe"]) a.keyframe = String(n["keyframe"], "keyframe");
    if (n["hold_keyframe"]) a.hold_keyframe = Bool(n["hold_keyframe"], "hold_keyframe");
    if (n["include_world"]) a.include_world = Bool(n["include_world"], "include_world");
    if (const auto c = n["cameras"]) {
      if (c.IsSequence()) {
        a.cameras = Names(c, a.name + ".cameras");
      } else {
        a.all_cameras = Bool(c, a.name + ".cameras (true, false or a list of camera names)");
      }
    }
    if (n["twist"]) {
      a.twist = Twist(n["twist"], a.name + ".twist");
      a.twist_given = true;
      a.twist_mode_given = static_cast<bool>(n["twist"]["mode"]);
    }
    if (const auto in = n["input"]) {
      if (!in.IsSequence()) Fail(in, a.name + ".input must be a list of bindings");
      for (const auto& b : in) a.input.push_back(InputBinding(b, a.name + ".input"));
    }
    if (const auto l = n["latency"]) a.latency = Latency(l, a.name + ".latency");
    return a;
  }

  physics::ArticulationLatency Latency(const YAML::Node& n, const std::string& where) const {
    CheckKeys(n, where, {"control", "observation"});
    physics::ArticulationLatency l;
    if (n["control"]) l.control = LatencyEntry(n["control"], where + ".control");
    if (n["observation"]) l.observation = LatencyEntry(n["observation"], where + ".observation");
    return l;
  }

  // The list section `key` of entries parsed by `parse` into `out`; each name (spec.name) must be
  // new in `names`, the scene's one namespace.
  template <typename T>
  void NamedList(const YAML::Node& root, const char* key, std::vector<T>* out,
                 T (Parser::*parse)(const YAML::Node&) const, std::set<std::string>* names) const {
    const YAML::Node list = root[key];
    if (!list) return;
    if (!list.IsSequence()) Fail(list, std::string(key) + " must be a list");
    for (const auto& entry : list) {
      out->push_back((this->*parse)(entry));
      if (!names->insert(out->back().spec.name).second) {
        Fail(entry, "the name '" + out->back().spec.name +
                        "' is used twice (articulations, props, terrain and launchers share one "
                        "namespace)");
      }
    }
  }

  SceneConfig Scene(const YAML::Node& root) const {
    SceneConfig s;
    s.path = path();
    if (!root || root.IsNull()) throw InputError({path(), 0}, "the scene file is empty");
    const std::set<std::string> registered = SceneSectionNames();
    if (root.IsMap()) {
      for (const auto& kv : root) {
        if (!kv.first.IsScalar()) continue;  // reported by CheckKeys
        for (const auto& [key, feature] : kNotYetSupported) {
          if (kv.first.Scalar() == key) {
            Fail(kv.first, "'" + std::string(key) + ":' is not a scene section: " + feature +
                               "; remove the section");
          }
        }
        for (const auto& [key, owner] : kSubsystemSections) {
          if (kv.first.Scalar() == key && !registered.contains(key)) {
            Fail(kv.first, "'" + std::string(key) + ":' is a section of " + owner +
                               ", which this program did not register; register it before "
                               "parsing scenes, or remove the section");
          }
        }
      }
    }
    // The scene's own keys, and the sections registered subsystems parse.
    std::set<std::string> keys = {"articulations",  "props",          "terrain",
                                  "launchers",      "options",        "size",
                                  "control_source", "save_debug_xml", "seed"};
    keys.insert(registered.begin(), registered.end());
    CheckKeys(root, "the scene", keys);
    const YAML::Node arts = root["articulations"];
    if (!arts || !arts.IsSequence() || arts.size() == 0) {
      Fail(arts ? arts : root, "the scene needs a non-empty list 'articulations'");
    }
    std::set<std::string> names;
    for (const auto& a : arts) {
      s.articulations.push_back(Articulation(a));
      if (!names.insert(s.articulations.back().name).second) {
        Fail(a, "two articulations are named '" + s.articulations.back().name + "'");
      }
    }
    // Props, terrain and launchers share the articulations' namespace.
    NamedList(root, "props", &s.props, &Parser::Prop, &names);
    NamedList(root, "terrain", &s.terrain, &Parser::Terrain, &names);
    NamedList(root, "launchers", &s.launchers, &Parser::Launcher, &names);
    if (root["options"]) s.options = Options(root["options"], "options");
    if (const auto n = root["size"]) {
      CheckKeys(n, "size", {"njmax", "nconmax", "nstack", "nuserdata"});
      for (const auto& [key, value] : Entries(n, "size")) {
        if (!value.IsScalar()) Fail(value, "size." + key + " must be an integer");
        // The grammar's check: an integer within int, -1 ("as needed") or more.
        CheckAttribute(value, "size", key, value.Scalar(), "size");
        s.size[key] = value.Scalar();
      }
    }
    if (root["control_source"]) s.control_source = Source(root["control_source"]);
    if (const auto n = root["seed"]) {
      // A whole number a double holds exactly: the step server's and the batch's seed range.
      const double v = Number(n, "seed", Range{0, 9007199254740991.0});
      if (v != std::floor(v)) Fail(n, "seed must be a whole number, not " + n.Scalar());
      s.seed = static_cast<std::uint64_t>(v);
    }
    if (const auto n = root["save_debug_xml"]) {
      if (n.IsScalar() && (n.as<std::string>() == "true" || n.as<std::string>() == "false")) {
        if (Bool(n, "save_debug_xml")) {
          s.save_debug_xml = (fs::path(path()).parent_path() / "Saved" / "URLab").string();
        }
      } else {
        fs::path p(String(n, "save_debug_xml"));
        if (p.is_relative()) p = fs::path(path()).parent_path() / p;
        s.save_debug_xml = p.lexically_normal().string();
      }
    }
    // The sections subsystems own, each given the scene's own keys parsed above.
    for (const auto& [key, node] : Entries(root, "the scene")) {
      if (const SectionParser parse = FindSceneSection(key))
        s.sections.Set(key, parse(*this, node, s));
    }
    return s;
  }
};

}  // namespace

SceneConfig ParseScene(const std::string& yaml, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::ParserException& e) {
    throw InputError({path, e.mark.line + 1}, "malformed YAML: " + e.msg);
  }
  try {
    return Parser(path).Scene(root);
  } catch (const YAML::Exception& e) {
    // A conversion the parser did not foresee: still located.
    throw InputError({path, e.mark.is_null() ? 0 : e.mark.line + 1}, "scene: " + e.msg);
  }
}

SceneConfig LoadSceneFile(const std::string& path) {
  // Made absolute without resolving symlinks: relative paths inside resolve from the folder the
  // user named (a symlinked scene folder behaves as the folder it appears to be).
  const std::string shown = fs::absolute(path).lexically_normal().string();
  return ParseScene(ReadInputFile(shown, "scene file"), shown);
}

SceneConfig LoadSceneOrModel(const std::string& path) {
  if (IsSceneFile(path)) return LoadSceneFile(path);
  const std::string shown = fs::absolute(path).lexically_normal().string();
  CheckInputFile(shown, "model file");
  const std::string name = ModelArticulationName(shown);
  SceneConfig scene;
  scene.path = shown;
  ArticulationConfig a;
  a.name = name;
  a.mjcf = scene.path;
  a.where = {scene.path, 0};
  scene.articulations.push_back(std::move(a));
  return scene;
}

bool IsSceneFile(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".yaml" || ext == ".yml";
}

}  // namespace urlab::world
