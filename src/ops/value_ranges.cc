#include "ops/value_ranges.h"

#include <mujoco/mujoco.h>

#include <cmath>
#include <stdexcept>

#include "urlab/ops/error.h"

namespace urlab::ops {

namespace {

std::string Format(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

bool Within(double x, const ValueRange& r) {
  if (!std::isfinite(x)) return false;
  if (r.min_open ? !(x > r.min) : !(x >= r.min)) return false;
  if (!(x <= r.max)) return false;
  return !r.integer || x == std::floor(x);
}

}  // namespace

const ValueRange& RangeOf(std::string_view field) {
  for (const ValueRange& r : ValueRanges()) {
    if (field == r.field) return r;
  }
  throw std::logic_error("no range for field '" + std::string(field) + "'");
}

std::string RangeText(const ValueRange& r) {
  return std::string(r.integer ? "an integer in " : "in ") + (r.min_open ? "(" : "[") +
         Format(r.min) + ", " + Format(r.max) + "]";
}

void CheckRange(double x, std::string_view field, std::string_view what) {
  const ValueRange& r = RangeOf(field);
  if (Within(x, r)) return;
  Fail("bad_value", std::string(what.empty() ? field : what) + " must be " + RangeText(r) +
                        ", got " + Format(x));
}

void CheckRanges(const std::vector<double>& values, std::string_view field, std::string_view what) {
  const ValueRange& r = RangeOf(field);  // once: a batch step checks thousands of values
  for (const double x : values) {
    if (!Within(x, r)) CheckRange(x, field, what);
  }
}

void CheckQposQuaternions(const mjModel* m, const std::vector<physics::cmd::SetState::Run>& runs,
                          std::string_view what) {
  // The value written at qpos address `adr`, if any.
  const auto at = [&runs](int adr, double* out) {
    for (const auto& run : runs) {
      if (adr >= run.adr && adr < run.adr + static_cast<int>(run.values.size())) {
        *out = run.values[static_cast<std::size_t>(adr - run.adr)];
        return true;
      }
    }
    return false;
  };
  for (int j = 0; j < m->njnt; ++j) {
    int q = -1;
    if (m->jnt_type[j] == mjJNT_FREE) q = m->jnt_qposadr[j] + 3;
    if (m->jnt_type[j] == mjJNT_BALL) q = m->jnt_qposadr[j];
    if (q < 0) continue;
    double v[4];
    bool whole = true;
    for (int i = 0; i < 4 && whole; ++i) whole = at(q + i, &v[i]);
    if (!whole) continue;
    const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
    const char* name = mj_id2name(m, mjOBJ_JOINT, j);
    CheckRange(norm, "quaternion norm",
               std::string(what) + ": the quaternion of joint '" + (name ? name : "?") +
                   "' (qpos " + std::to_string(q) + ".." + std::to_string(q + 3) +
                   ") has a norm that");
  }
}

}  // namespace urlab::ops
