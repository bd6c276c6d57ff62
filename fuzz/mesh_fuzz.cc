// libFuzzer target for the mesh-loading path we own: the first byte picks the decoder (binary
// or ASCII STL, OBJ, a decomposition cache file), the rest is the file. A parsed mesh is
// oriented consistently (PlanConsistentOrientation; for OBJ the face lines are rewritten with
// ReverseObjFaces and must parse to the same triangles, reversed where planned), cleaned, written
// back as STL and OBJ and parsed again (same triangle count), and a small one
// (at most 64 triangles, coordinates within 1e6) is decomposed with small settings. Any input
// must parse or fail with urlab::Error; never crash, leak, hang or allocate without bound.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.h"
#include "urlab/convert/decompose.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"

namespace {

bool SmallAndTame(const urlab::convert::TriMesh& m) {
  if (m.triangles.size() > 64) return false;
  for (const auto& v : m.vertices) {
    for (double x : v) {
      if (!(std::abs(x) < 1e6)) return false;
    }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool quiet = [] {
    urlab::fuzz::QuietStart();
    return true;
  }();
  (void)quiet;
  if (size < 1) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  using namespace urlab::convert;
  try {
    if (data[0] % 3 == 2) {
      (void)ParseDecomposition(bytes, 0);
      return 0;
    }
    const bool obj = data[0] % 3 == 1;
    TriMesh m = obj ? ParseObj(bytes, "fuzz.obj") : ParseStl(bytes, "fuzz.stl");
    const OrientationPlan plan = PlanConsistentOrientation(m, !obj);
    if (plan.flip.size() != m.triangles.size()) __builtin_trap();
    if (obj) {
      // The same triangles as vertex sets (a reversed polygon is fanned in the other order).
      const TriMesh turned = ParseObj(ReverseObjFaces(bytes, plan.flip, "fuzz.obj"), "fuzz.obj");
      auto sets = [](const TriMesh& mesh) {
        std::vector<Triangle> out = mesh.triangles;
        for (Triangle& t : out) std::sort(t.begin(), t.end());
        std::sort(out.begin(), out.end());
        return out;
      };
      if (sets(turned) != sets(m)) __builtin_trap();
    }
    CleanMesh(m);
    const TriMesh again_stl = ParseStl(StlBytes(m), "again.stl");
    const TriMesh again_obj = ParseObj(ObjBytes(m), "again.obj");
    if (again_stl.triangles.size() != m.triangles.size() ||
        again_obj.triangles.size() != m.triangles.size()) {
      __builtin_trap();
    }
    if (!m.empty() && SmallAndTame(m)) {
      DecomposeOptions o;
      o.threads = 1;
      o.resolution = 8;
      o.samples = 200;
      o.candidates = 3;
      o.max_parts = 4;
      const Decomposition d = Decompose(m, o);
      (void)ParseDecomposition(SerializeDecomposition(d, 7), 7);
    }
  } catch (const urlab::Error&) {
  }
  return 0;
}
