#include "net/loopback.h"

namespace urlab::net {

bool IsLoopbackEndpoint(std::string_view e) {
  if (e.starts_with("ipc://") || e.starts_with("inproc://")) return true;
  for (const std::string_view scheme : {"tcp://", "ws://"}) {
    if (!e.starts_with(scheme)) continue;
    const std::string_view host = e.substr(scheme.size());
    return host.starts_with("127.") || host.starts_with("localhost:") || host.starts_with("[::1]:");
  }
  return false;  // any other transport (pgm, udp, ...) reaches beyond the host
}

}  // namespace urlab::net
