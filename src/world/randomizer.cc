#include "world/randomizer.h"

#include <algorithm>

#include "urlab/physics/delay_line.h"

namespace urlab::world {

namespace {

std::vector<mjtNum> Copy(const mjtNum* v, int n) { return std::vector<mjtNum>(v, v + n); }

}  // namespace

Randomizer::Randomizer(const mjModel* m, std::vector<Target> targets)
    : targets_(std::move(targets)),
      friction_(Copy(m->geom_friction, 3 * m->ngeom)),
      mass_(Copy(m->body_mass, m->nbody)),
      inertia_(Copy(m->body_inertia, 3 * m->nbody)),
      damping_(Copy(m->dof_damping, m->nv)),
      armature_(Copy(m->dof_armature, m->nv)),
      frictionloss_(Copy(m->dof_frictionloss, m->nv)),
      gainprm_(Copy(m->actuator_gainprm, mjNGAIN * m->nu)),
      biasprm_(Copy(m->actuator_biasprm, mjNBIAS * m->nu)) {
  std::copy_n(m->opt.gravity, 3, gravity_);
}

const Randomizer::Target* Randomizer::Find(const std::string& name) const {
  for (const Target& t : targets_) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

std::string Randomizer::Check(const RandomizeConfig& config) const {
  for (const auto& [axis, range] : config.gravity) {
    if (axis != "x" && axis != "y" && axis != "z") {
      return "gravity: unknown component '" + axis + "' (x, y or z)";
    }
    if (const std::string outside = CheckLimits("gravity", range); !outside.empty()) {
      return "gravity." + axis + ": " + outside;
    }
  }
  for (const auto& [name, params] : config.targets) {
    const Target* t = Find(name);
    if (!t) return "no articulation or prop '" + name + "' in the scene";
    for (const auto& [key, range] : params) {
      if (!IsRandomParam(key, t->prop)) {
        std::string known;
        for (const RandomParamInfo& p : RandomParams()) {
          if (!t->prop || p.props) known += (known.empty() ? "" : ", ") + std::string(p.key);
        }
        return name + ": unknown parameter '" + key + "' for " +
               (t->prop ? "a prop" : "an articulation") + " (known: " + known + ")";
      }
      if (const std::string outside = CheckLimits(key, range); !outside.empty()) {
        return name + "." + key + ": " + outside;
      }
      if ((key == "kp" || key == "kv") && !t->pd) {
        return name + ": '" + key + "' needs a PD controller (controller type pd)";
      }
    }
  }
  return "";
}

std::uint64_t Randomizer::ResetSeed(std::uint64_t seed, std::uint64_t n) {
  // "RAND": the draws' streams differ from the latency jitter's for the same scene seed.
  return physics::DeriveSeed(seed ^ 0x52414E44u, n);
}

Randomizer::Applied Randomizer::Apply(const RandomizeConfig& config, std::uint64_t seed, mjModel* m,
                                      const PdOf& pd_of) const {
  const auto pd = [&](std::size_t target) { return pd_of ? pd_of(target) : targets_[target].pd; };
  // The mass distribution before this reset (a previous draw's, or nominal).
  const bool inertial_was_drawn = !std::equal(mass_.begin(), mass_.end(), m->body_mass) ||
                                  !std::equal(inertia_.begin(), inertia_.end(), m->body_inertia) ||
                                  !std::equal(armature_.begin(), armature_.end(), m->dof_armature);
  // Nominal first: each reset draws from the model as compiled, never from the last draw.
  std::copy(friction_.begin(), friction_.end(), m->geom_friction);
  std::copy(mass_.begin(), mass_.end(), m->body_mass);
  std::copy(inertia_.begin(), inertia_.end(), m->body_inertia);
  std::copy(damping_.begin(), damping_.end(), m->dof_damping);
  std::copy(armature_.begin(), armature_.end(), m->dof_armature);
  std::copy(frictionloss_.begin(), frictionloss_.end(), m->dof_frictionloss);
  std::copy(gainprm_.begin(), gainprm_.end(), m->actuator_gainprm);
  std::copy(biasprm_.begin(), biasprm_.end(), m->actuator_biasprm);
  std::copy_n(gravity_, 3, m->opt.gravity);
  for (std::size_t k = 0; k < targets_.size(); ++k) {
    control::PdController* c = targets_[k].pd ? pd(k) : nullptr;
    if (!c) continue;
    for (std::size_t i = 0; i < targets_[k].nominal_gains.size(); ++i) {
      c->SetGains(static_cast<int>(i), targets_[k].nominal_gains[i]);
    }
  }

  Applied out;
  out.draws.seed = seed;
  std::uint64_t state = seed;
  static constexpr const char* kAxes[] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    const auto it = config.gravity.find(kAxes[k]);
    if (it == config.gravity.end()) continue;
    const double v = DrawParam("gravity", it->second, &state);
    m->opt.gravity[k] = gravity_[k] + v;
    out.draws.gravity[kAxes[k]] = v;
  }
  for (std::size_t ti = 0; ti < targets_.size(); ++ti) {
    const Target& t = targets_[ti];
    const auto params = config.targets.find(t.name);
    if (params == config.targets.end()) continue;
    auto& drawn = out.draws.targets[t.name];
    for (const RandomParamInfo& p : RandomParams()) {
      const auto it = params->second.find(std::string(p.key));
      if (it == params->second.end()) continue;
      const RandomRange& range = it->second;
      if (p.key == "qpos_noise") {  // one draw per joint
        for (const auto& [joint, adr] : t.joints) {
          const double v = DrawParam(p.key, range, &state);
          drawn["qpos_noise." + joint] = v;
          out.qpos_offsets.emplace_back(adr, v);
        }
        continue;
      }
      const double v = DrawParam(p.key, range, &state);
      drawn[std::string(p.key)] = v;
      if (p.key == "friction") {
        for (int g : t.geoms) m->geom_friction[3 * g] = friction_[3 * g] * v;
      } else if (p.key == "mass") {
        for (int b : t.bodies) {
          m->body_mass[b] = mass_[b] * v;
          for (int k = 0; k < 3; ++k) m->body_inertia[3 * b + k] = inertia_[3 * b + k] * v;
        }
      } else if (p.key == "damping") {
        for (int i : t.dofs) m->dof_damping[i] = damping_[i] * v;
      } else if (p.key == "armature") {
        for (int i : t.dofs) m->dof_armature[i] = armature_[i] * v;
      } else if (p.key == "frictionloss") {
        for (int i : t.dofs) m->dof_frictionloss[i] = frictionloss_[i] * v;
      } else if (p.key == "gain") {
        for (int a : t.actuators) {
          m->actuator_gainprm[mjNGAIN * a] = gainprm_[mjNGAIN * a] * v;
          if (m->actuator_biastype[a] == mjBIAS_AFFINE) {  // a position servo's -kp, -kv
            m->actuator_biasprm[mjNBIAS * a + 1] = biasprm_[mjNBIAS * a + 1] * v;
            m->actuator_biasprm[mjNBIAS * a + 2] = biasprm_[mjNBIAS * a + 2] * v;
          }
        }
      } else if (p.key == "kp" || p.key == "kv") {
        control::PdController* c = t.pd ? pd(ti) : nullptr;
        for (std::size_t i = 0; c && i < t.nominal_gains.size(); ++i) {
          control::PdGains g = c->gains(static_cast<int>(i));
          (p.key == "kp" ? g.kp : g.kv) =
              (p.key == "kp" ? t.nominal_gains[i].kp : t.nominal_gains[i].kv) * v;
          c->SetGains(static_cast<int>(i), g);
        }
      } else if (p.key == "obs_noise") {
        out.obs_noise.emplace_back(t.name, std::max(0.0, v));
      }
    }
  }
  // What the compiler derives from masses, inertias and armature (subtree masses, the inverse
  // weights that scale constraint impedance, actuator_acc0, the mean inertia) follows the draw,
  // as if the model had been compiled with it. mj_setConst overwrites the mjData it is given, so
  // it gets a scratch one: the running simulation's state is untouched until the reset.
  const bool inertial_drawn = !std::equal(mass_.begin(), mass_.end(), m->body_mass) ||
                              !std::equal(inertia_.begin(), inertia_.end(), m->body_inertia) ||
                              !std::equal(armature_.begin(), armature_.end(), m->dof_armature);
  if (inertial_was_drawn || inertial_drawn) {
    mjData* scratch = mj_makeData(m);
    if (scratch) {
      mj_setConst(m, scratch);
      mj_deleteData(scratch);
    }
  }
  return out;
}

}  // namespace urlab::world
