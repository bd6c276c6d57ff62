#pragma once
// Commands for the physics thread and the queue that carries them. Every change another thread
// asks of the simulation (resets, restores, state writes, mocap poses, one-shot forces, option
// changes, a replaced model, pause) is one Command with a sequence number; the physics thread
// applies them in submission order at the top of an iteration, and a caller can wait until its
// command has taken effect.
//
// Threading contract (CommandQueue)
// - Any thread: Push (assigns the sequence number), Wait, last_applied, pending.
// - Physics thread (the engine's step mutex held): TakeAll, then Finish once per taken command,
//   in order.
#include <mujoco/mujoco.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "urlab/physics/model.h"
#include "urlab/physics/state.h"

namespace urlab::physics {

// A hook run on the physics thread with the step mutex held.
using StepCallback = std::function<void(const mjModel*, mjData*)>;

namespace cmd {
// mj_resetData.
struct Reset {};
// mj_resetDataKeyframe(key).
struct ResetKeyframe {
  int key = -1;
};
// Runs `fn` (e.g. a per-articulation keyframe reset); `label` names it in events.
struct ResetCustom {
  StepCallback fn;
  std::string label;
};
// Restores a full state (bit-exact continuation).
struct Restore {
  PhysicsState state;
};
// Writes qpos[adr .. adr + values.size()) (e.g. one joint's positions).
struct SetQpos {
  int adr = 0;
  std::vector<mjtNum> values;
};
// Writes qvel[adr .. adr + values.size()).
struct SetQvel {
  int adr = 0;
  std::vector<mjtNum> values;
};
// Sets the pose of one mocap body (quaternion normalised when applied).
struct SetMocap {
  int mocap_id = -1;
  std::array<mjtNum, 3> pos{};
  std::array<mjtNum, 4> quat{1, 0, 0, 0};
};
// Adds a wrench at a body's centre of mass (world frame, xfrc_applied layout) for the next
// `steps` steps only: it is removed again after the last of them (and at a reset or restore).
struct ApplyForce {
  int body = -1;
  std::array<mjtNum, 3> force{};
  std::array<mjtNum, 3> torque{};
  int steps = 1;
};
// Changes physics options (timestep, gravity, integrator, ...); `label` names it in events.
struct SetOptions {
  std::function<void(mjOption&)> fn;
  std::string label;
};
// Copies the values of `model` (compiled from the scene's edited or re-read spec) into the
// running model in place (CopyModelValuesInPlace, model.h), then mj_forward: mjData, the whole
// state, is untouched. Refused at submission when `model` does not have the running model's
// structure (InPlaceDifference). `keep_options`: the options in effect (run-time changes
// included) stay instead of the new model's. `label` names it in logs.
struct ReplaceModel {
  std::shared_ptr<const Model> model;
  bool keep_options = false;
  std::string label;
};
// Pauses or resumes the loop, in order with the other commands.
struct SetPaused {
  bool paused = true;
};
// Writes the given pieces of the state (each a run of values at an address of qpos, qvel or
// ctrl) and, when given, the time, then mj_forward: the client owns the state (puppet mode).
struct SetState {
  struct Run {
    int adr = 0;
    std::vector<mjtNum> values;
  };
  std::vector<Run> qpos, qvel, ctrl;
  std::optional<double> time;
};
// Runs `fn` with the current model and state, read only: a query that needs more than a state
// frame carries (e.g. the contact list with forces). `label` names it in events.
struct Inspect {
  std::function<void(const mjModel*, const mjData*)> fn;
  std::string label;
};
// mj_forward: recomputes the derived quantities from the current state (no discontinuity).
struct Forward {};
// Runs exactly `n` full iterations (controls, step, post-step work) even while paused, without
// pacing; the command is finished after the last one, and commands queued behind it wait until
// then (lockstep stepping).
struct Step {
  int n = 1;
};
}  // namespace cmd

using Command =
    std::variant<cmd::Reset, cmd::ResetKeyframe, cmd::ResetCustom, cmd::Restore, cmd::SetQpos,
                 cmd::SetQvel, cmd::SetMocap, cmd::ApplyForce, cmd::SetOptions, cmd::SetPaused,
                 cmd::Step, cmd::Forward, cmd::SetState, cmd::Inspect, cmd::ReplaceModel>;

// Short name of a command's kind ("reset", "restore", "set_qpos", ...; declared with its
// validation and application in src/physics/command_kinds.cc).
const char* CommandName(const Command& c);

// The outcome of one command.
enum class CommandStatus {
  kApplied,  // took effect
  kFailed,   // applying it threw (error says why); the simulation was left as before or reset
  kTimeout,  // not applied within the wait (it still will be, in order)
  kUnknown,  // no such sequence number was ever issued
};

struct CommandResult {
  CommandStatus status = CommandStatus::kUnknown;
  std::string error;  // kFailed: the reason
  bool ok() const { return status == CommandStatus::kApplied; }
};

// FIFO of commands with sequence numbers and waiters.
class CommandQueue {
 public:
  using Clock = std::chrono::steady_clock;
  struct Entry {
    std::uint64_t seq = 0;
    Command command;
  };

  // Any thread: appends a command; returns its sequence number (1, 2, ...).
  std::uint64_t Push(Command command);
  // Any thread: blocks until command `seq` was applied or failed, or `timeout` passed.
  CommandResult Wait(std::uint64_t seq, Clock::duration timeout);
  // Any thread: newest sequence number applied or failed (all older ones are too).
  std::uint64_t last_applied() const { return finished_.load(std::memory_order_acquire); }
  // Any thread: commands pushed but not yet taken.
  bool pending() const { return has_pending_.load(std::memory_order_acquire); }

  // Physics thread: moves every queued command (in order) to the end of *out.
  void TakeAll(std::deque<Entry>* out);
  // Physics thread: records the outcome of the oldest taken, unfinished command (`error` empty
  // on success) and releases its waiters.
  void Finish(std::uint64_t seq, std::string error = {});

  // Failures remembered for Wait; a wait for an older failed command reports it as applied
  // (callers wait right after submitting, so only a very stale wait could see this).
  static constexpr std::size_t kRememberedFailures = 1024;

 private:
  std::mutex mutex_;  // guards queue_, next_seq_, failures_
  std::condition_variable cv_;
  std::deque<Entry> queue_;
  std::uint64_t next_seq_ = 1;
  std::map<std::uint64_t, std::string> failures_;
  std::atomic<bool> has_pending_{false};
  std::atomic<std::uint64_t> finished_{0};
  std::atomic<int> waiters_{0};
};

}  // namespace urlab::physics
