#include "urlab/world/randomize.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "urlab/physics/delay_line.h"

namespace urlab::world {

namespace {

constexpr struct {
  Distribution dist;
  const char* name;
} kDistributions[] = {
    {Distribution::kUniform, "uniform"},
    {Distribution::kNormal, "normal"},
    {Distribution::kLogUniform, "log_uniform"},
};

}  // namespace

std::optional<Distribution> ParseDistribution(std::string_view name) {
  for (const auto& d : kDistributions) {
    if (name == d.name) return d.dist;
  }
  return std::nullopt;
}

const char* DistributionName(Distribution d) {
  for (const auto& x : kDistributions) {
    if (x.dist == d) return x.name;
  }
  return "?";
}

std::string MakeRange(std::string_view dist, double a, double b, RandomRange* out) {
  const auto d = ParseDistribution(dist);
  if (!d) {
    return "unknown distribution '" + std::string(dist) +
           "' (expected uniform: [low, high], normal: [mean, std] or log_uniform: [low, high])";
  }
  if (!std::isfinite(a) || !std::isfinite(b)) return std::string(dist) + " needs finite numbers";
  switch (*d) {
    case Distribution::kUniform:
      if (a > b) return "uniform: [low, high] needs low <= high";
      break;
    case Distribution::kLogUniform:
      if (!(a > 0) || a > b) return "log_uniform: [low, high] needs 0 < low <= high";
      break;
    case Distribution::kNormal:
      if (b < 0) return "normal: [mean, std] needs std >= 0";
      break;
  }
  *out = {*d, a, b};
  return "";
}

double Draw(const RandomRange& r, std::uint64_t* state) {
  switch (r.dist) {
    case Distribution::kUniform:
      return r.a + (r.b - r.a) * physics::UnitDouble(state);
    case Distribution::kLogUniform:
      return std::exp(std::log(r.a) + (std::log(r.b) - std::log(r.a)) * physics::UnitDouble(state));
    case Distribution::kNormal: {
      // Box-Muller from two draws (u1 in (0, 1], so the log is finite).
      const double u1 = 1.0 - physics::UnitDouble(state);
      const double u2 = physics::UnitDouble(state);
      return r.a + r.b * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    }
  }
  return r.a;
}

double Cdf(const RandomRange& r, double x) {
  switch (r.dist) {
    case Distribution::kUniform:
      if (r.b == r.a) return x < r.a ? 0 : 1;
      return std::clamp((x - r.a) / (r.b - r.a), 0.0, 1.0);
    case Distribution::kLogUniform:
      if (x <= 0) return 0;
      if (r.b == r.a) return x < r.a ? 0 : 1;
      return std::clamp((std::log(x) - std::log(r.a)) / (std::log(r.b) - std::log(r.a)), 0.0, 1.0);
    case Distribution::kNormal:
      if (r.b == 0) return x < r.a ? 0 : 1;
      return 0.5 * std::erfc(-(x - r.a) / (r.b * std::sqrt(2.0)));
  }
  return 0;
}

const std::vector<RandomParamInfo>& RandomParams() {
  static const std::vector<RandomParamInfo> table = {
      {"friction", "scale of its geoms' sliding friction", true},
      {"mass", "scale of its bodies' mass and rotational inertia", true},
      {"damping", "scale of its joints' damping", false},
      {"armature", "scale of its joints' armature", false},
      {"frictionloss", "scale of its joints' frictionloss", false},
      {"gain", "scale of its actuators' gain (gainprm[0], and biasprm[1] of position servos)",
       false},
      {"kp", "scale of its PD controller's kp", false},
      {"kv", "scale of its PD controller's kv", false},
      {"qpos_noise", "added to each hinge and slide joint's position after the reset", false},
      {"obs_noise",
       "standard deviation of the Gaussian noise on its observed qpos, qvel and "
       "sensors, every step",
       false},
  };
  return table;
}

std::optional<ParamLimits> LimitsOf(std::string_view key) {
  static constexpr struct {
    std::string_view key;
    ParamLimits limits;
  } kLimits[] = {
      {"friction", {0, 100}},
      {"mass", {0.001, 1000}},
      {"damping", {0, 1000}},
      {"armature", {0, 1000}},
      {"frictionloss", {0, 1000}},
      {"gain", {0, 100}},
      {"kp", {0, 100}},
      {"kv", {0, 100}},
      {"qpos_noise", {-10, 10}},
      {"obs_noise", {0, 10}},
      {"gravity", {-100, 100}},
  };
  for (const auto& l : kLimits) {
    if (l.key == key) return l.limits;
  }
  return std::nullopt;
}

std::string CheckLimits(std::string_view key, const RandomRange& r) {
  const auto l = LimitsOf(key);
  if (!l) return "";
  const auto num = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  const std::string allowed = "[" + num(l->lo) + ", " + num(l->hi) + "]";
  const std::string given =
      std::string(DistributionName(r.dist)) + " [" + num(r.a) + ", " + num(r.b) + "]";
  if (r.dist == Distribution::kNormal) {
    if (!(r.a >= l->lo && r.a <= l->hi)) {
      return given + ": the mean leaves the allowed range " + allowed;
    }
    if (!(r.b <= l->hi - l->lo)) {
      return given + ": the std exceeds the width of the allowed range " + allowed;
    }
    return "";
  }
  if (!(r.a >= l->lo && r.b <= l->hi)) return given + " leaves the allowed range " + allowed;
  return "";
}

double DrawParam(std::string_view key, const RandomRange& r, std::uint64_t* state) {
  const double v = Draw(r, state);
  const auto l = LimitsOf(key);
  return l ? std::clamp(v, l->lo, l->hi) : v;
}

bool IsRandomParam(std::string_view key, bool prop) {
  for (const RandomParamInfo& p : RandomParams()) {
    if (p.key == key) return !prop || p.props;
  }
  return false;
}

}  // namespace urlab::world
