#include "net/port_owner.h"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace urlab::net {

namespace fs = std::filesystem;

namespace {

// The inode of a listening socket on `port` in one /proc/net table, "" when none.
std::string ListeningInode(const char* table, int port) {
  std::ifstream in(table);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string sl, local, remote, state, queues, timer, retr, uid, timeout, inode;
    if (!(f >> sl >> local >> remote >> state >> queues >> timer >> retr >> uid >> timeout >>
          inode)) {
      continue;
    }
    const auto colon = local.rfind(':');
    if (colon == std::string::npos || state != "0A") continue;  // 0A: LISTEN
    if (std::stoi(local.substr(colon + 1), nullptr, 16) == port) return inode;
  }
  return "";
}

}  // namespace

std::string DescribePortOwner(int port) {
  if (port <= 0) return "";
  std::string inode = ListeningInode("/proc/net/tcp", port);
  if (inode.empty()) inode = ListeningInode("/proc/net/tcp6", port);
  if (inode.empty() || inode == "0") return "";
  const std::string target = "socket:[" + inode + "]";
  std::error_code ec;
  for (const auto& proc : fs::directory_iterator("/proc", ec)) {
    const std::string pid = proc.path().filename().string();
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    for (const auto& fd : fs::directory_iterator(proc.path() / "fd", ec)) {
      std::error_code lec;
      if (fs::read_symlink(fd.path(), lec).string() != target) continue;
      std::ifstream comm(proc.path() / "comm");
      std::string name;
      std::getline(comm, name);
      return "process " + pid + (name.empty() ? "" : " (" + name + ")");
    }
    ec.clear();
  }
  return "";
}

int EndpointPort(const std::string& endpoint) {
  if (!endpoint.starts_with("tcp://")) return -1;
  const auto colon = endpoint.rfind(':');
  if (colon == std::string::npos || colon + 1 >= endpoint.size()) return -1;
  const std::string port = endpoint.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos) {
    return -1;
  }
  return std::stoi(port);
}

}  // namespace urlab::net
