// The dialect bridge's keyframe pass: keys shorter than the model padded as 3.x does, and the
// keys of attached models written at their elements' addresses.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <memory>
#include <type_traits>

#include "mjcf/bridge_pass.h"
#include "mjcf/trial_compile.h"
#include "urlab/document/orientation.h"
#include "urlab/mjcf/writer.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Element;
using document::ParseReals;

class KeyframesPasses : public Pass {
 public:
  using Pass::Pass;

  // ---- keyframes shorter than the model ----
  // 3.x pads a key's qpos with qpos0, qvel/act/ctrl with zeros, mpos/mquat with the mocap bodies'
  // poses; 2.2.2 refuses a key of the wrong length. The padding needs the compiled sizes and
  // qpos0: a trial compile without the keys.
  // Whether every key already has the document's sizes, counted from its joints and actuators
  // (no trial compile needed). False when unsure (composites, mocap or act values).
  bool KeysFitTheDocument(const Element& section) {
    int nq = 0, nv = 0, nu = 0;
    bool unsure = false;
    doc_.root().Visit([&](const Element& e) {
      if (InDefault(e)) return;
      if (e.tag() == "composite") unsure = true;
      if (e.tag() == "freejoint") {
        nq += 7;
        nv += 6;
      } else if (e.tag() == "joint" && e.parent() && e.parent()->tag() == "body") {
        const std::string* t = Resolve(e, "type");
        const std::string type = t ? *t : "hinge";
        nq += type == "free" ? 7 : type == "ball" ? 4 : 1;
        nv += type == "free" ? 6 : type == "ball" ? 3 : 1;
      } else if (IsActuatorTag(e.tag()) && e.parent() && e.parent()->tag() == "actuator") {
        ++nu;
      }
    });
    if (unsure) return false;
    for (const auto& k : section.children()) {
      if (k->Has("act") || k->Has("mpos") || k->Has("mquat")) return false;
      auto count = [&](const char* a) {
        const std::string* v = k->Get(a);
        return v ? static_cast<int>(ParseReals(*v).value_or(std::vector<double>{}).size()) : -1;
      };
      const int q = count("qpos"), v = count("qvel"), c = count("ctrl");
      if ((q >= 0 && q != nq) || (v >= 0 && v != nv) || (c >= 0 && c != nu)) return false;
    }
    return true;
  }

  // An attached model's keyframe (bridge_attach.h) as a key of the whole model: qpos0, zero
  // velocities, controls and activations, mocap bodies at their poses, then the child's values
  // at its elements' addresses.
  void WriteAttachedKey(const mjModel* m, const AttachedKey& k) {
    std::vector<double> qpos(m->qpos0, m->qpos0 + m->nq), qvel(static_cast<size_t>(m->nv));
    std::vector<double> ctrl(static_cast<size_t>(m->nu)), act(static_cast<size_t>(m->na));
    std::vector<double> mpos(static_cast<size_t>(3 * m->nmocap));
    std::vector<double> mquat(static_cast<size_t>(4 * m->nmocap));
    for (int b = 0; b < m->nbody; ++b) {
      if (const int id = m->body_mocapid[b]; id >= 0) {
        std::copy_n(m->body_pos + 3 * b, 3, mpos.begin() + 3 * id);
        std::copy_n(m->body_quat + 4 * b, 4, mquat.begin() + 4 * id);
      }
    }
    auto place = [&](mjtObj type, const auto& values, auto address, std::vector<double>& into) {
      for (const auto& [name, v] : values) {
        const int id = mj_name2id(m, type, name.c_str());
        const int at = id < 0 ? -1 : address(id);
        if (at < 0) continue;  // not attached (outside the subtree, or stayed in the child)
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, double>) {
          into[static_cast<size_t>(at)] = v;
        } else {
          std::copy(v.begin(), v.end(), into.begin() + at);
        }
      }
    };
    place(
        mjOBJ_JOINT, k.qpos, [&](int j) { return m->jnt_qposadr[j]; }, qpos);
    place(
        mjOBJ_JOINT, k.qvel, [&](int j) { return m->jnt_dofadr[j]; }, qvel);
    place(
        mjOBJ_ACTUATOR, k.ctrl, [](int a) { return a; }, ctrl);
    place(
        mjOBJ_ACTUATOR, k.act,
        [&](int a) { return m->actuator_dyntype[a] == mjDYN_NONE ? -1 : a - (m->nu - m->na); },
        act);
    place(
        mjOBJ_BODY, k.mpos, [&](int b) { return 3 * m->body_mocapid[b]; }, mpos);
    place(
        mjOBJ_BODY, k.mquat, [&](int b) { return 4 * m->body_mocapid[b]; }, mquat);
    if (k.time != 0) k.key->SetReals("time", std::vector<double>{k.time});
    k.key->SetReals("qpos", qpos);
    if (m->nv) k.key->SetReals("qvel", qvel);
    if (m->nu) k.key->SetReals("ctrl", ctrl);
    if (m->na) k.key->SetReals("act", act);
    if (m->nmocap) {
      k.key->SetReals("mpos", mpos);
      k.key->SetReals("mquat", mquat);
    }
  }

  void PadKeyframes() {
    Element* section = nullptr;
    for (Element* k : Find({"keyframe"})) section = k;
    if (!section || section->children().empty()) return;
    if (state_.attached_keys.empty() && KeysFitTheDocument(*section)) return;
    std::string xml;  // the document without its keys
    {
      std::unique_ptr<Element> keys = doc_.root().RemoveChild(section);
      try {
        xml = WriteString(doc_);
      } catch (...) {
        doc_.root().InsertChild(doc_.root().children().size(), std::move(keys));
        throw;
      }
      doc_.root().InsertChild(doc_.root().children().size(), std::move(keys));
    }
    std::string error;
    const physics::ModelPtr model = TrialCompile(xml, &error);
    const mjModel* m = model.get();
    if (!m) return;  // the real compile reports it
    for (const AttachedKey& k : state_.attached_keys) WriteAttachedKey(m, k);
    for (const auto& k : section->children()) {
      std::vector<std::string> padded;
      auto pad = [&](const char* attr, int size, const mjtNum* fill) {
        const std::string* v = k->Get(attr);
        if (!v) return;
        std::vector<double> x = ParseReals(*v).value_or(std::vector<double>{});
        if (static_cast<int>(x.size()) >= size) return;
        const size_t had = x.size();
        for (int i = static_cast<int>(had); i < size; ++i) x.push_back(fill ? fill[i] : 0.0);
        k->SetReals(attr, x);
        padded.push_back(std::string(attr) + " " + std::to_string(had) + " -> " +
                         std::to_string(size));
      };
      std::vector<mjtNum> mpos, mquat;
      for (int b = 0; b < m->nbody; ++b) {
        if (m->body_mocapid[b] < 0) continue;
        mpos.insert(mpos.end(), m->body_pos + 3 * b, m->body_pos + 3 * b + 3);
        mquat.insert(mquat.end(), m->body_quat + 4 * b, m->body_quat + 4 * b + 4);
      }
      pad("qpos", m->nq, m->qpos0);
      pad("qvel", m->nv, nullptr);
      pad("act", m->na, nullptr);
      pad("ctrl", m->nu, nullptr);
      pad("mpos", 3 * m->nmocap, mpos.data());
      pad("mquat", 4 * m->nmocap, mquat.data());
      if (!padded.empty()) {
        Note("keyframe.pad", *k,
             Tag(*k) +
                 " shorter than the model, padded as MuJoCo 3.x does (qpos with qpos0, "
                 "mocap with the bodies' poses, the rest with zeros): " +
                 Join(padded, ", "));
      }
    }
  }
};

}  // namespace

void PadKeyframes(State& s) { KeyframesPasses(s).PadKeyframes(); }

}  // namespace urlab::mjcf::bridge
