#pragma once
// Heightfields from terrain (the description's heightfield actor): one or more meshes (the
// whitelist: only these are traced) sampled on a regular grid by vertical ray casts with Embree
// 3, or a PNG height map taken as it is. The result is a document with an <hfield> asset and a
// static hfield geom, composed into a scene like an articulation named after the terrain. The
// sampled grid is cached as a MuJoCo binary hfield file keyed by the inputs' bytes and the
// sampling settings, so a second compilation does not trace a single ray.
//
// Thread: any; no shared state (cache files are written atomically).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "urlab/convert/mesh.h"
#include "urlab/document/document.h"

namespace urlab::convert {

struct TerrainMesh {
  std::string file;  // absolute path
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 3> scale = {1, 1, 1};
};

struct TerrainSpec {
  std::string name = "terrain";
  std::vector<TerrainMesh> meshes;                     // sampled by ray casts (the whitelist)
  std::string png;                                     // or a PNG height map (absolute path)
  std::array<double, 4> png_size = {1, 1, 0.1, 0.05};  // PNG: MuJoCo's hfield size
  double resolution = 0.05;                            // grid spacing (m)
  // x min, y min, x max, y max of the sampled area (default: the meshes' bounds).
  std::optional<std::array<double, 4>> bounds;
  double base = 0.05;  // thickness below the lowest sample (m)
  std::array<double, 3> friction = {1, 0.005, 0.0001};
};

// A sampled grid: heights[r * cols + c] at x = x0 + c * dx, y = y0 + r * dy (metres).
struct HeightGrid {
  int rows = 0, cols = 0;
  double x0 = 0, y0 = 0, dx = 0, dy = 0;
  std::vector<float> heights;
  double zmin = 0, zmax = 0;
  std::size_t misses = 0;  // rays that hit nothing (set to zmin)
};

// Samples the triangles of `meshes` (already placed) over the spec's area. Throws
// urlab::Error for an empty area or more than kMaxHeightfieldSamples samples.
HeightGrid SampleHeights(const std::vector<TriMesh>& meshes, const TerrainSpec& spec);

// Most grid samples a terrain may have (4096 x 4096).
constexpr std::size_t kMaxHeightfieldSamples = 4096ull * 4096ull;

struct TerrainDocument {
  document::Document doc;
  HeightGrid grid;  // empty for a PNG terrain
  bool cache_hit = false;
  std::vector<std::string> report;
};

// The terrain's document: <hfield name="hfield"> and <geom name="geom" type="hfield"> placed so
// that the hfield covers the sampled area at the sampled heights (world frame). Throws
// InputError naming the file for unreadable meshes, the terrain for a bad area.
TerrainDocument BuildTerrainDocument(const TerrainSpec& spec, const std::string& cache_dir);

}  // namespace urlab::convert
