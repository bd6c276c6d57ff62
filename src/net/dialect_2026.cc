#include "net/dialect_2026.h"

#include <array>

#include "urlab/ops/error.h"

namespace urlab::net::dialect2026 {

// ---------------------------------------------------------------------------------------------
// The tables

const std::vector<Rename> kModes = {
    {"live", "freerun"}, {"direct", "stepped"}, {"puppet", "statepushed"}};
const std::vector<Rename> kControlSources = {{"network", "zmq"}, {"ui", "ui"}};
// In MuJoCo's enum order: a reply's integer is the row.
const std::vector<Rename> kIntegrators = {
    {"Euler", "euler"}, {"RK4", "rk4"}, {"implicit", "implicit"}};
const std::vector<Rename> kCones = {{"pyramidal", "pyramidal"}, {"elliptic", "elliptic"}};
const std::vector<Rename> kSolvers = {{"PGS", "pgs"}, {"CG", "cg"}, {"Newton", "newton"}};

const std::vector<Field> kRequestFields = {
    {"set_qpos", "articulation", "target"},
    {"recording_start", "path", "name"},
    {"recording_start", "max_duration", "max_duration_s"},
    {"recording_save", "path", "name"},
    {"replay_load", "path", "name"},
    {"replay_set_active", "session", "name"},
    {"replay_start", "session", "name"},
    {"replay_unload", "session", "name"},
    {"step", "per_articulation", "arts"},
};

const std::vector<Field> kReplyFields = {
    {"set_qpos", "articulation", "target"},
    {"get_contacts", "count", "n_contacts"},
    {"recording_start", "path", "name"},
    {"recording_start", "max_duration", "max_duration_s"},
    {"recording_stop", "frames", "frame_count"},
    {"recording_stop", "duration", "sim_duration_s"},
    {"recording_status", "frames", "frame_count"},
    {"recording_status", "duration", "sim_duration_s"},
    {"replay_load", "session", "name"},
    {"replay_load", "frames", "total_frames"},
    {"replay_set_active", "session", "name"},
    {"replay_start", "session", "active_session"},
    {"replay_start", "frames", "total_frames"},
    {"replay_status", "session", "active_session"},
    {"replay_status", "frames", "total_frames"},
};

const std::vector<OpPlace> kOpPlaces = {
    {"hello", "session", "session"},
    {"meta", "session", "session"},
    {"bye", "session", "session"},
    {"step", "simulation", "sim"},
    {"reset", "simulation", "sim"},
    {"forward", "simulation", "sim"},
    {"set_mode", "simulation", "sim"},
    {"set_paused", "simulation", "sim"},
    {"set_sim_speed", "simulation", "sim"},
    {"set_sim_options", "simulation", "sim"},
    {"cancel", "simulation", "sim"},
    {"set_qpos", "state", "sim"},
    {"set_mocap_pose", "state", "scene"},
    {"read_mocap_pose", "state", "scene"},
    {"list_keyframes", "queries", "scene"},
    {"get_contacts", "queries", "scene"},
    {"get_counters", "queries", "runtime"},
    {"set_control_source", "controllers", "runtime"},
    {"set_twist", "controllers", "runtime"},
    {"fire_launcher", "controllers", "runtime"},
    {"configure_controller", "controllers", "runtime"},
    {"set_latency", "controllers", "runtime"},
    {"get_latency", "controllers", "runtime"},
    {"batch_info", "batch", "batch"},
    {"batch_step", "batch", "batch"},
    {"batch_reset", "batch", "batch"},
};

OpPlace PlaceOf(std::string_view op) {
  for (const OpPlace& p : kOpPlaces) {
    if (p.op == op) return p;
  }
  if (op.starts_with("recording_") || op.starts_with("snapshot_")) {
    return {op, "recording", "runtime"};
  }
  if (op.starts_with("replay_")) return {op, "replay", "runtime"};
  return {op, "runtime", "runtime"};
}

// The editor's operations: exact names, and the families by how their names begin or end.
namespace {
constexpr std::array<std::string_view, 3> kEditorOps = {"begin_pie", "stop_pie", "pie_status"};
constexpr std::array<std::string_view, 9> kEditorPrefixes = {
    "pie_",   "level",      "actor",        "outliner",   "viewport",
    "debug_", "draw_debug", "upload_model", "render_farm"};
constexpr std::array<std::string_view, 8> kEditorParts = {
    "_pie",      "_level",        "_actor",       "_outliner",
    "_viewport", "_debug_marker", "_render_farm", "_debug_draw"};
}  // namespace

std::optional<std::string> EditorOnly(std::string_view op) {
  bool editor = false;
  for (std::string_view e : kEditorOps) editor = editor || op == e;
  for (std::string_view p : kEditorPrefixes) editor = editor || op.starts_with(p);
  for (std::string_view p : kEditorParts) editor = editor || op.find(p) != std::string_view::npos;
  if (!editor) return std::nullopt;
  return "'" + std::string(op) +
         "' belongs to the Unreal editor (play sessions, levels, actors, outliner, viewport, "
         "debug markers, model upload, render farm); URLab runs MuJoCo without Unreal and has no "
         "such operation";
}

// ---------------------------------------------------------------------------------------------
// Lookups

std::optional<std::string_view> Ours(const std::vector<Rename>& table, std::string_view theirs) {
  for (const Rename& r : table) {
    if (r.theirs == theirs) return r.ours;
  }
  return std::nullopt;
}

std::optional<std::string_view> Theirs(const std::vector<Rename>& table, std::string_view ours) {
  for (const Rename& r : table) {
    if (r.ours == ours) return r.theirs;
  }
  return std::nullopt;
}

bool Speaks(const Json& hello) {
  const auto it = hello.find("client_version");
  return it != hello.end() && it->is_string() &&
         it->get_ref<const std::string&>().starts_with(kClientVersionPrefix);
}

namespace {

using ops::Fail;

// A string field named in `table` by its 2026 name: replaced by ours (ours pass unchanged).
void RenameValue(Json& body, const char* field, const std::vector<Rename>& table) {
  const auto it = body.find(field);
  if (it == body.end() || !it->is_string()) return;
  if (const auto ours = Ours(table, it->get_ref<const std::string&>())) {
    *it = std::string(*ours);
  }
}

// Ours for theirs, when the request has theirs and not ours.
void MoveField(Json& body, std::string_view ours, std::string_view theirs) {
  const std::string t(theirs), o(ours);
  const auto it = body.find(t);
  if (it == body.end() || body.contains(o)) return;
  Json v = std::move(*it);
  body.erase(t);
  body[o] = std::move(v);
}

// A step's articulation entry: ctrl given as {name: value} is our ctrl_map; control_mode passes.
void TranslateStepEntry(Json& entry) {
  if (!entry.is_object()) return;
  if (const auto c = entry.find("ctrl"); c != entry.end() && c->is_object()) {
    Json map = std::move(*c);
    entry.erase("ctrl");
    if (!entry.contains("ctrl_map")) entry["ctrl_map"] = std::move(map);
  }
}

// configure_controller's params: {kp|kv|torque_limit: {name: v} or v, default_*: v} to ours:
// {kp|kv|torque_limit: v (every actuator), gains {name: {kp, kv, torque_limit}}}. The defaults
// go first, then the names: a default applies to the names not mentioned.
void TranslateGains(Json& params) {
  if (!params.is_object()) return;
  Json ours = Json::object();
  Json gains = params.contains("gains") ? params["gains"] : Json::object();
  for (const auto& [key, value] : params.items()) {
    if (key == "gains") continue;
    std::string field = key;
    if (key.starts_with("default_")) field = key.substr(8);
    if (field != "kp" && field != "kv" && field != "torque_limit") {
      ours[key] = value;  // the operation names what it does not take
      continue;
    }
    if (value.is_object() && !key.starts_with("default_")) {
      if (!gains.is_object()) Fail("controller_schema_violation", "gains must be a map");
      for (const auto& [name, v] : value.items()) gains[name][field] = v;
    } else {
      ours[field] = value;
    }
  }
  if (!gains.empty()) ours["gains"] = std::move(gains);
  params = std::move(ours);
}

void TranslateOptions(Json& options) {
  if (!options.is_object()) return;
  RenameValue(options, "integrator", kIntegrators);
  RenameValue(options, "cone", kCones);
  RenameValue(options, "solver", kSolvers);
}

// An option echoed as MuJoCo's integer: its 2026 name.
void OptionName(Json& options, const char* field, const std::vector<Rename>& table) {
  const auto it = options.find(field);
  if (it == options.end() || !it->is_number_integer()) return;
  const auto i = it->get<std::int64_t>();
  if (i >= 0 && static_cast<std::size_t>(i) < table.size()) {
    *it = std::string(table[static_cast<std::size_t>(i)].theirs);
  }
}

}  // namespace

void TranslateRequest(Json& body) {
  const auto op_it = body.find("op");
  if (op_it == body.end() || !op_it->is_string()) return;
  const std::string op = op_it->get<std::string>();
  for (const Field& f : kRequestFields) {
    if (f.op == op) MoveField(body, f.ours, f.theirs);
  }
  if (op == "set_mode" || op == "step") RenameValue(body, "mode", kModes);
  if (op == "set_control_source") RenameValue(body, "source", kControlSources);
  if (op == "set_sim_options") {
    if (const auto it = body.find("options"); it != body.end()) TranslateOptions(*it);
  }
  if (op == "set_qpos") {
    if (const auto by = body.find("target_by"); by != body.end()) {
      // The articulation's name is its actor name and its prefix (hello's entities).
      if (!by->is_string() || (*by != "actor_name" && *by != "prefix")) {
        Fail("bad_value", "target_by must be \"actor_name\" or \"prefix\"");
      }
      body.erase("target_by");
    }
  }
  if (op == "step") {
    if (const auto it = body.find("per_articulation"); it != body.end() && it->is_object()) {
      for (auto& [name, entry] : it->items()) TranslateStepEntry(entry);
    }
  }
  if (op == "configure_controller") {
    if (const auto it = body.find("params"); it != body.end()) TranslateGains(*it);
  }
}

void TranslateReply(std::string_view op, const Json& request, Json& reply) {
  if (reply.value("op", "") == "error") return;
  for (const Field& f : kReplyFields) {
    if (f.op != op) continue;
    if (const auto it = reply.find(std::string(f.ours)); it != reply.end()) {
      reply[std::string(f.theirs)] = *it;
    }
  }
  const auto rename = [&](const char* field, const std::vector<Rename>& table) {
    const auto it = reply.find(field);
    if (it == reply.end() || !it->is_string()) return;
    if (const auto theirs = Theirs(table, it->get_ref<const std::string&>())) {
      *it = std::string(*theirs);
    }
  };
  if (op == "set_mode") {
    rename("previous_mode", kModes);
    rename("current_mode", kModes);
  }
  if (op == "hello") rename("mode", kModes);
  if (op == "set_control_source") rename("source", kControlSources);
  if (op == "set_sim_options") {
    if (const auto it = reply.find("options"); it != reply.end() && it->is_object()) {
      OptionName(*it, "integrator", kIntegrators);
      OptionName(*it, "cone", kCones);
      OptionName(*it, "solver", kSolvers);
    }
  }
  if (op == "replay_list_sessions") {
    if (const auto it = reply.find("sessions"); it != reply.end() && it->is_array()) {
      Json names = Json::array();
      for (const Json& s : *it) names.push_back(s.is_object() ? s.value("session", Json()) : s);
      *it = std::move(names);
    }
  }
  if (op == "configure_controller") {
    // Ours: params {gains {name: {kp, kv, torque_limit}}}; theirs: a map per gain, plus the
    // defaults the request gave, in the request's shape.
    const auto it = reply.find("params");
    if (it == reply.end() || !it->is_object()) return;
    Json theirs{{"kp", Json::object()}, {"kv", Json::object()}, {"torque_limit", Json::object()}};
    if (const auto g = it->find("gains"); g != it->end() && g->is_object()) {
      for (const auto& [name, gains] : g->items()) {
        for (const char* field : {"kp", "kv", "torque_limit"}) {
          if (gains.contains(field)) theirs[field][name] = gains[field];
        }
      }
    }
    if (const auto p = request.find("params"); p != request.end() && p->is_object()) {
      for (const char* field : {"default_kp", "default_kv", "default_torque_limit"}) {
        if (p->contains(field)) theirs[field] = (*p)[field];
      }
    }
    *it = std::move(theirs);
  }
}

}  // namespace urlab::net::dialect2026
