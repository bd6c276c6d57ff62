#pragma once
// TwistController: drives an articulation with a free base by a body twist (vx forward, vy left,
// yaw rate), the description's MjTwistController. It is attached by the viewer's Possess or the
// network's set_twist, holds the commanded twist (clamped to the scene's maxima) and the action
// bits, and what that twist moves depends on its mode (TwistMode):
// - gait: the articulation's GaitController (gait.h) reads the twist and walks the legs through
//   their actuators; this class applies nothing itself;
// - policy: nothing is applied; a walking policy reads the twist from the `{art}/twist` topic;
// - hover, for bodies without legs: a PD on the base's planar velocity through the root body's
//   xfrc_applied: every step it writes
//   force   = M * linear_gain * (v_cmd - v)      in the world's horizontal plane (z force 0)
//   torque  = Izz * yaw_gain * (yaw_rate_cmd - wz)   about the world's z axis
// where M is the articulation's mass, v_cmd is (vx, vy) turned from the base's heading frame
// (the yaw of the root body's x axis) into the world, v and wz are the free joint's linear and
// yaw velocities, and Izz is the articulation's inertia about the vertical through its centre of
// mass (each body's own z inertia plus m * horizontal distance^2, recomputed every step); the
// force acts at that centre of mass (its lever to the root body's is added as torque). The
// gains are decay rates (1/s) of the velocity errors. The actuators keep following their own
// control source: this moves the base like a hovercraft (a legged robot slides and tips; give it
// a gait controller instead). In hover mode, while attached the root body's xfrc_applied row
// belongs to the controller (other forces on it are overwritten; one-shot forces such as the
// viewer's perturbation are added on top by the engine); detaching zeroes the row once.
//
// Commands are clamped to the scene's per-articulation maxima. Up to 10 action bits (held action
// keys or gamepad buttons) travel beside the twist for a policy to read.
//
// Threading contract
// - Main thread, before the engine runs: construction, Bind.
// - Any thread: SetTwist, twist, SetActions, actions, Attach, attached, settings.
// - Physics thread (step mutex held): Apply.
#include <mujoco/mujoco.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string_view>
#include <vector>

namespace urlab::control {

// What the commanded twist drives (the scene's `twist: {mode: ...}`).
enum class TwistMode {
  kPolicy,  // nothing here: the twist is published for a walking policy (`{art}/twist`)
  kGait,    // the articulation's gait controller (gait.h) walks it, through its actuators
  kHover,   // the root-body force and torque below: for bodies without legs
};
// "policy", "gait", "hover"; ParseTwistMode is the inverse (std::nullopt for other names).
const char* ToString(TwistMode mode);
std::optional<TwistMode> ParseTwistMode(std::string_view name);

struct TwistSettings {
  TwistMode mode = TwistMode::kPolicy;
  double max_vx = 1.0;        // m/s, forward and back
  double max_vy = 0.5;        // m/s, left and right
  double max_yaw_rate = 1.5;  // rad/s
  double linear_gain = 4.0;   // 1/s
  double yaw_gain = 4.0;      // 1/s
};

struct Twist {
  double vx = 0, vy = 0, yaw_rate = 0;
  bool operator==(const Twist&) const = default;
};

inline constexpr int kNumActionBits = 10;

class TwistController {
 public:
  explicit TwistController(TwistSettings settings = {}) : settings_(settings) {}

  // Binds to the articulation whose free joint is `free_joint` (its body is the root). Throws
  // Error when the joint is not a free joint.
  void Bind(const mjModel* m, int free_joint);
  int root_body() const { return root_; }
  const TwistSettings& settings() const { return settings_; }

  // Sets the commanded twist, each component clamped to +-its maximum; returns what was stored.
  Twist SetTwist(Twist t);
  Twist twist() const;
  // Held action bits (bits above kNumActionBits are dropped).
  void SetActions(std::uint32_t mask) {
    actions_.store(mask & ((1u << kNumActionBits) - 1), std::memory_order_relaxed);
  }
  std::uint32_t actions() const { return actions_.load(std::memory_order_relaxed); }
  // Attaching starts the controller (with a zero twist and no actions); detaching stops it.
  void Attach(bool on);
  bool attached() const { return attached_.load(std::memory_order_acquire); }

  // Physics thread: in hover mode writes the root body's xfrc_applied row (see above); otherwise
  // nothing.
  void Apply(const mjModel* m, mjData* d);

 private:
  TwistSettings settings_;
  int root_ = -1, dof_ = -1;
  std::vector<int> bodies_;   // the root's subtree
  mutable std::mutex mutex_;  // guards twist_
  Twist twist_;
  std::atomic<std::uint32_t> actions_{0};
  std::atomic<bool> attached_{false};
  bool applied_ = false;  // physics thread: the row holds our force
};

}  // namespace urlab::control
