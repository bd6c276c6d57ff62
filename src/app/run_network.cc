#include "app/run_network.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/core/version.h"

namespace urlab::app {

namespace {

// `endpoint` with its port replaced by `port` (a number or "*"); endpoints that are not
// tcp://host:port (ipc://, inproc://, "") come back unchanged.
std::string WithPort(const std::string& endpoint, const std::string& port) {
  if (!endpoint.starts_with("tcp://")) return endpoint;
  const auto colon = endpoint.rfind(':');
  const auto bracket = endpoint.rfind(']');  // tcp://[::1]:5555
  if (colon == std::string::npos || colon < 6 ||
      (bracket != std::string::npos && colon < bracket)) {
    return endpoint;
  }
  return endpoint.substr(0, colon + 1) + port;
}

}  // namespace

void ChooseNetworkPorts(net::NetworkConfig& n, const std::string& ports, int port_base) {
  if (ports == "auto") {
    for (std::string* e : {&n.state, &n.control, &n.info, &n.rpc}) *e = WithPort(*e, "*");
    return;
  }
  if (port_base <= 0) return;
  n.state = WithPort(n.state, std::to_string(port_base));
  n.control = WithPort(n.control, std::to_string(port_base + 1));
  n.info = WithPort(n.info, std::to_string(port_base + 2));
  n.camera_base_port = port_base + 3;
  n.rpc = WithPort(n.rpc, std::to_string(port_base + 4));
}

std::string SceneName(const std::string& scene_path) {
  return std::filesystem::path(scene_path).stem().string();
}

std::string NewServerSession() {
  std::random_device random;
  std::uniform_int_distribution<unsigned> nibble(0, 15);
  std::string id;
  for (int i = 0; i < 16; ++i) id += "0123456789abcdef"[nibble(random)];
  return id;
}

std::string AnnounceJson(const net::NetworkOptions& options,
                         const net::NetworkSubsystem::Endpoints& bound,
                         const world::CameraStreams* cameras) {
  nlohmann::ordered_json j;
  j["format"] = 1;
  j["pid"] = static_cast<long>(::getpid());
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  j["host"] = host;
  j["urlab_version"] = kVersion;
  j["scene"] = options.scene_name;
  j["instance"] = options.instance;
  j["session"] = options.server_session;
  const auto or_null = [](const std::string& e) {
    return e.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(e);
  };
  j["endpoints"] = {{"state", or_null(bound.state)},
                    {"control", or_null(bound.control)},
                    {"info", or_null(bound.info)},
                    {"rpc", or_null(bound.rpc)}};
  nlohmann::ordered_json cams = nlohmann::ordered_json::array();
  if (cameras) {
    for (const world::CameraStreamInfo& s : cameras->Streams()) {
      if (s.endpoint.empty()) continue;
      cams.push_back({{"articulation", s.articulation},
                      {"stream", s.stream},
                      {"topic", s.topic},
                      {"endpoint", s.endpoint}});
    }
  }
  j["cameras"] = std::move(cams);
  // How a client can reach the step server, best first. Other transports add their offer here.
  nlohmann::ordered_json transports = nlohmann::ordered_json::array();
  if (!bound.rpc.empty()) transports.push_back({{"kind", "zmq"}, {"endpoint", bound.rpc}});
  j["transports"] = std::move(transports);
  return j.dump(2) + "\n";
}

namespace {

// True when `file` (a regular file) holds an announce file's JSON: an object with "format" and
// "endpoints" (at most 1 MiB of it is read).
bool IsAnnounceFile(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  std::string text(1 << 20, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  return j.is_object() && j.contains("format") && j.contains("endpoints");
}

}  // namespace

AnnounceFile::AnnounceFile(std::string path) : path_(std::move(path)) {
  const OutputTarget t = ResolveOutput(path_);  // refuses "" and a folder, naming the path
  struct stat st {};
  if (t.mode == OutputTarget::Mode::kReplace && ::stat(t.file.c_str(), &st) == 0 &&
      S_ISREG(st.st_mode) && !IsAnnounceFile(t.file)) {
    throw Error("--announce " + path_ + ": " +
                (t.file == path_ ? std::string("a file") : "it points to " + t.file + ", a file") +
                " that is not an announce file is there already (it would be overwritten, then "
                "removed when the run ends); name another file or remove it");
  }
}

AnnounceFile::~AnnounceFile() { Remove(); }

void AnnounceFile::Write(const std::string& json) {
  const OutputTarget t = ResolveOutput(path_);
  if (t.mode == OutputTarget::Mode::kInPlace) {
    // A device or FIFO: opened without waiting (a FIFO nobody reads refuses at once) and
    // written as is; never removed.
    const int fd = t.descriptor >= 0 ? ::dup(t.descriptor)
                                     : ::open(t.file.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      if (errno == ENXIO) {
        spdlog::warn("--announce {}: a FIFO with no reader; the endpoints are not announced",
                     path_);
        return;
      }
      throw Error("--announce " + path_ + ": cannot open: " + std::strerror(errno));
    }
    std::size_t done = 0;
    while (done < json.size()) {
      const ssize_t n = ::write(fd, json.data() + done, json.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && errno == EAGAIN) {  // a reader that does not read: not waited for either
        spdlog::warn("--announce {}: its reader does not read; the announcement is cut short",
                     path_);
        break;
      }
      if (n < 0) {
        const std::string why = std::strerror(errno);
        ::close(fd);
        throw Error("--announce " + path_ + ": cannot write: " + why);
      }
      done += static_cast<std::size_t>(n);
    }
    ::close(fd);
    return;
  }
  // A regular file or nothing (through a symbolic link: its target): renamed into place. The
  // temporary's identity is the file's once renamed.
  unsigned long long device = 0, inode = 0;
  WriteFileAtomic(t.file, json, [&](const std::string& temporary) {
    struct stat st {};
    if (::stat(temporary.c_str(), &st) == 0) {
      device = st.st_dev;
      inode = st.st_ino;
    }
  });
  written_ = t.file;
  device_ = device;
  inode_ = inode;
}

void AnnounceFile::Remove() {
  if (written_.empty()) return;
  struct stat st {};
  if (::lstat(written_.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_dev == device_ &&
      st.st_ino == inode_) {
    ::unlink(written_.c_str());
  }
  written_.clear();
}

}  // namespace urlab::app
