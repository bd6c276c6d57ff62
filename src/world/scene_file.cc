#include "urlab/world/scene_file.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "urlab/document/orientation.h"

namespace urlab::world {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

class Parser {
 public:
  explicit Parser(std::string path) : path_(std::move(path)) {}

  SourceLocation At(const YAML::Node& n) const { return {path_, n.Mark().line + 1}; }

  [[noreturn]] void Fail(const YAML::Node& n, const std::string& what) const {
    throw InputError(At(n), what);
  }

  void CheckKeys(const YAML::Node& map, const std::string& where,
                 const std::set<std::string>& allowed) const {
    if (!map.IsMap()) Fail(map, where + " must be a mapping");
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        Fail(kv.first,
             "unknown key '" + key + "' in " + where + " (expected one of: " + list + ")");
      }
    }
  }

  template <typename T>
  T As(const YAML::Node& n, const std::string& what) const {
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      Fail(n, what + ": wrong type");
    }
  }

  double Number(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be a number");
    return As<double>(n, what + " must be a number");
  }

  std::vector<double> Numbers(const YAML::Node& n, const std::string& what, size_t count) const {
    if (!n.IsSequence() || n.size() != count) {
      Fail(n, what + " must be a list of " + std::to_string(count) + " numbers");
    }
    std::vector<double> out;
    for (const auto& v : n) out.push_back(Number(v, what));
    return out;
  }

  bool Bool(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be true or false");
    return As<bool>(n, what + " must be true or false");
  }

  std::string String(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be a string");
    return n.as<std::string>();
  }

  std::map<std::string, std::string> Options(const YAML::Node& n, const std::string& where) const {
    if (!n.IsMap()) Fail(n, where + " must be a mapping of MJCF <option> attributes");
    std::map<std::string, std::string> out;
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (key == "flag") {
        if (!kv.second.IsMap()) Fail(kv.second, where + ".flag must be a mapping");
        for (const auto& f : kv.second) {
          out["flag." + f.first.as<std::string>()] = Scalar(f.second, where + ".flag");
        }
        continue;
      }
      out[key] = Scalar(kv.second, where + "." + key);
    }
    return out;
  }

  // A scalar or a list of scalars as MJCF attribute text.
  std::string Scalar(const YAML::Node& n, const std::string& what) const {
    if (n.IsScalar()) return n.as<std::string>();
    if (n.IsSequence()) {
      std::string s;
      for (const auto& v : n) s += (s.empty() ? "" : " ") + String(v, what);
      return s;
    }
    Fail(n, what + " must be a value or a list of values");
  }

  ControlSource Source(const YAML::Node& n) const {
    const std::string s = String(n, "control_source");
    if (s == "network" || s == "zmq") return ControlSource::kNetwork;
    if (s == "ui") return ControlSource::kUi;
    Fail(n, "control_source must be 'network' or 'ui', not '" + s + "'");
  }

  PdGains Gains(const YAML::Node& n, const std::string& where) const {
    CheckKeys(n, where, {"kp", "kv", "torque_limit"});
    PdGains g;
    if (n["kp"]) g.kp = Number(n["kp"], where + ".kp");
    if (n["kv"]) g.kv = Number(n["kv"], where + ".kv");
    if (n["torque_limit"]) g.torque_limit = Number(n["torque_limit"], where + ".torque_limit");
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
                 "start_delay"});
      if (!n["type"]) Fail(n, "controller needs a type (pd, passthrough, keyframe)");
      c.type = String(n["type"], "controller.type");
      if (n["kp"]) c.defaults.kp = Number(n["kp"], "controller.kp");
      if (n["kv"]) c.defaults.kv = Number(n["kv"], "controller.kv");
      if (n["torque_limit"]) c.defaults.torque_limit = Number(n["torque_limit"], "torque_limit");
      if (const auto g = n["gains"]) {
        if (!g.IsMap()) Fail(g, "controller.gains must map joint names to gains");
        for (const auto& kv : g) {
          c.gains[kv.first.as<std::string>()] = Gains(kv.second, "controller.gains");
        }
      }
      if (const auto s = n["sequence"]) {
        if (!s.IsSequence()) Fail(s, "controller.sequence must be a list");
        for (const auto& step : s) {
          CheckKeys(step, "controller.sequence entry", {"keyframe", "hold", "blend"});
          KeyframeStep k;
          if (!step["keyframe"]) Fail(step, "a sequence entry needs a keyframe");
          k.keyframe = String(step["keyframe"], "keyframe");
          if (step["hold"]) k.hold = Number(step["hold"], "hold");
          if (step["blend"]) k.blend = Number(step["blend"], "blend");
          if (k.hold < 0 || k.blend < 0) Fail(step, "hold and blend must be >= 0");
          c.sequence.push_back(k);
        }
      }
      if (n["loop"]) c.loop = Bool(n["loop"], "controller.loop");
      if (n["autoplay"]) c.autoplay = Bool(n["autoplay"], "controller.autoplay");
      if (n["start_delay"]) c.start_delay = Number(n["start_delay"], "controller.start_delay");
    }
    if (c.type != "none" && c.type != "pd" && c.type != "passthrough" && c.type != "keyframe") {
      throw InputError(c.where, "controller type must be none, pd, passthrough or keyframe, not '" +
                                    c.type + "'");
    }
    if (c.type == "keyframe" && c.sequence.empty()) {
      throw InputError(c.where, "a keyframe controller needs a sequence of keyframes");
    }
    return c;
  }

  ArticulationConfig Articulation(const YAML::Node& n) const {
    CheckKeys(n, "articulation",
              {"name", "mjcf", "pos", "quat", "euler", "axisangle", "options", "control_source",
               "controller", "keyframe", "hold_keyframe", "include_world"});
    ArticulationConfig a;
    a.where = At(n);
    if (!n["name"]) Fail(n, "an articulation needs a name");
    a.name = String(n["name"], "name");
    if (a.name.empty() || a.name.find_first_of(" /\t") != std::string::npos) {
      Fail(n["name"], "articulation name '" + a.name + "' must be non-empty without spaces or /");
    }
    if (!n["mjcf"]) Fail(n, a.name + ": an articulation needs an mjcf file");
    fs::path p(String(n["mjcf"], "mjcf"));
    if (p.is_relative()) p = fs::path(path_).parent_path() / p;
    a.mjcf = fs::absolute(p).lexically_normal().string();
    if (!fs::exists(a.mjcf)) Fail(n["mjcf"], a.name + ": mjcf file '" + a.mjcf + "' not found");
    if (n["pos"]) {
      auto v = Numbers(n["pos"], "pos", 3);
      a.pos = {v[0], v[1], v[2]};
    }
    int orientations = 0;
    if (n["quat"]) {
      auto v = Numbers(n["quat"], "quat", 4);
      a.quat = document::QuatNormalize({v[0], v[1], v[2], v[3]});
      ++orientations;
    }
    if (n["euler"]) {
      auto v = Numbers(n["euler"], "euler (degrees)", 3);
      a.quat = document::EulerToQuat({v[0] * kPi / 180, v[1] * kPi / 180, v[2] * kPi / 180}, "xyz");
      ++orientations;
    }
    if (n["axisangle"]) {
      auto v = Numbers(n["axisangle"], "axisangle (axis, degrees)", 4);
      const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      if (len < 1e-12) Fail(n["axisangle"], "axisangle axis must not be zero");
      const double h = v[3] * kPi / 360;
      a.quat = {std::cos(h), std::sin(h) * v[0] / len, std::sin(h) * v[1] / len,
                std::sin(h) * v[2] / len};
      ++orientations;
    }
    if (orientations > 1) Fail(n, a.name + ": give at most one of quat, euler, axisangle");
    if (n["options"]) a.options = Options(n["options"], a.name + ".options");
    if (n["control_source"]) a.control_source = Source(n["control_source"]);
    if (n["controller"]) a.controller = Controller(n["controller"]);
    if (n["keyframe"]) a.keyframe = String(n["keyframe"], "keyframe");
    if (n["hold_keyframe"]) a.hold_keyframe = Bool(n["hold_keyframe"], "hold_keyframe");
    if (n["include_world"]) a.include_world = Bool(n["include_world"], "include_world");
    return a;
  }

  SceneConfig Scene(const YAML::Node& root) const {
    SceneConfig s;
    s.path = path_;
    if (!root || root.IsNull()) throw InputError({path_, 0}, "the scene file is empty");
    CheckKeys(root, "the scene",
              {"articulations", "options", "size", "control_source", "network", "save_debug_xml"});
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
    if (root["options"]) s.options = Options(root["options"], "options");
    if (const auto n = root["size"]) {
      CheckKeys(n, "size", {"njmax", "nconmax", "nstack", "nuserdata"});
      for (const auto& kv : n) {
        s.size[kv.first.as<std::string>()] =
            std::to_string(static_cast<long long>(Number(kv.second, "size")));
      }
    }
    if (root["control_source"]) s.control_source = Source(root["control_source"]);
    if (const auto n = root["network"]) {
      CheckKeys(n, "network",
                {"enabled", "state", "control", "info", "rpc", "step_mode", "full_state",
                 "camera_base_port"});
      if (n["enabled"]) s.network.enabled = Bool(n["enabled"], "network.enabled");
      if (n["state"]) s.network.state = String(n["state"], "network.state");
      if (n["control"]) s.network.control = String(n["control"], "network.control");
      if (n["info"]) s.network.info = String(n["info"], "network.info");
      if (n["rpc"]) s.network.rpc = String(n["rpc"], "network.rpc");
      if (n["full_state"]) {
        s.network.full_state = String(n["full_state"], "network.full_state");
        if (s.network.full_state == "none") s.network.full_state.clear();
        if (!s.network.full_state.empty() && s.network.full_state != "minimal" &&
            s.network.full_state != "standard" && s.network.full_state != "full") {
          throw InputError(At(n["full_state"]),
                           "network.full_state must be minimal, standard, full or none");
        }
      }
      if (n["step_mode"]) {
        s.network.step_mode = String(n["step_mode"], "network.step_mode");
        if (s.network.step_mode != "live" && s.network.step_mode != "direct") {
          throw InputError(At(n["step_mode"]), "network.step_mode must be live or direct");
        }
      }
      if (n["camera_base_port"]) s.network.camera_base_port = String(n["camera_base_port"], "port");
    }
    if (const auto n = root["save_debug_xml"]) {
      if (n.IsScalar() && (n.as<std::string>() == "true" || n.as<std::string>() == "false")) {
        if (Bool(n, "save_debug_xml")) {
          s.save_debug_xml = (fs::path(path_).parent_path() / "Saved" / "URLab").string();
        }
      } else {
        fs::path p(String(n, "save_debug_xml"));
        if (p.is_relative()) p = fs::path(path_).parent_path() / p;
        s.save_debug_xml = p.lexically_normal().string();
      }
    }
    return s;
  }

 private:
  std::string path_;
};

}  // namespace

SceneConfig ParseScene(const std::string& yaml, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::ParserException& e) {
    throw InputError({path, e.mark.line + 1}, "malformed YAML: " + e.msg);
  }
  return Parser(path).Scene(root);
}

SceneConfig LoadSceneFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError({path, 0}, "scene file not found");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseScene(ss.str(), fs::absolute(path).lexically_normal().string());
}

bool IsSceneFile(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".yaml" || ext == ".yml";
}

}  // namespace urlab::world
