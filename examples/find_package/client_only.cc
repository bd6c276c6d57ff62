// A program that only talks to a running simulator: it links urlab::client, which brings the wire
// format and ZeroMQ and nothing of the server (no MuJoCo model code, assimp, Embree or renderer).
// Here it encodes and decodes a control message (the wire format alone) and names the endpoints a
// running `urlab run` serves; examples/cpp_controller.cc is a client that drives one.
#include <cstdio>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "urlab/client/client.h"
#include "urlab/wire/wire.h"

int main() {
  try {
    const std::vector<std::pair<std::int32_t, float>> values = {{0, 0.5f}, {1, -0.25f}};
    std::string payload;
    urlab::wire::AppendControl(&payload, values);
    std::vector<std::pair<std::int32_t, float>> back;
    if (urlab::wire::DecodeControl(payload, &back) || back != values) {
      std::fprintf(stderr, "wire round trip failed\n");
      return 1;
    }
    std::printf("%s: %zu-byte control message for %zu actuators round-trips\n",
                urlab::wire::ControlTopic("robot").c_str(), payload.size(), back.size());
    std::printf("step server of a running urlab: %s\n",
                urlab::client::Endpoints::OnHost("127.0.0.1").rpc.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
