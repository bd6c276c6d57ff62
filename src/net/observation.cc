#include "net/observation.h"

#include <chrono>
#include <cstring>

#include "core/gcc_workarounds.h"

namespace urlab::net {

namespace {

// The JSON backend of the observation layout: the same calls as MsgpackWriter, building a tree.
// Containers announce their size, so each one is closed after its last value.
class JsonWriter {
 public:
  // Fills `root` (an object) with `entries` entries.
  JsonWriter(Json* root, std::size_t entries) { open_.push_back({root, entries}); }

  void Map(std::size_t entries) { Open(Json::object(), entries); }
  void Key(std::string_view k) {
    URLAB_GCC_IGNORE("-Wrestrict")  // GCC PR 105329: std::string assign at -O3
    key_ = k;
    URLAB_GCC_RESTORE
  }
  void Double(double v) { Put(Json(v)); }
  void Int(std::int64_t v) { Put(Json(v)); }
  void UInt(std::uint64_t v) { Put(Json(v)); }
  void Bool(bool v) { Put(Json(v)); }
  void Doubles(const double* v, std::size_t n, bool binary) { Put(net::Array(v, n, binary)); }

 private:
  struct Open_ {
    Json* node;
    std::size_t remaining;
  };
  Json* Put(Json v) {
    Open_& top = open_.back();
    Json* slot = &(*top.node)[key_];  // containers are maps (arrays travel whole)
    *slot = std::move(v);
    if (--top.remaining == 0) open_.pop_back();
    return slot;
  }
  void Open(Json v, std::size_t n) {
    Json* slot = Put(std::move(v));
    if (n > 0) open_.push_back({slot, n});
  }
  std::vector<Open_> open_;
  std::string key_;
};

template <typename Out>
void Time(Out& out, double seconds) {
  const double sec = std::floor(seconds);
  out.Map(2);
  out.Key("sec");
  out.Int(static_cast<std::int64_t>(sec));
  out.Key("nsec");
  out.Int(static_cast<std::int64_t>((seconds - sec) * 1e9));
}

template <typename Out>
void WriteArticulations(Out& out, const std::vector<ArticulationTopics>& tables,
                        const physics::StateFrame& f, ObsLevel level, bool binary,
                        bool bodies_by_name) {
  thread_local std::vector<double> tmp;
  const auto gather = [&](const std::vector<double>& src, const std::vector<int>& adrs) {
    tmp.clear();
    for (int a : adrs) tmp.push_back(src[static_cast<std::size_t>(a)]);
    out.Doubles(tmp.data(), tmp.size(), binary);
  };
  out.Map(tables.size());
  // Full level: xpos, xquat, actuator_force (ours); bodies, actuator_force (2026).
  const std::size_t fields = level == ObsLevel::kMinimal    ? 2
                             : level == ObsLevel::kStandard ? 5
                             : bodies_by_name               ? 7
                                                            : 8;
  for (const ArticulationTopics& t : tables) {
    // standard and full: the twist and held actions while a twist controller is attached.
    const bool twist = level != ObsLevel::kMinimal && t.twist && t.twist->attached();
    const control::Twist tw = twist ? t.twist->twist() : control::Twist{};
    const std::uint32_t actions = twist ? t.twist->actions() : 0;
    out.Key(t.name);
    out.Map(fields + (twist ? 2 : 0));
    out.Key("qpos");
    gather(f.qpos, t.qpos_adrs);
    out.Key("qvel");
    gather(f.qvel, t.dof_adrs);
    if (level != ObsLevel::kMinimal) {
      out.Key("ctrl");
      gather(f.ctrl, t.actuator_ids);
      out.Key("act");
      gather(f.act, t.act_adrs);
      out.Key("sensors");
      out.Map(t.sensors.size());
      for (std::size_t i = 0; i < t.sensors.size(); ++i) {
        const SensorTopicEntry& s = t.sensors[i];
        out.Key(t.sensor_names[i]);
        out.Doubles(f.sensordata.data() + s.adr, static_cast<std::size_t>(s.dim), binary);
      }
    }
    if (twist) {
      const double v[3] = {tw.vx, tw.vy, tw.yaw_rate};
      out.Key("twist");
      out.Doubles(v, 3, binary);
      out.Key("actions");
      out.Int(actions);
    }
    if (level == ObsLevel::kFull) {
      const auto xpos = [&](std::size_t i) {
        out.Doubles(f.xpos.data() + 3 * static_cast<std::size_t>(t.body_ids[i]), 3, binary);
      };
      const auto xquat = [&](std::size_t i) {
        out.Doubles(f.xquat.data() + 4 * static_cast<std::size_t>(t.body_ids[i]), 4, binary);
      };
      if (bodies_by_name) {
        out.Key("bodies");
        out.Map(t.body_ids.size());
        for (std::size_t i = 0; i < t.body_ids.size(); ++i) {
          out.Key(t.body_names[i]);
          out.Map(2);
          out.Key("xpos");
          xpos(i);
          out.Key("xquat");
          xquat(i);
        }
      } else {
        out.Key("xpos");
        out.Map(t.body_ids.size());
        for (std::size_t i = 0; i < t.body_ids.size(); ++i) {
          out.Key(t.body_names[i]);
          xpos(i);
        }
        out.Key("xquat");
        out.Map(t.body_ids.size());
        for (std::size_t i = 0; i < t.body_ids.size(); ++i) {
          out.Key(t.body_names[i]);
          xquat(i);
        }
      }
      out.Key("actuator_force");
      gather(f.actuator_force, t.actuator_ids);
    }
  }
}

// Free bodies: each one's free joint, {qpos [7], qvel [6]}.
template <typename Out>
void WriteFreeBodies(Out& out, const std::vector<FreeBodyEntry>* free_bodies,
                     const physics::StateFrame& f, bool binary) {
  out.Map(free_bodies ? free_bodies->size() : 0);
  if (!free_bodies) return;
  for (const FreeBodyEntry& b : *free_bodies) {
    out.Key(b.name);
    out.Map(2);
    out.Key("qpos");
    out.Doubles(f.qpos.data() + b.qpos_adr, 7, binary);
    out.Key("qvel");
    out.Doubles(f.qvel.data() + b.dof_adr, 6, binary);
  }
}

template <typename Out>
void WriteEntries(Out& out, const std::vector<ArticulationTopics>& tables,
                  const physics::StateFrame& f, ObsLevel level, bool binary, ObsKeys keys,
                  const std::vector<FreeBodyEntry>* free_bodies) {
  out.Key("time");
  out.Double(f.time);
  out.Key("step");
  out.UInt(f.step);
  out.Key("sim_time");
  Time(out, f.time);
  out.Key("wall_time");
  const auto wall = std::chrono::system_clock::now().time_since_epoch();
  Time(out, std::chrono::duration<double>(wall).count());
  out.Key("paused");
  out.Bool(f.paused);
  out.Key("frame_id");  // the state frame's publication number: monotonic
  out.UInt(f.frame);
  if (keys != ObsKeys::k2026) {
    out.Key("per_articulation");
    WriteArticulations(out, tables, f, level, binary, false);
    out.Key("entities");
    WriteFreeBodies(out, free_bodies, f, binary);
  }
  if (keys != ObsKeys::kOurs) {
    out.Key("arts");
    WriteArticulations(out, tables, f, level, binary, true);
    out.Key("scene");
    WriteFreeBodies(out, free_bodies, f, binary);
  }
}

}  // namespace

std::optional<ObsLevel> ParseObservationLevel(std::string_view level) {
  if (level == "minimal") return ObsLevel::kMinimal;
  if (level == "standard") return ObsLevel::kStandard;
  if (level == "full") return ObsLevel::kFull;
  return std::nullopt;
}

Json Array(const double* v, std::size_t n, bool binary) {
  if (binary) {
    std::vector<std::uint8_t> bytes(n * sizeof(double));
    if (n > 0) std::memcpy(bytes.data(), v, bytes.size());  // little-endian f64 (x86-64, arm64)
    return Json::binary(std::move(bytes));
  }
  Json a = Json::array();
  for (std::size_t i = 0; i < n; ++i) a.push_back(v[i]);
  return a;
}

void WriteObservationEntries(MsgpackWriter& out, const std::vector<ArticulationTopics>& tables,
                             const physics::StateFrame& f, ObsLevel level, bool binary,
                             ObsKeys keys, const std::vector<FreeBodyEntry>* free_bodies) {
  WriteEntries(out, tables, f, level, binary, keys, free_bodies);
}

void AddObservation(Json* reply, const std::vector<ArticulationTopics>& tables,
                    const physics::StateFrame& f, ObsLevel level, bool binary, ObsKeys keys,
                    const std::vector<FreeBodyEntry>* free_bodies) {
  JsonWriter w(reply, ObservationEntries(keys));
  WriteEntries(w, tables, f, level, binary, keys, free_bodies);
}

Json Observation(const std::vector<ArticulationTopics>& tables, const physics::StateFrame& f,
                 ObsLevel level, bool binary, ObsKeys keys,
                 const std::vector<FreeBodyEntry>* free_bodies) {
  Json o = Json::object();
  AddObservation(&o, tables, f, level, binary, keys, free_bodies);
  return o;
}

}  // namespace urlab::net
