#include "urlab/convert/mesh_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "assimp_reader.h"
#include "ply_header.h"
#include "urlab/core/error.h"
#include "urlab/core/files.h"

namespace urlab::convert {

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Extension(const std::string& path) {
  return Lower(std::filesystem::path(path).extension().string());
}

// True when every byte is printable ASCII or white space (an ASCII STL); binary triangle records
// hold NULs and control bytes (float bits) within their first few records.
bool LooksLikeText(std::string_view bytes) {
  for (char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') return false;
    if (c == 0x7f) return false;
  }
  return true;
}

bool IsAsciiStl(std::string_view bytes) {
  // "solid" starts ASCII files, but also some binary headers: binary wins when its size matches,
  // and when the bytes after the 80-byte header are not text (a binary file whose count is
  // wrong must not be read as ASCII and lose its triangles).
  if (bytes.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (84 + 50ull * n == bytes.size()) return false;
  }
  std::size_t i = 0;
  while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
  if (bytes.substr(i, 5) != "solid") return false;
  return LooksLikeText(bytes.substr(0, 84 + 50 * 64));
}

// Whitespace-separated tokens of a line.
class Tokens {
 public:
  explicit Tokens(std::string_view line) : rest_(line) {}
  bool Next(std::string_view* tok) {
    std::size_t i = 0;
    while (i < rest_.size() && std::isspace(static_cast<unsigned char>(rest_[i]))) ++i;
    std::size_t j = i;
    while (j < rest_.size() && !std::isspace(static_cast<unsigned char>(rest_[j]))) ++j;
    if (i == j) return false;
    *tok = rest_.substr(i, j - i);
    rest_ = rest_.substr(j);
    return true;
  }

 private:
  std::string_view rest_;
};

bool ParseDouble(std::string_view s, double* out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// The three numbers after a vertex keyword; `what` names the format in the error.
Vec3 ReadVertex(Tokens& t, const std::string& name, int line, const char* what) {
  Vec3 v{};
  for (double& x : v) {
    std::string_view num;
    if (!t.Next(&num) || !ParseDouble(num, &x)) {
      throw InputError({name, line}, std::string(what) + " vertex needs three numbers");
    }
  }
  return v;
}

void CheckTriangleCount(std::size_t n, const std::string& name) {
  if (n > kMaxMeshTriangles) {
    throw InputError({name, 0}, fmt::format("more than {} triangles", kMaxMeshTriangles));
  }
}

TriMesh ParseAsciiStl(std::string_view bytes, const std::string& name) {
  TriMesh m;
  int line = 1, corner = 0;
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string_view::npos) end = bytes.size();
    Tokens t(bytes.substr(pos, end - pos));
    std::string_view tok;
    if (t.Next(&tok) && tok == "vertex") {
      m.vertices.push_back(ReadVertex(t, name, line, "STL"));
      if (++corner == 3) {
        const auto n = static_cast<std::int32_t>(m.vertices.size());
        m.triangles.push_back({n - 3, n - 2, n - 1});
        CheckTriangleCount(m.triangles.size(), name);
        corner = 0;
      }
    } else if (tok == "endfacet" && corner != 0) {
      throw InputError({name, line}, "STL facet with other than three vertices");
    }
    pos = end + 1;
    ++line;
  }
  return m;
}

}  // namespace

TriMesh ParseStl(std::string_view bytes, const std::string& name) {
  if (IsAsciiStl(bytes)) return ParseAsciiStl(bytes, name);
  if (bytes.size() < 84) throw InputError({name, 0}, "not an STL file (shorter than its header)");
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  if (84 + 50ull * n > bytes.size()) {
    throw InputError({name, 0}, fmt::format("binary STL truncated: header says {} triangles, the "
                                            "file holds {}",
                                            n, (bytes.size() - 84) / 50));
  }
  // More whole triangle records than the header counts: reading n would silently drop the rest.
  // (A few trailing bytes, less than one record, are padding some exporters write.)
  if (const std::uint64_t held = (bytes.size() - 84) / 50; held > n) {
    throw InputError({name, 0}, fmt::format("binary STL: the header says {} triangles but the "
                                            "file holds {} triangle records; its triangle count "
                                            "(bytes 80-83) is wrong",
                                            n, held));
  }
  CheckTriangleCount(n, name);
  TriMesh m;
  m.vertices.reserve(3ull * n);
  m.triangles.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const char* rec = bytes.data() + 84 + 50ull * i + 12;  // skip the normal
    for (int k = 0; k < 3; ++k) {
      float f[3];
      std::memcpy(f, rec + 12 * k, 12);
      m.vertices.push_back({f[0], f[1], f[2]});
    }
    const auto b = static_cast<std::int32_t>(3 * i);
    m.triangles.push_back({b, b + 1, b + 2});
  }
  return m;
}

TriMesh ParseObj(std::string_view bytes, const std::string& name) {
  TriMesh m;
  int line = 1;
  std::size_t pos = 0;
  std::vector<std::int32_t> face;
  while (pos < bytes.size()) {
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string_view::npos) end = bytes.size();
    Tokens t(bytes.substr(pos, end - pos));
    std::string_view tok;
    if (t.Next(&tok)) {
      if (tok == "v") {
        m.vertices.push_back(ReadVertex(t, name, line, "OBJ"));
        if (m.vertices.size() > 3 * kMaxMeshTriangles) {
          throw InputError({name, line}, "too many vertices");
        }
      } else if (tok == "f") {
        face.clear();
        std::string_view corner;
        while (t.Next(&corner)) {
          // v, v/vt, v//vn, v/vt/vn: the vertex index is the first field; negative is relative.
          const std::string_view idx = corner.substr(0, corner.find('/'));
          long long v = 0;
          const auto r = std::from_chars(idx.data(), idx.data() + idx.size(), v);
          if (r.ec != std::errc() || r.ptr != idx.data() + idx.size() || v == 0) {
            throw InputError({name, line}, fmt::format("bad face index '{}'", corner));
          }
          const long long count = static_cast<long long>(m.vertices.size());
          const long long abs = v > 0 ? v - 1 : count + v;
          if (abs < 0 || abs >= count) {
            throw InputError({name, line}, fmt::format("face index {} out of range (the file "
                                                       "has {} vertices so far)",
                                                       v, count));
          }
          face.push_back(static_cast<std::int32_t>(abs));
        }
        if (face.size() < 3) throw InputError({name, line}, "a face needs three vertices");
        for (std::size_t k = 1; k + 1 < face.size(); ++k) {
          m.triangles.push_back({face[0], face[k], face[k + 1]});
        }
        CheckTriangleCount(m.triangles.size(), name);
      }
    }
    pos = end + 1;
    ++line;
  }
  return m;
}

bool IsMujocoMeshFormat(const std::string& path) {
  const std::string e = Extension(path);
  return e == ".stl" || e == ".obj" || e == ".msh";
}

bool IsReadableMeshFormat(const std::string& path) {
  const std::string e = Extension(path);
  return e == ".stl" || e == ".obj" || internal::AssimpCanRead(e);
}

std::string MujocoStlRefusal(const std::string& path) {
  if (Extension(path) != ".stl") return {};
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  if (ec || !in) return {};
  char header[84] = {};
  if (size < 84 || !in.read(header, 84)) return "shorter than a binary STL header";
  std::uint32_t n = 0;
  std::memcpy(&n, header + 80, 4);
  if (84 + 50ull * n != size) return "not a binary STL (MuJoCo reads no ASCII STL)";
  if (n == 0) return "a binary STL without faces";
  if (n > kMujocoMaxStlFaces) {
    return fmt::format("a binary STL of {} faces (MuJoCo reads at most {})", n, kMujocoMaxStlFaces);
  }
  return {};
}

TriMesh LimitForMujoco(TriMesh mesh, std::string* note) {
  if (mesh.triangles.size() <= kMujocoMaxStlFaces) return mesh;
  const std::size_t before = mesh.triangles.size();
  int cells = 0;
  TriMesh small = SimplifyToAtMost(mesh, kMujocoMaxStlFaces, 1024, true, &cells);
  const std::size_t dropped = MakeEdgesOrientable(small);
  if (note) {
    *note = fmt::format(
        "simplified from {} to {} triangles for MuJoCo (vertex clustering on a {}-cell "
        "grid{})",
        before, small.triangles.size(), cells,
        dropped ? fmt::format("; {} triangles on non-manifold edges dropped", dropped) : "");
  }
  return small;
}

TriMesh ReadMesh(const std::string& path) {
  const std::string e = Extension(path);
  CheckInputFile(path, "mesh file", {}, kMaxMeshFileBytes);
  TriMesh m;
  if (e == ".stl" || e == ".obj") {
    const std::string bytes = ReadInputFile(path, "mesh file", {}, kMaxMeshFileBytes);
    m = e == ".stl" ? ParseStl(bytes, path) : ParseObj(bytes, path);
  } else if (internal::AssimpCanRead(e)) {
    if (e == ".ply") {
      // Declared counts against the file's size before assimp allocates for them.
      std::ifstream in(path, std::ios::binary);
      std::string head(internal::kMaxPlyHeaderBytes, '\0');
      in.read(head.data(), static_cast<std::streamsize>(head.size()));
      head.resize(static_cast<std::size_t>(in.gcount()));
      internal::CheckPlyHeader(head, std::filesystem::file_size(path), path);
    }
    m = internal::AssimpRead(path);
  } else {
    throw InputError({path, 0}, "unknown mesh format '" + e +
                                    "' (readable: .stl .obj .ply .gltf .glb .fbx .dae .3ds ...)");
  }
  if (m.triangles.empty()) throw InputError({path, 0}, "the mesh has no triangles");
  return m;
}

std::string ReverseObjFaces(std::string_view obj, const std::vector<bool>& flip,
                            const std::string& name) {
  std::string out;
  out.reserve(obj.size());
  std::size_t pos = 0, triangle = 0;
  int line = 1;
  std::vector<std::string_view> corners;
  while (pos < obj.size()) {
    std::size_t end = obj.find('\n', pos);
    const bool newline = end != std::string_view::npos;
    if (!newline) end = obj.size();
    std::string_view text = obj.substr(pos, end - pos);
    Tokens t(text);
    std::string_view tok;
    if (t.Next(&tok) && tok == "f") {
      corners.clear();
      std::string_view corner;
      while (t.Next(&corner)) corners.push_back(corner);
      if (corners.size() < 3 || triangle + corners.size() - 2 > flip.size()) {
        throw InputError({name, line}, "face lines do not match the parsed triangles");
      }
      if (flip[triangle]) {
        out += "f ";
        out += corners[0];
        for (std::size_t k = corners.size() - 1; k >= 1; --k) {
          out += ' ';
          out += corners[k];
        }
        if (!text.empty() && text.back() == '\r') out += '\r';
      } else {
        out += text;
      }
      triangle += corners.size() - 2;
    } else {
      out += text;
    }
    if (newline) out += '\n';
    pos = end + 1;
    ++line;
  }
  if (triangle != flip.size()) {
    throw InputError({name, 0}, "face lines do not match the parsed triangles");
  }
  return out;
}

std::string StlBytes(const TriMesh& mesh, std::string_view header) {
  std::string out(84 + 50 * mesh.triangles.size(), '\0');
  std::memcpy(out.data(), header.data(), std::min<std::size_t>(header.size(), 80));
  const auto n = static_cast<std::uint32_t>(mesh.triangles.size());
  std::memcpy(out.data() + 80, &n, 4);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    char* rec = out.data() + 84 + 50 * i;
    float f[12] = {};
    for (int k = 0; k < 3; ++k) {
      const Vec3& v = mesh.vertices[static_cast<std::size_t>(mesh.triangles[i][k])];
      for (int c = 0; c < 3; ++c) f[3 + 3 * k + c] = static_cast<float>(v[c]);
    }
    std::memcpy(rec, f, 48);
  }
  return out;
}

std::string ObjBytes(const TriMesh& mesh) {
  std::string out;
  out.reserve(mesh.vertices.size() * 40 + mesh.triangles.size() * 24);
  for (const Vec3& v : mesh.vertices) out += fmt::format("v {} {} {}\n", v[0], v[1], v[2]);
  for (const Triangle& t : mesh.triangles) {
    out += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  return out;
}

}  // namespace urlab::convert
