#pragma once
// Mesh preprocessing for MJCF models (the description's import pipeline, done at load time):
// MuJoCo loads only STL (binary, at most 200,000 faces), OBJ and MSH, so every <mesh file> of
// another format (PLY, glTF/GLB, FBX, DAE, ...) and every STL MuJoCo refuses (ASCII, or more
// faces: simplified to at most that many by vertex clustering, which moves the surface by about
// one grid cell; see LimitForMujoco) is converted through assimp into an OBJ in the cache folder,
// named after the source and its content hash (converted once; two sources with the same stem,
// such as link1.dae and link1.ply, never share a file), and the mesh keeps the name MuJoCo
// would have given it. Unnamed meshes whose file stems clash (link1.obj and link1.stl both
// named "link1" by MuJoCo) get distinct names (link1, link1_1). A mesh that cannot be read is an
// InputError naming the file and the <mesh> element's line, unless only visual geoms use it
// (contype and conaffinity 0): then those geoms and the mesh are dropped with a warning and the
// collision geometry stays (the description's fallback).
//
// Thread: any thread owning the spec; the cache files are written atomically.
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "urlab/core/diagnostics.h"

namespace urlab::convert {

struct MeshAssetReport {
  std::vector<std::string> steps;    // one line per conversion, rename or cache hit
  std::vector<Diagnostic> warnings;  // dropped visual meshes
};

// The file a <mesh> of `spec` names, resolved as MuJoCo resolves it (the model file's folder,
// then the compiler's meshdir); "" when it names none.
std::string MeshFilePath(const mjSpec* spec, const mjsMesh* mesh);

// Converts, renames and drops as described above, in `spec` (parsed from `model_file`). Throws
// InputError.
MeshAssetReport PrepareMeshAssets(mjSpec* spec, const std::string& model_file,
                                  const std::string& cache_dir);

}  // namespace urlab::convert
