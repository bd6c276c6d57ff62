#include "urlab/ops/scene_export.h"

#include <cctype>
#include <span>
#include <string_view>

#include "urlab/document/element.h"

namespace urlab::ops {
namespace {

// How one <option> attribute reads its value out of mjOption.
struct RealOption {
  const char* attribute;
  std::span<const mjtNum> (*values)(const mjOption&);
};
struct IntOption {
  const char* attribute;
  int (*value)(const mjOption&);
  std::vector<const char*> keywords;  // the MJCF keywords by enum value; empty: a plain integer
};

#define URLAB_REALS(name, field, n)                                              \
  {                                                                              \
    name, [](const mjOption& o) { return std::span<const mjtNum>(&o.field, n); } \
  }
#define URLAB_ARRAY(name, field)                                             \
  {                                                                          \
    name, [](const mjOption& o) { return std::span<const mjtNum>(o.field); } \
  }

// The table of exported options (MuJoCo 2.2.2's mjOption, MJCF names).
const std::vector<RealOption>& RealOptions() {
  static const std::vector<RealOption> table = {
      URLAB_REALS("timestep", timestep, 1),
      URLAB_REALS("apirate", apirate, 1),
      URLAB_REALS("impratio", impratio, 1),
      URLAB_REALS("tolerance", tolerance, 1),
      URLAB_REALS("noslip_tolerance", noslip_tolerance, 1),
      URLAB_REALS("mpr_tolerance", mpr_tolerance, 1),
      URLAB_ARRAY("gravity", gravity),
      URLAB_ARRAY("wind", wind),
      URLAB_ARRAY("magnetic", magnetic),
      URLAB_REALS("density", density, 1),
      URLAB_REALS("viscosity", viscosity, 1),
      URLAB_REALS("o_margin", o_margin, 1),
      URLAB_ARRAY("o_solref", o_solref),
      URLAB_ARRAY("o_solimp", o_solimp),
  };
  return table;
}
#undef URLAB_REALS
#undef URLAB_ARRAY

const std::vector<IntOption>& IntOptions() {
  static const std::vector<IntOption> table = {
      {"integrator", [](const mjOption& o) { return o.integrator; }, {"Euler", "RK4", "implicit"}},
      {"collision",
       [](const mjOption& o) { return o.collision; },
       {"all", "predefined", "dynamic"}},
      {"cone", [](const mjOption& o) { return o.cone; }, {"pyramidal", "elliptic"}},
      {"jacobian", [](const mjOption& o) { return o.jacobian; }, {"dense", "sparse", "auto"}},
      {"solver", [](const mjOption& o) { return o.solver; }, {"PGS", "CG", "Newton"}},
      {"iterations", [](const mjOption& o) { return o.iterations; }, {}},
      {"noslip_iterations", [](const mjOption& o) { return o.noslip_iterations; }, {}},
      {"mpr_iterations", [](const mjOption& o) { return o.mpr_iterations; }, {}},
  };
  return table;
}

// mjDISABLESTRING / mjENABLESTRING lower-cased are the <flag> attributes.
std::string FlagName(const char* mujoco_name) {
  std::string s = mujoco_name;
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::vector<std::string> WriteOptionChanges(const mjOption& compiled, const mjOption& now,
                                            document::Document& doc) {
  std::vector<std::string> written;
  document::Element* option = nullptr;
  auto section = [&]() -> document::Element& {
    if (!option) option = &doc.Section("option");
    return *option;
  };
  for (const RealOption& r : RealOptions()) {
    const auto a = r.values(compiled), b = r.values(now);
    if (std::equal(a.begin(), a.end(), b.begin(), b.end())) continue;
    if (b.size() == 1) {
      section().SetReal(r.attribute, b[0]);
    } else {
      section().SetReals(r.attribute, std::vector<double>(b.begin(), b.end()));
    }
    written.emplace_back(r.attribute);
  }
  for (const IntOption& i : IntOptions()) {
    const int a = i.value(compiled), b = i.value(now);
    if (a == b) continue;
    if (!i.keywords.empty() && b >= 0 && b < static_cast<int>(i.keywords.size())) {
      section().Set(i.attribute, i.keywords[static_cast<std::size_t>(b)]);
    } else {
      section().SetInt(i.attribute, b);
    }
    written.emplace_back(i.attribute);
  }
  document::Element* flag = nullptr;
  auto flags = [&]() -> document::Element& {
    if (!flag) {
      flag = section().FirstChild("flag");
      if (!flag) flag = &section().AddChild("flag");
    }
    return *flag;
  };
  // Each flag that differs, by its MJCF name: disable flags then enable flags, in bit order.
  auto write_flags = [&](int now_bits, int compiled_bits, const char* const* names, int count,
                         const char* set_word, const char* clear_word) {
    const unsigned set = static_cast<unsigned>(now_bits);
    const unsigned changed = set ^ static_cast<unsigned>(compiled_bits);
    for (unsigned i = 0; i < static_cast<unsigned>(count); ++i) {
      const unsigned bit = 1u << i;
      if ((changed & bit) == 0) continue;
      const std::string name = FlagName(names[i]);
      flags().Set(name, (set & bit) ? set_word : clear_word);
      written.push_back("flag." + name);
    }
  };
  write_flags(now.disableflags, compiled.disableflags, mjDISABLESTRING, mjNDISABLE, "disable",
              "enable");
  write_flags(now.enableflags, compiled.enableflags, mjENABLESTRING, mjNENABLE, "enable",
              "disable");
  return written;
}

std::string SceneXml(world::Session& session, const mjcf::WriteOptions& options,
                     std::vector<std::string>* changed) {
  const world::CompiledScene& scene = session.scene();
  const physics::Model now = session.engine().CopyModel();  // the options in effect
  document::Document doc = scene.doc.Clone();
  std::vector<std::string> written = WriteOptionChanges(session.compiled_options(), now->opt, doc);
  std::string xml = mjcf::WriteString(written.empty() ? scene.doc : doc, options);
  if (changed) *changed = std::move(written);
  return xml;
}

}  // namespace urlab::ops
