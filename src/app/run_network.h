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

// The announce file of one run. It removes only what this run wrote: the file (after following
// symbolic links) it renamed into place, and only while that file is still there (the same
// inode: a later run announcing in the same place replaced it with its own, which stays). It
// never blocks: a FIFO is opened without waiting for a reader (none: logged, not announced).
class AnnounceFile {
 public:
  // Checks the path before anything runs (core/files.h's output rule; throws Error naming it):
  // a folder is refused, and so is a regular file that is there already and is not an announce
  // file (the user's, which would be overwritten and then deleted); an announce file, a run's
  // or a stale one, may be replaced.
  explicit AnnounceFile(std::string path);
  ~AnnounceFile();  // Remove()
  AnnounceFile(const AnnounceFile&) = delete;
  AnnounceFile& operator=(const AnnounceFile&) = delete;

  // Writes `json` (a temporary renamed into place; in place on a FIFO or device, without
  // blocking). Throws Error on a write error.
  void Write(const std::string& json);
  // Removes the file written, if it is still the one written; idempotent.
  void Remove();

 private:
  std::string path_;
  std::string written_;  // the file renamed into place ("": none)
  unsigned long long device_ = 0, inode_ = 0;
};

}  // namespace urlab::app
