#include "assimp_reader.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>

#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"

namespace urlab::convert::internal {

bool AssimpCanRead(const std::string& ext) {
  if (ext.empty() || ext == ".stl" || ext == ".obj") return false;  // ours
  Assimp::Importer importer;
  return importer.IsExtensionSupported(ext);
}

TriMesh AssimpRead(const std::string& path) {
  Assimp::Importer importer;
  // Points and lines are dropped; node transforms are baked into the vertices.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene) {
    throw InputError({path, 0}, std::string("cannot read the mesh: ") + importer.GetErrorString());
  }
  TriMesh m;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* mesh = scene->mMeshes[i];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      m.vertices.push_back({p.x, p.y, p.z});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      m.triangles.push_back({base + static_cast<std::int32_t>(face.mIndices[0]),
                             base + static_cast<std::int32_t>(face.mIndices[1]),
                             base + static_cast<std::int32_t>(face.mIndices[2])});
    }
    if (m.triangles.size() > kMaxMeshTriangles) {
      throw InputError({path, 0}, "more than the triangle limit");
    }
  }
  return m;
}

}  // namespace urlab::convert::internal
