#pragma once
// Who holds a TCP port, for "address already in use" messages. Linux only: reads /proc/net/tcp
// and /proc/net/tcp6 for a listening socket on the port and /proc/<pid>/fd for its inode.
#include <string>

namespace urlab::net {

// "pid 1234 (urlab run scene.yaml)" for the process listening on `port` (its command line,
// shortened), "" when it cannot tell (another user's process, or no /proc).
std::string DescribePortOwner(int port);

// The port of a "tcp://host:port" endpoint, -1 when there is none (ipc://, a wildcard port).
int EndpointPort(const std::string& endpoint);

// Why a socket could not bind, for the log and for the error of a run that needs its network:
// "port 5559 (step server) is in use by pid 1234 (urlab run scene.yaml)" when the port is taken
// (or "... in use by a process this user cannot see" when /proc does not tell), else
// "cannot bind the step server socket to ENDPOINT: REASON". `err` is the errno of the failure.
std::string DescribeBindFailure(const std::string& what, const std::string& endpoint, int err,
                                const std::string& reason);

}  // namespace urlab::net
