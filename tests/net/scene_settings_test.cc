// The network's scene section (urlab/net/scene_settings.h): registered with the scene parser,
// `network:` is parsed by the net module into its own settings; bad input is an InputError at its
// file:line as when world/scene_file parsed it.
#include "urlab/net/scene_settings.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "mujoco_test.h"
#include "scene_errors.h"
#include "urlab/net/network.h"
#include "urlab/world/scene_file.h"

namespace urlab {
namespace {

using testing::WithArm;

class NetworkSceneSection : public ::testing::Test {
 protected:
  void SetUp() override {
    net::RegisterSceneSections();
    dir_ = testing::MakeTempDir("network_section");
  }
  std::string dir_;
};

TEST_F(NetworkSceneSection, BadInputIsRefusedAtItsLine) {
  testing::WriteTextFile(dir_, "file.txt", "not a folder\n");
  struct Case {
    std::string yaml;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {WithArm("network: true\n"), 4, "network must be a mapping"},
      {WithArm("network: {port: 1}\n"), 4, "unknown key 'port' in network"},
      {WithArm("network: {enabled: maybe}\n"), 4, "network.enabled must be true or false"},
      {WithArm("network: {state: [a]}\n"), 4, "network.state must be a string"},
      {WithArm("network: {step_mode: fast}\n"), 4, "network.step_mode must be live or direct"},
      {WithArm("network: {full_state: all}\n"), 4,
       "network.full_state must be minimal, standard, full or none"},
      {WithArm("network: {camera_base_port: abc}\n"), 4, "network.camera_base_port must be"},
      {WithArm("network:\n  camera_base_port: -1\n"), 5,
       "network.camera_base_port must be 1 to 65535, not -1"},
      {WithArm("network: {camera_base_port: 99999}\n"), 4, "must be 1 to 65535, not 99999"},
      {WithArm("network: {camera_base_port: 5558.5}\n"), 4, "whole number"},
      {WithArm("network: {max_queued_steps: 0}\n"), 4,
       "network.max_queued_steps must be 1 to 10000000"},
      {WithArm("network: {files_dir: \"\"}\n"), 4, "network.files_dir must name a folder"},
      {WithArm("network: {files_dir: file.txt}\n"), 4, "exists and is not a folder"},
      {WithArm("network: {}\nnetwork: {}\n"), 5, "duplicate key 'network' in the scene"},
  };
  for (const Case& c : cases)
    testing::ExpectSceneRefusedAt(c.yaml, dir_ + "/s.yaml", c.line, c.message);
}

// Issue 38, case 9: two sockets on one endpoint (state equal to control passed validate and the
// run blamed its own pid for the port) and endpoints ZeroMQ cannot bind (a garbage endpoint
// failed at run time, with no scene line) are refused at their line.
TEST_F(NetworkSceneSection, EndpointsAreCheckedAtTheirLine) {
  struct Case {
    std::string yaml;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {WithArm("network:\n  state: tcp://127.0.0.1:6000\n  control: tcp://127.0.0.1:6000\n"), 6,
       "network.control: tcp://127.0.0.1:6000 is network.state's port 6000 too"},
      {WithArm("network:\n  rpc: tcp://*:5556\n"), 5,
       "network.rpc: tcp://*:5556 is network.control's port 5556 too"},
      {WithArm("network:\n  info: ipc:///tmp/a\n  rpc: ipc:///tmp/a\n"), 6,
       "network.rpc: ipc:///tmp/a is network.info's too"},
      {WithArm("network: {state: garbage}\n"), 4,
       "network.state: 'garbage' is not an endpoint (tcp://HOST:PORT, ipc://PATH or "
       "inproc://NAME)"},
      {WithArm("network: {rpc: \"tcp://127.0.0.1\"}\n"), 4, "network.rpc: 'tcp://127.0.0.1'"},
      {WithArm("network: {rpc: \"tcp://127.0.0.1:70000\"}\n"), 4, "port 1 to 65535 or *"},
      {WithArm("network: {rpc: \"tcp://:5559\"}\n"), 4, "network.rpc"},
      {WithArm("network: {rpc: \"ipc://\"}\n"), 4, "network.rpc"},
  };
  for (const Case& c : cases)
    testing::ExpectSceneRefusedAt(c.yaml, dir_ + "/s.yaml", c.line, c.message);
  // Ports the system chooses may repeat; "" is no socket; ipc and inproc names are fine.
  EXPECT_NO_THROW(world::ParseScene(
      WithArm("network:\n  state: tcp://127.0.0.1:*\n  control: tcp://127.0.0.1:*\n"
              "  info: \"\"\n  rpc: ipc:///tmp/urlab-rpc\n"),
      dir_ + "/ok.yaml"));
}

TEST_F(NetworkSceneSection, GoodValuesReachTheNetworksSettings) {
  const world::SceneConfig s = world::ParseScene(
      WithArm("network:\n  enabled: false\n  state: tcp://*:6000\n  rpc: ipc:///tmp/x.rpc\n"
              "  step_mode: direct\n  full_state: none\n  camera_base_port: 7000\n"
              "  files_dir: out\n  max_queued_steps: 10\n"),
      dir_ + "/s.yaml");
  const net::NetworkConfig& n = net::NetworkOf(s);
  EXPECT_FALSE(n.enabled);  // network: is parsed and used: not refused
  EXPECT_EQ(n.state, "tcp://*:6000");
  EXPECT_EQ(n.control, "tcp://127.0.0.1:5556");  // the default
  EXPECT_EQ(n.rpc, "ipc:///tmp/x.rpc");
  EXPECT_EQ(n.step_mode, "direct");
  EXPECT_EQ(n.full_state, "");
  EXPECT_EQ(n.camera_base_port, 7000);
  EXPECT_EQ(n.files_dir, (std::filesystem::path(dir_) / "out").string());
  EXPECT_EQ(n.max_queued_steps, 10u);
  // What the network subsystem and the cameras are given.
  const net::NetworkOptions o = net::NetworkOptionsFromScene(n);
  EXPECT_EQ(o.state, "tcp://*:6000");
  EXPECT_EQ(o.step_mode, "direct");
  EXPECT_EQ(o.max_queued_steps, 10u);
  EXPECT_EQ(net::EndpointPorts(n), (std::vector<int>{6000, 5556, 5557}));
  // A scene without the section has the defaults (docs/protocol.md's ports).
  world::SceneConfig plain = world::ParseScene(WithArm(""), dir_ + "/p.yaml");
  EXPECT_TRUE(net::NetworkOf(plain).enabled);
  EXPECT_EQ(net::NetworkOf(plain).camera_base_port, 5558);
  EXPECT_EQ(net::EndpointPorts(net::NetworkOf(plain)), (std::vector<int>{5555, 5556, 5557, 5559}));
  net::EditNetwork(plain).step_mode = "direct";
  EXPECT_EQ(net::NetworkOf(plain).step_mode, "direct");
}

}  // namespace
}  // namespace urlab
