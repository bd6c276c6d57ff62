// The step server's latency operations (docs/network.md, "Emulated latency"): set_latency and
// get_latency. What the settings mean is physics/latency.h; the session
// applies them under the step mutex, so they take effect at the next step.
#include <string>

#include "net/request_fields.h"
#include "net/step_server.h"
#include "urlab/physics/latency.h"

namespace urlab::net {

using namespace request;

namespace {

// One setting from a request map {"delay_steps": 3, "jitter": 0.002, "rate_hz": 50}.
physics::LatencySetting Setting(const Json& v, const std::string& what) {
  if (!v.is_object()) {
    Fail("bad_value",
         what + " must be a map (delay_steps or delay, jitter_steps or jitter, rate_hz)");
  }
  physics::LatencySetting s;
  bool delay = false, jitter = false;
  for (const auto& [key, value] : v.items()) {
    const bool is_delay = key == "delay" || key == "delay_steps";
    const bool is_jitter = key == "jitter" || key == "jitter_steps";
    if ((is_delay && delay) || (is_jitter && jitter)) {
      Fail("bad_value", what + ": give the " + (is_delay ? "delay" : "jitter") +
                            " in steps or in seconds, not both");
    }
    delay |= is_delay;
    jitter |= is_jitter;
    if (!value.is_number()) Fail("bad_value", what + "." + key + " must be a number");
    const std::string problem = physics::SetLatencyKey(&s, key, value.get<double>());
    if (!problem.empty()) Fail("bad_value", what + ": " + problem);
  }
  return s;
}

Json Fields(const physics::LatencySetting& s) {
  Json out = Json::object();
  for (const auto& [k, v] : physics::LatencyFields(s)) out[k] = v;
  return out;
}

Json Describe(const std::string& name, const physics::ArticulationLatency& l, std::uint64_t seed) {
  return Json{{"articulation", name},
              {"seed", seed},
              {"control", Fields(l.control)},
              {"observation", Fields(l.observation)}};
}

std::optional<std::uint64_t> Seed(const Json& body) {
  const auto it = body.find("seed");
  if (it == body.end()) return std::nullopt;
  if (!it->is_number_unsigned() && !(it->is_number_integer() && it->get<std::int64_t>() >= 0)) {
    Fail("bad_value", "seed must be a whole number >= 0");
  }
  return it->get<std::uint64_t>();
}

}  // namespace

StepServer::Outcome StepServer::SetLatency(Request& r) {
  const ArticulationTopics& t = Articulation(r.body["articulation"]);
  // Channels given replace the articulation's; the others keep theirs. Validated whole first.
  physics::ArticulationLatency l = session_.Latency(t.name);
  for (const auto& [key, value] : r.body.items()) {
    if (key == "control") {
      l.control = Setting(value, "control");
    } else if (key == "observation") {
      l.observation = Setting(value, "observation");
    }
  }
  const std::optional<std::uint64_t> seed = Seed(r.body);
  session_.SetLatency(t.name, l, seed);
  Json reply = Describe(t.name, session_.Latency(t.name), session_.latency_seed());
  reply["op"] = "set_latency_ok";
  return {reply};
}

StepServer::Outcome StepServer::GetLatency(Request& r) {
  const ArticulationTopics& t = Articulation(r.body["articulation"]);
  Json reply = Describe(t.name, session_.Latency(t.name), session_.latency_seed());
  reply["op"] = "get_latency_ok";
  return {reply};
}

}  // namespace urlab::net
