#pragma once
// ObservationDelay: per articulation (a group of state addresses), the state as an observer sees
// it: each group's qpos, qvel, qacc, act, sensordata, actuator forces and body poses pass
// through a DelayLine (physics/delay_line.h) ticked once per physics step; the frame's time,
// step and command bookkeeping stay current. The StatePublisher runs it for subscriptions made
// as `observed` (the network's topics and step replies), never for the recorder or the viewer,
// which see the true state.
//
// Ticks: a stepped frame is one tick; a frame without a step (commands, pause) shows the last
// output; a discontinuity (reset, restore, set state, options) restarts every line, whose first
// value is then the state right after it.
//
// Threading contract: AddGroup on the main thread before the engine runs; Configure, Apply and
// everything else on the thread that publishes (the physics thread, or any thread holding the
// engine's step mutex: PhysicsEngine::WithLockedData).
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "urlab/physics/delay_line.h"
#include "urlab/physics/state_frame.h"

namespace urlab::physics {

// The state addresses of one articulation.
struct ObservedSlice {
  std::vector<int> qpos;      // qpos addresses
  std::vector<int> dof;       // qvel/qacc addresses
  std::vector<int> act;       // act addresses
  std::vector<int> sensor;    // sensordata addresses
  std::vector<int> actuator;  // actuator ids (actuator_force)
  std::vector<int> body;      // body ids (xpos, xquat)
};

class ObservationDelay {
 public:
  // Adds a group; returns its index.
  int AddGroup(std::string name, ObservedSlice slice);
  int num_groups() const { return static_cast<int>(groups_.size()); }
  // Index of a group by name, -1 when absent.
  int Find(const std::string& name) const;
  // Sets a group's delay (restarts its line). With `d`, the current state enters the line as its
  // first value (tick 0, like the state right after a reset), so the first step is tick 1.
  void Configure(int group, const DelaySpec& spec, const mjData* d = nullptr);
  const DelaySpec& spec(int group) const;
  // Observation noise: Gaussian with standard deviation `stddev` added to the group's qpos, qvel
  // and sensor values each time a step's state enters its line (so a delayed value carries the
  // noise of its measurement), drawn from `seed` (restarted with the line). 0: none.
  void SetNoise(int group, double stddev, std::uint64_t seed);
  // True when any group delays or adds noise.
  bool active() const;
  // Turns the current state in *frame into the observed one (see the ticks above).
  void Apply(StateFrame* frame);
  // The jitter drawn for a group's last tick, and its ticks since the last restart.
  int last_jitter(int group) const;
  std::int64_t ticks(int group) const;

 private:
  struct Group {
    std::string name;
    ObservedSlice slice;
    DelayLine<std::vector<mjtNum>> line;
    std::vector<mjtNum> scratch;
    double noise = 0;
    std::uint64_t noise_seed = 0, noise_state = 0;
  };
  static void AddNoise(Group& g);
  static void Gather(const ObservedSlice& s, const StateFrame& f, std::vector<mjtNum>* out);
  static void GatherData(const ObservedSlice& s, const mjData* d, std::vector<mjtNum>* out);
  static void Scatter(const ObservedSlice& s, const std::vector<mjtNum>& in, StateFrame* f);
  std::vector<Group> groups_;
};

}  // namespace urlab::physics
