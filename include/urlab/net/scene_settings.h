#pragma once
// The network's scene section `network:`: the endpoints of the streaming topics, discovery and the
// step server, the step server's initial mode, the state/full level, the first camera port, the
// folder step-server clients name files in and a client's lockstep queue. The net module owns the
// settings and their parser; the scene file parser hands it the section through the registration
// (src/world/scene_section.h), so a bad value is an InputError at its file:line. The command line
// (`urlab run --ports/--port-base/--step-mode/--files-dir`) changes them after loading
// (EditNetwork).
//
// The cameras' first port is the network's setting but the camera subsystem's socket: the app
// passes camera_base_port (and the ports the endpoints bind, EndpointPorts) to it (camera sits
// beside net, not above it).
//
// Threading contract: RegisterSceneSections before any scene is parsed (main thread at start);
// the settings are value types.
#include <cstddef>
#include <string>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/world/scene_file.h"

namespace urlab::net {

struct NetworkConfig {
  bool enabled = true;
  std::string state = "tcp://*:5555";
  std::string control = "tcp://127.0.0.1:5556";
  std::string info = "tcp://*:5557";
  std::string rpc = "tcp://127.0.0.1:5559";  // the step server (request/reply)
  std::string step_mode = "live";            // live | direct (lockstep)
  std::string full_state = "standard";       // state/full level: minimal|standard|full, "": none
  int camera_base_port = 5558;               // a TCP port 1..65535: the first camera stream's
  // The folder whose files step-server clients name (absolute; relative in the scene: to the
  // scene file's folder). "" : recordings/ in the working folder of the run.
  std::string files_dir;
  std::size_t max_queued_steps = 100000;  // lockstep steps one client may queue
  SourceLocation where;
};

inline constexpr const char* kNetworkSection = "network";

// Registers the parser of `network:` (idempotent).
void RegisterSceneSections();

// The scene's settings, or the defaults when it has no `network:` section.
const NetworkConfig& NetworkOf(const world::SceneConfig& scene);
// The scene's settings to change (made the defaults first when absent).
NetworkConfig& EditNetwork(world::SceneConfig& scene);

// The port numbers of the endpoints that name one (state, control, info, rpc), for the cameras
// to skip.
std::vector<int> EndpointPorts(const NetworkConfig& network);

}  // namespace urlab::net
