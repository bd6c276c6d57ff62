#pragma once
// NumPy .npz export: a zip archive (stored, uncompressed) of .npy arrays of little-endian doubles
// ('<f8', NPY format 1.0, data 64-byte aligned in its entry), which numpy.load reads directly.
//
// Only f8 arrays are written: the names of a trajectory's qpos/qvel columns are in its CSV export
// (ExportCsv, csv.h) and in `urlab replay --info`.
//
// Thread: any; no shared state.
#include <cstddef>
#include <string>
#include <vector>

#include "urlab/replay/tables.h"
#include "urlab/replay/trajectory.h"

namespace urlab::replay {

struct NpyArray {
  std::string name;                // the entry is "{name}.npy"; np.load(path)[name]
  std::vector<std::size_t> shape;  // C order; {} is a scalar (data holds 1 value)
  std::vector<double> data;        // product(shape) values
};

// Writes `arrays` to `path` as a .npz file, atomically (WriteFileAtomic). Throws Error, before
// writing anything, when a name is empty, contains '/', '\' or NUL, or repeats another; when a
// shape's product is not data.size(); or when an entry or the archive would reach 4 GiB (ZIP64 is
// not written) or hold more than 65535 arrays.
void WriteNpz(const std::string& path, const std::vector<NpyArray>& arrays);

// Writes `traj` as a .npz file with arrays `time` (rows), `qpos` (rows x nq) and, when the
// trajectory has velocities, `qvel` (rows x nv), then the `extra` arrays. Throws Error when traj
// fails Trajectory::Check, for a bad extra array (as WriteNpz), or when the file cannot be
// written.
void ExportNpz(const std::string& path, const ModelTables& tables, const Trajectory& traj,
               const std::vector<NpyArray>& extra = {});

}  // namespace urlab::replay
