// Domain randomisation over the step server: `reset {seed, randomize: {...}}` (docs/network.md,
// "Domain randomisation"). The request's `randomize` overrides the scene's section for that
// reset; the values drawn come back as `randomized`. What the parameters mean is
// world/randomize.h; the session applies them to its own model.
#include <string>

#include "net/request_fields.h"
#include "net/step_server.h"
#include "urlab/replay/recorder.h"
#include "urlab/world/randomize.h"

namespace urlab::net {

using namespace request;

namespace {

world::RandomRange Range(const Json& v, const std::string& what, std::string_view key) {
  if (!v.is_object() || v.size() != 1) {
    Fail("bad_value", what +
                          " must be one of {\"uniform\": [low, high]}, {\"normal\": [mean, "
                          "std]}, {\"log_uniform\": [low, high]}");
  }
  const auto it = v.begin();
  const std::string dist = it.key();
  const std::vector<double> n = Numbers(it.value(), "randomize");
  if (n.size() != 2) Fail("bad_value", what + "." + dist + " needs two numbers");
  world::RandomRange r;
  const std::string problem = world::MakeRange(dist, n[0], n[1], &r);
  if (!problem.empty()) Fail("bad_value", what + ": " + problem);
  if (const std::string outside = world::CheckLimits(key, r); !outside.empty()) {
    Fail("bad_value", what + ": " + outside);
  }
  return r;
}

world::RandomizeConfig Config(const Json& v) {
  if (!v.is_object()) Fail("bad_value", "randomize must be a map of articulation/prop to params");
  world::RandomizeConfig c;
  for (const auto& [name, params] : v.items()) {
    if (!params.is_object()) Fail("bad_value", "randomize." + name + " must be a map");
    for (const auto& [key, range] : params.items()) {
      const world::RandomRange r =
          Range(range, "randomize." + name + "." + key, name == "gravity" ? "gravity" : key);
      if (name == "gravity") {
        c.gravity[key] = r;
      } else {
        c.targets[name][key] = r;
      }
    }
  }
  return c;
}

}  // namespace

Json StepServer::DrawsJson(const world::RandomDraws& d) {
  Json out = Json::object();
  out["seed"] = d.seed;
  if (!d.gravity.empty()) out["gravity"] = d.gravity;
  for (const auto& [name, params] : d.targets) out[name] = params;
  return out;
}

std::function<world::Session::RandomizedReset()> StepServer::RandomizerForReset(const Request& r) {
  const auto seed_it = r.body.find("seed");
  const auto config_it = r.body.find("randomize");
  const bool given = config_it != r.body.end() && !config_it->is_null();
  if (!given && !session_.randomizes()) return {};  // the seed alone: nothing to draw
  std::optional<std::uint64_t> seed;
  if (seed_it != r.body.end() && !seed_it->is_null()) {
    if (!seed_it->is_number_integer() || seed_it->get<std::int64_t>() < 0) {
      Fail("bad_value", "seed must be a whole number >= 0");
    }
    seed = seed_it->get<std::uint64_t>();
  }
  std::optional<world::RandomizeConfig> config;
  if (given) config = Config(*config_it);
  // A recording holds one model: new draws in the middle of one would not replay.
  if (recorder_ && recorder_->recorder() && recorder_->recorder()->active()) {
    Fail("recording_active",
         "a randomised reset changes the model, which a running recording cannot follow; stop "
         "the recording first (and start a new one after the reset)");
  }
  return [this, seed, config = std::move(config)] {
    try {
      return session_.ResetRandomized(seed, config ? &*config : nullptr);
    } catch (const Error& e) {
      Fail("bad_value", e.what());
    }
  };
}

}  // namespace urlab::net
