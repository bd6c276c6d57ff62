// The ranges the operations accept, whoever asks (the step server, a topic, the viewer, the
// CLI); ops/value_ranges.h is the mechanism, docs/network.md lists them. Bounds are wide enough for
// any model we know and narrow enough that a typo or a hostile value (a negative viscosity, a time
// of 1e300) is refused instead of destabilising the run.
#include "ops/value_ranges.h"

namespace urlab::ops {

namespace {

constexpr double kBig = 1e6;   // positions (m, rad), velocities, physical option vectors
constexpr double kHuge = 1e9;  // controls, forces and torques

constexpr ValueRange kTable[] = {
    // set_sim_options
    {"timestep", 0, 1, /*min_open=*/true},
    {"impratio", 0, kBig, /*min_open=*/true},
    {"tolerance", 0, 1},
    {"density", 0, kBig},
    {"viscosity", 0, kBig},
    {"iterations", 1, 10000, false, /*integer=*/true},
    {"gravity", -kBig, kBig},
    {"wind", -kBig, kBig},
    {"magnetic", -kBig, kBig},
    // step, puppet step, set_qpos, reset, set_mocap_pose
    {"n_steps", 1, 100000, false, true},
    {"time", 0, 1e9},
    {"qpos", -kBig, kBig},
    {"qvel", -kBig, kBig},
    {"ctrl", -kHuge, kHuge},
    {"ctrl_map", -kHuge, kHuge},
    {"xfrc_applied", -kHuge, kHuge},
    {"pos", -kBig, kBig},
    {"quaternion norm", 0.9, 1.1},
    // batch_step, batch_reset (seeds: whole numbers a double holds exactly)
    {"actions", -kHuge, kHuge},
    {"seed", 0, 9007199254740991.0, false, true},
    // get_contacts, replay_start
    {"max_contacts", 0, 100000, false, true},
    {"speed", 0, 1000, /*min_open=*/true},
};

}  // namespace

std::span<const ValueRange> ValueRanges() { return kTable; }

}  // namespace urlab::ops
