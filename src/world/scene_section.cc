#include "world/scene_section.h"

#include <cmath>
#include <mutex>
#include <shared_mutex>

#include "urlab/document/element.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

std::string NumberRange::Text() const {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  if (max == kInfinity && min == -kInfinity) return "a number (not NaN)";
  if (max == kInfinity)
    return std::string(min_exclusive ? "> " : ">= ") + document::FormatReal(min);
  if (max == std::numeric_limits<double>::max()) {
    return std::string(min_exclusive ? "> " : ">= ") + document::FormatReal(min) + " and finite";
  }
  if (min_exclusive) {
    return "> " + document::FormatReal(min) + " and <= " + document::FormatReal(max);
  }
  return document::FormatReal(min) + " to " + document::FormatReal(max);
}

std::string SectionReader::Key(const YAML::Node& key, const std::string& where) const {
  if (!key.IsScalar() || key.Tag() == "tag:yaml.org,2002:null" || key.Scalar().empty()) {
    Fail(key, "keys in " + where + " must be names (strings), not " +
                  (key.IsMap()        ? "a mapping"
                   : key.IsSequence() ? "a list"
                                      : "empty/null"));
  }
  return key.Scalar();
}

std::vector<std::pair<std::string, YAML::Node>> SectionReader::Entries(
    const YAML::Node& map, const std::string& where) const {
  if (!map.IsMap()) Fail(map, where + " must be a mapping");
  std::vector<std::pair<std::string, YAML::Node>> out;
  std::map<std::string, int> seen;
  for (const auto& kv : map) {
    const std::string key = Key(kv.first, where);
    const int line = kv.first.Mark().line + 1;
    if (auto [it, fresh] = seen.emplace(key, line); !fresh) {
      Fail(kv.first, "duplicate key '" + key + "' in " + where + " (first at line " +
                         std::to_string(it->second) + ")");
    }
    out.emplace_back(key, kv.second);
  }
  return out;
}

void SectionReader::CheckKeys(const YAML::Node& map, const std::string& where,
                              const std::set<std::string>& allowed) const {
  Entries(map, where);  // keys are strings, each once
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      Fail(kv.first, "unknown key '" + key + "' in " + where + " (expected one of: " + list + ")");
    }
  }
}

double SectionReader::Number(const YAML::Node& n, const std::string& what,
                             const NumberRange& range) const {
  if (!n.IsScalar()) Fail(n, what + " must be a number");
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    Fail(n, what + " must be a number: wrong type");
  }
  if (!range.Contains(v)) Fail(n, what + " must be " + range.Text() + ", not " + n.Scalar());
  return v;
}

int SectionReader::Whole(const YAML::Node& n, const std::string& what, int min, int max) const {
  const double v = Number(n, what, NumberRange{static_cast<double>(min), static_cast<double>(max)});
  if (v != std::floor(v)) Fail(n, what + " must be a whole number, not " + n.Scalar());
  return static_cast<int>(v);
}

std::vector<double> SectionReader::Numbers(const YAML::Node& n, const std::string& what,
                                           std::size_t count) const {
  if (!n.IsSequence() || n.size() != count) {
    Fail(n, what + " must be a list of " + std::to_string(count) + " numbers");
  }
  std::vector<double> out;
  for (const auto& v : n) out.push_back(Number(v, what, kFiniteNumber));
  return out;
}

bool SectionReader::Bool(const YAML::Node& n, const std::string& what) const {
  if (!n.IsScalar()) Fail(n, what + " must be true or false");
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    Fail(n, what + " must be true or false: wrong type");
  }
}

std::string SectionReader::String(const YAML::Node& n, const std::string& what) const {
  if (!n.IsScalar()) Fail(n, what + " must be a string");
  return n.as<std::string>();
}

std::vector<std::string> SectionReader::Names(const YAML::Node& n, const std::string& what) const {
  if (!n.IsSequence()) Fail(n, what + " must be a list of names");
  std::vector<std::string> out;
  for (const auto& v : n) out.push_back(String(v, what));
  return out;
}

physics::LatencySetting SectionReader::LatencyEntry(const YAML::Node& n,
                                                    const std::string& where) const {
  if (!n.IsMap()) Fail(n, where + " must be a mapping (delay_steps, delay, jitter_steps, ...)");
  physics::LatencySetting s;
  bool delay = false, jitter = false;
  for (const auto& [key, v] : Entries(n, where)) {
    const bool is_delay = key == "delay" || key == "delay_steps";
    const bool is_jitter = key == "jitter" || key == "jitter_steps";
    if ((is_delay && delay) || (is_jitter && jitter)) {
      Fail(v, where + ": give the " + (is_delay ? "delay" : "jitter") +
                  " in steps or in seconds, not both");
    }
    delay |= is_delay;
    jitter |= is_jitter;
    const double value = Number(v, where + "." + key, kFiniteNumber);
    const std::string problem = physics::SetLatencyKey(&s, key, value);
    if (!problem.empty()) Fail(v, where + ": " + problem);
  }
  return s;
}

namespace {

struct Table {
  Table() {
    for (const SectionSpec& spec : {RandomizeSection()}) specs.emplace(spec.name, spec);
  }
  std::shared_mutex mutex;
  std::map<std::string, SectionSpec> specs;
};
Table& TheTable() {
  static Table table;
  return table;
}

}  // namespace

void RegisterSceneSection(const SectionSpec& spec) {
  Table& t = TheTable();
  const std::unique_lock lock(t.mutex);
  t.specs.emplace(spec.name, spec);
}

SectionParser FindSceneSection(const std::string& name) {
  Table& t = TheTable();
  const std::shared_lock lock(t.mutex);
  const auto it = t.specs.find(name);
  return it == t.specs.end() ? nullptr : it->second.parse;
}

std::set<std::string> SceneSectionNames() {
  Table& t = TheTable();
  const std::shared_lock lock(t.mutex);
  std::set<std::string> out;
  for (const auto& [name, spec] : t.specs) out.insert(name);
  return out;
}

void CheckSceneSections(const SceneConfig& scene, const CompiledScene& compiled,
                        Diagnostics& sink) {
  std::vector<std::pair<SectionCompiledCheck, const std::any*>> checks;
  {
    Table& t = TheTable();
    const std::shared_lock lock(t.mutex);
    for (const auto& [name, spec] : t.specs) {
      const std::any* settings = scene.sections.Find(name);
      if (spec.check_compiled && settings) checks.emplace_back(spec.check_compiled, settings);
    }
  }
  for (const auto& [check, settings] : checks) check(*settings, scene, compiled, sink);
}

}  // namespace urlab::world
