#pragma once
// Shared set-up of the libFuzzer targets: a private temporary folder (removed at exit), quiet
// logs, MuJoCo's handlers, and a small real scene (an arm with PD control) built into a Session.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab::fuzz {

// Two hinges and a slide driven by two motors and a position servo, two sensors, a mocap body
// and two keyframes: enough for every kind of name and id the decoders resolve.
inline constexpr const char* kArmXml = R"(<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.5" range="-2 2" limited="true"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="lower" pos="0.3 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="0.5"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.025" mass="0.5"/>
        <body name="tip" pos="0.3 0 0">
          <joint name="slider" type="slide" axis="1 0 0" range="0 0.1" limited="true"/>
          <geom type="sphere" size="0.03" mass="0.1"/>
        </body>
      </body>
    </body>
    <body name="target" mocap="true" pos="0 0 2">
      <geom type="sphere" size="0.05" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="shoulder_motor" joint="shoulder" ctrlrange="-5 5" ctrllimited="true"/>
    <motor name="elbow_motor" joint="elbow"/>
    <position name="slider_servo" joint="slider" kp="50"/>
  </actuator>
  <sensor>
    <jointpos name="shoulder_angle" joint="shoulder"/>
    <framepos name="tip_pos" objtype="body" objname="tip"/>
  </sensor>
  <keyframe>
    <key name="home" qpos="0 0 0"/>
    <key name="raised" qpos="0.7 -0.4 0.05"/>
  </keyframe>
</mujoco>
)";

// A fresh folder under $TMPDIR for this process, removed when it exits.
inline const std::string& TempDir() {
  static const std::string dir = [] {
    std::string t = (std::filesystem::temp_directory_path() / "urlab-fuzz-XXXXXX").string();
    if (!::mkdtemp(t.data())) std::abort();
    static std::string to_remove;
    to_remove = t;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(to_remove, ec);
    });
    return t;
  }();
  return dir;
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// tools/fuzz.sh asks a target for its largest input by running it with URLAB_FUZZ_PRINT_MAX_LEN=1
// (from LLVMFuzzerInitialize, before any set-up): it prints `max_len`, the limit of the decoder
// it feeds, and exits, so -max_len follows the decoder's own constant.
inline void AnswerMaxLenQuery(std::size_t max_len) {
  if (!std::getenv("URLAB_FUZZ_PRINT_MAX_LEN")) return;
  std::printf("%zu\n", max_len);
  std::exit(0);
}

// Logs off (a fuzzer prints its own progress), MuJoCo errors as exceptions.
inline void QuietStart() {
  SetLogLevel("off");
  InstallMujocoHandlers();
}

// The arm as a one-articulation scene "arm" under PD control, built (not started).
inline std::shared_ptr<world::Session> MakeArmSession() {
  QuietStart();
  WriteText(TempDir() + "/arm.xml", kArmXml);
  const world::SceneConfig scene = world::ParseScene(
      "control_source: network\n"
      "articulations:\n"
      "  - {name: arm, mjcf: arm.xml, keyframe: home,\n"
      "     controller: {type: pd, kp: 20, kv: 2, gains: {elbow: {kp: 10, kv: 1}}}}\n",
      TempDir() + "/scene.yaml");
  return world::Session::Create(scene);
}

}  // namespace urlab::fuzz
