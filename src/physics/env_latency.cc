#include "urlab/physics/env_latency.h"

#include <cmath>

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

void EnvLatency::SetNoise(const std::vector<Noise>& noise) {
  noise_.clear();
  for (const Noise& n : noise) {
    if (n.stddev > 0 && !n.observed.empty()) noise_.push_back({n, n.seed});
  }
}

void EnvLatency::AddNoise(double* row) {
  for (NoiseState& n : noise_) {
    for (int i : n.noise.observed) {  // Box-Muller, u1 in (0, 1] (as ObservationDelay)
      const double u1 = 1.0 - UnitDouble(&n.state);
      const double u2 = UnitDouble(&n.state);
      row[i] += n.noise.stddev * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    }
  }
}

void EnvLatency::RestartObservation(double* row) {
  for (NoiseState& n : noise_) n.state = n.noise.seed;
  AddNoise(row);
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
  AddNoise(row);
  for (Line& o : observation_) {
    Take(o.index, row, &o.scratch);
    Put(o.index, o.line.Push(o.scratch), row);
  }
}

}  // namespace urlab::physics
