// Convex decomposition benchmark: on every mesh of a folder (tools/gen_bench_meshes.py writes
// the set), our decomposition, Bullet's HACD (libbullet-extras-dev, run in a child process with
// a time cap) and the single convex hull, each scored by the same metrics
// (convert/evaluate.h: parts, concavity, volume error, Hausdorff, all as fractions of the
// bounding-box diagonal or volume) and timed in this process. Times are wall-clock on this
// machine; the comparison is the ratio HACD time / our time.
//
//   /usr/bin/python3 tools/gen_bench_meshes.py /tmp/meshes
//   build/bench/bench_decompose /tmp/meshes [--hacd-cap 120] [--threshold 0.05] [--max-parts 32]
//                                           [--no-hacd] [--threads N]
#include <hacdHACD.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "urlab/convert/decompose.h"
#include "urlab/convert/evaluate.h"
#include "urlab/convert/mesh_io.h"
#include "urlab/core/error.h"

namespace fs = std::filesystem;
using urlab::convert::TriMesh;

namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Result {
  std::string method;
  bool ok = false;
  std::string note;  // "timeout", "failed"
  std::size_t parts = 0;
  double seconds = 0;
  urlab::convert::HullSetMetrics metrics;
};

Result Score(std::string method, const TriMesh& mesh, std::vector<TriMesh> hulls, double seconds) {
  Result r;
  r.method = std::move(method);
  r.ok = true;
  r.parts = hulls.size();
  r.seconds = seconds;
  r.metrics = urlab::convert::EvaluateHulls(mesh, hulls);
  return r;
}

bool WriteAll(int fd, const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n) {
    const ssize_t w = write(fd, p, n);
    if (w <= 0) return false;
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

// Bullet's HACD in a child process (it cannot be interrupted in-process): the hulls come back
// through a pipe; after `cap` seconds the child is killed.
Result RunHacd(const TriMesh& mesh, double threshold, double cap) {
  Result r;
  r.method = "hacd";
  int fds[2];
  if (pipe(fds) != 0) {
    r.note = "pipe failed";
    return r;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    std::vector<HACD::Vec3<HACD::Real>> points;
    std::vector<HACD::Vec3<long>> tris;
    for (const auto& v : mesh.vertices) points.emplace_back(v[0], v[1], v[2]);
    for (const auto& t : mesh.triangles) tris.emplace_back(t[0], t[1], t[2]);
    const urlab::convert::Bounds b = urlab::convert::ComputeBounds(mesh);
    const auto size = b.Size();
    const double longest = std::max({size[0], size[1], size[2]});
    HACD::HACD hacd;
    hacd.SetPoints(points.data());
    hacd.SetNPoints(points.size());
    hacd.SetTriangles(tris.data());
    hacd.SetNTriangles(tris.size());
    // Bullet's ConvexDecompositionDemo settings, with the concavity limit set to ours: HACD
    // normalises the mesh so that its longest side is 1000.
    hacd.SetCompacityWeight(0.1);
    hacd.SetVolumeWeight(0.0);
    hacd.SetNClusters(1);
    hacd.SetNVerticesPerCH(100);
    hacd.SetConcavity(threshold * 1000 * b.Diagonal() / longest);
    hacd.SetAddExtraDistPoints(false);
    hacd.SetAddNeighboursDistPoints(false);
    hacd.SetAddFacesPoints(false);
    hacd.Compute();
    const std::uint64_t n = hacd.GetNClusters();
    WriteAll(fds[1], &n, 8);
    for (std::size_t c = 0; c < n; ++c) {
      const std::uint64_t np = hacd.GetNPointsCH(c), nt = hacd.GetNTrianglesCH(c);
      std::vector<HACD::Vec3<HACD::Real>> pts(np);
      std::vector<HACD::Vec3<long>> ts(nt);
      hacd.GetCH(c, pts.data(), ts.data());
      WriteAll(fds[1], &np, 8);
      for (const auto& p : pts) {
        const double xyz[3] = {p.X(), p.Y(), p.Z()};
        WriteAll(fds[1], xyz, sizeof xyz);
      }
    }
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string bytes;
  bool timed_out = false;
  for (;;) {
    const double left = cap - Seconds(t0);
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min(left, 1.0) * 1000) + 1);
    if (ready <= 0) continue;
    char buf[65536];
    const ssize_t got = read(fds[0], buf, sizeof buf);
    if (got <= 0) break;
    bytes.append(buf, static_cast<std::size_t>(got));
  }
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  r.seconds = Seconds(t0);
  if (timed_out) {
    r.note = "timeout";
    return r;
  }
  std::vector<TriMesh> hulls;
  std::size_t pos = 0;
  auto take = [&](void* out, std::size_t n) {
    if (pos + n > bytes.size()) return false;
    std::memcpy(out, bytes.data() + pos, n);
    pos += n;
    return true;
  };
  std::uint64_t n = 0;
  if (!take(&n, 8)) {
    r.note = "failed";
    return r;
  }
  for (std::uint64_t c = 0; c < n; ++c) {
    std::uint64_t np = 0;
    if (!take(&np, 8)) break;
    TriMesh h;
    for (std::uint64_t i = 0; i < np; ++i) {
      double xyz[3];
      if (!take(xyz, sizeof xyz)) break;
      h.vertices.push_back({xyz[0], xyz[1], xyz[2]});
    }
    hulls.push_back(std::move(h));
  }
  const double seconds = r.seconds;
  r = Score("hacd", mesh, std::move(hulls), seconds);
  return r;
}

std::vector<TriMesh> HullsOf(const urlab::convert::Decomposition& d) {
  std::vector<TriMesh> out;
  for (const auto& p : d.parts) out.push_back(p.hull);
  return out;
}

void Print(const std::string& mesh, std::size_t tris, const Result& r) {
  if (!r.ok) {
    std::printf("%-14s %7zu  %-7s %5s %10s %9s %9s %9.2f  %s\n", mesh.c_str(), tris,
                r.method.c_str(), "-", "-", "-", "-", r.seconds, r.note.c_str());
    return;
  }
  std::printf("%-14s %7zu  %-7s %5zu %10.4f %9.4f %9.4f %9.2f\n", mesh.c_str(), tris,
              r.method.c_str(), r.parts, r.metrics.concavity, r.metrics.volume_error,
              r.metrics.hausdorff, r.seconds);
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir;
  double cap = 120, threshold = 0.05;
  int max_parts = 32, threads = 0;
  bool hacd = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(105);
      }
      return std::string(argv[++i]);
    };
    if (a == "--hacd-cap") {
      cap = std::stod(next());
    } else if (a == "--threshold") {
      threshold = std::stod(next());
    } else if (a == "--max-parts") {
      max_parts = std::stoi(next());
    } else if (a == "--threads") {
      threads = std::stoi(next());
    } else if (a == "--no-hacd") {
      hacd = false;
    } else if (a.starts_with("-")) {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 105;
    } else {
      dir = a;
    }
  }
  if (dir.empty()) {
    std::fprintf(stderr,
                 "usage: bench_decompose MESH_DIR [--hacd-cap S] [--threshold T] [--max-parts N] "
                 "[--threads N] [--no-hacd]\n  (write the meshes with /usr/bin/python3 "
                 "tools/gen_bench_meshes.py MESH_DIR)\n");
    return 105;
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && urlab::convert::IsReadableMeshFormat(e.path().string())) {
      files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  std::printf(
      "threshold %.3f, max parts %d, HACD cap %.0f s; concavity and Hausdorff are "
      "fractions of the bounding-box diagonal, volume error of the mesh volume\n",
      threshold, max_parts, cap);
  std::printf("%-14s %7s  %-7s %5s %10s %9s %9s %9s\n", "mesh", "tris", "method", "parts",
              "concavity", "vol.err", "hausdorff", "seconds");
  int fewer_parts = 0, compared = 0, not_worse = 0, hacd_timeouts = 0;
  double total_ours = 0, total_hacd = 0;
  for (const fs::path& f : files) {
    TriMesh mesh;
    try {
      mesh = urlab::convert::ReadMesh(f.string());
    } catch (const urlab::Error& e) {
      std::printf("%s: %s\n", f.filename().c_str(), e.what());
      continue;
    }
    urlab::convert::CleanMesh(mesh);
    const std::string name = f.filename().string();
    urlab::convert::DecomposeOptions o;
    o.threshold = threshold;
    o.max_parts = max_parts;
    o.threads = threads;
    auto t0 = std::chrono::steady_clock::now();
    const urlab::convert::Decomposition ours = urlab::convert::Decompose(mesh, o);
    const Result r_ours = Score("ours", mesh, HullsOf(ours), Seconds(t0));
    Print(name, mesh.triangles.size(), r_ours);
    t0 = std::chrono::steady_clock::now();
    const urlab::convert::Decomposition single = urlab::convert::SingleHull(mesh, o);
    Print(name, mesh.triangles.size(), Score("hull", mesh, HullsOf(single), Seconds(t0)));
    total_ours += r_ours.seconds;
    if (hacd) {
      const Result r_hacd = RunHacd(mesh, threshold, cap);
      Print(name, mesh.triangles.size(), r_hacd);
      total_hacd += r_hacd.seconds;
      ++compared;
      if (!r_hacd.ok) {
        ++hacd_timeouts;
        ++fewer_parts;
        ++not_worse;
      } else {
        fewer_parts += r_ours.parts <= r_hacd.parts;
        not_worse += r_ours.metrics.concavity <= r_hacd.metrics.concavity + 1e-9;
      }
    }
    std::fflush(stdout);
  }
  std::printf("ours: %.2f s in total\n", total_ours);
  if (hacd && compared) {
    std::printf("hacd: %.2f s in total (%d of %d capped at %.0f s)\n", total_hacd, hacd_timeouts,
                compared, cap);
    std::printf(
        "meshes where ours has no more parts than HACD: %d of %d; concavity no higher: "
        "%d of %d (a capped HACD run counts for ours)\n",
        fewer_parts, compared, not_worse, compared);
    std::printf("ratio=%.2f (HACD time / our time, capped runs at the cap)\n",
                total_hacd / std::max(total_ours, 1e-9));
  }
  return 0;
}
