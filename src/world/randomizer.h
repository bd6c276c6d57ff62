#pragma once
// Randomizer: the mechanism that applies domain-randomisation draws (world/randomize.h, the
// policy) to one simulation's own model: it keeps the values the model was compiled with and,
// for each reset, writes nominal x scale (or nominal + offset) into the mjModel fields of each
// target, the PD controllers' gains, and returns the joint position offsets for the reset.
//
// Threading contract: construction on the main thread (engine not running); Apply with the
// engine's step mutex held (PhysicsEngine::WithLockedData); Check on any thread (reads only
// what construction recorded).
#include <mujoco/mujoco.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "urlab/control/controllers.h"
#include "urlab/physics/views.h"
#include "urlab/world/randomize.h"

namespace urlab::world {

class Randomizer {
 public:
  // One target: an articulation (bindings and its PD controller, if any) or a prop.
  struct Target {
    std::string name;
    bool prop = false;
    std::vector<int> geoms, bodies, dofs, actuators;
    std::vector<std::pair<std::string, int>> joints;  // hinge/slide joints: short name, qpos adr
    control::PdController* pd = nullptr;
    std::vector<control::PdGains> nominal_gains;  // per PD binding
  };
  // Records the nominal values of `m` (as compiled).
  Randomizer(const mjModel* m, std::vector<Target> targets);

  // The seed of the n-th randomised reset of a simulation whose draws derive from `seed` (a
  // session's: the scene's seed).
  static std::uint64_t ResetSeed(std::uint64_t seed, std::uint64_t n);

  // "" when `config` names only known targets and parameters they take, else the problem.
  std::string Check(const RandomizeConfig& config) const;

  // The result of one reset's draws.
  struct Applied {
    RandomDraws draws;
    std::vector<std::pair<int, double>> qpos_offsets;       // qpos address, offset
    std::vector<std::pair<std::string, double>> obs_noise;  // target, standard deviation
  };
  // Puts every field back to its nominal value, then draws `config` from `seed` (gravity x, y,
  // z first, then the targets in their order, each in the parameter table's order) and writes
  // the draws into `m` and the controllers; when masses, inertias or armature changed, the
  // constants MuJoCo derives from them are recomputed (mj_setConst). Step mutex held.
  // `pd_of` (empty: each target's own, Target::pd) gives the PD controller a target's gains go
  // to in the simulation `m` belongs to (a batch environment's own controllers); nullptr: the
  // gains are drawn (the same stream) but neither written nor put back.
  using PdOf = std::function<control::PdController*(std::size_t target)>;
  Applied Apply(const RandomizeConfig& config, std::uint64_t seed, mjModel* m,
                const PdOf& pd_of = {}) const;

 private:
  const Target* Find(const std::string& name) const;
  std::vector<Target> targets_;
  std::vector<mjtNum> friction_, mass_, inertia_, damping_, armature_, frictionloss_, gainprm_,
      biasprm_;
  mjtNum gravity_[3] = {0, 0, 0};
};

}  // namespace urlab::world
