#include "urlab/ops/scene_export.h"

#include "urlab/mjcf/spec.h"

namespace urlab::ops {

std::vector<std::string> ChangedOptions(const mjOption& compiled, const mjOption& now) {
  const std::map<std::string, std::string> before = mjcf::OptionText(compiled);
  std::vector<std::string> out;
  for (const auto& [k, v] : mjcf::OptionText(now)) {
    if (before.at(k) != v) out.push_back(k);
  }
  return out;
}

std::string SceneXml(world::Session& session, const std::string& relative_to,
                     std::vector<std::string>* changed) {
  const physics::Model now = session.engine().CopyModel();  // the options in effect
  if (changed) *changed = ChangedOptions(session.compiled_options(), now->opt);
  return world::SceneXml(session.spec().get(), &now->opt, relative_to);
}

}  // namespace urlab::ops
