#pragma once
// EnvLatency: emulated control and observation latency for one environment of a batch, on its
// packed rows (physics/batch.h: an action row in actuator order, an observation row of qpos,
// qvel and sensordata). The mechanism is the DelayLine (physics/delay_line.h); what a setting
// means and how it resolves to ticks is policy (physics/latency.h). One group per articulation
// with a latency: its control line delays the actions of its actuators on their way to ctrl,
// its observation line the entries of the observation row that are its state. Both tick once
// per physics step, with the semantics of ArticulationControl's control delay and of
// ObservationDelay (the single-environment run's):
// - Restart (after every reset of the environment): each line restarts from its seed; a control
//   line is primed with the controls the reset left in ctrl (until the first action is released
//   the environment runs with them); an observation line takes the row right after the reset as
//   its tick 0.
// - ApplyControl, before each step: the step's actions enter, the released ones go to ctrl.
// - Observe, after each step: the new row enters, the group's entries are replaced by the
//   released ones (the other entries stay current).
//
// Threading: none of its own; the thread stepping the environment, one at a time.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <vector>

#include "urlab/physics/delay_line.h"

namespace urlab::physics {

class EnvLatency {
 public:
  struct Group {
    std::vector<int> actuators;  // actuator ids (= indices into the action row and ctrl)
    std::vector<int> observed;   // indices into the observation row
    DelaySpec control, observation;
  };
  // Observation noise (a randomised `obs_noise`): Gaussian noise of standard deviation `stddev`
  // added to the entries `observed` of every row that enters (the reset's and each step's,
  // before its delay: a delayed value carries the noise of its measurement), drawn from `seed`
  // (restarted with the observation lines), as ObservationDelay adds it.
  struct Noise {
    std::vector<int> observed;
    double stddev = 0;
    std::uint64_t seed = 0;
  };
  // Sets the groups (inactive ones are dropped) and restarts nothing: call Restart before the
  // first step.
  void Configure(const std::vector<Group>& groups);
  // Replaces the noise (entries of 0 are dropped); takes effect at the next RestartObservation.
  void SetNoise(const std::vector<Noise>& noise);
  bool controls_delayed() const { return !control_.empty(); }
  // True when observations are delayed or carry noise (the observed row differs from the state).
  bool observations_delayed() const { return !observation_.empty() || !noise_.empty(); }
  // After a reset: `d` as the reset left it, `row` its observation row, turned into the
  // observed one in place (both halves below).
  void Restart(const mjData* d, double* row) {
    RestartControl(d);
    RestartObservation(row);
  }
  void RestartControl(const mjData* d);  // restarts and primes the control lines
  // Restarts the observation lines and the noise from `row` (tick 0), observed in place.
  void RestartObservation(double* row);
  // Before a step: `actions` (the environment's action row) through the control lines into
  // d->ctrl (only the delayed groups' actuators are written).
  void ApplyControl(const double* actions, mjData* d);
  // After a step: `row` (the current observation row) through the observation lines, in place.
  void Observe(double* row);

 private:
  struct Line {
    std::vector<int> index;  // actuator ids or observation row indices
    DelayLine<std::vector<double>> line;
    std::vector<double> scratch;
  };
  struct NoiseState {
    Noise noise;
    std::uint64_t state = 0;
  };
  void AddNoise(double* row);
  std::vector<Line> control_, observation_;
  std::vector<NoiseState> noise_;
};

}  // namespace urlab::physics
