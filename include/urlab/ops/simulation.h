#pragma once
// Simulation control: reset (the initial state, a keyframe, joint values after it), one
// articulation's keyframe reset, pause, speed, lockstep steps and a forward pass. One typed
// function per operation with one validation (ops::OpError with the wire code, nothing applied),
// called alike by the step server (reset, set_paused, set_mode, set_sim_speed, step in direct mode,
// forward), the viewer's panel and hotkeys (Reset, Pause/Run, Step, the speed slider, an
// articulation's keyframe Reset) and the CLI (`urlab run`: SIGUSR1 pause, the reset after a
// divergence).
//
// Thread: any (each queues engine commands or sets an engine atomic; see world/session.h).
// Functions that queue a command return its sequence number (PhysicsEngine::WaitForCommand).
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/ops/error.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// The articulation named `name`; unknown_articulation otherwise.
const world::Articulation& RequireArticulation(const world::Session& session,
                                               std::string_view name);

// One joint's qpos values (its qpos width: 7 free, 4 ball, 1 hinge/slide), by the articulation's
// short joint name.
struct JointQpos {
  std::string articulation, joint;
  std::vector<double> qpos;
};

struct ResetRequest {
  // "": the initial state (qpos0, then every articulation's initial keyframe). Else a keyframe
  // of the whole model by full ("dog_home") or short ("home") name; a short name two
  // articulations share is ambiguous_keyframe, an unknown one unknown_keyframe.
  std::string keyframe;
  // Written after the reset, in the same iteration's commands (dim_mismatch for a wrong width,
  // bad_value for an unknown joint, a value out of range or a quaternion whose norm is not ~1).
  std::vector<JointQpos> joints;
  // Replaces the reset to the initial state once the request was checked (a randomised reset,
  // which draws new model parameters first; returns its command's sequence number). With a
  // keyframe it runs first and the keyframe sets the state after it.
  std::function<std::uint64_t()> randomize;
};
std::uint64_t Reset(world::Session& session, const ResetRequest& request);

// One articulation to keyframe `keyframe` (its initial keyframe when empty); the rest of the
// scene is untouched. unknown_articulation, unknown_keyframe.
std::uint64_t ResetArticulation(world::Session& session, std::string_view articulation,
                                std::string_view keyframe = {});

// Pauses or resumes: in order with the other commands (a command; its sequence number), or at
// once (the engine's atomic, as a user's key or signal expects; returns 0).
enum class When { kInOrder, kNow };
std::uint64_t SetPaused(world::Session& session, bool paused, When when = When::kInOrder);

// The pacing speed in percent of real time: a finite number (bad_value), clamped to 5..100 and
// rounded. Returns the speed now in effect.
int SetSpeed(world::Session& session, double percent);

// Recomputes the derived quantities of the current state (mj_forward) without stepping.
std::uint64_t Forward(world::Session& session);

// Queues a window of `steps` physics steps (lockstep: the engine is paused between windows);
// `steps` an integer in the range of n_steps (bad_value).
std::uint64_t Step(world::Session& session, int steps);

}  // namespace urlab::ops
