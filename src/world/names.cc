#include "urlab/world/names.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "urlab/core/error.h"
#include "urlab/mjcf/reader.h"

namespace urlab::world {

namespace fs = std::filesystem;

namespace {

std::string Sanitized(std::string_view text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  const std::size_t first = out.find_first_not_of('_');
  if (first == std::string::npos) return "";
  return out.substr(first, out.find_last_not_of('_') - first + 1);
}

int IdOf(const mjModel* m, mjtObj type, const std::string& name) {
  return mj_name2id(m, type, name.c_str());
}

void AddCandidates(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name,
                   std::vector<int>* out) {
  if (name.empty()) return;
  const std::string full = std::string(prefix) + std::string(name);
  for (const std::string& n : {full, std::string(name)}) {
    if (n == name && !name.starts_with(prefix)) continue;  // the full form carries the prefix
    const int id = IdOf(m, type, n);
    if (id >= 0) out->push_back(id);
  }
}

std::vector<int> Unique(std::vector<int> ids) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

int OneOf(const mjModel* m, mjtObj type, const std::vector<int>& ids, std::string_view name) {
  if (ids.empty()) return -1;
  if (ids.size() == 1) return ids.front();
  std::string list;
  for (int id : ids) {
    const char* n = mj_id2name(m, type, id);
    list += (list.empty() ? "" : ", ") + std::string(n ? n : "?");
  }
  throw Error(std::string(ObjectWord(type)) + " name '" + std::string(name) +
              "' is ambiguous: it could be " + list + "; give the full name");
}

std::string KnownList(const std::vector<std::string>& names) {
  if (names.empty()) return "it has none";
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  return "it has: " + list;
}

}  // namespace

std::string ModelArticulationName(const std::string& mjcf_path, std::string_view model_attribute) {
  const fs::path p(mjcf_path);
  std::string name;
  if (p.filename() == "scene.xml") {
    name = Sanitized(fs::absolute(p).lexically_normal().parent_path().filename().string());
  }
  if (name.empty()) name = Sanitized(model_attribute);
  if (name.empty()) name = Sanitized(p.stem().string());
  return name.empty() ? "model" : name;
}

std::string ModelArticulationName(const std::string& mjcf_path) {
  std::string model;
  if (fs::path(mjcf_path).filename() != "scene.xml") {
    mjcf::ReadOptions lenient;
    lenient.check_files = false;
    lenient.check_references = false;
    try {
      model = mjcf::ReadFile(mjcf_path, lenient).root().GetOr("model", "");
    } catch (const Error&) {
      // Unreadable: the build reports why; the stem names it meanwhile.
    }
  }
  return ModelArticulationName(mjcf_path, model);
}

const char* ObjectWord(mjtObj type) {
  switch (type) {
    case mjOBJ_KEY:
      return "keyframe";
    case mjOBJ_JOINT:
      return "joint";
    case mjOBJ_ACTUATOR:
      return "actuator";
    case mjOBJ_SENSOR:
      return "sensor";
    case mjOBJ_BODY:
      return "body";
    case mjOBJ_CAMERA:
      return "camera";
    case mjOBJ_SITE:
      return "site";
    case mjOBJ_GEOM:
      return "geom";
    default:
      return "element";
  }
}

std::vector<int> NameCandidates(const mjModel* m, mjtObj type, std::string_view prefix,
                                std::string_view name) {
  std::vector<int> ids;
  AddCandidates(m, type, prefix, name, &ids);
  return Unique(std::move(ids));
}

std::vector<int> NameCandidates(const mjModel* m, mjtObj type,
                                const std::vector<std::string>& prefixes, std::string_view name) {
  std::vector<int> ids;
  if (!name.empty()) {
    const int exact = IdOf(m, type, std::string(name));
    if (exact >= 0) ids.push_back(exact);
  }
  for (const std::string& prefix : prefixes) AddCandidates(m, type, prefix, name, &ids);
  return Unique(std::move(ids));
}

int FindNamed(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name) {
  return OneOf(m, type, NameCandidates(m, type, prefix, name), name);
}

int FindNamed(const mjModel* m, mjtObj type, const std::vector<std::string>& prefixes,
              std::string_view name) {
  return OneOf(m, type, NameCandidates(m, type, prefixes, name), name);
}

int RequireNamed(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name,
                 std::string_view owner) {
  const int id = FindNamed(m, type, prefix, name);
  if (id < 0) {
    throw Error("no " + std::string(ObjectWord(type)) + " '" + std::string(name) + "' in " +
                std::string(owner) + " (" + KnownList(ShortNames(m, type, prefix)) + ")");
  }
  return id;
}

int RequireNamed(const mjModel* m, mjtObj type, const std::vector<std::string>& prefixes,
                 std::string_view name) {
  const int id = FindNamed(m, type, prefixes, name);
  if (id < 0) {
    std::vector<std::string> all;
    for (const std::string& prefix : prefixes) {
      for (const std::string& n : ShortNames(m, type, prefix)) {
        all.push_back(prefix.substr(0, prefix.size() - 1) + ": " + n);
      }
    }
    throw Error("no " + std::string(ObjectWord(type)) + " '" + std::string(name) +
                "' in the scene (" + KnownList(all) + ")");
  }
  return id;
}

std::string ShortNameOf(const mjModel* m, mjtObj type, int id, std::string_view prefix) {
  const char* n = id >= 0 ? mj_id2name(m, type, id) : nullptr;
  if (!n) return "";
  const std::string_view full(n);
  return std::string(full.starts_with(prefix) ? full.substr(prefix.size()) : full);
}

std::vector<std::string> ShortNames(const mjModel* m, mjtObj type, std::string_view prefix) {
  std::vector<std::string> out;
  const int count = type == mjOBJ_KEY        ? m->nkey
                    : type == mjOBJ_JOINT    ? m->njnt
                    : type == mjOBJ_ACTUATOR ? m->nu
                    : type == mjOBJ_SENSOR   ? m->nsensor
                    : type == mjOBJ_BODY     ? m->nbody
                    : type == mjOBJ_CAMERA   ? m->ncam
                    : type == mjOBJ_SITE     ? m->nsite
                    : type == mjOBJ_GEOM     ? m->ngeom
                                             : 0;
  for (int id = 0; id < count; ++id) {
    const char* n = mj_id2name(m, type, id);
    if (n && std::string_view(n).starts_with(prefix)) out.push_back(n + prefix.size());
  }
  return out;
}

}  // namespace urlab::world
