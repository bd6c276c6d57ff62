#include "urlab/replay/trajectory.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "urlab/core/error.h"

namespace urlab::replay {

namespace {

// Below this norm a quaternion is zero (MuJoCo's mjMINVAL).
constexpr double kMinNorm = 1e-15;
// Below this angle between two quaternions (as 4-vectors) slerp divides by almost zero, and
// normalised linear interpolation is used instead (it differs from slerp by about angle^3).
constexpr double kNlerpAngle = 1e-9;

void Normalize4(double* q) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n >= kMinNorm)) {  // zero (or NaN)
    q[0] = 1;
    q[1] = q[2] = q[3] = 0;
    return;
  }
  for (int i = 0; i < 4; ++i) q[i] /= n;
}

}  // namespace

void Slerp(const double* a, const double* b, double s, double* out) {
  double qa[4], qb[4];
  std::memcpy(qa, a, sizeof qa);
  std::memcpy(qb, b, sizeof qb);
  Normalize4(qa);
  Normalize4(qb);
  const double dot = qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3];
  if (dot < 0) {  // -qb is the same rotation, and the short way round
    for (double& v : qb) v = -v;
  }
  // The angle between them as 2 atan2(|a - b|, |a + b|): accurate at every angle, unlike acos of
  // the dot product near an angle of 0.
  double diff = 0, sum = 0;
  for (int i = 0; i < 4; ++i) {
    diff += (qa[i] - qb[i]) * (qa[i] - qb[i]);
    sum += (qa[i] + qb[i]) * (qa[i] + qb[i]);
  }
  const double theta = 2 * std::atan2(std::sqrt(diff), std::sqrt(sum));
  double wa = 1 - s, wb = s;
  if (theta > kNlerpAngle) {
    const double sin_theta = std::sin(theta);
    wa = std::sin((1 - s) * theta) / sin_theta;
    wb = std::sin(s * theta) / sin_theta;
  }
  for (int i = 0; i < 4; ++i) out[i] = wa * qa[i] + wb * qb[i];
  Normalize4(out);
}

void Trajectory::CheckShape(const ModelTables& tables) const {
  if (nq != tables.nq || nv != tables.nv) {
    throw Error(fmt::format("trajectory has nq={} nv={}, the model nq={} nv={}", nq, nv, tables.nq,
                            tables.nv));
  }
  const std::size_t n = rows();
  if (qpos.size() != n * static_cast<std::size_t>(nq)) {
    throw Error(fmt::format("trajectory has {} times but {} qpos values ({} rows of {} expected)",
                            n, qpos.size(), n, nq));
  }
  if (!qvel.empty() && qvel.size() != n * static_cast<std::size_t>(nv)) {
    throw Error(fmt::format("trajectory has {} times but {} qvel values ({} rows of {} expected)",
                            n, qvel.size(), n, nv));
  }
}

void Trajectory::CheckFinite() const {
  for (std::size_t r = 0; r < rows(); ++r) {
    if (!std::isfinite(time[r])) {
      throw Error(fmt::format("trajectory row {}: time is {}", r, time[r]));
    }
    for (int i = 0; i < nq; ++i) {
      const double v = qpos[r * nq + i];
      if (!std::isfinite(v)) {
        throw Error(fmt::format("trajectory row {} (time {}): qpos[{}] is {}", r, time[r], i, v));
      }
    }
    if (qvel.empty()) continue;
    for (int i = 0; i < nv; ++i) {
      const double v = qvel[r * nv + i];
      if (!std::isfinite(v)) {
        throw Error(fmt::format("trajectory row {} (time {}): qvel[{}] is {}", r, time[r], i, v));
      }
    }
  }
}

void Trajectory::CheckTimes() const {
  for (std::size_t r = 1; r < rows(); ++r) {
    if (!(time[r] > time[r - 1])) {
      throw Error(fmt::format("trajectory row {}: time {} is not after row {}'s {}", r, time[r],
                              r - 1, time[r - 1]));
    }
  }
}

void Trajectory::Check(const ModelTables& tables) const {
  CheckShape(tables);
  CheckFinite();
  CheckTimes();
}

void Trajectory::SampleQpos(const ModelTables& tables, double t, double* qpos_out) const {
  CheckShape(tables);
  if (rows() == 0) throw Error("cannot sample a trajectory with no rows");
  if (std::isnan(t)) throw Error("cannot sample a trajectory at time NaN");
  const std::size_t bytes = static_cast<std::size_t>(nq) * sizeof(double);
  if (t <= time.front()) {
    std::memcpy(qpos_out, qpos_row(0), bytes);
    return;
  }
  if (t >= time.back()) {
    std::memcpy(qpos_out, qpos_row(rows() - 1), bytes);
    return;
  }
  // time[r] <= t < time[r + 1]
  const auto after = std::upper_bound(time.begin(), time.end(), t);
  const std::size_t r = static_cast<std::size_t>(after - time.begin()) - 1;
  const double s = (t - time[r]) / (time[r + 1] - time[r]);
  const double* a = qpos_row(r);
  if (s == 0) {
    std::memcpy(qpos_out, a, bytes);
    return;
  }
  const double* b = qpos_row(r + 1);
  for (int i = 0; i < nq; ++i) qpos_out[i] = a[i] + s * (b[i] - a[i]);
  for (const JointEntry& j : tables.joints) {
    int quat = -1;
    if (j.type == mjJNT_FREE) quat = j.qposadr + 3;
    if (j.type == mjJNT_BALL) quat = j.qposadr;
    if (quat >= 0) Slerp(a + quat, b + quat, s, qpos_out + quat);
  }
}

}  // namespace urlab::replay
