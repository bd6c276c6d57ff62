#include "urlab/convert/mesh_assets.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>

#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/mjcf/spec.h"

namespace urlab::convert {

namespace fs = std::filesystem;

namespace {

// The OBJ a mesh file is converted to: <cache>/meshes/<stem>-<content hash>.obj, written once
// (simplified when it has more faces than MuJoCo takes from an STL). `why` says why the
// source cannot be used as it is.
std::string Convert(const std::string& source, const std::string& why, const std::string& cache_dir,
                    std::vector<std::string>* steps) {
  const std::string bytes = ReadInputFile(source, "mesh file", {}, kMaxMeshFileBytes);
  const std::string out =
      (fs::path(cache_dir) / "meshes" /
       (fs::path(source).stem().string() + "-" + HashHex(HashBytes(bytes)).substr(0, 12) + ".obj"))
          .string();
  std::error_code ec;
  if (fs::is_regular_file(out, ec)) {
    steps->push_back(fmt::format("{}: converted before, using {}", source, out));
    return out;
  }
  std::string simplified;
  const TriMesh mesh = LimitForMujoco(ReadMesh(source), &simplified);
  WriteFileAtomic(out, ObjBytes(mesh));
  steps->push_back(fmt::format("{}: converted to {} ({} triangles; {}{}{})", source, out,
                               mesh.triangles.size(), why, simplified.empty() ? "" : "; ",
                               simplified));
  return out;
}

// The name MuJoCo gives a mesh: its own, else its file's stem.
std::string MeshName(const mjsMesh* mesh) {
  const std::string name = mjcf::SpecString(mjs_getName(mesh->element));
  if (!name.empty()) return name;
  return fs::path(mjcf::SpecString(mesh->file)).stem().string();
}

}  // namespace

std::string MeshFilePath(const mjSpec* spec, const mjsMesh* mesh) {
  return mjcf::ResolveAssetPath(spec, mjcf::SpecString(mesh->file), spec->compiler.meshdir);
}

MeshAssetReport PrepareMeshAssets(mjSpec* spec, const std::string& model_file,
                                  const std::string& cache_dir) {
  MeshAssetReport report;
  std::vector<mjsMesh*> meshes;
  std::set<std::string> names;
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_MESH); e; e = mjs_nextElement(spec, e)) {
    mjsMesh* m = mjs_asMesh(e);
    meshes.push_back(m);
    const std::string own = mjcf::SpecString(mjs_getName(e));
    if (!own.empty()) names.insert(own);
  }
  // Implicit names (file stems) that clash get a suffix.
  for (mjsMesh* m : meshes) {
    if (!mjcf::SpecString(mjs_getName(m->element)).empty() || mjcf::SpecString(m->file).empty()) {
      continue;
    }
    const std::string stem = MeshName(m);
    std::string name = stem;
    for (int k = 1; names.count(name); ++k) name = fmt::format("{}_{}", stem, k);
    names.insert(name);
    if (name != stem) {
      report.steps.push_back(
          fmt::format("{}: mesh '{}' renamed '{}' (another mesh file has the same stem)",
                      model_file, stem, name));
    }
    mjs_setName(m->element, name.c_str());
  }
  for (mjsMesh* m : meshes) {
    // Where the <mesh> names its file (MuJoCo does not say which line an element came from).
    const int line = mjcf::LineContaining(
        model_file, fs::path(mjcf::SpecString(m->file)).filename().string() + "\"");
    const std::string file = MeshFilePath(spec, m);
    if (file.empty()) continue;
    const std::string why =
        IsMujocoMeshFormat(file) ? MujocoStlRefusal(file) : "MuJoCo loads STL, OBJ and MSH";
    if (why.empty()) continue;
    const std::string name = MeshName(m);
    try {
      const std::string converted = Convert(file, why, cache_dir, &report.steps);
      mjs_setName(m->element, name.c_str());  // the name MuJoCo gave it from the original file
      mjs_setString(m->file, converted.c_str());
    } catch (const InputError& e) {
      // Geoms that use it: dropped with it when all of them are visual only.
      std::vector<mjsElement*> geoms;
      bool visual = true;
      for (mjsElement* g = mjs_firstElement(spec, mjOBJ_GEOM); g; g = mjs_nextElement(spec, g)) {
        const mjsGeom* geom = mjs_asGeom(g);
        if (mjcf::SpecString(geom->meshname) != name) continue;
        geoms.push_back(g);
        visual = visual && geom->contype == 0 && geom->conaffinity == 0;
      }
      if (!visual) {
        throw InputError({model_file, line}, fmt::format("mesh '{}': {}", name, e.what()));
      }
      report.warnings.push_back(
          {Diagnostic::Severity::kWarning,
           {model_file, line},
           fmt::format("mesh '{}' cannot be read ({}); its {} visual geom(s) are left out, the "
                       "collision geometry stays",
                       name, e.message(), geoms.size())});
      for (mjsElement* g : geoms) mjs_delete(spec, g);
      mjs_delete(spec, m->element);
    }
  }
  return report;
}

}  // namespace urlab::convert
