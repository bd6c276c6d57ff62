#include "urlab/world/randomize.h"

#include <algorithm>
#include <cmath>

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

bool IsRandomParam(std::string_view key, bool prop) {
  for (const RandomParamInfo& p : RandomParams()) {
    if (p.key == key) return !prop || p.props;
  }
  return false;
}

}  // namespace urlab::world
