#include "urlab/convert/mesh_assets.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <set>

#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/document/element.h"
#include "urlab/document/orientation.h"

namespace urlab::convert {

namespace fs = std::filesystem;

namespace {

// Geoms that name mesh `name`.
std::vector<document::Element*> GeomsUsing(document::Document& doc, const std::string& name) {
  std::vector<document::Element*> out;
  doc.root().Visit([&](document::Element& e) {
    if (e.tag() == "geom" && e.parent() && e.parent()->tag() != "default" &&
        e.GetOr("mesh", "") == name) {
      out.push_back(&e);
    }
  });
  return out;
}

bool VisualOnly(const document::Document& doc, const document::Element& geom) {
  for (const char* a : {"contype", "conaffinity"}) {
    const std::string* v = document::ResolveAttribute(doc, geom, a);
    if (!v || *v != "0") return false;  // MuJoCo's default is 1: collides
  }
  return true;
}

// The OBJ a mesh file is converted to: <cache>/meshes/<stem>-<content hash>.obj, written once.
std::string Convert(const std::string& source, const std::string& cache_dir,
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
  const TriMesh mesh = ReadMesh(source);
  WriteFileAtomic(out, ObjBytes(mesh));
  steps->push_back(
      fmt::format("{}: converted to {} ({} triangles; MuJoCo 2.2.2 loads STL, OBJ, "
                  "MSH)",
                  source, out, mesh.triangles.size()));
  return out;
}

}  // namespace

MeshAssetReport PrepareMeshAssets(document::Document& doc, const std::string& cache_dir) {
  MeshAssetReport report;
  std::vector<document::Element*> meshes;
  std::set<std::string> names;
  doc.root().Visit([&](document::Element& e) {
    if (e.tag() != "mesh" || !e.parent() || e.parent()->tag() != "asset") return;
    meshes.push_back(&e);
    if (e.Has("name")) names.insert(e.Name());
  });
  // Implicit names (file stems) that clash get a suffix.
  for (document::Element* m : meshes) {
    if (m->Has("name") || !m->Has("file")) continue;
    const std::string stem = document::DefinedName(*m);
    std::string name = stem;
    for (int k = 1; names.count(name); ++k) name = fmt::format("{}_{}", stem, k);
    names.insert(name);
    if (name != stem) {
      report.steps.push_back(
          fmt::format("{}: mesh '{}' renamed '{}' (another mesh file has the "
                      "same stem)",
                      m->location().str(), stem, name));
      m->Set("name", name);
    }
  }
  std::vector<document::Element*> dropped;
  for (document::Element* m : meshes) {
    const std::optional<std::string> file = m->ResolvedFile("file");
    if (!file || IsMujocoMeshFormat(*file)) continue;
    const std::string name = document::DefinedName(*m);
    try {
      const std::string converted = Convert(*file, cache_dir, &report.steps);
      m->Set("name", name);  // keep the name MuJoCo gave it from the original file
      m->Set("file", converted);
      m->set_file_bases(nullptr);  // an absolute path
    } catch (const InputError& e) {
      const std::vector<document::Element*> geoms = GeomsUsing(doc, name);
      const bool visual = std::all_of(geoms.begin(), geoms.end(), [&](const document::Element* g) {
        return VisualOnly(doc, *g);
      });
      if (!visual) {
        throw InputError(m->location(), fmt::format("mesh '{}': {}", name, e.what()));
      }
      report.warnings.push_back(
          {Diagnostic::Severity::kWarning, m->location(),
           fmt::format("mesh '{}' cannot be read ({}); its {} visual geom(s) are left out, the "
                       "collision geometry stays",
                       name, e.message(), geoms.size())});
      for (document::Element* g : geoms) g->parent()->RemoveChild(g);
      dropped.push_back(m);
    }
  }
  for (document::Element* m : dropped) m->parent()->RemoveChild(m);
  return report;
}

}  // namespace urlab::convert
