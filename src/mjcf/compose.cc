#include "urlab/mjcf/compose.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <utility>
#include <vector>

namespace urlab::mjcf {

bool Placement::IsIdentity() const {
  return pos == std::array<double, 3>{0, 0, 0} && quat == std::array<double, 4>{1, 0, 0, 0};
}

namespace {

std::string NameOf(mjsElement* e) { return SpecString(mjs_getName(e)); }

std::vector<double> Values(const mjDoubleVec* v) {
  int n = 0;
  const double* data = mjs_getDouble(v, &n);
  return std::vector<double>(data, data + n);
}

// The keyframes of an articulation's own spec, as written.
std::vector<ArticulationKeyframe> KeyframesOf(mjSpec* spec, const std::string& prefix) {
  std::vector<ArticulationKeyframe> out;
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_KEY); e; e = mjs_nextElement(spec, e)) {
    const mjsKey* k = mjs_asKey(e);
    ArticulationKeyframe key;
    key.name = NameOf(e);
    key.scene_name = prefix + key.name;
    key.time = k->time;
    key.qpos = Values(k->qpos);
    key.qvel = Values(k->qvel);
    key.act = Values(k->act);
    key.ctrl = Values(k->ctrl);
    key.mocap_pos = Values(k->mpos);
    key.mocap_quat = Values(k->mquat);
    out.push_back(std::move(key));
  }
  return out;
}

// Gives unnamed bodies, joints, sites, tendons, actuators, sensors, equalities, pairs, excludes
// and keys a stable generated name "{kind}{index}" (index = the order of that kind within the
// articulation), made unique with _1, _2 when a real name already uses it, so that every element
// can be bound and published (and MuJoCo's attach does not name two unnamed keys both "{prefix}").
void NameUnnamed(mjSpec* spec) {
  static const std::pair<mjtObj, const char*> kKinds[] = {
      {mjOBJ_BODY, "body"},         {mjOBJ_JOINT, "joint"},
      {mjOBJ_SITE, "site"},         {mjOBJ_TENDON, "tendon"},
      {mjOBJ_ACTUATOR, "actuator"}, {mjOBJ_SENSOR, "sensor"},
      {mjOBJ_EQUALITY, "equality"}, {mjOBJ_PAIR, "pair"},
      {mjOBJ_EXCLUDE, "exclude"},   {mjOBJ_KEY, "key"}};
  for (const auto& [type, base] : kKinds) {
    std::set<std::string> used;
    for (mjsElement* e = mjs_firstElement(spec, type); e; e = mjs_nextElement(spec, e)) {
      used.insert(NameOf(e));
    }
    int index = 0;
    for (mjsElement* e = mjs_firstElement(spec, type); e; e = mjs_nextElement(spec, e), ++index) {
      if (type == mjOBJ_BODY && NameOf(e) == "world") continue;
      if (!NameOf(e).empty()) continue;
      std::string n = base + std::to_string(index);
      for (int k = 1; used.count(n); ++k)
        n = base + std::to_string(index) + "_" + std::to_string(k);
      used.insert(n);
      mjs_setName(e, n.c_str());
    }
  }
}

// MuJoCo 3.17's mjs_attach prefixes a reference to the world body by name too ("world" becomes
// "{prefix}world", which names nothing: the element is dropped, or the compile fails). Before
// the attach, a connect or weld to body2 "world" names the world the default way (no body2).
void PrepareAttach(mjSpec* child) {
  for (mjsElement* e = mjs_firstElement(child, mjOBJ_EQUALITY); e; e = mjs_nextElement(child, e)) {
    mjsEquality* q = mjs_asEquality(e);
    if ((q->type == mjEQ_CONNECT || q->type == mjEQ_WELD) && q->objtype == mjOBJ_BODY &&
        SpecString(q->name2) == "world" && SpecString(q->name1) != "world") {
      mjs_setString(q->name2, "");
    }
  }
}

// After the attach: lights aimed at "{prefix}world" aim at the world again.
void FinishAttach(mjSpec* root, const std::string& prefix) {
  const std::string lost_world = prefix + "world";
  for (mjsElement* e = mjs_firstElement(root, mjOBJ_LIGHT); e; e = mjs_nextElement(root, e)) {
    mjsLight* light = mjs_asLight(e);
    if (SpecString(light->targetbody) == lost_world) mjs_setString(light->targetbody, "world");
  }
}

// The kinds CheckAttached counts (NameUnnamed names every one of them, so the prefix finds them;
// bodies are not counted: <compiler fusestatic> merges some away).
constexpr mjtObj kCounted[] = {mjOBJ_JOINT,  mjOBJ_SITE,     mjOBJ_TENDON, mjOBJ_ACTUATOR,
                               mjOBJ_SENSOR, mjOBJ_EQUALITY, mjOBJ_PAIR,   mjOBJ_EXCLUDE};

const char* KindName(mjtObj type) {
  const char* n = mju_type2Str(type);
  return n ? n : "element";
}

// Removes what the world body holds directly other than bodies and frames (a floor, lights,
// world cameras and sites), for composing many copies of a model that brings its own floor.
void DropWorldElements(mjSpec* spec) {
  mjsBody* world = mjs_findBody(spec, "world");
  for (mjtObj type : {mjOBJ_GEOM, mjOBJ_SITE, mjOBJ_CAMERA, mjOBJ_LIGHT}) {
    while (mjsElement* e = mjs_firstChild(world, type, 0)) {
      if (mjs_delete(spec, e) != 0) break;
    }
  }
}

// The option fields that tell two articulations' physics apart, as MJCF text.
std::map<std::string, std::string> Differences(const mjOption& a, const mjOption& b) {
  const std::map<std::string, std::string> ta = OptionText(a), tb = OptionText(b);
  std::map<std::string, std::string> out;
  for (const auto& [k, v] : ta) {
    if (tb.at(k) != v) out[k] = v;
  }
  return out;
}

// The compiler settings MuJoCo applies to a whole model when it compiles (not per element as it
// parses): the scene's are the first articulation's.
void CopyModelCompilerSettings(const mjsCompiler& from, mjsCompiler* to) {
  to->autolimits = from.autolimits;
  to->boundmass = from.boundmass;
  to->boundinertia = from.boundinertia;
  to->settotalmass = from.settotalmass;
  to->balanceinertia = from.balanceinertia;
  to->fitaabb = from.fitaabb;
  to->degree = from.degree;
  std::copy(from.eulerseq, from.eulerseq + 3, to->eulerseq);
  to->discardvisual = from.discardvisual;
  to->usethread = from.usethread;
  to->fusestatic = from.fusestatic;
  to->inertiafromgeom = from.inertiafromgeom;
  std::copy(from.inertiagrouprange, from.inertiagrouprange + 2, to->inertiagrouprange);
  to->alignfree = from.alignfree;
  to->LRopt = from.LRopt;
}

// The model-wide compiler settings where `a` and `b` differ, as MJCF attribute names.
std::vector<std::string> CompilerDifferences(const mjsCompiler& a, const mjsCompiler& b) {
  std::vector<std::string> out;
  if (a.boundmass != b.boundmass) out.push_back("boundmass");
  if (a.boundinertia != b.boundinertia) out.push_back("boundinertia");
  if (a.balanceinertia != b.balanceinertia) out.push_back("balanceinertia");
  if (a.fusestatic != b.fusestatic) out.push_back("fusestatic");
  if (a.alignfree != b.alignfree) out.push_back("alignfree");
  if (a.inertiafromgeom != b.inertiafromgeom) out.push_back("inertiafromgeom");
  if (a.inertiagrouprange[0] != b.inertiagrouprange[0] ||
      a.inertiagrouprange[1] != b.inertiagrouprange[1]) {
    out.push_back("inertiagrouprange");
  }
  return out;
}

}  // namespace

std::vector<Diagnostic> KeyframeLengthProblems(mjSpec* spec, const std::string& file,
                                               const std::string& name) {
  std::size_t nq = 0, nv = 0, nu = 0, na = 0, nmocap = 0;
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_JOINT); e; e = mjs_nextElement(spec, e)) {
    const mjtJoint type = mjs_asJoint(e)->type;
    nq += type == mjJNT_FREE ? 7 : type == mjJNT_BALL ? 4 : 1;
    nv += type == mjJNT_FREE ? 6 : type == mjJNT_BALL ? 3 : 1;
  }
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_ACTUATOR); e; e = mjs_nextElement(spec, e)) {
    const mjsActuator* a = mjs_asActuator(e);
    ++nu;
    if (a->dyntype != mjDYN_NONE) na += a->actdim > 0 ? static_cast<std::size_t>(a->actdim) : 1;
  }
  for (mjsElement* e = mjs_firstElement(spec, mjOBJ_BODY); e; e = mjs_nextElement(spec, e)) {
    nmocap += mjs_asBody(e)->mocap ? 1 : 0;
  }
  std::vector<Diagnostic> out;
  for (const ArticulationKeyframe& key : KeyframesOf(spec, "")) {
    const struct {
      const char* attribute;
      std::size_t given, expected;
      const char* size;
    } fields[] = {{"qpos", key.qpos.size(), nq, "nq"},
                  {"qvel", key.qvel.size(), nv, "nv"},
                  {"act", key.act.size(), na, "na"},
                  {"ctrl", key.ctrl.size(), nu, "nu"},
                  {"mpos", key.mocap_pos.size(), 3 * nmocap, "3*nmocap"},
                  {"mquat", key.mocap_quat.size(), 4 * nmocap, "4*nmocap"}};
    for (const auto& f : fields) {
      if (f.given <= f.expected) continue;  // MuJoCo fills a shorter one from the model
      out.push_back({Diagnostic::Severity::kError,
                     {file, key.name.empty() ? 0 : LineContaining(file, "\"" + key.name + "\"")},
                     name + ": keyframe '" + key.name + "': " + f.attribute + " has " +
                         std::to_string(f.given) + " value(s), the model has " + f.size + "=" +
                         std::to_string(f.expected) + " (MuJoCo takes at most that many)"});
    }
  }
  return out;
}

void SetSize(mjSpec* spec, const std::string& key, const std::string& value) {
  auto whole = [&](double max) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0' || errno == ERANGE || v != std::floor(v) || v < -1 ||
        v > max) {
      throw Error("size " + key + "=\"" + value + "\": needs a whole number from -1 to " +
                  std::to_string(static_cast<long long>(max)));
    }
    return static_cast<long long>(v);
  };
  if (key == "memory") {
    // Bytes, with an optional K, M, G or T suffix (powers of 1024), as MuJoCo reads it.
    std::string digits = value;
    long long scale = 1;
    if (!digits.empty()) {
      const char unit = static_cast<char>(std::toupper(static_cast<unsigned char>(digits.back())));
      const std::string units = "KMGT";
      if (const auto at = units.find(unit); at != std::string::npos) {
        scale = 1LL << (10 * (at + 1));
        digits.pop_back();
      }
    }
    char* end = nullptr;
    const double v = std::strtod(digits.c_str(), &end);
    if (digits.empty() || end == digits.c_str() || *end != '\0' || v != std::floor(v) || v < -1 ||
        v * static_cast<double>(scale) > 1e15) {
      throw Error("size memory=\"" + value +
                  "\": needs bytes (a whole number, optionally with K, "
                  "M, G or T)");
    }
    spec->memory = v < 0 ? -1 : static_cast<mjtSize>(v) * scale;
    return;
  }
  struct IntSize {
    const char* name;
    int mjSpec::*field;
  };
  static const IntSize kInts[] = {
      {"nuserdata", &mjSpec::nuserdata},       {"nuser_body", &mjSpec::nuser_body},
      {"nuser_jnt", &mjSpec::nuser_jnt},       {"nuser_geom", &mjSpec::nuser_geom},
      {"nuser_site", &mjSpec::nuser_site},     {"nuser_cam", &mjSpec::nuser_cam},
      {"nuser_tendon", &mjSpec::nuser_tendon}, {"nuser_actuator", &mjSpec::nuser_actuator},
      {"nuser_sensor", &mjSpec::nuser_sensor}, {"njmax", &mjSpec::njmax},
      {"nconmax", &mjSpec::nconmax},           {"nkey", &mjSpec::nkey},
  };
  for (const IntSize& s : kInts) {
    if (key == s.name) {
      spec->*s.field = static_cast<int>(whole(1e9));
      return;
    }
  }
  if (key == "nstack") {
    spec->nstack = static_cast<mjtSize>(whole(1e12));
    return;
  }
  throw Error("'" + key + "' is not a size attribute of MuJoCo " + std::string(mj_versionString()));
}

ComposeResult Compose(std::vector<ArticulationInput> inputs,
                      const std::map<std::string, std::string>& scene_options) {
  ComposeResult result;
  result.spec.reset(mj_makeSpec());
  mjSpec* root = result.spec.get();
  // Every attachment is copied whole into the root, so the articulations' specs can go.
  mjs_setDeepCopy(root, 1);
  mjsBody* world = mjs_findBody(root, "world");

  // The scene's options, size and visual settings: the first articulation's (with its own
  // `options:`), then the scene's overrides.
  const ArticulationInput* first = nullptr;
  for (const ArticulationInput& in : inputs) {
    if (!in.takes_scene_options) {
      first = &in;
      break;
    }
  }
  auto apply = [](mjOption* o, const std::map<std::string, std::string>& options,
                  const std::string& who) {
    for (const auto& [k, v] : options) {
      try {
        SetOption(o, k, v);
      } catch (const Error& e) {
        throw InputError({}, who + e.what());
      }
    }
  };
  if (first) {
    root->option = first->spec->option;
    apply(&root->option, first->options, first->name + ": ");
    root->visual = first->spec->visual;
    root->stat = first->spec->stat;
    CopyModelCompilerSettings(first->spec->compiler, &root->compiler);
  }
  apply(&root->option, scene_options, "scene: ");
  if (first) mjs_setString(root->modelname, SpecString(first->spec->modelname).c_str());

  int nkey = root->nkey;
  std::size_t articulations = 0;
  for (const ArticulationInput& in : inputs) articulations += in.takes_scene_options ? 0 : 1;
  for (ArticulationInput& in : inputs) {
    mjSpec* child = in.spec.get();
    if (!in.takes_scene_options) {
      const std::vector<Diagnostic> keys = KeyframeLengthProblems(child, in.file, in.name);
      if (!keys.empty()) {
        throw InputError(
            keys[0].where,
            keys[0].message +
                (keys.size() > 1 ? " (and " + std::to_string(keys.size() - 1) + " more problem(s))"
                                 : ""));
      }
      if (articulations > 1 && child->compiler.settotalmass > 0) {
        throw InputError({in.file, LineContaining(in.file, "settotalmass")},
                         in.name +
                             ": <compiler settotalmass> rescales a whole model's mass; it "
                             "cannot be composed into a scene of several articulations "
                             "(give the bodies their masses)");
      }
    }
    const std::string prefix = in.name + "_";
    ArticulationLayout layout;
    layout.name = in.name;
    layout.prefix = prefix;
    layout.file = in.file;
    layout.line = in.line;
    layout.placement = in.placement;
    if (!in.takes_scene_options) {
      apply(&child->option, in.options, in.name + ": ");
      if (&in != first) {
        const std::vector<std::string> compiler =
            CompilerDifferences(child->compiler, root->compiler);
        if (!compiler.empty()) {
          std::string names;
          for (const std::string& n : compiler) names += (names.empty() ? "" : ", ") + n;
          result.diagnostics.push_back({Diagnostic::Severity::kWarning,
                                        {in.file, LineContaining(in.file, "<compiler")},
                                        in.name + ": its <compiler> " + names +
                                            " differ(s) from the first articulation's (" +
                                            first->name +
                                            "); MuJoCo compiles the scene with the first's"});
        }
        // The scene runs one set of options: say which of this articulation's differ.
        for (const auto& [k, v] : Differences(child->option, root->option)) {
          if (scene_options.count(k)) continue;
          result.diagnostics.push_back(
              {Diagnostic::Severity::kWarning,
               {in.file, 0},
               in.name + ": option " + k + "=\"" + v + "\" differs from the scene's \"" +
                   OptionText(root->option).at(k) + "\" (the first articulation's, " + first->name +
                   "); the scene's applies"});
        }
      }
    }
    // What MuJoCo would report as an attach conflict is resolved here: the scene's settings,
    // and sizes large enough for every articulation.
    child->option = root->option;
    child->visual = root->visual;
    child->stat = root->stat;
    for (int mjSpec::*size :
         {&mjSpec::nuserdata, &mjSpec::nuser_body, &mjSpec::nuser_jnt, &mjSpec::nuser_geom,
          &mjSpec::nuser_site, &mjSpec::nuser_cam, &mjSpec::nuser_tendon, &mjSpec::nuser_actuator,
          &mjSpec::nuser_sensor, &mjSpec::njmax, &mjSpec::nconmax, &mjSpec::nemax}) {
      child->*size = root->*size = std::max(root->*size, child->*size);
    }
    for (mjtSize mjSpec::*size : {&mjSpec::memory, &mjSpec::nstack}) {
      child->*size = root->*size = std::max(root->*size, child->*size);
    }
    // <size nkey>: the scene's is set once every articulation's keys are in (before, MuJoCo would
    // put the padding keys first).
    nkey = std::max(nkey, child->nkey);
    child->nkey = root->nkey;
    if (mjsElement* tuple = mjs_firstElement(child, mjOBJ_TUPLE)) {
      throw InputError({in.file, LineContaining(in.file, "<tuple")},
                       in.name + ": <custom><tuple name=\"" + NameOf(tuple) +
                           "\"> cannot be composed: MuJoCo " + mj_versionString() +
                           "'s mjs_attach does not carry tuples (nor the sensors that read "
                           "them); remove it or load the file on its own");
    }
    if (!in.include_world) DropWorldElements(child);
    NameUnnamed(child);
    layout.keyframes = KeyframesOf(child, prefix);
    for (mjtObj type : kCounted) {
      int n = 0;
      for (mjsElement* e = mjs_firstElement(child, type); e; e = mjs_nextElement(child, e)) {
        ++n;
      }
      layout.own_counts[type] = n;
    }

    PrepareAttach(child);
    mjsFrame* frame = mjs_addFrame(world, nullptr);
    std::copy(in.placement.pos.begin(), in.placement.pos.end(), frame->pos);
    std::copy(in.placement.quat.begin(), in.placement.quat.end(), frame->quat);
    mjs_setString(frame->info, (in.name + (in.file.empty() ? "" : " (" + in.file + ")")).c_str());
    if (!mjs_attach(frame->element, child->element, prefix.c_str(), "")) {
      throw InputError({in.file, 0}, in.name + ": MuJoCo could not attach it: " +
                                         TidyMujocoMessage(mjs_getError(root)));
    }
    FinishAttach(root, prefix);
    in.spec.reset();
    result.articulations.push_back(std::move(layout));
  }
  root->nkey = nkey;
  return result;
}

void LayoutOf(const mjModel* m, ArticulationLayout* layout) {
  const std::string& prefix = layout->prefix;
  auto mine = [&](mjtObj type, int id) {
    const char* name = mj_id2name(m, type, id);
    return name && std::strncmp(name, prefix.c_str(), prefix.size()) == 0 ? name : nullptr;
  };
  layout->joints.clear();
  layout->bodies.clear();
  layout->actuators.clear();
  layout->sensors.clear();
  layout->mocap_bodies.clear();
  layout->free_joints_at_top.clear();
  for (int j = 0; j < m->njnt; ++j) {
    const char* n = mine(mjOBJ_JOINT, j);
    if (!n) continue;
    layout->joints.push_back(n);
    if (m->jnt_type[j] == mjJNT_FREE && m->body_parentid[m->jnt_bodyid[j]] == 0) {
      layout->free_joints_at_top.push_back(n);
    }
  }
  for (int b = 1; b < m->nbody; ++b) {
    const char* n = mine(mjOBJ_BODY, b);
    if (!n) continue;
    layout->bodies.push_back(n);
    if (m->body_mocapid[b] >= 0) layout->mocap_bodies.push_back(n);
  }
  for (int a = 0; a < m->nu; ++a) {
    if (const char* n = mine(mjOBJ_ACTUATOR, a)) layout->actuators.push_back(n);
  }
  for (int s = 0; s < m->nsensor; ++s) {
    if (const char* n = mine(mjOBJ_SENSOR, s)) layout->sensors.push_back(n);
  }
}

void CheckAttached(const mjModel* m, const std::vector<ArticulationLayout>& layouts) {
  for (const ArticulationLayout& art : layouts) {
    for (const auto& [type, expected] : art.own_counts) {
      int found = 0;
      const int n = type == mjOBJ_JOINT      ? static_cast<int>(m->njnt)
                    : type == mjOBJ_SITE     ? static_cast<int>(m->nsite)
                    : type == mjOBJ_TENDON   ? static_cast<int>(m->ntendon)
                    : type == mjOBJ_ACTUATOR ? static_cast<int>(m->nu)
                    : type == mjOBJ_SENSOR   ? static_cast<int>(m->nsensor)
                    : type == mjOBJ_EQUALITY ? static_cast<int>(m->neq)
                    : type == mjOBJ_PAIR     ? static_cast<int>(m->npair)
                                             : static_cast<int>(m->nexclude);
      for (int i = 0; i < n; ++i) {
        const char* name = mj_id2name(m, type, i);
        found += name && std::strncmp(name, art.prefix.c_str(), art.prefix.size()) == 0;
      }
      if (found >= expected) continue;
      // MuJoCo's own word on the file alone, at its line.
      if (!art.file.empty() && std::filesystem::is_regular_file(art.file)) {
        SpecPtr alone = ParseFile(art.file);
        if (!mj_compile(alone.get(), nullptr)) {
          const std::string raw = mjs_getError(alone.get());
          throw InputError({art.file, LineOfMujocoMessage(raw)},
                           art.name + ": " + TidyMujocoMessage(raw));
        }
      }
      throw InputError({art.file, 0}, art.name + ": MuJoCo's attach left out " +
                                          std::to_string(expected - found) + " " +
                                          KindName(static_cast<mjtObj>(type)) +
                                          "(s) of it (a reference that names nothing?)");
    }
  }
}

void PlaceKeyframes(const std::vector<ArticulationLayout>& layouts, mjModel* m, mjSpec* spec) {
  for (const ArticulationLayout& art : layouts) {
    if (art.placement.IsIdentity()) continue;
    for (const ArticulationKeyframe& key : art.keyframes) {
      if (key.qpos.empty()) continue;  // qpos0: placed already
      const int k = mj_name2id(m, mjOBJ_KEY, key.scene_name.c_str());
      if (k < 0) continue;
      mjtNum* row = m->key_qpos + static_cast<std::size_t>(k) * static_cast<std::size_t>(m->nq);
      for (const std::string& jn : art.free_joints_at_top) {
        const int j = mj_name2id(m, mjOBJ_JOINT, jn.c_str());
        if (j < 0) continue;
        mjtNum* q = row + m->jnt_qposadr[j];
        mjtNum pos[3], quat[4];
        mju_rotVecQuat(pos, q, art.placement.quat.data());
        mju_addTo3(pos, art.placement.pos.data());
        mju_mulQuat(quat, art.placement.quat.data(), q + 3);
        mju_normalize4(quat);
        mju_copy3(q, pos);
        mju_copy4(q + 3, quat);
      }
      if (mjsElement* e = mjs_findElement(spec, mjOBJ_KEY, key.scene_name.c_str())) {
        mjs_setDouble(mjs_asKey(e)->qpos, row, static_cast<int>(m->nq));
      }
    }
    // Mocap bodies attached to the world: their keyframe poses too.
    for (const ArticulationKeyframe& key : art.keyframes) {
      if (key.mocap_pos.empty() && key.mocap_quat.empty()) continue;
      const int k = mj_name2id(m, mjOBJ_KEY, key.scene_name.c_str());
      if (k < 0) continue;
      mjtNum* mpos = m->key_mpos + static_cast<std::size_t>(k) * 3 * m->nmocap;
      mjtNum* mquat = m->key_mquat + static_cast<std::size_t>(k) * 4 * m->nmocap;
      for (const std::string& bn : art.mocap_bodies) {
        const int b = mj_name2id(m, mjOBJ_BODY, bn.c_str());
        if (b < 0 || m->body_parentid[b] != 0) continue;
        const int id = m->body_mocapid[b];
        if (!key.mocap_pos.empty()) {
          mjtNum pos[3];
          mju_rotVecQuat(pos, mpos + 3 * id, art.placement.quat.data());
          mju_addTo3(pos, art.placement.pos.data());
          mju_copy3(mpos + 3 * id, pos);
        }
        if (!key.mocap_quat.empty()) {
          mjtNum quat[4];
          mju_mulQuat(quat, art.placement.quat.data(), mquat + 4 * id);
          mju_normalize4(quat);
          mju_copy4(mquat + 4 * id, quat);
        }
      }
      if (mjsElement* e = mjs_findElement(spec, mjOBJ_KEY, key.scene_name.c_str())) {
        mjs_setDouble(mjs_asKey(e)->mpos, mpos, static_cast<int>(3 * m->nmocap));
        mjs_setDouble(mjs_asKey(e)->mquat, mquat, static_cast<int>(4 * m->nmocap));
      }
    }
  }
}

}  // namespace urlab::mjcf
