#pragma once
// A joint-space trajectory: a time column and, per row, the model's qpos (and optionally qvel),
// laid out as in MuJoCo (the joint tables of tables.h say where each joint's values are). What
// CSV/.npz import and export read and write, and what playback samples in between rows.
//
// Pure data; any thread. A const Trajectory may be read from several threads at once.
#include <cstddef>
#include <vector>

#include "urlab/replay/tables.h"

namespace urlab::replay {

struct Trajectory {
  int nq = 0;
  int nv = 0;
  std::vector<double> time;  // seconds, strictly increasing
  std::vector<double> qpos;  // rows() * nq, row-major
  std::vector<double> qvel;  // rows() * nv, row-major; or empty (no velocities)

  std::size_t rows() const { return time.size(); }
  bool has_qvel() const { return !qvel.empty(); }
  const double* qpos_row(std::size_t row) const { return qpos.data() + row * nq; }
  const double* qvel_row(std::size_t row) const { return qvel.data() + row * nv; }

  // The qpos at time `t` into qpos_out[0..nq): the first row before the first time, the last row
  // after the last; between two rows hinge and slide values and free-joint positions are
  // interpolated linearly, and the quaternions of free (qpos[3..6]) and ball joints (w x y z) by
  // Slerp below. At a row's time exactly, that row's values bit for bit. Throws Error when the
  // trajectory has no rows, when its sizes disagree with `tables` (CheckShape) or `t` is NaN.
  void SampleQpos(const ModelTables& tables, double t, double* qpos_out) const;

  // Throws Error unless nq/nv match `tables` and qpos (and qvel, when present) hold rows() rows.
  void CheckShape(const ModelTables& tables) const;
  // Throws Error naming the first value (row, time or qpos/qvel index) that is NaN or infinite.
  void CheckFinite() const;
  // Throws Error naming the first row whose time is not after the previous row's.
  void CheckTimes() const;
  // CheckShape, CheckFinite and CheckTimes: what every exporter asks of a trajectory.
  void Check(const ModelTables& tables) const;
};

// Spherical linear interpolation of unit quaternions (w x y z) a and b at s in [0, 1], along the
// shortest arc (b and -b are the same rotation, so b is negated when a.b < 0); nearly identical
// quaternions are interpolated linearly and normalised. The result is unit-norm; s = 0 gives a
// (normalised). A zero input gives the identity (1 0 0 0), as MuJoCo's mju_normalize4 does.
// `out` may alias `a` or `b`.
void Slerp(const double* a, const double* b, double s, double* out);

}  // namespace urlab::replay
