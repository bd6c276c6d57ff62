#include "net/port_owner.h"

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <iterator>
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

// " (urlab run scene.yaml)": the program's file name and its arguments, shortened; the short
// name from `comm` when the command line cannot be read.
std::string CommandLine(const fs::path& proc) {
  std::ifstream in(proc / "cmdline", std::ios::binary);
  const std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string text;
  std::size_t start = 0;
  while (start < raw.size()) {
    std::size_t end = raw.find('\0', start);
    if (end == std::string::npos) end = raw.size();
    std::string arg = raw.substr(start, end - start);
    if (text.empty()) arg = fs::path(arg).filename().string();  // the program: its name
    if (!arg.empty()) text += (text.empty() ? "" : " ") + arg;
    start = end + 1;
  }
  if (text.empty()) {
    std::ifstream comm(proc / "comm");
    std::getline(comm, text);
  }
  constexpr std::size_t kMax = 120;
  if (text.size() > kMax) text = text.substr(0, kMax - 3) + "...";
  return text.empty() ? "" : " (" + text + ")";
}

}  // namespace

std::string DescribeBindFailure(const std::string& what, const std::string& endpoint, int err,
                                const std::string& reason) {
  const int port = EndpointPort(endpoint);
  if (err == EADDRINUSE && port > 0) {
    const std::string owner = DescribePortOwner(port);
    return "port " + std::to_string(port) + " (" + what + ") is in use by " +
           (owner.empty() ? "a process this user cannot see (another user's, or outside this "
                            "process namespace)"
                          : owner);
  }
  return "cannot bind the " + what + " socket to " + endpoint + ": " + reason;
}

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
      return "pid " + pid + CommandLine(proc.path());
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
