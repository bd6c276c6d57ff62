#include "urlab/physics/env_latency.h"

namespace urlab::physics {

namespace {

void Take(const std::vector<int>& index, const double* from, std::vector<double>* out) {
  out->resize(index.size());
  for (std::size_t k = 0; k < index.size(); ++k) (*out)[k] = from[index[k]];
}

void Put(const std::vector<int>& index, const std::vector<double>& values, double* to) {
  for (std::size_t k = 0; k < index.size() && k < values.size(); ++k) to[index[k]] = values[k];
}

}  // namespace

void EnvLatency::Configure(const std::vector<Group>& groups) {
  control_.clear();
  observation_.clear();
  for (const Group& g : groups) {
    if (g.control.active() && !g.actuators.empty()) {
      control_.push_back({g.actuators, DelayLine<std::vector<double>>(g.control), {}});
    }
    if (g.observation.active() && !g.observed.empty()) {
      observation_.push_back({g.observed, DelayLine<std::vector<double>>(g.observation), {}});
    }
  }
}

void EnvLatency::RestartControl(const mjData* d) {
  for (Line& c : control_) {
    c.line.Restart();
    Take(c.index, d->ctrl, &c.scratch);
    c.line.Prime(c.scratch);
  }
}

void EnvLatency::RestartObservation(const double* row) {
  for (Line& o : observation_) {
    o.line.Restart();
    Take(o.index, row, &o.scratch);
    o.line.Push(o.scratch);  // tick 0: the state right after the reset
  }
}

void EnvLatency::ApplyControl(const double* actions, mjData* d) {
  for (Line& c : control_) {
    Take(c.index, actions, &c.scratch);
    Put(c.index, c.line.Push(c.scratch), d->ctrl);
  }
}

void EnvLatency::Observe(double* row) {
  for (Line& o : observation_) {
    Take(o.index, row, &o.scratch);
    Put(o.index, o.line.Push(o.scratch), row);
  }
}

}  // namespace urlab::physics
