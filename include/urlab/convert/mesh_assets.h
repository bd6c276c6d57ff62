#pragma once
// Mesh preprocessing for MJCF models (the description's import pipeline, done at load time):
// MuJoCo 2.2.2 loads only STL, OBJ and MSH, so every <mesh file> of another format (PLY,
// glTF/GLB, FBX, DAE, ...) is converted through assimp into an OBJ in the cache folder, named
// after the source and its content hash (converted once; two sources with the same stem, such
// as link1.dae and link1.ply, never share a file), and the mesh keeps the name MuJoCo would have
// given it. So is an STL that 2.2.2 refuses (ASCII, or more than 200,000 faces: simplified to
// at most that many by vertex clustering, which moves the surface by about one grid cell: the
// finest grid from 1,024 cells along the longest side that is small enough; see
// LimitForMujoco). Unnamed meshes whose file stems clash (link1.obj and link1.stl both named
// "link1" by MuJoCo) get distinct names (link1, link1_1). A mesh that cannot be read is an
// InputError naming the file and the <mesh> element's file:line, unless only visual geoms use it
// (contype and conaffinity 0): then those geoms and the mesh are dropped with a warning and the
// collision geometry stays (the description's fallback).
//
// Face orientation (the dialect bridge's rule `mesh.orientation`): MuJoCo 2.2.2 rejects an OBJ
// mesh whose faces run an edge the same way twice ("faces have inconsistent orientation") as
// soon as a body's inertia uses it, and with `compiler exactmeshinertia="true"` (which the bridge
// sets for 3.x documents) weighs an STL or OBJ by signed volumes, so a flipped face subtracts.
// MuJoCo 3.x's default (legacy) inertia accepts both. Such meshes get their faces oriented
// consistently and outwards (PlanConsistentOrientation) in a copy in the cache folder
// (<stem>-<hash>-oriented.obj/.stl; OBJ: only the face lines' corner order changes, texture
// coordinates and normals stay), reported as bridge changes with the <mesh> element's file:line.
// Files found consistent leave a marker (<stem>-<hash>.oriented-ok) so they are parsed once.
//
// Thread: any thread owning the document; the cache files are written atomically.
#include <string>
#include <vector>

#include "urlab/core/diagnostics.h"
#include "urlab/document/document.h"
#include "urlab/mjcf/bridge.h"

namespace urlab::convert {

struct MeshAssetReport {
  std::vector<std::string> steps;    // one line per conversion, rename or cache hit
  std::vector<Diagnostic> warnings;  // dropped visual meshes, meshes that cannot be oriented
  std::vector<mjcf::BridgeChange> bridge_changes;  // orientation repairs (rule mesh.orientation)
};

// Converts, renames, orients and drops as described above. Throws InputError.
MeshAssetReport PrepareMeshAssets(document::Document& doc, const std::string& cache_dir);

}  // namespace urlab::convert
