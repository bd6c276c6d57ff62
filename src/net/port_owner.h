#pragma once
// Who holds a TCP port, for "address already in use" messages. Linux only: reads /proc/net/tcp
// and /proc/net/tcp6 for a listening socket on the port and /proc/<pid>/fd for its inode.
#include <string>

namespace urlab::net {

// "process 1234 (urlab)" for the process listening on `port`, "" when it cannot tell (another
// user's process, or no /proc).
std::string DescribePortOwner(int port);

// The port of a "tcp://host:port" endpoint, -1 when there is none (ipc://, a wildcard port).
int EndpointPort(const std::string& endpoint);

}  // namespace urlab::net
