// The step server's latency operations (docs/network.md, "Emulated latency"): set_latency and
// get_latency. What the settings mean is physics/latency.h; the session
// applies them under the step mutex, so they take effect at the next step.
#include <string>

#include "net/latency_request.h"
#include "net/request_fields.h"
#include "net/step_server.h"
#include "urlab/physics/latency.h"

namespace urlab::net {

using namespace request;

namespace {

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
  return SeedFromRequest(*it, "seed");
}

}  // namespace

StepServer::Outcome StepServer::SetLatency(Request& r) {
  const ArticulationTopics& t = Articulation(r.body["articulation"]);
  // Channels given replace the articulation's; the others keep theirs. Validated whole first.
  physics::ArticulationLatency l = session_.Latency(t.name);
  for (const auto& [key, value] : r.body.items()) {
    if (key == "control") {
      l.control = LatencySettingFromRequest(value, "control");
    } else if (key == "observation") {
      l.observation = LatencySettingFromRequest(value, "observation");
    }
  }
  // The ticks a delay line holds are bounded (physics/latency.h): refused, not allocated.
  const double dt = session_.engine().timestep();
  for (const auto& [channel, setting] :
       {std::pair{"control", &l.control}, std::pair{"observation", &l.observation}}) {
    if (const std::string problem = physics::CheckLatency(*setting, dt); !problem.empty()) {
      Fail("bad_value", std::string(channel) + ": " + problem);
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
