#pragma once
// The composed model as self-contained MJCF for a client (hello's include_assets): the XML with
// every asset file renamed to a bare name, and those files' bytes under the same names, so that
// a client can compile it from a virtual file system (MuJoCo's VFS, or the Python package's
// assets dict) on another machine. Thread: any (reads the text and the asset files only).
#include <string>
#include <utility>
#include <vector>

namespace urlab::net {

struct ModelWithAssets {
  std::string xml;
  std::vector<std::pair<std::string, std::string>> assets;  // bare name, file bytes
  std::size_t bytes = 0;                                    // sum of the assets' sizes
};

// Two different files with the same base name get distinct names ("box.stl", "box_2.stl").
// Throws InputError naming a file that cannot be read (or is larger than `max_file_bytes`).
// `xml` is MJCF with absolute asset paths (world::SceneXml).
ModelWithAssets FlattenAssets(const std::string& xml, std::uintmax_t max_file_bytes = 256ull << 20);

}  // namespace urlab::net
