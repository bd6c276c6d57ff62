#include "net/observation.h"

#include <chrono>
#include <cstring>

namespace urlab::net {

Json TimeOf(double seconds) {
  const double sec = std::floor(seconds);
  return Json{{"sec", static_cast<std::int64_t>(sec)},
              {"nsec", static_cast<std::int64_t>((seconds - sec) * 1e9)}};
}

Json Array(const double* v, std::size_t n, bool binary) {
  if (binary) {
    std::vector<std::uint8_t> bytes(n * sizeof(double));
    std::memcpy(bytes.data(), v, bytes.size());  // little-endian f64 (x86-64, arm64)
    return Json::binary(std::move(bytes));
  }
  Json a = Json::array();
  for (std::size_t i = 0; i < n; ++i) a.push_back(v[i]);
  return a;
}

Json Observation(const std::vector<ArticulationTopics>& tables, const physics::StateFrame& f,
                 const std::string& level, bool binary) {
  Json o;
  o["time"] = f.time;
  o["step"] = f.step;
  o["sim_time"] = TimeOf(f.time);
  const auto wall = std::chrono::system_clock::now().time_since_epoch();
  o["wall_time"] = TimeOf(std::chrono::duration<double>(wall).count());
  o["paused"] = f.paused;
  Json per = Json::object();
  std::vector<double> tmp;
  const auto gather = [&](const std::vector<double>& src, const std::vector<int>& adrs) {
    tmp.clear();
    for (int a : adrs) tmp.push_back(src[static_cast<std::size_t>(a)]);
    return Array(tmp.data(), tmp.size(), binary);
  };
  for (const ArticulationTopics& t : tables) {
    Json a;
    a["qpos"] = gather(f.qpos, t.qpos_adrs);
    a["qvel"] = gather(f.qvel, t.dof_adrs);
    if (level != "minimal") {
      a["ctrl"] = gather(f.ctrl, t.actuator_ids);
      a["act"] = gather(f.act, t.act_adrs);
      Json sensors = Json::object();
      for (std::size_t i = 0; i < t.sensors.size(); ++i) {
        const SensorTopicEntry& s = t.sensors[i];
        sensors[t.sensor_names[i]] =
            Array(f.sensordata.data() + s.adr, static_cast<std::size_t>(s.dim), binary);
      }
      a["sensors"] = std::move(sensors);
    }
    if (level == "full") {
      Json xpos = Json::object(), xquat = Json::object();
      for (std::size_t i = 0; i < t.body_ids.size(); ++i) {
        const auto b = static_cast<std::size_t>(t.body_ids[i]);
        xpos[t.body_names[i]] = Array(f.xpos.data() + 3 * b, 3, binary);
        xquat[t.body_names[i]] = Array(f.xquat.data() + 4 * b, 4, binary);
      }
      a["xpos"] = std::move(xpos);
      a["xquat"] = std::move(xquat);
      a["actuator_force"] = gather(f.actuator_force, t.actuator_ids);
    }
    per[t.name] = std::move(a);
  }
  o["per_articulation"] = std::move(per);
  o["entities"] = Json::object();
  return o;
}

bool IsObservationLevel(const std::string& level) {
  return level == "minimal" || level == "standard" || level == "full";
}

}  // namespace urlab::net
