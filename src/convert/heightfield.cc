#include "urlab/convert/heightfield.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "core/byte_io.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/document/element.h"

namespace urlab::convert {

namespace fs = std::filesystem;

namespace {

struct DeviceDeleter {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
using DevicePtr = std::unique_ptr<RTCDeviceTy, DeviceDeleter>;
using ScenePtr = std::unique_ptr<RTCSceneTy, SceneDeleter>;

// The cache: a MuJoCo hfield file (int32 rows, int32 cols, float32 heights) and a sidecar with
// the grid's placement.
struct CacheFiles {
  std::string hfield, sidecar;
};

CacheFiles CachePaths(const std::string& cache_dir, std::uint64_t key) {
  const fs::path base = fs::path(cache_dir) / ("hfield-" + HashHex(key));
  return {base.string() + ".bin", base.string() + ".grid"};
}

std::string HfieldBytes(const HeightGrid& g) {
  urlab::internal::ByteWriter w;
  w.Put(static_cast<std::int32_t>(g.rows));
  w.Put(static_cast<std::int32_t>(g.cols));
  for (float h : g.heights) w.Put(h);
  return std::move(w.bytes());
}

std::string SidecarText(const HeightGrid& g) {
  return fmt::format("urlab-heightfield 1\n{} {} {} {} {} {} {} {} {}\n", g.rows, g.cols, g.x0,
                     g.y0, g.dx, g.dy, g.zmin, g.zmax, g.misses);
}

// The cached grid, or nullopt when absent or inconsistent (then it is sampled again).
std::optional<HeightGrid> ReadCache(const CacheFiles& files) {
  std::error_code ec;
  if (!fs::is_regular_file(files.hfield, ec) || !fs::is_regular_file(files.sidecar, ec)) {
    return std::nullopt;
  }
  std::ifstream side(files.sidecar);
  std::string magic;
  int version = 0;
  HeightGrid g;
  if (!(side >> magic >> version >> g.rows >> g.cols >> g.x0 >> g.y0 >> g.dx >> g.dy >> g.zmin >>
        g.zmax >> g.misses) ||
      magic != "urlab-heightfield" || version != 1 || g.rows < 2 || g.cols < 2) {
    return std::nullopt;
  }
  const std::uint64_t n = static_cast<std::uint64_t>(g.rows) * static_cast<std::uint64_t>(g.cols);
  if (n > kMaxHeightfieldSamples || fs::file_size(files.hfield, ec) != 8 + 4 * n) {
    return std::nullopt;
  }
  return g;  // heights stay in the file MuJoCo reads
}

std::uint64_t CacheKey(const TerrainSpec& spec) {
  std::uint64_t h = HashBytes(fmt::format(
      "v1 {} {} {} {}", spec.resolution, spec.base,
      spec.bounds ? fmt::format("{}", fmt::join(*spec.bounds, " ")) : std::string("auto"),
      spec.meshes.size()));
  for (const TerrainMesh& m : spec.meshes) {
    h = HashBytes(ReadInputFile(m.file, "terrain mesh", {}, kMaxMeshFileBytes), h);
    h = HashBytes(fmt::format("{} {}", fmt::join(m.pos, " "), fmt::join(m.scale, " ")), h);
    h = HashBytes(fs::path(m.file).extension().string(), h);
  }
  return h;
}

// The largest height map side we hand MuJoCo (its grid is nrow x ncol floats).
constexpr std::uint32_t kMaxPngSide = 8192;

std::uint32_t Be32(const std::string& b, std::size_t at) {
  return static_cast<std::uint32_t>(static_cast<std::uint8_t>(b[at])) << 24 |
         static_cast<std::uint32_t>(static_cast<std::uint8_t>(b[at + 1])) << 16 |
         static_cast<std::uint32_t>(static_cast<std::uint8_t>(b[at + 2])) << 8 |
         static_cast<std::uint32_t>(static_cast<std::uint8_t>(b[at + 3]));
}

// Checks a PNG height map as MuJoCo's decoder will read it, so that a bad one is an error at the
// terrain's scene line (InputError at the file) instead of MuJoCo's, on the composed model: the
// signature, an IHDR of a supported kind and size, every chunk's CRC, and image data that
// inflates to exactly the bytes the header implies.
void CheckPngHeightMap(const std::string& path) {
  const std::string b = ReadInputFile(path, "png height map");
  const auto fail = [&](const std::string& why) { throw InputError({path, 0}, why); };
  if (b.size() < 8 || b.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) {
    fail("not a PNG (no PNG signature)");
  }
  std::uint32_t width = 0, height = 0;
  int depth = 0, type = -1, interlace = 0;
  std::string idat;
  bool ended = false;
  for (std::size_t at = 8; !ended;) {
    if (b.size() - at < 12) fail("the file ends inside a chunk (truncated)");
    const std::uint32_t length = Be32(b, at);
    const std::string kind = b.substr(at + 4, 4);
    if (length > b.size() - at - 12) fail("the file ends inside chunk " + kind + " (truncated)");
    const std::uint32_t crc = static_cast<std::uint32_t>(
        crc32(0, reinterpret_cast<const Bytef*>(b.data() + at + 4), length + 4));
    if (crc != Be32(b, at + 8 + length)) fail("chunk " + kind + ": checksum mismatch");
    const std::string data = b.substr(at + 8, length);
    if (at == 8) {
      if (kind != "IHDR" || length != 13) fail("not a PNG (no IHDR chunk first)");
      width = Be32(data, 0);
      height = Be32(data, 4);
      depth = static_cast<std::uint8_t>(data[8]);
      type = static_cast<std::uint8_t>(data[9]);
      interlace = static_cast<std::uint8_t>(data[12]);
    } else if (kind == "IDAT") {
      idat += data;
    } else if (kind == "IEND") {
      ended = true;
    }
    at += 12 + length;
  }
  if (width < 1 || height < 1 || width > kMaxPngSide || height > kMaxPngSide) {
    fail(fmt::format("{} x {} pixels; a height map is 1 to {} pixels a side", width, height,
                     kMaxPngSide));
  }
  // Samples per pixel by colour type: grey, -, RGB, palette, grey + alpha, -, RGBA.
  static constexpr int kChannels[7] = {1, 0, 3, 1, 2, 0, 4};
  if (type < 0 || type > 6 || kChannels[type] == 0) {
    fail(fmt::format("unknown PNG colour type {}", type));
  }
  const int channels = kChannels[type];
  const bool depth_ok = type == 0
                            ? depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16
                        : type == 3 ? depth == 1 || depth == 2 || depth == 4 || depth == 8
                                    : depth == 8 || depth == 16;
  if (!depth_ok || interlace > 1) {
    fail(fmt::format("unsupported PNG: colour type {}, bit depth {}, interlace {}", type, depth,
                     interlace));
  }
  // The bytes the image data must inflate to: per row a filter byte and the packed pixels, per
  // pass of Adam7 when interlaced.
  const std::uint64_t bits =
      static_cast<std::uint64_t>(depth) * static_cast<std::uint64_t>(channels);
  const auto rows_bytes = [&](std::uint64_t w, std::uint64_t h) -> std::uint64_t {
    return w == 0 || h == 0 ? 0 : h * (1 + (w * bits + 7) / 8);
  };
  std::uint64_t expected = 0;
  if (interlace == 0) {
    expected = rows_bytes(width, height);
  } else {
    static constexpr int kPass[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                        {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
    for (const auto& p : kPass) {
      const std::uint64_t w =
          (width + static_cast<std::uint64_t>(p[2] - p[0] - 1)) / static_cast<std::uint64_t>(p[2]);
      const std::uint64_t h =
          (height + static_cast<std::uint64_t>(p[3] - p[1] - 1)) / static_cast<std::uint64_t>(p[3]);
      expected += rows_bytes(w, h);
    }
  }
  // Inflate, counting (never holding more than a buffer of it), up to one byte past expected.
  z_stream z{};
  if (inflateInit(&z) != Z_OK) fail("cannot start zlib");
  z.next_in = reinterpret_cast<Bytef*>(idat.data());
  z.avail_in = static_cast<uInt>(idat.size());
  std::vector<Bytef> buffer(1 << 16);
  std::uint64_t produced = 0;
  int rc = Z_OK;
  while (rc == Z_OK && produced <= expected) {
    z.next_out = buffer.data();
    z.avail_out = static_cast<uInt>(buffer.size());
    rc = inflate(&z, Z_NO_FLUSH);
    produced += buffer.size() - z.avail_out;
    if (rc == Z_BUF_ERROR && z.avail_in == 0) break;  // the data ends early
    if (rc == Z_BUF_ERROR) rc = Z_OK;
  }
  inflateEnd(&z);
  if (rc != Z_STREAM_END && rc != Z_OK && rc != Z_BUF_ERROR) {
    fail("its image data is not a valid zlib stream");
  }
  if (produced != expected) {
    fail(fmt::format("its image data holds {}{} bytes, {} x {} pixels need {}",
                     produced > expected ? "more than " : "", std::min(produced, expected + 1),
                     width, height, expected));
  }
}

}  // namespace

HeightGrid SampleHeights(const std::vector<TriMesh>& meshes, const TerrainSpec& spec) {
  Bounds all;
  bool any = false;
  for (const TriMesh& m : meshes) {
    if (m.empty()) continue;
    const Bounds b = ComputeBounds(m);
    for (int k = 0; k < 3; ++k) {
      all.min[k] = any ? std::min(all.min[k], b.min[k]) : b.min[k];
      all.max[k] = any ? std::max(all.max[k], b.max[k]) : b.max[k];
    }
    any = true;
  }
  if (!any) throw Error(spec.name + ": the terrain meshes have no triangles");
  std::array<double, 4> area =
      spec.bounds.value_or(std::array<double, 4>{all.min[0], all.min[1], all.max[0], all.max[1]});
  if (!(area[2] > area[0]) || !(area[3] > area[1])) {
    throw Error(fmt::format("{}: the sampled area [{}] is empty", spec.name, fmt::join(area, " ")));
  }
  if (!(spec.resolution > 0)) throw Error(spec.name + ": resolution must be > 0");
  HeightGrid g;
  const double nx = std::ceil((area[2] - area[0]) / spec.resolution) + 1;
  const double ny = std::ceil((area[3] - area[1]) / spec.resolution) + 1;
  if (nx * ny > static_cast<double>(kMaxHeightfieldSamples)) {
    throw Error(fmt::format("{}: {} x {} samples is more than {} (raise resolution)", spec.name, nx,
                            ny, kMaxHeightfieldSamples));
  }
  g.cols = std::max(2, static_cast<int>(nx));
  g.rows = std::max(2, static_cast<int>(ny));
  g.x0 = area[0];
  g.y0 = area[1];
  g.dx = (area[2] - area[0]) / (g.cols - 1);
  g.dy = (area[3] - area[1]) / (g.rows - 1);
  // Embree works in float: coordinates relative to the area's centre keep their precision.
  const double cx = (area[0] + area[2]) / 2, cy = (area[1] + area[3]) / 2, cz = all.min[2];
  DevicePtr device(rtcNewDevice("threads=1"));
  if (!device) throw Error("embree: cannot create a device");
  ScenePtr scene(rtcNewScene(device.get()));
  for (const TriMesh& m : meshes) {
    if (m.empty()) continue;
    RTCGeometry geom = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.vertices.size()));
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), m.triangles.size()));
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      vb[3 * i] = static_cast<float>(m.vertices[i][0] - cx);
      vb[3 * i + 1] = static_cast<float>(m.vertices[i][1] - cy);
      vb[3 * i + 2] = static_cast<float>(m.vertices[i][2] - cz);
    }
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(m.triangles[i][k]);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene.get(), geom);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(scene.get());
  const float top = static_cast<float>(all.max[2] - cz + 1.0);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  g.heights.resize(static_cast<std::size_t>(g.rows) * static_cast<std::size_t>(g.cols));
  std::vector<bool> hit(g.heights.size());
  // One vertical ray; nullopt when it hits nothing.
  auto cast = [&](double x, double y) -> std::optional<float> {
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(x - cx);
    rh.ray.org_y = static_cast<float>(y - cy);
    rh.ray.org_z = top;
    rh.ray.dir_x = 0;
    rh.ray.dir_y = 0;
    rh.ray.dir_z = -1;
    rh.ray.tnear = 0;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene.get(), &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    return static_cast<float>(cz + (top - rh.ray.tfar));
  };
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      const double x = g.x0 + c * g.dx, y = g.y0 + r * g.dy;
      std::optional<float> z = cast(x, y);
      if (!z) {
        // On the mesh's outline a ray can pass between edges: nudge it inwards once.
        z = cast(x + (c == 0 ? 1 : -1) * 1e-3 * g.dx, y + (r == 0 ? 1 : -1) * 1e-3 * g.dy);
      }
      const std::size_t i = static_cast<std::size_t>(r) * g.cols + c;
      if (z) {
        g.heights[i] = *z;
        hit[i] = true;
      }
    }
  }
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  for (std::size_t i = 0; i < g.heights.size(); ++i) {
    if (!hit[i]) continue;
    zmin = std::min(zmin, static_cast<double>(g.heights[i]));
    zmax = std::max(zmax, static_cast<double>(g.heights[i]));
  }
  if (!std::isfinite(zmin)) throw Error(spec.name + ": no ray hit the terrain meshes");
  for (std::size_t i = 0; i < g.heights.size(); ++i) {
    if (!hit[i]) {
      g.heights[i] = static_cast<float>(zmin);
      ++g.misses;
    }
  }
  g.zmin = zmin;
  g.zmax = zmax;
  return g;
}

TerrainDocument BuildTerrainDocument(const TerrainSpec& spec, const std::string& cache_dir) {
  TerrainDocument out;
  document::Document doc(spec.name);
  document::Element& hfield = doc.Section("asset").AddChild("hfield");
  hfield.Set("name", "hfield");
  document::Element& geom = doc.Section("worldbody").AddChild("geom");
  geom.Set("name", "geom");
  geom.Set("type", "hfield");
  geom.Set("hfield", "hfield");
  geom.SetReals("friction", std::vector<double>(spec.friction.begin(), spec.friction.end()));
  if (!spec.png.empty()) {
    CheckInputFile(spec.png, spec.name + ": png height map");
    CheckPngHeightMap(spec.png);
    hfield.Set("file", spec.png);
    hfield.SetReals("size", std::vector<double>(spec.png_size.begin(), spec.png_size.end()));
    out.report.push_back(fmt::format("height map {} ({} x {} m, {} m high)", spec.png,
                                     2 * spec.png_size[0], 2 * spec.png_size[1], spec.png_size[2]));
    out.doc = std::move(doc);
    return out;
  }
  if (spec.meshes.empty()) throw InputError({}, spec.name + ": a terrain needs meshes or a png");
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t key = CacheKey(spec);
  const CacheFiles files = CachePaths(cache_dir, key);
  std::optional<HeightGrid> cached = ReadCache(files);
  if (cached) {
    out.grid = *cached;
    out.cache_hit = true;
  } else {
    std::vector<TriMesh> meshes;
    std::size_t triangles = 0;
    for (const TerrainMesh& m : spec.meshes) {
      TriMesh mesh = ReadMesh(m.file);
      for (Vec3& v : mesh.vertices) {
        for (int k = 0; k < 3; ++k) v[k] = v[k] * m.scale[k] + m.pos[k];
      }
      triangles += mesh.triangles.size();
      meshes.push_back(std::move(mesh));
    }
    try {
      out.grid = SampleHeights(meshes, spec);
    } catch (const InputError&) {
      throw;
    } catch (const Error& e) {
      throw InputError({spec.meshes.front().file, 0}, e.what());
    }
    WriteFileAtomic(files.hfield, HfieldBytes(out.grid));
    WriteFileAtomic(files.sidecar, SidecarText(out.grid));
    out.report.push_back(fmt::format("sampled {} triangles on {} x {} rays ({} missed)", triangles,
                                     out.grid.cols, out.grid.rows, out.grid.misses));
  }
  const HeightGrid& g = out.grid;
  const double elevation = std::max(g.zmax - g.zmin, 1e-6);
  const double rx = g.dx * (g.cols - 1) / 2, ry = g.dy * (g.rows - 1) / 2;
  hfield.Set("file", files.hfield);
  hfield.SetReals("size", std::vector<double>{rx, ry, elevation, spec.base});
  geom.SetReals("pos", std::vector<double>{g.x0 + rx, g.y0 + ry, g.zmin});
  out.report.push_back(fmt::format(
      "{} heightfield {} x {} ({:.3f} x {:.3f} m, heights {:.3f}..{:.3f} m) in {:.3f} s",
      out.cache_hit ? "cached" : "new", g.cols, g.rows, 2 * rx, 2 * ry, g.zmin, g.zmax,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()));
  out.doc = std::move(doc);
  return out;
}

}  // namespace urlab::convert
