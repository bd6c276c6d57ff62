#pragma once
// Subsystem: a part of a running world that the Manager starts, ticks and ends (network,
// recorder, viewer, cameras, input, debug drawing). A subsystem reads state through its own
// subscription (PhysicsEngine::SubscribeState / SubscribeEveryStep, made in BeginPlay), never
// live mjData, and sends work to the physics thread as queued commands or command frames.
//
// Threading contract
// - Main thread: every hook. Work on other threads (an I/O thread, a render thread) is the
//   subsystem's own, started in BeginPlay and joined in EndPlay.
// - The physics thread starts after every subsystem's BeginPlay and stops after every
//   subsystem's EndPlay. The Session passed in stays valid as long as the subsystem keeps
//   session.shared_from_this().
#include <string>
#include <string_view>
#include <vector>

#include "urlab/physics/engine.h"

namespace urlab::world {

class Session;

// The phases of one main-thread frame, in order.
enum class TickPhase {
  kInput,    // read input (window events, sockets) and turn it into commands
  kUpdate,   // advance the subsystem's own state
  kPresent,  // draw, publish, write out
};

// One line of a subsystem's status for a panel or a log ("endpoint", "tcp://*:5555").
struct StatusLine {
  std::string key;
  std::string value;
};

class Subsystem {
 public:
  virtual ~Subsystem() = default;
  // A short name for logs and lookups ("network", "viewer").
  virtual std::string_view name() const = 0;
  // After the scene is built and bound, before the physics thread starts: subscribe to state,
  // register callbacks, open sockets and windows. Throwing aborts BeginPlay (subsystems already
  // begun are ended in reverse order).
  virtual void BeginPlay(Session& session) = 0;
  // Once per phase of every Manager::Tick.
  virtual void Tick(Session& /*session*/, TickPhase /*phase*/) {}
  // Every engine event (reset, restore, divergence, error), on the main thread inside Tick,
  // after the event log and before the manager's listeners.
  virtual void OnEngineEvent(Session& /*session*/, const physics::EngineEvent& /*event*/) {}
  // Before the physics thread stops, in reverse order of BeginPlay: stop own threads, remove
  // callbacks (the engine still runs; subscriptions may simply be dropped).
  virtual void EndPlay(Session& /*session*/) {}
  // What the subsystem is doing, for the viewer's panel (endpoints, counters, a recording's
  // state). Main thread, while playing; empty by default.
  virtual std::vector<StatusLine> Status() const { return {}; }
  // True when the subsystem asks the host to end play (a viewer window closed, a screenshot
  // taken). The host's loop checks Manager::StopRequested() after each Tick. Main thread.
  virtual bool RequestsStop() const { return false; }
};

}  // namespace urlab::world
