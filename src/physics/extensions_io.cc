// The canonical text of a model's extensions (model.h: SerializeExtensions / ParseExtensions):
// what a recording stores beside the MJB and what the content hash covers.
#include <nlohmann/json.hpp>

#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab::physics {

namespace {

// Bumped when the text changes meaning; a reader refuses a version it does not know.
constexpr int kExtensionsVersion = 1;

constexpr std::pair<SoftwareSensorKind, const char*> kKinds[] = {
    {SoftwareSensorKind::kJointActuatorForce, "jointactuatorfrc"},
    {SoftwareSensorKind::kTendonActuatorForce, "tendonactuatorfrc"},
    {SoftwareSensorKind::kKineticEnergy, "e_kinetic"},
    {SoftwareSensorKind::kPotentialEnergy, "e_potential"},
    {SoftwareSensorKind::kInsideSite, "insidesite"},
    {SoftwareSensorKind::kContact, "contact"},
};

const char* KindName(SoftwareSensorKind k) {
  for (const auto& [kind, name] : kKinds) {
    if (kind == k) return name;
  }
  return "?";
}

SoftwareSensorKind KindOf(const std::string& name) {
  for (const auto& [kind, n] : kKinds) {
    if (name == n) return kind;
  }
  throw Error("model extensions: unknown software sensor kind '" + name + "'");
}

}  // namespace

std::string SerializeExtensions(const SoftwareModelSpec& e) {
  if (e.sensors.empty() && e.gravcomp.empty() && e.deadband_springs.empty() &&
      e.site_equalities.empty()) {
    return {};
  }
  // nlohmann's objects keep their keys sorted and its doubles print in shortest round-trip form:
  // equal extensions give equal text.
  nlohmann::json sensors = nlohmann::json::array();
  for (const SoftwareSensorSpec& s : e.sensors) {
    sensors.push_back({{"name", s.sensor_name}, {"kind", KindName(s.kind)}, {"params", s.params}});
  }
  nlohmann::json gravcomp = nlohmann::json::array();
  for (const GravityCompensationSpec& g : e.gravcomp) {
    gravcomp.push_back({{"body", g.body_name}, {"gravcomp", g.gravcomp}});
  }
  nlohmann::json springs = nlohmann::json::array();
  for (const DeadbandSpringSpec& t : e.deadband_springs) {
    springs.push_back(
        {{"tendon", t.tendon_name}, {"stiffness", t.stiffness}, {"lo", t.lo}, {"hi", t.hi}});
  }
  nlohmann::json equalities = nlohmann::json::array();
  for (const SiteEqualitySpec& q : e.site_equalities) {
    equalities.push_back({{"equality", q.equality}, {"site1", q.site1}, {"site2", q.site2}});
  }
  const nlohmann::json j = {{"version", kExtensionsVersion},
                            {"sensors", sensors},
                            {"gravcomp", gravcomp},
                            {"deadband_springs", springs},
                            {"site_equalities", equalities}};
  try {
    return j.dump();
  } catch (const nlohmann::json::type_error& error) {
    // MuJoCo takes any bytes as a name; the extensions' text is JSON, which must be UTF-8.
    throw Error(std::string("a software sensor, passive force or site equality refers to a name "
                            "that is not UTF-8 text (") +
                error.what() + ")");
  }
}

SoftwareModelSpec ParseExtensions(std::string_view text) {
  SoftwareModelSpec e;
  if (text.empty()) return e;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    const int version = j.at("version").get<int>();
    if (version != kExtensionsVersion) {
      throw Error("model extensions: version " + std::to_string(version) +
                  " is not supported (this URLab reads version " +
                  std::to_string(kExtensionsVersion) + ")");
    }
    for (const nlohmann::json& s : j.at("sensors")) {
      e.sensors.push_back({s.at("name").get<std::string>(), KindOf(s.at("kind").get<std::string>()),
                           s.at("params").get<std::map<std::string, std::string>>()});
    }
    for (const nlohmann::json& g : j.at("gravcomp")) {
      e.gravcomp.push_back({g.at("body").get<std::string>(), g.at("gravcomp").get<double>()});
    }
    for (const nlohmann::json& t : j.at("deadband_springs")) {
      e.deadband_springs.push_back({t.at("tendon").get<std::string>(),
                                    t.at("stiffness").get<double>(), t.at("lo").get<double>(),
                                    t.at("hi").get<double>()});
    }
    for (const nlohmann::json& q : j.at("site_equalities")) {
      e.site_equalities.push_back({q.at("equality").get<std::string>(),
                                   q.at("site1").get<std::string>(),
                                   q.at("site2").get<std::string>()});
    }
  } catch (const nlohmann::json::exception& x) {
    throw Error(std::string("model extensions: ") + x.what());
  }
  return e;
}

}  // namespace urlab::physics
