#pragma once
// Legs of a floating-base robot, found from the model's joint structure, with their forward and
// inverse kinematics in the root body's frame. Used by the gait controller (gait.h).
//
// A leg is the chain of actuated hinge joints below one child body of the root: the bodies from
// that child down to the deepest body holding one of those joints (a serial chain, no branching
// joints), and a foot point: the site or geom centre of that end body's subtree that is lowest
// in the standing pose. The kinematics are MuJoCo's own (mj_kinematics' composition of body
// offsets and joint rotations), evaluated on the model's constants for any joint angles, so
// nothing here reads or writes mjData after construction.
//
// Threading: FindLegs on the main thread (it makes a scratch mjData); the rest are pure
// functions of their arguments, safe on any thread.
#include <mujoco/mujoco.h>

#include <span>
#include <string>
#include <vector>

#include "urlab/control/controller.h"

namespace urlab::control::legs {

// One actuated hinge of a leg.
struct LegJoint {
  int joint = -1;    // MuJoCo joint id
  int binding = -1;  // index into the controller's bindings (its actuator)
  int qpos_adr = -1, dof_adr = -1;
  double qpos0 = 0;
  bool limited = false;
  double range[2] = {0, 0};
  double pos[3] = {0, 0, 0};   // anchor in its body's frame
  double axis[3] = {0, 0, 1};  // axis in its body's frame
};

// One body of the chain: its offset from the parent and the leg joints it holds.
struct ChainLink {
  double pos[3] = {0, 0, 0};
  double quat[4] = {1, 0, 0, 0};
  std::vector<int> joints;  // indices into Leg::joints, in the body's joint order
};

struct Leg {
  std::string name;              // the end body's name
  std::vector<ChainLink> links;  // from the root's child to the end body
  std::vector<LegJoint> joints;  // root outwards
  double foot[3] = {0, 0, 0};    // foot point in the end body's frame
  int foot_geom = -1;            // the colliding geom nearest the foot point, -1 when none
  std::vector<double> stand_q;   // joint angles of the standing pose
  double stand[3] = {0, 0, 0};   // foot point of the standing pose, root frame
  double hip[3] = {0, 0, 0};     // first joint's anchor, root frame
};

// The legs of the articulation rooted at body `root` among the actuated joints of `bindings`, in
// the standing pose `stand_qpos` (the model's full qpos). Throws Error naming what is wrong:
// no free joint on the root, an actuated joint that is not a hinge, a branching leg, a leg with
// fewer than three hinges, a passive hinge inside a leg.
std::vector<Leg> FindLegs(const mjModel* m, int root, std::span<const ActuatorBinding> bindings,
                          const mjtNum* stand_qpos);

// Foot point of `leg` in the root frame for joint angles q (one per leg joint); with `jac`
// (3 x n, row-major) also d(foot)/dq.
void FootPosition(const Leg& leg, std::span<const double> q, double foot[3], double* jac);

// Joint angles that put the foot at `target` (root frame): damped least squares from the angles
// in q (updated in place), within the joint ranges. Returns the remaining distance (m).
double SolveIk(const Leg& leg, const double target[3], std::span<double> q);

}  // namespace urlab::control::legs
