#pragma once
// Mesh files through assimp (internal: no assimp type leaves assimp_reader.cc).
// Thread: any; each call has its own importer.
#include <string>

#include "urlab/convert/mesh.h"

namespace urlab::convert::internal {

// True when assimp reads files with extension `ext` (".ply", lower case, with the dot).
bool AssimpCanRead(const std::string& ext);
// Every triangle of every mesh in the file's scene, node transforms applied. Throws InputError
// naming the file and assimp's reason.
TriMesh AssimpRead(const std::string& path);

}  // namespace urlab::convert::internal
