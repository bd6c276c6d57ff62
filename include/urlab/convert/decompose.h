#pragma once
// Approximate convex decomposition of our own, in the spirit of CoACD (collision-aware
// approximate convex decomposition): a part's concavity is the larger of a surface term (how
// deep the part's own surface lies inside its convex hull) and a volume term (the radius of a
// ball holding the volume its hull adds), measured against the mesh's bounding-box diagonal;
// parts whose concavity exceeds the threshold are cut recursively with the axis-aligned plane
// that lowers it most (a coarse search refined around the best; when no single cut helps much,
// as on a ring, a few candidates are compared two cuts ahead), split into connected pieces,
// then neighbouring parts are merged while the merged part stays within the threshold and until
// at most max_parts remain; every part's hull is computed with Qhull.
//
// The result depends only on the mesh and the options (threads change the time, never the
// parts). Thread: Decompose may be called from any thread; it runs its own worker threads and
// calls `progress` from the calling thread only; `cancelled` is polled from every thread.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/convert/mesh.h"
#include "urlab/core/error.h"

namespace urlab::convert {

// Thrown by Decompose (and what calls it) once DecomposeOptions::cancelled said so: nothing of
// the decomposition is kept or cached.
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

struct DecomposeOptions {
  double threshold = 0.05;     // concavity limit, as a fraction of the bounding-box diagonal
  int max_parts = 32;          // at most this many parts (parts are merged to get there)
  int resolution = 50;         // voxels along the longest side (the volume term's grid)
  int samples = 20000;         // surface samples for the surface term
  double volume_weight = 0.3;  // weight of the volume term (CoACD's k)
  int candidates = 10;         // cutting planes tried per axis (then refined around the best)
  int threads = 0;             // worker threads; 0: the machine's hardware threads
  // Meshes with more triangles are first simplified by vertex clustering (bounded time and
  // memory for a 2M-triangle scan); the parts are computed on the simplified mesh.
  std::size_t max_triangles = 200000;
  // Called with a fraction in [0, 1] and what is being done (on the calling thread).
  std::function<void(double fraction, std::string_view stage)> progress;
  // Polled between stages and before each unit of parallel work, on the calling thread and the
  // worker threads (so it must be thread-safe and cheap, e.g. an atomic load); once it returns
  // true the decomposition stops within one unit of work and throws Cancelled. Not part of the
  // result (nor of OptionsKey).
  std::function<bool()> cancelled;
  // Called with true where the work writes nothing (reading, checking, decomposing) and with
  // false before it writes a file (the cache, the parts), on the calling thread: a host may let
  // a stop signal end the process at once in the first (nothing is half-written, and no unit of
  // work is waited for) and finish the writes first (`urlab convert`). Not part of the result.
  std::function<void(bool)> interruptible;
};

// Throws Cancelled when `options.cancelled` says so.
void ThrowIfCancelled(const DecomposeOptions& options);
// Calls `options.interruptible(on)` when there is one.
void Interruptible(const DecomposeOptions& options, bool on);

struct ConvexPart {
  TriMesh hull;          // outward triangles
  double concavity = 0;  // of the mesh part this hull wraps (fraction of the diagonal)
  double volume = 0;     // of the hull
};

struct Decomposition {
  std::vector<ConvexPart> parts;
  double concavity = 0;    // the largest part concavity (fraction of the diagonal)
  double mesh_volume = 0;  // of the input (0 for an open mesh)
  int cuts = 0, merges = 0;
  std::vector<std::string> notes;  // what was done to the input ("simplified ...", "open ...")
};

// Decomposes `mesh` (cleaned first; see CleanMesh). Throws urlab::InputError-free
// urlab::Error for a mesh without triangles or without extent (a point or a line) and for
// options out of range (threshold <= 0, max_parts < 1, resolution < 4 or > 400, samples < 100).
Decomposition Decompose(TriMesh mesh, const DecomposeOptions& options = {});

// The single convex hull of `mesh` as a one-part decomposition (the baseline to compare with).
Decomposition SingleHull(TriMesh mesh, const DecomposeOptions& options = {});

// Text naming every option that changes the result (for cache keys).
std::string OptionsKey(const DecomposeOptions& options);

// Decompose with a disk cache in `cache_dir` keyed by the mesh's hash and OptionsKey: a hit
// reads the parts back (a damaged cache file is ignored and rewritten). `hit`, when given, says
// which happened. Cache files are written atomically.
Decomposition DecomposeCached(const TriMesh& mesh, const DecomposeOptions& options,
                              const std::string& cache_dir, bool* hit = nullptr);

// Cache file bytes of a decomposition, and back. ParseDecomposition throws urlab::Error for
// bytes that are not a complete, consistent cache file (untrusted: size-checked throughout).
std::string SerializeDecomposition(const Decomposition& d, std::uint64_t key);
Decomposition ParseDecomposition(std::string_view bytes, std::uint64_t key);

}  // namespace urlab::convert
