#pragma once
// Impulse launchers (scene `launchers:`): a launcher is a pose whose +x is the launch direction,
// a projectile shape, mass and speed, and a pool of projectiles compiled into the scene (free
// bodies "{name}_projectile{i}" parked in a row on a static tray under the launcher at qpos0),
// so firing one needs no recompilation: it is a state write (world/session.h FireLauncher).
// The tray collides with the projectiles only (collision bit 2), so robots walk through it.
// Thread: pure functions and plain data; any thread that owns them.
#include <mujoco/mujoco.h>

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/document/document.h"

namespace urlab::world {

// One projectile shape a launcher may fire: its MJCF geom type and size (metres).
struct ProjectileShape {
  const char* name;  // as written in the scene file; the MJCF geom type too
  int size_count;    // numbers of the MJCF geom size
  std::array<double, 3> default_size;
  const char* size_help;  // what the numbers are
};
// The shapes, the first being the default.
inline constexpr ProjectileShape kProjectileShapes[] = {
    {"sphere", 1, {0.05, 0, 0}, "radius"},
    {"box", 3, {0.05, 0.05, 0.05}, "half sizes x y z"},
    {"capsule", 2, {0.03, 0.05, 0}, "radius and half length"},
};
// nullptr when `name` is no shape.
const ProjectileShape* FindProjectileShape(std::string_view name);

inline constexpr int kMaxLauncherPool = 64;

// What a scene entry asks for.
struct LauncherSpec {
  std::string name;                           // prefix "{name}_"
  std::array<double, 3> pos = {0, 0, 0};      // world frame
  std::array<double, 4> quat = {1, 0, 0, 0};  // the launch direction is this frame's +x
  std::string shape = "sphere";
  std::vector<double> size;  // MJCF geom size; empty: the shape's default
  double mass = 0.5;         // kg
  double speed = 5;          // m/s
  int pool = 5;              // projectiles compiled in, 1..kMaxLauncherPool
  std::array<double, 4> rgba = {0.95, 0.55, 0.1, 1};
};

// The launcher's document: in world coordinates (compose it without a placement), the tray and
// a visual-only barrel marker on the world body and `pool` free bodies "projectile{i}" (joint
// "projectile{i}", geom "projectile{i}") resting on the tray. Throws InputError for a shape or
// size that does not fit (callers add the scene file's line).
document::Document BuildLauncherDocument(const LauncherSpec& spec);

// A launcher in the compiled model.
struct LauncherLayout {
  std::string name;
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};
  std::array<double, 3> direction = {1, 0, 0};  // the launcher's +x in the world frame
  std::array<double, 3> muzzle = {0, 0, 0};     // where a launched projectile starts
  // Its orientation there: the launcher's, a capsule's axis turned along the launch direction.
  std::array<double, 4> launch_quat = {1, 0, 0, 0};
  double speed = 0;
  // Per projectile, in pool order: body id and its free joint's qpos / qvel addresses.
  std::vector<int> bodies, qpos_adr, qvel_adr;
};

// Finds the pool of `spec` in a compiled model (prefix "{name}_"). Throws Error when a
// projectile is missing.
LauncherLayout LauncherLayoutOf(const mjModel* m, const LauncherSpec& spec);

// Throws InputError when the tray of `spec` in `m` lies below a ground plane (an upward plane
// geom of the world body): its parked projectiles would start inside the ground and be thrown
// out at compile. The message gives the lowest launcher height that fits (callers add the scene
// file's line).
void CheckTrayAboveGround(const mjModel* m, const LauncherSpec& spec);

// The free joint's state of a projectile leaving `l`: qpos (muzzle position, launch_quat) and qvel
// (speed along the launch direction, no spin).
struct LaunchState {
  std::array<mjtNum, 7> qpos{};
  std::array<mjtNum, 6> qvel{};
};
LaunchState LaunchStateOf(const LauncherLayout& l);

}  // namespace urlab::world
