#pragma once
// The network choices of `urlab run`/`record`/`view` beyond the scene file: the ports
// (`--ports auto`: the system chooses; `--port-base N`: N.. N+4 in the defaults' layout), the
// identity a step-server client can require (scene name, instance id, the run's session id), and
// the announce file a launcher waits for (`--announce FILE`: the bound endpoints as JSON).
// Thread: main.
#include <string>
#include <vector>

#include "urlab/net/network.h"
#include "urlab/world/camera_streams.h"
#include "urlab/world/scene_file.h"

namespace urlab::app {

// Rewrites the port of every tcp:// endpoint of the scene's network section: "auto" gives each
// a port the system chooses (`*`), `port_base` > 0 gives state N, control N+1, info N+2, cameras
// from N+3 upward and the step server N+4 (the defaults are N = 5555). ipc:// and other
// transports, and empty endpoints, are left as they are. "scene" with port_base 0: unchanged.
// (With "auto" the caller gives the cameras ephemeral ports: CameraOptions::base_port = 0.)
void ChooseNetworkPorts(net::NetworkConfig& network, const std::string& ports, int port_base);

// The scene's name: the scene file's stem ("arm" for scenes/arm.yaml).
std::string SceneName(const std::string& scene_path);

// A fresh id for this run (16 hex digits from the system's random source).
std::string NewServerSession();

// The announce file's JSON (docs/network.md, "Announce file"): format version, pid, host,
// scene, instance, session, the bound endpoints, each camera stream's endpoint, and the
// transports the step server offers.
std::string AnnounceJson(const net::NetworkOptions& options,
                         const net::NetworkSubsystem::Endpoints& bound,
                         const world::CameraStreams* cameras);

}  // namespace urlab::app
