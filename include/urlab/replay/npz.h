#pragma once
// NumPy .npz export: a zip archive (stored, uncompressed) of .npy arrays of little-endian doubles
// ('<f8') or of unicode strings ('<U{n}', UTF-32, for name arrays), NPY format 1.0, data 64-byte
// aligned in its entry, which numpy.load reads directly (no pickle).
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
  // With `strings`, a string array instead ('<U{longest}'): product(shape) UTF-8 strings in
  // `text`, `data` empty.
  std::vector<std::string> text;
  bool strings = false;
};

// The export of a recording segment beside its trajectory: name arrays and per-step extras.
struct NpzExtras {
  std::vector<double> ctrl;        // rows x nu
  std::vector<double> targets;     // rows x command targets (empty: none)
  std::vector<double> sensordata;  // rows x nsensordata (empty: not recorded)
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

// The arrays a recording's export adds to its trajectory (`rows` steps): `ctrl`, `targets` and
// `sensordata` when given, and the names of every column: `qpos_names` (nq: "{art}/{joint}",
// "[i]" after a joint of several values), `qvel_names` (nv), `ctrl_names` (nu: "{art}/{actuator}"),
// `target_names`, `sensor_names` (nsensordata, "[i]" after a sensor of several values),
// `articulations` and `joint_names` (one per joint). Names are short, beside their articulation
// (world/names.h); an element outside every articulation keeps its full name.
std::vector<NpyArray> ExportArrays(const ModelTables& tables, std::size_t rows,
                                   const NpzExtras& extras);

}  // namespace urlab::replay
