#include "urlab/convert/prop.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>

#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/document/element.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::convert {

namespace fs = std::filesystem;

namespace {

std::string Vertices(const TriMesh& m) {
  std::vector<double> v;
  v.reserve(m.vertices.size() * 3);
  for (const Vec3& p : m.vertices) v.insert(v.end(), p.begin(), p.end());
  return document::FormatReals(v);
}

std::string Faces(const TriMesh& m) {
  std::string s;
  for (const Triangle& t : m.triangles) {
    s += fmt::format("{}{} {} {}", s.empty() ? "" : " ", t[0], t[1], t[2]);
  }
  return s;
}

// The file MuJoCo reads for the visual mesh: the source when MuJoCo loads it as it is, else an
// OBJ written into the cache (simplified when the mesh has more faces than MuJoCo takes
// from an STL), named after the source and its content (so two sources with the same stem never
// share a file).
std::string VisualFile(const std::string& source, const TriMesh& mesh, const std::string& cache_dir,
                       const DecomposeOptions& options, std::vector<std::string>* report) {
  const std::string why =
      IsMujocoMeshFormat(source) ? MujocoStlRefusal(source) : "MuJoCo loads STL, OBJ, MSH";
  if (why.empty()) return source;
  std::string simplified;
  const std::string bytes = ObjBytes(LimitForMujoco(mesh, &simplified));
  const std::string out =
      (fs::path(cache_dir) / "meshes" /
       (fs::path(source).stem().string() + "-" + HashHex(HashBytes(bytes)).substr(0, 12) + ".obj"))
          .string();
  std::error_code ec;
  if (!fs::is_regular_file(out, ec)) {
    Interruptible(options, false);
    WriteFileAtomic(out, bytes);
    Interruptible(options, true);
    report->push_back(fmt::format("visual mesh: converted {} to {} ({}{}{})", source, out, why,
                                  simplified.empty() ? "" : "; ", simplified));
  } else {
    report->push_back(fmt::format("visual mesh: converted {}: cached {}", source, out));
  }
  return out;
}

// The visual mesh alone, compiled by MuJoCo as the prop's model will compile it: a mesh MuJoCo
// refuses (flat: no volume; faces it finds inconsistently oriented) is reported before
// minutes of decomposition, not after.
void CheckVisualMesh(const PropSpec& spec, const std::string& file) {
  document::Document doc(spec.name);
  doc.Section("compiler").Set("angle", "radian");
  document::Element& mesh = doc.Section("asset").AddChild("mesh");
  mesh.Set("name", kVisualGeomName);
  mesh.Set("file", file);
  if (spec.scale != std::array<double, 3>{1, 1, 1}) {
    mesh.SetReals("scale", std::vector<double>(spec.scale.begin(), spec.scale.end()));
  }
  // In a body, as in the prop: MuJoCo weighs a body's meshes (even at density 0), a world
  // geom's never.
  document::Element& geom = doc.Section("worldbody").AddChild("body").AddChild("geom");
  geom.Set("type", "mesh");
  geom.Set("mesh", kVisualGeomName);
  geom.SetInt("contype", 0);
  geom.SetInt("conaffinity", 0);
  geom.SetReal("density", 0);
  try {
    physics::CompileXmlString(mjcf::WriteString(doc));
  } catch (const physics::CompileError& e) {
    std::string message = e.what();
    for (const char* generated : {"\nElement", "\nObject"}) {
      // The line of the generated check model means nothing to the user.
      if (const auto cut = message.find(generated); cut != std::string::npos) message.erase(cut);
    }
    if (message.starts_with("Error: ")) message.erase(0, 7);
    std::string hint;
    if (message.find("volume") != std::string::npos) {
      hint =
          "; the mesh is flat or encloses no volume: MuJoCo needs a closed solid, so "
          "give the surface a thickness (e.g. extrude it) before converting";
    } else if (message.find("orientation") != std::string::npos) {
      hint =
          "; its faces are not consistently oriented (a non-manifold surface): repair it "
          "(e.g. merge duplicate vertices, remove faces sharing an edge three ways)";
    }
    throw InputError({spec.mesh, 0},
                     "MuJoCo cannot use this mesh as the visual mesh: " + message + hint);
  }
}

}  // namespace

const char* PropModeName(PropMode mode) {
  switch (mode) {
    case PropMode::kStatic:
      return "static";
    case PropMode::kDynamic:
      return "dynamic";
    case PropMode::kMocap:
      return "mocap";
  }
  return "?";
}

std::optional<PropMode> ParsePropMode(const std::string& word) {
  for (PropMode m : {PropMode::kStatic, PropMode::kDynamic, PropMode::kMocap}) {
    if (word == PropModeName(m)) return m;
  }
  return std::nullopt;
}

std::string DefaultCacheDir() {
  if (const char* d = std::getenv("URLAB_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) {
    return (fs::path(d) / "urlab").string();
  }
  if (const char* d = std::getenv("HOME"); d && *d) {
    return (fs::path(d) / ".cache" / "urlab").string();
  }
  return "/tmp/urlab-cache";
}

PropDocument BuildPropDocument(const PropSpec& spec, const std::string& cache_dir,
                               const std::string& parts_dir) {
  PropDocument out;
  const auto t0 = std::chrono::steady_clock::now();
  // Reading, checking and decomposing write nothing but whole cache files.
  Interruptible(spec.decompose, true);
  TriMesh mesh = ReadMesh(spec.mesh);
  out.report.push_back(fmt::format("read {}: {} triangles", spec.mesh, mesh.triangles.size()));
  ThrowIfCancelled(spec.decompose);
  // The visual mesh first: what MuJoCo refuses is found before the decomposition runs.
  const std::string visual = VisualFile(spec.mesh, mesh, cache_dir, spec.decompose, &out.report);
  CheckVisualMesh(spec, visual);
  for (Vec3& v : mesh.vertices) {
    for (int k = 0; k < 3; ++k) v[k] *= spec.scale[k];
  }
  try {
    out.decomposition = DecomposeCached(mesh, spec.decompose, cache_dir, &out.cache_hit);
  } catch (const InputError&) {
    throw;
  } catch (const Cancelled&) {
    throw;
  } catch (const Error& e) {
    throw InputError({spec.mesh, 0}, e.what());
  }
  Interruptible(spec.decompose, false);  // from here on the parts are written
  ThrowIfCancelled(spec.decompose);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.report.push_back(fmt::format(
      "{} {} into {} convex parts (concavity {:.4f} of the diagonal, threshold {}) in {:.2f} s",
      out.cache_hit ? "read the cached decomposition of" : "decomposed", spec.mesh,
      out.decomposition.parts.size(), out.decomposition.concavity, spec.decompose.threshold,
      seconds));
  for (const std::string& n : out.decomposition.notes) out.report.push_back(n);

  document::Document doc(spec.name);
  doc.Section("compiler").Set("angle", "radian");
  document::Element& asset = doc.Section("asset");
  // Every generated element is located at the mesh file, so a MuJoCo message about one names
  // the file the user gave, not a line of text they never saw (a scene relocates them to its
  // entry).
  document::Element& vmesh = asset.AddChild("mesh");
  vmesh.Set("name", kVisualGeomName);
  vmesh.Set("file", visual);
  if (spec.scale != std::array<double, 3>{1, 1, 1}) {
    vmesh.SetReals("scale", std::vector<double>(spec.scale.begin(), spec.scale.end()));
  }
  double total_volume = 0;
  for (const ConvexPart& p : out.decomposition.parts) total_volume += p.volume;
  document::Element& body = doc.Section("worldbody").AddChild("body");
  body.Set("name", kPropBodyName);
  if (spec.mode == PropMode::kMocap) body.Set("mocap", "true");
  if (spec.mode == PropMode::kDynamic) body.AddChild("freejoint").Set("name", "joint");
  document::Element& vgeom = body.AddChild("geom");
  vgeom.Set("name", kVisualGeomName);
  vgeom.Set("type", "mesh");
  vgeom.Set("mesh", kVisualGeomName);
  vgeom.SetInt("group", kVisualGroup);
  vgeom.SetInt("contype", 0);
  vgeom.SetInt("conaffinity", 0);
  vgeom.SetReal("density", 0);
  vgeom.SetReals("rgba", std::vector<double>(spec.rgba.begin(), spec.rgba.end()));
  for (std::size_t i = 0; i < out.decomposition.parts.size(); ++i) {
    const ConvexPart& p = out.decomposition.parts[i];
    const std::string name = fmt::format("{}{}", kPartGeomPrefix, i);
    document::Element& m = asset.AddChild("mesh");
    m.Set("name", name);
    if (parts_dir.empty()) {
      m.Set("vertex", Vertices(p.hull));
      m.Set("face", Faces(p.hull));
    } else {
      const std::string file = (fs::path(parts_dir) / (name + ".stl")).string();
      WriteFileAtomic(file, StlBytes(p.hull, spec.name + " " + name));
      m.Set("file", file);
    }
    document::Element& g = body.AddChild("geom");
    g.Set("name", name);
    g.Set("type", "mesh");
    g.Set("mesh", name);
    g.SetInt("group", kPartGroup);
    g.SetReals("friction", std::vector<double>(spec.friction.begin(), spec.friction.end()));
    g.SetReals("rgba", std::vector<double>{spec.rgba[0], spec.rgba[1], spec.rgba[2], 0.5});
    if (spec.mass) {
      g.SetReal("mass", total_volume > 0 ? *spec.mass * p.volume / total_volume
                                         : *spec.mass / out.decomposition.parts.size());
    } else if (spec.density) {
      g.SetReal("density", *spec.density);
    }
  }
  doc.root().Visit([&](document::Element& e) { e.set_location({spec.mesh, 0}); });
  out.doc = std::move(doc);
  return out;
}

}  // namespace urlab::convert
