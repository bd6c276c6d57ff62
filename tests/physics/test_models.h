#pragma once
// Small MJCF models shared by the physics tests.
#include <string>

namespace urlab::testing {

// URLab's own humanoid (21 hinges on a free base: nq 28, nv 27, nu 21).
inline const char* kHumanoidPath = URLAB_SOURCE_DIR "/examples/models/humanoid.xml";

// A two-link arm with position/velocity sensors, a mocap body, user data, a filtered actuator
// (activation state) and two named keyframes. Names start with "arm_" like an articulation.
inline const char* kArmXml = R"(
<mujoco model="arm">
  <compiler angle="radian"/>
  <option timestep="0.002"/>
  <size nuserdata="3"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 .1"/>
    <body name="arm_target" mocap="true" pos="0.3 0 0.5">
      <geom type="sphere" size="0.02" contype="0" conaffinity="0"/>
    </body>
    <body name="arm_upper" pos="0 0 0.5">
      <joint name="arm_shoulder" type="hinge" axis="0 1 0" range="-2 2" limited="true"
             damping="0.1"/>
      <geom name="arm_upper_geom" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <site name="arm_shoulder_site" pos="0 0 0" size="0.01"/>
      <body name="arm_lower" pos="0.3 0 0">
        <joint name="arm_elbow" type="hinge" axis="0 1 0" range="-2.5 2.5" limited="true"
               damping="0.1"/>
        <geom name="arm_lower_geom" type="capsule" fromto="0 0 0 0.3 0 0" size="0.025"
              mass="0.5"/>
        <site name="arm_tip" pos="0.3 0 0" size="0.01"/>
      </body>
    </body>
    <body name="box" pos="0.6 0 0.05">
      <freejoint name="box_free"/>
      <geom name="box_geom" type="box" size="0.05 0.05 0.05" mass="0.2"/>
    </body>
  </worldbody>
  <tendon>
    <fixed name="arm_coupling">
      <joint joint="arm_shoulder" coef="1"/>
      <joint joint="arm_elbow" coef="-1"/>
    </fixed>
  </tendon>
  <actuator>
    <motor name="arm_shoulder_motor" joint="arm_shoulder" gear="1" ctrllimited="true"
           ctrlrange="-50 50"/>
    <position name="arm_elbow_servo" joint="arm_elbow" kp="20"/>
    <general name="arm_filtered" joint="arm_elbow" dyntype="filter" dynprm="0.05" gainprm="1"/>
  </actuator>
  <sensor>
    <jointpos name="arm_shoulder_pos" joint="arm_shoulder"/>
    <jointvel name="arm_elbow_vel" joint="arm_elbow"/>
    <framepos name="arm_tip_pos" objtype="site" objname="arm_tip"/>
  </sensor>
  <keyframe>
    <key name="arm_home" qpos="0 0  0.6 0 0.05 1 0 0 0"/>
    <key name="arm_bent" qpos="0.8 -1.2  0.6 0 0.05 1 0 0 0"/>
  </keyframe>
</mujoco>
)";

// A single pendulum at 500 Hz for pacing tests.
inline const char* kPendulumXml = R"(
<mujoco model="pendulum">
  <option timestep="0.002"/>
  <worldbody>
    <body name="pole" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.01"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/>
    </body>
  </worldbody>
</mujoco>
)";

// A motor-driven arm whose link is gravity-compensated (body gravcomp `gravcomp`), a ball on a
// rope with a dead-band spring, a joint actuator force sensor (the first sensor), and a weld
// between two sites: what MuJoCo 2.2.2 lacked and MuJoCo 3 computes itself.
inline std::string CompensatedArmXml(double gravcomp) {
  std::string xml = R"(<mujoco>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <site name="anchor" pos="0 0 2"/>
    <body name="arm" pos="1 0 1" gravcomp="%GRAVCOMP%">
      <joint name="h" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05" mass="1"/>
    </body>
    <body name="ball" pos="0 0 1">
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom size="0.1" mass="2"/>
      <site name="top" pos="0 0 0.1"/>
    </body>
    <body name="box" pos="-1 0 1">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" mass="0.5"/>
      <site name="box_site" pos="0.1 0 0"/>
    </body>
    <site name="hook" pos="-0.85 0 1.05"/>
  </worldbody>
  <tendon>
    <spatial name="rope" stiffness="200" springlength="0.8 0.95"><site site="anchor"/><site site="top"/></spatial>
  </tendon>
  <equality>
    <weld name="hold" site1="box_site" site2="hook"/>
  </equality>
  <actuator>
    <motor name="m" joint="h" gear="2"/>
  </actuator>
  <sensor>
    <jointactuatorfrc name="h_force" joint="h"/>
    <jointpos name="h_pos" joint="h"/>
    <jointpos name="z_pos" joint="z"/>
  </sensor>
</mujoco>)";
  ;
  xml.replace(xml.find("%GRAVCOMP%"), 10, std::to_string(gravcomp));
  return xml;
}

}  // namespace urlab::testing
