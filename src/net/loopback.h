#pragma once
// Whether a ZeroMQ endpoint is reachable only from this host (ipc://, inproc://, or tcp:// on a
// loopback address: 127.x.x.x, localhost, [::1]); sockets bound beyond it are logged.
// Thread: pure; any thread.
#include <string_view>

namespace urlab::net {

bool IsLoopbackEndpoint(std::string_view endpoint);

}  // namespace urlab::net
