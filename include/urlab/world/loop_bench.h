#pragma once
// Loop overhead benchmark shared by bench/bench_loop and `urlab bench loop`: the full physics
// loop (PhysicsEngine thread, an articulation's controller, one pre-step and one post-step
// callback, as fast as possible) against a bare mj_step loop on the same model, in one process.
// Trials alternate and start from the same reset state; the bare loop replays the controls the
// full loop computed, so both integrate the very same trajectory through the same contacts.
// Thread: main (it starts and stops its own physics thread).
#include <mujoco/mujoco.h>

#include <functional>
#include <string>
#include <vector>

#include "urlab/control/articulation_control.h"
#include "urlab/physics/engine.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

struct LoopBenchOptions {
  int steps = 20000;  // steps per trial
  int trials = 9;
  // The articulation driven by the loop: its actuators are those whose names start with this.
  std::string prefix;
  // Installs the controller and targets on the articulation (bound to model `m`). Default: a PD
  // controller (kp 20, kv 2, torque limit 100) on every actuator, then SetBenchTargets.
  std::function<void(const mjModel* m, control::ArticulationControl&)> setup;
  // State readers attached to the full loop, as subsystems attach them: reader 0 takes every
  // frame from a ring (a recorder), odd readers poll the newest frame every millisecond (a
  // network broadcaster), even ones at 60 Hz (a viewer). Their threads run through the bare
  // trials too, so both loops share the machine with the same background.
  int subscribers = 0;
  // Something to weigh against the loop without it (`bench loop --record`): `attach` is called
  // once with the engine (stopped; subscribe here), `toggle(true)` before and `toggle(false)`
  // after each of its trials. Each trial then also runs the loop with it on, and the result's
  // attached_ratio is the loop's rate with it over the loop's rate without.
  std::function<void(physics::PhysicsEngine&)> attach;
  std::function<void(bool on)> toggle;
  // Receives the report lines (model line, one per trial, medians); empty: silent.
  std::function<void(const std::string&)> report;
};

struct LoopBenchResult {
  int nq = 0, nu = 0;
  bool identical = false;  // the bare loop reproduced the full loop's trajectory
  std::vector<double> bare_rates, loop_rates;  // steps per second, per trial
  double ratio = 0;                            // best full-loop rate / best bare rate
  double median_ratio = 0;                     // median full-loop rate / median bare rate
  std::vector<double> attached_rates;          // with LoopBenchOptions::attach: the loop with it on
  double attached_ratio = 0;                   // best attached rate / best loop rate
  double attached_median_ratio = 0;            // median attached rate / median loop rate
};

// Small alternating targets (0.1 * ((i % 3) - 1)) on every actuator, network source.
void SetBenchTargets(control::ArticulationControl& articulation);

// Drives the scene's first articulation as `urlab bench` does: `options.prefix` from `compiled`,
// and a setup that installs its controller (a PD when the scene gives none) and SetBenchTargets.
// Returns that articulation's configuration (controller type resolved).
ArticulationConfig DriveFirstArticulation(const SceneConfig& scene, const CompiledScene& compiled,
                                          LoopBenchOptions* options);

// Runs the benchmark on copies of `model`. Throws Error for steps or trials < 1.
LoopBenchResult RunLoopBench(const physics::Model& model, const LoopBenchOptions& options);

}  // namespace urlab::world
