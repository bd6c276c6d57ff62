#include "net/model_assets.h"

#include <filesystem>
#include <map>

#include "urlab/core/files.h"
#include "urlab/mjcf/spec.h"

namespace urlab::net {

ModelWithAssets FlattenAssets(const std::string& xml, std::uintmax_t max_file_bytes) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> bare;  // resolved path -> bare name
  std::map<std::string, int> taken;         // bare name -> uses
  ModelWithAssets out;
  auto rename = [&](const std::string& resolved) -> std::string {
    if (const auto it = bare.find(resolved); it != bare.end()) return it->second;
    const fs::path p(resolved);
    std::string name = p.filename().string();
    for (int n = 2; taken.count(name) != 0; ++n) {
      name = p.stem().string() + "_" + std::to_string(n) + p.extension().string();
    }
    taken[name] = 1;
    bare.emplace(resolved, name);
    std::string bytes = ReadInputFile(resolved, "asset file", {}, max_file_bytes);
    out.bytes += bytes.size();
    out.assets.emplace_back(name, std::move(bytes));
    return name;
  };
  out.xml = mjcf::MapAssetPaths(xml, rename);
  return out;
}

}  // namespace urlab::net
