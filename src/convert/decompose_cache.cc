// The on-disk cache of decompositions (DecomposeCached, SerializeDecomposition,
// ParseDecomposition).
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/byte_io.h"
#include "urlab/convert/decompose.h"
#include "urlab/core/files.h"

namespace urlab::convert {

namespace {

constexpr std::string_view kMagic = "URLABCD1";
constexpr std::uint32_t kMaxParts = 100000;
constexpr std::uint32_t kMaxNotes = 64;

}  // namespace

std::string SerializeDecomposition(const Decomposition& d, std::uint64_t key) {
  urlab::internal::ByteWriter w;
  w.PutBytes(kMagic);
  w.Put(key);
  w.Put(static_cast<std::uint32_t>(d.parts.size()));
  w.Put(d.concavity);
  w.Put(d.mesh_volume);
  w.Put(static_cast<std::int32_t>(d.cuts));
  w.Put(static_cast<std::int32_t>(d.merges));
  w.Put(static_cast<std::uint32_t>(d.notes.size()));
  for (const std::string& n : d.notes) w.PutString(n);
  for (const ConvexPart& p : d.parts) {
    w.Put(p.concavity);
    w.Put(p.volume);
    w.Put(static_cast<std::uint32_t>(p.hull.vertices.size()));
    w.Put(static_cast<std::uint32_t>(p.hull.triangles.size()));
    for (const Vec3& v : p.hull.vertices) w.Put(v);
    for (const Triangle& t : p.hull.triangles) w.Put(t);
  }
  w.Put(HashBytes(w.bytes()));
  return std::move(w.bytes());
}

Decomposition ParseDecomposition(std::string_view bytes, std::uint64_t key) {
  const std::string what = "decomposition cache";
  if (bytes.size() < kMagic.size() + 8 || bytes.substr(0, kMagic.size()) != kMagic) {
    throw Error(what + ": not a cache file");
  }
  {
    std::uint64_t sum = 0;
    std::memcpy(&sum, bytes.data() + bytes.size() - 8, 8);
    if (sum != HashBytes(bytes.substr(0, bytes.size() - 8))) throw Error(what + ": checksum");
  }
  urlab::internal::ByteReader r(bytes.substr(0, bytes.size() - 8), what);
  r.GetBytes(kMagic.size());
  if (r.Get<std::uint64_t>() != key) throw Error(what + ": another mesh or options");
  Decomposition d;
  const auto nparts = r.Get<std::uint32_t>();
  if (nparts > kMaxParts) throw Error(what + ": too many parts");
  d.concavity = r.Get<double>();
  d.mesh_volume = r.Get<double>();
  d.cuts = r.Get<std::int32_t>();
  d.merges = r.Get<std::int32_t>();
  const auto nnotes = r.Get<std::uint32_t>();
  if (nnotes > kMaxNotes) throw Error(what + ": too many notes");
  for (std::uint32_t i = 0; i < nnotes; ++i) d.notes.push_back(r.GetString(4096));
  r.NeedItems(nparts, 24);
  for (std::uint32_t i = 0; i < nparts; ++i) {
    ConvexPart p;
    p.concavity = r.Get<double>();
    p.volume = r.Get<double>();
    const auto nv = r.Get<std::uint32_t>();
    const auto nt = r.Get<std::uint32_t>();
    r.NeedItems(nv, sizeof(Vec3));
    p.hull.vertices.resize(nv);
    for (Vec3& v : p.hull.vertices) {
      v = r.Get<Vec3>();
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        throw Error(what + ": non-finite vertex");
      }
    }
    r.NeedItems(nt, sizeof(Triangle));
    p.hull.triangles.resize(nt);
    for (Triangle& t : p.hull.triangles) {
      t = r.Get<Triangle>();
      for (std::int32_t k : t) {
        if (k < 0 || static_cast<std::uint32_t>(k) >= nv) throw Error(what + ": bad index");
      }
    }
    d.parts.push_back(std::move(p));
  }
  if (r.remaining() != 0) throw Error(what + ": trailing bytes");
  return d;
}

Decomposition DecomposeCached(const TriMesh& mesh, const DecomposeOptions& options,
                              const std::string& cache_dir, bool* hit) {
  const std::uint64_t key = HashBytes(OptionsKey(options), HashMesh(mesh));
  const std::string path =
      (std::filesystem::path(cache_dir) / ("decomposition-" + HashHex(key) + ".bin")).string();
  if (hit) *hit = false;
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) {
    try {
      std::ifstream in(path, std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      Decomposition d = ParseDecomposition(ss.str(), key);
      if (hit) *hit = true;
      return d;
    } catch (const Error& e) {
      spdlog::warn("{}: {}; decomposing again", path, e.what());
    }
  }
  Decomposition d = Decompose(mesh, options);
  Interruptible(options, false);  // the cache file is written whole, or not at all
  try {
    WriteFileAtomic(path, SerializeDecomposition(d, key));
  } catch (const Error& e) {
    spdlog::warn("cannot write the decomposition cache: {}", e.what());
  }
  Interruptible(options, true);
  return d;
}

}  // namespace urlab::convert
