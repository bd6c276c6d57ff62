#pragma once
// Import normalization helpers: every MJCF orientation form as a quaternion, fromto resolution
// for geoms and sites, and default-class resolution (what value an unset attribute inherits).
// Thread: pure functions over a document; any thread that owns the document.
#include <array>
#include <optional>
#include <string>

#include "urlab/document/document.h"

namespace urlab::document {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // MuJoCo order: w, x, y, z

inline constexpr Quat kIdentityQuat = {1, 0, 0, 0};

// The element's own orientation (quat, axisangle, euler, xyaxes or zaxis, whichever it sets)
// as a unit quaternion, honouring the compiler's angle unit and eulerseq; nullopt when it sets
// none. Throws InputError for malformed values (wrong count, zero axis).
std::optional<Quat> OwnOrientation(const Element& e, const CompilerSettings& compiler);

// Quaternion helpers (MuJoCo conventions).
Quat QuatMul(const Quat& a, const Quat& b);
Vec3 QuatRotate(const Quat& q, const Vec3& v);
Quat QuatNormalize(const Quat& q);
// Minimal rotation taking +Z to `z` (MuJoCo's zaxis / fromto rule).
Quat QuatZ2Vec(const Vec3& z);
// Rotation of the euler sequence `seq` (e.g. "xyz", "XYZ", "zyx") by `angles` in radians.
Quat EulerToQuat(const Vec3& angles, const std::string& seq);

// Which default class applies to `e`: its `class`, else the nearest ancestor's `childclass`,
// else "main".
std::string EffectiveClass(const Element& e);

// The value an attribute of `e` takes: its own text when set, else the first default class in
// the chain (effective class, its parents, ..., main) whose template for e's kind sets it.
// nullptr when nothing sets it (MuJoCo's built-in default applies).
const std::string* ResolveAttribute(const Document& doc, const Element& e, std::string_view name);

// The pose a geom or site inherits from its default classes (the description's "visual
// offset"): pos and orientation set on the default template, not on the element itself.
struct InheritedPose {
  Vec3 pos = {0, 0, 0};
  Quat quat = kIdentityQuat;
  bool any = false;  // false when no default sets a pose
};
InheritedPose InheritedDefaultPose(const Document& doc, const Element& e);

// fromto of a geom or site resolved as MuJoCo 2.2.2 does: pos at the midpoint, orientation
// taking +Z along the segment (from the second point towards the first, as the engine does),
// half-length in slot `slot` of size (1 for capsule/cylinder, 2 for box/ellipsoid). nullopt when
// the element has no fromto.
struct FromTo {
  Vec3 pos;
  Quat quat;
  double half_length = 0;
  int slot = 1;
};
std::optional<FromTo> ResolveFromTo(const Document& doc, const Element& e);

// Rewrites a fromto geom/site into explicit pos, quat and size with the export rule: when the
// element did not set size itself, only the half-length slot is its own and the radius comes
// from the default chain (written explicitly, MJCF text cannot leave a size slot out).
// Returns false when the element has no fromto.
bool NormalizeFromTo(const Document& doc, Element& e);

}  // namespace urlab::document
