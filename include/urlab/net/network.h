#pragma once
// NetworkSubsystem: docs/protocol.md over ZeroMQ. One I/O thread owns every socket: it publishes
// each physics step's state (joint, ball joint, base_state and sensor topics) from its own
// every-step state subscription, drains the control SUB socket (control and set_gains topics,
// validated, applied as whole command frames or gain changes, or dropped and counted per
// reason), publishes discovery info at the protocol's cadence, and serves the step server
// (request/reply, msgpack or JSON; see src/net/step_server.h).
//
// Threading contract
// - Main thread: construction, the Subsystem hooks (the manager calls them), endpoints().
// - I/O thread (started in BeginPlay, joined in EndPlay): every ZeroMQ socket; nothing else
//   touches them.
// - Any thread: the counters (drops, published, dropped_frames).
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/net/scene_settings.h"
#include "urlab/wire/wire.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/subsystem.h"

namespace urlab::replay {
class PlaybackSlot;
class RecorderSubsystem;
}  // namespace urlab::replay
namespace urlab::world {
class BatchSubsystem;
class CameraStreams;
}  // namespace urlab::world

namespace urlab::net {

struct NetworkOptions {
  std::string state = "tcp://*:5555";            // PUB: state topics
  std::string control = "tcp://127.0.0.1:5556";  // SUB: control and set_gains
  std::string info = "tcp://*:5557";             // PUB: discovery
  std::string rpc = "tcp://127.0.0.1:5559";      // ROUTER: the step server ("" : none)
  std::string step_mode = "live";                // the step server's initial mode
  // Observation level of the state/full topic (minimal, standard, full), "" for none.
  std::string full_state = "standard";
  std::chrono::milliseconds lease_timeout{5000};
  // Added to the nice value of the I/O thread (and ZeroMQ's own I/O thread), so that under CPU
  // contention the physics thread keeps its rate; 0 leaves them as they are.
  int io_nice = 5;
  // Frames the I/O thread may fall behind the physics thread before frames are dropped.
  std::size_t ring_capacity = 4096;
  // The folder whose files step-server clients name (snapshots, recordings, replays): relative
  // to the working folder; "" : recordings/ there. The scene's inputs are never written.
  std::string files_dir;
  // Lockstep steps one client may have queued (beyond: queue_full).
  std::size_t max_queued_steps = 100000;
  // Shared-memory channels for step-server clients on this host that ask in hello (false:
  // ZeroMQ only), made in `shm_dir` ("": /dev/shm, else the temporary folder).
  bool shared_memory = true;
  std::string shm_dir;
  // A socket that cannot bind makes BeginPlay throw (before the simulation starts), naming the
  // port and the process holding it; false: logged, and the run goes on without that socket.
  bool require_bind = false;
  // Who this server is, for the step server's hello_ok (clients may require them): the scene's
  // name, an instance id, and the id of this run (unique per start; "" : none given).
  std::string scene_name;
  std::string instance;
  std::string server_session;
};

// The endpoints a scene file's `network:` section names (docs/protocol.md's defaults otherwise).
NetworkOptions NetworkOptionsFromScene(const NetworkConfig& config);

// Counts of what the network did, readable from any thread.
struct NetworkCounters {
  std::array<std::uint64_t, wire::kNumDrops> drops{};  // inbound messages dropped, per reason
  std::uint64_t controls_applied = 0;                  // control messages applied
  std::uint64_t gains_applied = 0;                     // set_gains messages applied
  std::uint64_t steps_published = 0;  // physics steps whose state went out (while subscribed)
  std::uint64_t frames_dropped = 0;   // steps the I/O thread could not keep up with
  std::uint64_t info_published = 0;   // discovery messages
  // State topic messages sent (topics no subscriber asked for are not sent, nor encoded).
  std::uint64_t state_messages = 0;
  std::uint64_t total_drops() const;
};

class NetworkSubsystem : public world::Subsystem {
 public:
  explicit NetworkSubsystem(NetworkOptions options = {});
  ~NetworkSubsystem() override;

  std::string_view name() const override { return "network"; }
  void BeginPlay(world::Session& session) override;
  void EndPlay(world::Session& session) override;
  // The bound endpoints and the counters, for the viewer's panel.
  std::vector<world::StatusLine> Status() const override;

  // The endpoints actually bound (a wildcard port resolved), "" for one that failed to bind.
  // Main thread, after BeginPlay.
  struct Endpoints {
    std::string state, control, info, rpc;
    std::vector<std::string> failures;  // why a configured socket did not bind, one line each
  };
  const Endpoints& endpoints() const { return bound_; }
  // Any thread.
  NetworkCounters counters() const;
  // The recorder the step server's recording operations use (its recorder() is looked up when a
  // request comes; add it to the Manager before this subsystem). nullptr: none. Main thread,
  // before BeginPlay.
  void SetRecorder(replay::RecorderSubsystem* recorder) { recorder_ = recorder; }
  // The cameras discovery lists and the step server's include_cameras reads (add their subsystem
  // to the Manager before this one, so its streams are bound when this begins). nullptr: none.
  // Main thread, before BeginPlay.
  void SetCameras(world::CameraStreams* cameras) { cameras_ = cameras; }
  // Where the step server shows the replay replay_start plays (the viewer's timeline: give the
  // viewer the same slot). nullptr: nowhere. Main thread, before BeginPlay.
  void SetPlayback(std::shared_ptr<replay::PlaybackSlot> slot) { playback_ = std::move(slot); }
  // The batched environments the step server's batch operations drive (add it to the Manager
  // before this subsystem). nullptr: none (they answer no_batch). Main thread, before BeginPlay.
  void SetBatch(world::BatchSubsystem* batch) { batch_ = batch; }

 private:
  struct Impl;
  NetworkOptions options_;
  Endpoints bound_;
  replay::RecorderSubsystem* recorder_ = nullptr;
  world::CameraStreams* cameras_ = nullptr;
  std::shared_ptr<replay::PlaybackSlot> playback_;
  world::BatchSubsystem* batch_ = nullptr;
  std::unique_ptr<Impl> impl_;
};

}  // namespace urlab::net
