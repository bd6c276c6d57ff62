#include "world/env_controls.h"

#include <limits>

#include "urlab/world/controller_factory.h"

namespace urlab::world {

EnvControls::EnvControls(const Session& session) {
  const mjModel* m = session.engine().model();
  for (const Articulation& a : session.articulations()) {
    auto control = std::make_unique<control::ArticulationControl>(*a.bindings);
    InstallController(a.config, *control, m);
    InstallTwist(a.config, *a.bindings, *control, m);  // detached: the gait walks on no twist
    targets_.emplace_back(static_cast<std::size_t>(control->num_actuators()), 0.0);
    controls_.push_back(std::move(control));
  }
  actions_.assign(static_cast<std::size_t>(m->nu), 0.0);
}

bool EnvControls::Needed(const Session& session) {
  for (const Articulation& a : session.articulations()) {
    if (!dynamic_cast<const control::PassthroughController*>(a.control->controller())) return true;
  }
  return false;
}

void EnvControls::TargetBounds(std::vector<double>* low, std::vector<double>* high) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (const auto& c : controls_) {
    const control::Controller& controller = *c->controller();
    const bool positions = controller.TargetsArePositions();
    for (const control::ActuatorBinding& b : controller.bindings()) {
      const auto u = static_cast<std::size_t>(b.actuator_id);
      double range[2];
      if (b.TargetRange(positions, range)) {
        (*low)[u] = range[0];
        (*high)[u] = range[1];
      } else {
        (*low)[u] = -kInf;
        (*high)[u] = kInf;
      }
    }
  }
}

void EnvControls::Apply(const mjModel* m, mjData* d) {
  // ctrl holds the actions; each controller reads its articulation's as targets, then writes.
  actions_.assign(d->ctrl, d->ctrl + m->nu);
  for (std::size_t i = 0; i < controls_.size(); ++i) {
    const std::vector<int>& ids = controls_[i]->actuator_ids();
    std::vector<double>& targets = targets_[i];
    for (std::size_t k = 0; k < ids.size(); ++k) {
      targets[k] = actions_[static_cast<std::size_t>(ids[k])];
    }
    controls_[i]->controller()->ComputeAndApply(m, d, targets);
  }
}

void EnvControls::Restart() {
  for (const auto& c : controls_) c->controller()->Restart();
}

control::PdController* EnvControls::pd(std::size_t articulation) const {
  if (articulation >= controls_.size()) return nullptr;
  return dynamic_cast<control::PdController*>(controls_[articulation]->controller());
}

}  // namespace urlab::world
