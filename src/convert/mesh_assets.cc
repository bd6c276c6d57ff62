#include "urlab/convert/mesh_assets.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
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

// The OBJ a mesh file is converted to: <cache>/meshes/<stem>-<content hash>.obj, written once
// (simplified when it has more faces than MuJoCo 2.2.2 takes from an STL). `why` says why the
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

bool IsMshFile(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".msh";
}

// Whether any <compiler> asks for exact (signed-volume) mesh inertia.
bool ExactMeshInertia(const document::Document& doc) {
  bool exact = false;
  doc.root().Visit([&](const document::Element& e) {
    if (e.tag() == "compiler" && e.GetOr("exactmeshinertia", "false") == "true") exact = true;
  });
  return exact;
}

// The mesh file MuJoCo should load for `source` (an OBJ or STL) so that its faces agree (see
// the header): `source` itself when they do or when nothing depends on it; a repaired copy in
// the cache otherwise. Adds the bridge change or the warning for `mesh`.
std::string OrientedFile(const document::Element& mesh, const std::string& name,
                         const std::string& source, bool exact, const std::string& cache_dir,
                         MeshAssetReport* report) {
  std::string ext = fs::path(source).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool obj = ext == ".obj";
  if (!obj && !exact) return source;  // 2.2.2 neither checks nor weighs STL faces then
  const std::string bytes = ReadInputFile(source, "mesh file", {}, kMaxMeshFileBytes);
  const fs::path base = fs::path(cache_dir) / "meshes" /
                        (fs::path(source).stem().string() + "-" +
                         HashHex(HashBytes(bytes)).substr(0, 12) + (exact ? "-x" : ""));
  const std::string ok_marker = base.string() + ".oriented-ok";
  const std::string repaired = base.string() + "-oriented" + (obj ? ".obj" : ".stl");
  std::error_code ec;
  if (fs::is_regular_file(ok_marker, ec)) return source;
  const TriMesh parsed = obj ? ParseObj(bytes, source) : ParseStl(bytes, source);
  const OrientationPlan plan = PlanConsistentOrientation(parsed, !obj);
  // Without exact inertia only what 2.2.2 rejects matters: an edge run twice the same way.
  const bool matters = exact ? plan.needed() || plan.repeated_edges > 0 : plan.repeated_edges > 0;
  if (!matters) {
    WriteFileAtomic(ok_marker, "");
    return source;
  }
  if (plan.repeated_after > 0 || plan.non_orientable > 0) {
    report->warnings.push_back(
        {Diagnostic::Severity::kWarning, mesh.location(),
         fmt::format("mesh '{}' ({}): its faces cannot be oriented consistently ({} directed "
                     "edges still repeated: non-manifold or non-orientable); MuJoCo 2.2.2 "
                     "rejects it when a body's inertia uses it, and weighs it wrongly with "
                     "exact mesh inertia",
                     name, source, plan.repeated_after)});
    return source;
  }
  if (!fs::is_regular_file(repaired, ec)) {
    if (obj) {
      // Face lines are reversed whole (their first triangle decides): checked like MuJoCo does.
      std::string text = ReverseObjFaces(bytes, plan.flip, source);
      if (PlanConsistentOrientation(ParseObj(text, source), false).repeated_edges > 0) {
        report->warnings.push_back(
            {Diagnostic::Severity::kWarning, mesh.location(),
             fmt::format("mesh '{}' ({}): its faces cannot be oriented consistently (a face "
                         "line whose triangles disagree); MuJoCo 2.2.2 rejects it when a "
                         "body's inertia uses it",
                         name, source)});
        return source;
      }
      WriteFileAtomic(repaired, text);
    } else {
      TriMesh m = parsed;
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        if (plan.flip[t]) std::swap(m.triangles[t][1], m.triangles[t][2]);
      }
      WriteFileAtomic(repaired, StlBytes(m, "urlab: faces oriented consistently"));
    }
  }
  std::string why;
  if (plan.repeated_edges > 0 && obj) {
    why = fmt::format(
        "{} edges were run twice the same way (MuJoCo 2.2.2 rejects such an OBJ: "
        "\"faces have inconsistent orientation\"; 3.x's default legacy inertia "
        "accepts it)",
        plan.repeated_edges);
  } else if (plan.repeated_edges > 0) {
    why = fmt::format(
        "{} edges were run twice the same way: faces turned against their "
        "neighbours, whose volume exact mesh inertia would subtract (3.x's default "
        "legacy inertia counts it)",
        plan.repeated_edges);
  }
  if (plan.turned_outwards > 0) {
    why += fmt::format(
        "{}{} closed piece(s) faced inwards (exact mesh inertia would weigh them "
        "negative)",
        why.empty() ? "" : "; ", plan.turned_outwards);
  }
  if (why.empty()) {
    why = "flipped faces would subtract their volume under exact mesh inertia";
  }
  report->bridge_changes.push_back(
      {mjcf::BridgeChange::Kind::kTranslated, mesh.location(),
       fmt::format("mesh '{}' ({}): {} of {} triangles reversed so that the faces agree and "
                   "face outwards: {}; MuJoCo loads {}",
                   name, source, plan.flipped, parsed.triangles.size(), why, repaired),
       "mesh.orientation"});
  return repaired;
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
    if (!file) continue;
    const std::string why =
        IsMujocoMeshFormat(*file) ? MujocoStlRefusal(*file) : "MuJoCo 2.2.2 loads STL, OBJ, MSH";
    if (why.empty()) continue;
    const std::string name = document::DefinedName(*m);
    try {
      const std::string converted = Convert(*file, why, cache_dir, &report.steps);
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
  // Face orientation of the OBJ and STL files MuJoCo will load (converted ones included).
  const bool exact = ExactMeshInertia(doc);
  for (document::Element* m : meshes) {
    if (std::find(dropped.begin(), dropped.end(), m) != dropped.end()) continue;
    const std::optional<std::string> file = m->ResolvedFile("file");
    if (!file || !IsMujocoMeshFormat(*file) || IsMshFile(*file)) continue;
    const std::string name = document::DefinedName(*m);
    try {
      const std::string oriented = OrientedFile(*m, name, *file, exact, cache_dir, &report);
      if (oriented != *file) {
        m->Set("name", name);
        m->Set("file", oriented);
        m->set_file_bases(nullptr);
      }
    } catch (const InputError& e) {
      throw InputError(m->location(), fmt::format("mesh '{}': {}", name, e.what()));
    }
  }
  return report;
}

}  // namespace urlab::convert
