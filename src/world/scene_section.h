#pragma once
// Scene sections a subsystem owns: the registration (a table of section name -> parser and
// compiled-scene check) and the reader a parser gets. The scene file parser (scene_file.cc) keeps
// the scene's own keys and, after them, dispatches every other top-level key to the parser
// registered under its name; the parser turns the section into the subsystem's settings (stored
// type-erased in SceneConfig::sections, urlab/world/scene_sections.h) or throws an InputError at
// the offending line through the reader's checks, the same ones the scene's own keys use. What a
// section names in the compiled model is checked by its check_compiled, which
// world::CheckCompiledScene runs: `urlab validate` and begin-play (run, view, compile) report the
// same errors.
//
// Layering: the parsers and their settings types live in the subsystems' modules (viewer,
// camera, net), above world; world only holds this table. The modules register from the top:
// the `urlab` tool registers every subsystem's sections at start (src/app/main.cc), a test or
// program registers those it parses. A top-level key no registered parser claims is an unknown
// key, except the `urlab` tool's own sections (network, cameras, viewer, cinematic: a table in
// scene_file.cc), which a program that did not register them is told how to register.
//
// Threading contract: register before any scene is parsed (main thread at start; registering a
// name again replaces nothing and is harmless); parsing reads the table from any thread.
#include <yaml-cpp/yaml.h>

#include <any>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "urlab/core/diagnostics.h"
#include "urlab/core/error.h"
#include "urlab/physics/latency.h"

namespace urlab::world {

// A closed or half-open interval a number must lie in; NaN never does.
struct NumberRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool Contains(double v) const {
    return (min_exclusive ? v > min : v >= min) && v <= max;  // false for NaN
  }
  std::string Text() const;
};
inline constexpr NumberRange kFiniteNumber{-std::numeric_limits<double>::max(),
                                           std::numeric_limits<double>::max()};
inline constexpr NumberRange kNonNegativeFiniteNumber{0, std::numeric_limits<double>::max()};

// The checks every part of a scene file is read with; each failure is an InputError at the
// node's file:line.
class SectionReader {
 public:
  explicit SectionReader(std::string path) : path_(std::move(path)) {}
  virtual ~SectionReader() = default;

  const std::string& path() const { return path_; }
  SourceLocation At(const YAML::Node& n) const { return {path_, n.Mark().line + 1}; }
  [[noreturn]] void Fail(const YAML::Node& n, const std::string& what) const {
    throw InputError(At(n), what);
  }

  // The key of a mapping entry: a plain string, never a list, mapping or null.
  std::string Key(const YAML::Node& key, const std::string& where) const;
  // Every key of `map` once, as a string (duplicates and non-string keys are errors).
  std::vector<std::pair<std::string, YAML::Node>> Entries(const YAML::Node& map,
                                                          const std::string& where) const;
  // Entries, and each key one of `allowed` ("unknown key ... (expected one of: ...)").
  void CheckKeys(const YAML::Node& map, const std::string& where,
                 const std::set<std::string>& allowed) const;

  double Number(const YAML::Node& n, const std::string& what,
                const NumberRange& range = kFiniteNumber) const;
  // A whole number min..max.
  int Whole(const YAML::Node& n, const std::string& what, int min, int max) const;
  std::vector<double> Numbers(const YAML::Node& n, const std::string& what,
                              std::size_t count) const;
  bool Bool(const YAML::Node& n, const std::string& what) const;
  std::string String(const YAML::Node& n, const std::string& what) const;
  // A list of strings.
  std::vector<std::string> Names(const YAML::Node& n, const std::string& what) const;
  // One emulated delay: the keys of physics/latency.h (delay_steps | delay, jitter_steps |
  // jitter, rate_hz), each given once, in steps or in seconds.
  physics::LatencySetting LatencyEntry(const YAML::Node& n, const std::string& where) const;

 private:
  std::string path_;
};

struct SceneConfig;
struct CompiledScene;

// A section's parser: the settings (any copyable type) of `section`, the node under its key.
// `scene` holds the scene's own keys, already parsed (articulations, props, terrain, launchers,
// options, seed...), for a section whose entries name them; never the other sections.
using SectionParser = std::any (*)(const SectionReader& reader, const YAML::Node& section,
                                   const SceneConfig& scene);
// A section's checks against the composed and compiled scene (what it names exists in the
// model): run by world::CheckCompiledScene, so `urlab validate` reports what `run` and `view`
// refuse, at the section's file:line (kept in the settings). Called only for a scene that has
// the section.
using SectionCompiledCheck = void (*)(const std::any& settings, const SceneConfig& scene,
                                      const CompiledScene& compiled, Diagnostics& sink);

struct SectionSpec {
  const char* name;  // the top-level key
  SectionParser parse;
  SectionCompiledCheck check_compiled = nullptr;  // none: nothing to check after compiling
};

// World's own sections, in the table from the start (not registered from the top: world reads
// them itself): `randomize:` (src/world/randomize_section.cc).
SectionSpec RandomizeSection();

// Adds `spec` to the table (a name registered again keeps its first parser). World's own
// sections (`randomize:`, world/randomize_settings.h) are in the table from the start.
void RegisterSceneSection(const SectionSpec& spec);
// The parser registered for `name`, nullptr when none.
SectionParser FindSceneSection(const std::string& name);
// Every registered name.
std::set<std::string> SceneSectionNames();
// Runs the compiled-scene check of every registered section `scene` has, in name order.
void CheckSceneSections(const SceneConfig& scene, const CompiledScene& compiled, Diagnostics& sink);

}  // namespace urlab::world
