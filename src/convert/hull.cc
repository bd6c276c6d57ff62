#include "hull.h"

#include <cstdio>
#include <limits>
#include <memory>

#include "geometry.h"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace urlab::convert::internal {

namespace {

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};

}  // namespace

double Hull::Depth(const Vec3& p) const {
  double depth = std::numeric_limits<double>::infinity();
  for (const HullPlane& pl : planes) depth = std::min(depth, pl.offset - Dot(pl.normal, p));
  return depth;
}

std::optional<Hull> ComputeHull(const std::vector<Vec3>& points, bool with_mesh) {
  if (points.size() < 4) return std::nullopt;
  std::vector<coordT> coords;
  coords.reserve(points.size() * 3);
  for (const Vec3& p : points) coords.insert(coords.end(), p.begin(), p.end());
  // Qhull prints its errors to a stream; they are not ours to show (a flat input is an answer).
  std::unique_ptr<FILE, FileCloser> sink(std::fopen("/dev/null", "w"));
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, sink.get());
  char flags[] = "qhull Qt Qs";
  const int code = qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False, flags,
                                nullptr, sink.get());
  std::optional<Hull> out;
  if (code == 0) {
    Hull h;
    qh_getarea(qh, qh->facet_list);
    h.volume = qh->totvol;
    h.area = qh->totarea;
    facetT* facet;
    FORALLfacets {
      h.planes.push_back({{facet->normal[0], facet->normal[1], facet->normal[2]}, -facet->offset});
    }
    if (with_mesh) {
      std::vector<std::int32_t> remap(points.size(), -1);
      FORALLfacets {
        if (qh_setsize(qh, facet->vertices) != 3) continue;
        Triangle t{};
        int k = 0;
        vertexT *vertex, **vertexp;
        FOREACHvertex_(facet->vertices) {
          const int id = qh_pointid(qh, vertex->point);
          if (id < 0 || static_cast<std::size_t>(id) >= points.size()) continue;
          std::int32_t& m = remap[static_cast<std::size_t>(id)];
          if (m < 0) {
            m = static_cast<std::int32_t>(h.mesh.vertices.size());
            h.mesh.vertices.push_back(points[static_cast<std::size_t>(id)]);
          }
          if (k < 3) t[k++] = m;
        }
        if (k != 3) continue;
        const Vec3& a = h.mesh.vertices[static_cast<std::size_t>(t[0])];
        const Vec3 n = Cross(h.mesh.vertices[static_cast<std::size_t>(t[1])] - a,
                             h.mesh.vertices[static_cast<std::size_t>(t[2])] - a);
        if (Dot(n, {facet->normal[0], facet->normal[1], facet->normal[2]}) < 0) {
          std::swap(t[1], t[2]);
        }
        h.mesh.triangles.push_back(t);
      }
    }
    if (h.volume > 0 && !h.planes.empty()) out = std::move(h);
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return out;
}

}  // namespace urlab::convert::internal
