#pragma once
// Coordinate conversions for hosts in Unreal's convention (the description's MjUtils): MuJoCo is
// right-handed, Z up, metres; Unreal is left-handed, Z up, centimetres. A position keeps X and Z
// and negates Y, scaled by 100; a quaternion (MuJoCo w x y z) keeps w and y and negates x and z,
// which is the same rotation seen in the mirrored frame. Thread: any (pure).
#include <array>

namespace urlab::client {

inline constexpr double kMetresToCentimetres = 100.0;

// MuJoCo position (m) -> Unreal position (cm).
inline std::array<double, 3> MjToUePosition(const std::array<double, 3>& p) {
  return {p[0] * kMetresToCentimetres, -p[1] * kMetresToCentimetres, p[2] * kMetresToCentimetres};
}
// Unreal position (cm) -> MuJoCo position (m).
inline std::array<double, 3> UeToMjPosition(const std::array<double, 3>& p) {
  return {p[0] / kMetresToCentimetres, -p[1] / kMetresToCentimetres, p[2] / kMetresToCentimetres};
}
// MuJoCo quaternion (w x y z) -> Unreal quaternion, also written w x y z here (FQuat stores
// X Y Z W: take [1], [2], [3], [0]).
inline std::array<double, 4> MjToUeQuat(const std::array<double, 4>& q) {
  return {q[0], -q[1], q[2], -q[3]};
}
// Unreal quaternion (w x y z) -> MuJoCo quaternion (w x y z). Its own inverse.
inline std::array<double, 4> UeToMjQuat(const std::array<double, 4>& q) { return MjToUeQuat(q); }

}  // namespace urlab::client
