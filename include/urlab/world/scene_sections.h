#pragma once
// The settings of the scene sections subsystems own (`viewer:`, `cinematic:`, ...), as their
// parsers made them (src/world/scene_section.h: the registration), kept by section name in the
// SceneConfig. The settings types belong to the subsystems' modules; world stores them
// type-erased and never looks inside.
//
// Thread: a value type (copied with the SceneConfig); no synchronisation of its own.
#include <any>
#include <map>
#include <string>
#include <utility>

namespace urlab::world {

class SceneSections {
 public:
  // The settings of section `name` when the scene had it, else nullptr. T must be the type the
  // section's parser returns (another type is nullptr too).
  template <typename T>
  const T* Get(const std::string& name) const {
    const auto it = values_.find(name);
    return it == values_.end() ? nullptr : std::any_cast<T>(&it->second);
  }
  // The settings of `name`, made default when absent (for code that changes a loaded scene, as
  // the command line's overrides do).
  template <typename T>
  T& GetOrAdd(const std::string& name) {
    std::any& v = values_[name];
    if (!v.has_value() || !std::any_cast<T>(&v)) v = T{};
    return *std::any_cast<T>(&v);
  }
  // The settings of `name` as stored, nullptr when the scene has no such section.
  const std::any* Find(const std::string& name) const {
    const auto it = values_.find(name);
    return it == values_.end() ? nullptr : &it->second;
  }
  void Set(const std::string& name, std::any settings) { values_[name] = std::move(settings); }
  bool Has(const std::string& name) const { return values_.count(name) != 0; }

 private:
  std::map<std::string, std::any> values_;
};

}  // namespace urlab::world
