#pragma once
// Domain randomisation policy: which parameters a scene's `randomize:` section (or a step-server
// `reset {randomize: ...}`) may draw, their distributions, and how a draw is made from a seed.
// The mechanism that applies draws to a simulation's own model lives in src/world/randomizer.h.
//
// Every parameter is one number drawn per reset (qpos_noise: one per joint). Scales multiply the
// value the MJCF gave (the model as compiled); gravity components and qpos noise are added;
// obs_noise is the standard deviation of the Gaussian noise added to every observed qpos, qvel
// and sensor value of the articulation at every step (physics/observation_delay.h).
// Thread: any (pure).
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace urlab::world {

enum class Distribution { kUniform, kNormal, kLogUniform };

// uniform: [a, b]; log_uniform: exp(uniform[log a, log b]), 0 < a <= b; normal: mean a,
// standard deviation b >= 0.
struct RandomRange {
  Distribution dist = Distribution::kUniform;
  double a = 0, b = 0;
  bool operator==(const RandomRange&) const = default;
};

// "uniform", "normal", "log_uniform"; nothing for anything else.
std::optional<Distribution> ParseDistribution(std::string_view name);
const char* DistributionName(Distribution d);
// A range from its distribution name and two numbers; an error message ("" when valid).
std::string MakeRange(std::string_view dist, double a, double b, RandomRange* out);

// The values a parameter may take (a key of RandomParams(), or "gravity" for a gravity
// component): scales of friction, gain, kp, kv in [0, 100]; of mass in [0.001, 1000] (zero or
// negative masses break the model); of damping, armature, frictionloss in [0, 1000];
// qpos_noise in [-10, 10]; obs_noise (a standard deviation) in [0, 10]; gravity components
// (added, m/s^2) in [-100, 100]. Nothing for an unknown key.
struct ParamLimits {
  double lo, hi;
};
std::optional<ParamLimits> LimitsOf(std::string_view key);
// "" when every draw of `r` can lie in the limits of `key` (uniform and log_uniform: both ends
// within; normal: the mean within and std at most the limits' width; its tails are cut, see
// DrawParam), else the problem, e.g. "uniform [-2, -1] leaves the allowed range [0.001, 1000]".
// Unknown keys pass (their name is checked elsewhere).
std::string CheckLimits(std::string_view key, const RandomRange& r);
// One draw of `r` for `key`, clamped to the key's limits (only a normal's tails can leave them).
double DrawParam(std::string_view key, const RandomRange& r, std::uint64_t* state);
// One draw. `state` is a splitmix64 state (physics/delay_line.h).
double Draw(const RandomRange& r, std::uint64_t* state);
// The distribution's cumulative distribution function at x.
double Cdf(const RandomRange& r, double x);

// The parameters of an articulation or prop, as a data table: key, what it does, where it
// applies (props take only friction and mass).
struct RandomParamInfo {
  std::string_view key;
  std::string_view effect;
  bool props;  // allowed for props
};
const std::vector<RandomParamInfo>& RandomParams();
bool IsRandomParam(std::string_view key, bool prop);

// What to randomise: per articulation or prop name, parameter key -> range; gravity components
// "x", "y", "z" -> range (added to the model's gravity).
struct RandomizeConfig {
  std::map<std::string, std::map<std::string, RandomRange>> targets;
  std::map<std::string, RandomRange> gravity;
  bool empty() const { return targets.empty() && gravity.empty(); }
  bool operator==(const RandomizeConfig&) const = default;
};

// The values one reset drew: per target, parameter -> value (qpos_noise: one per joint in
// joint order, named "qpos_noise.{joint}"); gravity components; and the seed drawn from.
struct RandomDraws {
  std::uint64_t seed = 0;
  std::map<std::string, std::map<std::string, double>> targets;
  std::map<std::string, double> gravity;
  bool operator==(const RandomDraws&) const = default;
};

}  // namespace urlab::world
