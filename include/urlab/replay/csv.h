#pragma once
// Trajectories as CSV: one row per time, a `time` column and one column per joint qpos value
// (optionally per qvel value), named after the model's joints.
//
// Columns. `time` (required), then joint columns by full (prefixed) name or by short name when
// that is unambiguous (see ModelTables::FindJoint), in any order:
//   hinge, slide         name
//   free (7 qpos)        name[0] .. name[6]   x y z, then the quaternion w x y z
//   ball (4 qpos)        name[0] .. name[3]   the quaternion w x y z
//   velocities           name.v (1 dof), name.v[0] .. name.v[nv-1] (free: 6, ball: 3)
// A column `time` is always the time, even in a model with a joint of that name.
//
// Import never guesses: columns naming no joint and short names two joints share are reported
// (CsvImportReport) and their cells ignored; joints without columns take the model's default
// qpos0 and are reported. Velocity columns are optional: without any, the trajectory has no qvel;
// with some, joints without velocity columns get 0 (MuJoCo's default qvel) and are reported.
// The cells of unmatched columns are not read.
// Everything else that is wrong is an InputError at "path:line" naming the column.
//
// Thread: any; no shared state.
#include <cstdint>
#include <string>
#include <vector>

#include "urlab/replay/tables.h"
#include "urlab/replay/trajectory.h"

namespace urlab::replay {

// Largest CSV file ImportCsv reads (about 25 bytes per value: 40 million values).
constexpr std::uintmax_t kMaxCsvBytes = 1ull << 30;

struct CsvImportReport {
  // Header cells naming no joint (typos, extra data, a name[i] index past the joint's values);
  // an unnamed column is listed as "(column N)", counting from 1.
  std::vector<std::string> unmatched_columns;
  // Columns whose name is a short name two or more joints share: name them by full name.
  std::vector<std::string> ambiguous_columns;
  // Full names of model joints no column names: their qpos is the model's qpos0.
  std::vector<std::string> unmatched_joints;
  // Full names of joints without velocity columns when other joints have some: their qvel is 0.
  // Empty when the file has no velocity columns.
  std::vector<std::string> joints_without_velocity;
};

// Reads the CSV file at `path` against the model described by `tables`; `qpos0` (tables.nq
// values, the model's default qpos) fills joints without columns. Quaternions are normalised
// (when their norm is off 1 by more than 1e-12, so a unit quaternion keeps its bits). Accepts
// commas with optional whitespace around cells, double quotes around cells (headers may contain
// commas inside quotes, "" is a quote), LF or CRLF line ends, a UTF-8 byte order mark and blank
// lines at the end. Throws InputError ("path:line: ...") for: no `time` column, a joint named
// twice, a joint with some but not all of its name[i] columns, a joint with more than one value
// named without [i], a cell that is not a number or is NaN/infinite, a row with more or fewer
// cells than the header, a time not after the previous row's, a zero quaternion, a blank line
// before the last row, an empty file or one without data rows, a file over kMaxCsvBytes.
// Throws Error when qpos0 has not tables.nq values. `report` may be null.
Trajectory ImportCsv(const std::string& path, const ModelTables& tables,
                     const std::vector<double>& qpos0, CsvImportReport* report);

struct CsvExportOptions {
  // Name columns by short name where that is unambiguous (full names otherwise).
  bool short_names = false;
  // Write the qvel columns too (when the trajectory has qvel).
  bool velocities = true;
  // Recorded sensor values (rows x nsensordata) to write as columns "sensor:{name}" (and
  // "sensor:{name}[i]" for a sensor of several values) after the joints; ImportCsv skips them.
  const std::vector<double>* sensordata = nullptr;
};

// Writes `traj` as CSV to `path` atomically (WriteFileAtomic): the header `time` and every joint's
// columns in joint order, then (options.velocities, when traj has qvel) the velocity columns;
// numbers in shortest round-trip form, so ImportCsv gives back every double bit for bit (but for
// quaternions whose norm is off 1 by more than 1e-12, which come back normalised). Names that need
// it are quoted. Throws Error when traj fails Trajectory::Check, when a joint has no
// name or is named `time`, or when the file cannot be written.
void ExportCsv(const std::string& path, const ModelTables& tables, const Trajectory& traj,
               const CsvExportOptions& options = {});

}  // namespace urlab::replay
