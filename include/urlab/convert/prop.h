#pragma once
// Quick Convert: a mesh becomes a MuJoCo body. The visual mesh goes in geom group 2 (no
// collisions, no mass) and the convex parts of its decomposition in group 3 (the collision
// geometry, with the prop's friction and mass or density); the body is static (welded to the
// world), dynamic (a free joint) or mocap (its pose driven by the host). The result is a
// document composed into a scene like an articulation named after the prop.
//
// Converted parts are recognisable in a compiled model: their geoms are named
// "{prefix}part{N}" (kPartGeomPrefix) and sit in group kPartGroup; the visual geom is
// "{prefix}visual" in group kVisualGroup.
//
// Thread: any; no shared state (the caches are files written atomically).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "urlab/convert/decompose.h"
#include "urlab/document/document.h"

namespace urlab::convert {

inline constexpr int kVisualGroup = 2;
inline constexpr int kPartGroup = 3;
inline constexpr const char* kPartGeomPrefix = "part";
inline constexpr const char* kVisualGeomName = "visual";
inline constexpr const char* kPropBodyName = "body";

enum class PropMode { kStatic, kDynamic, kMocap };

// The mode's scene-file word ("static", "dynamic", "mocap") and back (nullopt when unknown).
const char* PropModeName(PropMode mode);
std::optional<PropMode> ParsePropMode(const std::string& word);

struct PropSpec {
  std::string name = "prop";  // model name
  std::string mesh;           // absolute path of the mesh file (any readable format)
  std::array<double, 3> scale = {1, 1, 1};
  PropMode mode = PropMode::kStatic;
  std::optional<double> mass;     // total mass (kg), shared by the parts by hull volume
  std::optional<double> density;  // kg/m^3 (MuJoCo's 1000 when neither is given)
  std::array<double, 3> friction = {1, 0.005, 0.0001};
  std::array<double, 4> rgba = {0.8, 0.8, 0.8, 1};
  DecomposeOptions decompose;  // threshold, max_parts, ...
};

struct PropDocument {
  document::Document doc;
  Decomposition decomposition;
  bool cache_hit = false;
  std::vector<std::string> report;  // one line per step done ("read ...", "decomposed ...")
};

// Reads, cleans and decomposes the prop's mesh (cached in `cache_dir`) and builds its document:
// meshes inline (vertex and face lists), so nothing but the source mesh file is referenced (a
// source MuJoCo cannot load is written as OBJ into `cache_dir`). With `parts_dir` set, the part
// meshes are written there as STL files and referenced instead (for `urlab convert`). The
// visual mesh is compiled alone with MuJoCo before the decomposition runs, so a mesh MuJoCo
// refuses (flat, inconsistently oriented) fails in seconds. Throws InputError naming the mesh
// file for a mesh that cannot be read, used or decomposed, and Cancelled (nothing written or
// cached) once spec.decompose.cancelled says so. The document's elements are located at the
// mesh file.
PropDocument BuildPropDocument(const PropSpec& spec, const std::string& cache_dir,
                               const std::string& parts_dir = {});

// The folder decompositions, converted meshes and heightfields are cached in:
// $URLAB_CACHE_DIR, else $XDG_CACHE_HOME/urlab, else $HOME/.cache/urlab, else
// /tmp/urlab-cache.
std::string DefaultCacheDir();

}  // namespace urlab::convert
