#pragma once
// A session plus a step server on ports the system chooses: a world::Manager playing a scene from
// a folder of the test's own, served by a NetworkSubsystem whose endpoints are all loopback with
// ephemeral ports, so that any number of test runs can share the machine. Header-only: for the
// test executables that link urlab_net.
//
// Threading contract: test thread only (the manager's and the server's threads are their own).
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <zmq.hpp>

#include "support/mujoco_test.h"
#include "urlab/net/network.h"
#include "urlab/world/manager.h"
#include "urlab/world/scene_file.h"

namespace urlab::testing {

// Every endpoint on loopback, its port chosen by the system; `step_mode` as the scene's
// network: step_mode ("" keeps the default).
inline net::NetworkOptions AutoPorts(const std::string& step_mode = "") {
  net::NetworkOptions o;
  o.state = o.control = o.info = o.rpc = "tcp://127.0.0.1:*";
  if (!step_mode.empty()) o.step_mode = step_mode;
  return o;
}

// Adds a step server with `options` to `manager` (`configure` runs on it first: SetRecorder,
// SetBatch, ...) and begins play of `scene` (YAML text; paths in it relative to `dir`, where the
// scene file is said to be). Returns the server; a failure if it bound no step server.
inline net::NetworkSubsystem& Serve(
    world::Manager& manager, const std::string& dir, const std::string& scene,
    net::NetworkOptions options,
    const std::function<void(net::NetworkSubsystem&)>& configure = {}) {
  auto net = std::make_unique<net::NetworkSubsystem>(std::move(options));
  if (configure) configure(*net);
  auto& served = static_cast<net::NetworkSubsystem&>(manager.AddSubsystem(std::move(net)));
  manager.BeginPlay(world::ParseScene(scene, dir + "/scene.yaml"));
  EXPECT_FALSE(served.endpoints().rpc.empty()) << "no step server";
  return served;
}

// The fixture: the test writes its model files into dir_, adds what plays before the network (a
// recorder, a batch) to manager_, then calls Serve.
class ServedSessionTest : public MujocoTest {
 protected:
  void Serve(const std::string& scene, net::NetworkOptions options = AutoPorts(),
             const std::function<void(net::NetworkSubsystem&)>& configure = {}) {
    net_ = &testing::Serve(manager_, dir_, scene, std::move(options), configure);
  }
  std::string rpc() const { return net_->endpoints().rpc; }

  std::string dir_ = MakeTempDir("step_server");
  world::Manager manager_;
  net::NetworkSubsystem* net_ = nullptr;
  zmq::context_t ctx_{1};
};

}  // namespace urlab::testing
