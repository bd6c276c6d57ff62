#pragma once
// Reading and writing mesh files. STL (binary and ASCII) and OBJ (vertices and faces; faces
// with more than three corners are fanned) are read by our own parsers, which treat the bytes as
// untrusted (every count and index checked, sizes bounded); every other format assimp reads
// (PLY, glTF/GLB, FBX, DAE, 3DS, ...) goes through assimp, its scene flattened with node
// transforms applied. Errors are urlab::InputError naming the file (and line for OBJ).
// Thread: any; no shared state.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/convert/mesh.h"

namespace urlab::convert {

// Largest mesh file we read (a 2M-triangle binary STL is 100 MB).
constexpr std::uintmax_t kMaxMeshFileBytes = 512ull << 20;
// Most triangles one mesh may have (bounds memory on hostile files).
constexpr std::size_t kMaxMeshTriangles = 20'000'000;

// Reads a mesh file of any supported format (by extension, case-insensitive). Throws InputError
// for a missing or unreadable file, an unknown format, or a file that holds no triangles.
TriMesh ReadMesh(const std::string& path);

// Our parsers on bytes in memory; `name` names them in errors. Throw InputError.
TriMesh ParseStl(std::string_view bytes, const std::string& name);
TriMesh ParseObj(std::string_view bytes, const std::string& name);

// True for the formats MuJoCo loads itself (.stl, .obj, .msh).
bool IsMujocoMeshFormat(const std::string& path);
// True when ReadMesh can read the file's extension.
bool IsReadableMeshFormat(const std::string& path);

// MuJoCo reads a binary STL of at most this many faces, and no ASCII STL.
constexpr std::size_t kMujocoMaxStlFaces = 200'000;
// Why MuJoCo cannot load the STL file `path` (ASCII, or more than kMujocoMaxStlFaces
// faces), judged from its size and header as MuJoCo does; empty when it can, and when `path` is
// not an .stl or cannot be opened (ReadMesh names those errors).
std::string MujocoStlRefusal(const std::string& path);
// `mesh` unchanged when it has at most kMujocoMaxStlFaces triangles; else simplified to at most
// that many for MuJoCo to load and draw (SimplifyToAtMost from a 1024-cell grid, then
// MakeEdgesOrientable so that MuJoCo's orientation check passes), and `note` says how.
TriMesh LimitForMujoco(TriMesh mesh, std::string* note);

// The OBJ text with the faces ParseObj turned into the triangles `flip` marks reversed: such a
// face line keeps its first corner and lists the others backwards (a fanned polygon keeps its
// diagonals), everything else byte for byte. Throws InputError when `flip` does not match.
std::string ReverseObjFaces(std::string_view obj, const std::vector<bool>& flip,
                            const std::string& name);

// Binary STL and OBJ text of a mesh.
std::string StlBytes(const TriMesh& mesh, std::string_view header = "urlab");
std::string ObjBytes(const TriMesh& mesh);

}  // namespace urlab::convert
