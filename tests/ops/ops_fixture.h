#pragma once
// What every operation family's test plays: one articulation with a PD or no controller, a
// mocap body, a keyframe, behind the network subsystem (step server and topics on ephemeral
// loopback ports), so a test reaches one operation through the step server, through a topic and
// directly (the call the viewer's panel and the CLI make), and compares what each path answers.
// The ball (with its cap, two bodies) outnumbers the hinged link, so the ball's free joint is the
// articulation's free base (physics/free_base.h): set_twist and the 7-value qpos shortcut reach it.
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <zmq.hpp>

#include "net/step_test_client.h"
#include "support/step_server_fixture.h"
#include "urlab/ops/error.h"
#include "urlab/replay/recorder.h"

namespace urlab::ops::test {

using Json = nlohmann::json;
using net::test_client::Client;
using namespace std::chrono_literals;

inline constexpr const char* kArmXml = R"(<mujoco model="arm">
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
    <body name="ball" pos="0.5 0 0.049">
      <freejoint name="ball_free"/>
      <geom name="ball_geom" type="sphere" size="0.05" mass="0.1"/>
      <body name="ball_cap"><geom size="0.01" mass="0.001" contype="0" conaffinity="0"/></body>
    </body>
    <body name="target" mocap="true" pos="0 0 2">
      <geom type="sphere" size="0.05" contype="0" conaffinity="0"/>
    </body>
    <geom name="floor" type="plane" size="2 2 0.1"/>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
  </sensor>
  <keyframe>
    <key name="bent" qpos="0.7 0.5 0 0.049 1 0 0 0"/>
  </keyframe>
</mujoco>
)";

// What a refusal looks like, whichever path it took.
struct Refusal {
  std::string code, message;
  bool operator==(const Refusal&) const = default;
};
inline std::ostream& operator<<(std::ostream& os, const Refusal& r) {
  return os << r.code << ": " << r.message;
}
// The step server's error reply.
inline Refusal FromReply(const Json& reply) {
  return {reply.value("code", "(no error: " + reply.value("op", "?") + ")"),
          reply.value("message", "")};
}
// A direct call's OpError.
inline Refusal FromCall(const std::function<void()>& call) {
  try {
    call();
  } catch (const OpError& e) {
    return {e.code, e.message};
  }
  return {"(no error)", ""};
}

class OpsTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override { urlab::testing::WriteTextFile(dir_, "arm.xml", kArmXml); }
  // `controller`: ", controller: {...}" appended to the articulation's entry.
  // `recorder`: with a recorder subsystem the step server's recording operations use.
  void Play(const std::string& mode = "live", const std::string& controller = "",
            const std::string& extra = "", bool recorder = false) {
    if (recorder) {
      recorder_ = &static_cast<replay::RecorderSubsystem&>(
          manager_.AddSubsystem(std::make_unique<replay::RecorderSubsystem>()));
    }
    net::NetworkOptions o = urlab::testing::AutoPorts(mode);
    o.files_dir = dir_;  // clients name files in the test's folder
    Serve("control_source: network\narticulations:\n  - {name: arm, mjcf: arm.xml" + controller +
              "}\n" + extra,
          o, [&](net::NetworkSubsystem& net) { net.SetRecorder(recorder_); });
  }
  world::Session& session() { return manager_.session(); }
  // Waits for command `seq` (a direct call's) to take effect.
  void Wait(std::uint64_t seq) {
    ASSERT_TRUE(session().engine().WaitForCommand(seq, std::chrono::seconds(60)).ok());
  }

  replay::RecorderSubsystem* recorder_ = nullptr;
};

}  // namespace urlab::ops::test
