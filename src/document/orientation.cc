#include "urlab/document/orientation.h"

#include <cmath>

namespace urlab::document {

namespace {

constexpr double kPi = 3.14159265358979323846;

double Norm(const double* v, int n) {
  double s = 0;
  for (int i = 0; i < n; ++i) s += v[i] * v[i];
  return std::sqrt(s);
}

Vec3 Normalized(const Vec3& v, const Element& e, const char* what) {
  const double n = Norm(v.data(), 3);
  if (n < 1e-15) throw InputError(e.location(), "<" + e.tag() + "> " + what + " has zero length");
  return {v[0] / n, v[1] / n, v[2] / n};
}

std::vector<double> Values(const Element& e, std::string_view name, size_t count) {
  std::vector<double> v = *e.GetReals(name);
  if (v.size() != count) {
    throw InputError(e.location(), "<" + e.tag() + "> " + std::string(name) + " needs " +
                                       std::to_string(count) + " numbers");
  }
  return v;
}

Quat FrameToQuat(const Vec3& x, const Vec3& y, const Vec3& z) {
  // Rotation matrix with columns x, y, z to quaternion (Shepperd's method).
  const double m00 = x[0], m01 = y[0], m02 = z[0];
  const double m10 = x[1], m11 = y[1], m12 = z[1];
  const double m20 = x[2], m21 = y[2], m22 = z[2];
  const double tr = m00 + m11 + m22;
  Quat q;
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2;
    q = {0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s};
  } else if (m00 > m11 && m00 > m22) {
    const double s = std::sqrt(1.0 + m00 - m11 - m22) * 2;
    q = {(m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s};
  } else if (m11 > m22) {
    const double s = std::sqrt(1.0 + m11 - m00 - m22) * 2;
    q = {(m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s};
  } else {
    const double s = std::sqrt(1.0 + m22 - m00 - m11) * 2;
    q = {(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s};
  }
  if (q[0] < 0) q = {-q[0], -q[1], -q[2], -q[3]};
  return QuatNormalize(q);
}

const Element* FindDefaultClass(const Document& doc, const std::string& name) {
  const Element* found = nullptr;
  doc.root().Visit([&](const Element& e) {
    if (found || e.tag() != "default") return;
    const std::string* c = e.Get("class");
    const bool top = !e.parent() || e.parent()->tag() != "default";
    if ((c && *c == name) || (!c && top && name == "main")) found = &e;
  });
  return found;
}

// The template in default class `d` for elements with tag `tag` that sets `name` (last wins).
const std::string* TemplateValue(const Element& d, const std::string& tag, std::string_view name) {
  const std::string* value = nullptr;
  const bool actuator = IsActuatorTag(tag);
  for (const auto& c : d.children()) {
    const bool match = c->tag() == tag || (actuator && IsActuatorTag(c->tag()));
    if (!match) continue;
    if (const std::string* v = c->Get(name)) value = v;
  }
  return value;
}

}  // namespace

Quat QuatMul(const Quat& a, const Quat& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

Vec3 QuatRotate(const Quat& q, const Vec3& v) {
  const Quat p = {0, v[0], v[1], v[2]};
  const Quat qc = {q[0], -q[1], -q[2], -q[3]};
  const Quat r = QuatMul(QuatMul(q, p), qc);
  return {r[1], r[2], r[3]};
}

Quat QuatNormalize(const Quat& q) {
  const double n = Norm(q.data(), 4);
  if (n < 1e-15) return kIdentityQuat;
  return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

Quat QuatZ2Vec(const Vec3& vec) {
  const double n = Norm(vec.data(), 3);
  if (n < 1e-15) return kIdentityQuat;
  const Vec3 z = {vec[0] / n, vec[1] / n, vec[2] / n};
  Vec3 axis = {-z[1], z[0], 0};
  const double s = Norm(axis.data(), 3);
  if (s < 1e-10) return z[2] < 0 ? Quat{0, 1, 0, 0} : kIdentityQuat;
  axis = {axis[0] / s, axis[1] / s, axis[2] / s};
  const double a = std::atan2(s, z[2]);
  return {std::cos(a / 2), std::sin(a / 2) * axis[0], std::sin(a / 2) * axis[1],
          std::sin(a / 2) * axis[2]};
}

Quat EulerToQuat(const Vec3& angles, const std::string& seq) {
  Quat q = kIdentityQuat;
  for (int i = 0; i < 3; ++i) {
    const char c = seq[static_cast<size_t>(i)];
    Quat r = {std::cos(angles[i] / 2), 0, 0, 0};
    const double s = std::sin(angles[i] / 2);
    const char lower = static_cast<char>(std::tolower(c));
    r[lower == 'x' ? 1 : lower == 'y' ? 2 : 3] = s;
    // Lower case: axes move with the frame (post-multiply); upper case: fixed axes.
    q = (c == lower) ? QuatMul(q, r) : QuatMul(r, q);
  }
  return QuatNormalize(q);
}

std::optional<Quat> OwnOrientation(const Element& e, const CompilerSettings& compiler) {
  const double to_rad = compiler.degree ? kPi / 180.0 : 1.0;
  if (e.Has("quat")) {
    auto v = Values(e, "quat", 4);
    return QuatNormalize({v[0], v[1], v[2], v[3]});
  }
  if (e.Has("axisangle")) {
    auto v = Values(e, "axisangle", 4);
    const Vec3 axis = Normalized({v[0], v[1], v[2]}, e, "axisangle axis");
    const double a = v[3] * to_rad;
    return Quat{std::cos(a / 2), std::sin(a / 2) * axis[0], std::sin(a / 2) * axis[1],
                std::sin(a / 2) * axis[2]};
  }
  if (e.Has("euler")) {
    auto v = Values(e, "euler", 3);
    const std::string& seq = compiler.eulerseq;
    if (seq.size() != 3 || seq.find_first_not_of("xyzXYZ") != std::string::npos) {
      throw InputError(e.location(), "compiler eulerseq '" + seq + "' is not 3 of xyzXYZ");
    }
    return EulerToQuat({v[0] * to_rad, v[1] * to_rad, v[2] * to_rad}, seq);
  }
  if (e.Has("xyaxes")) {
    auto v = Values(e, "xyaxes", 6);
    const Vec3 x = Normalized({v[0], v[1], v[2]}, e, "xyaxes x axis");
    const double d = x[0] * v[3] + x[1] * v[4] + x[2] * v[5];
    const Vec3 y =
        Normalized({v[3] - x[0] * d, v[4] - x[1] * d, v[5] - x[2] * d}, e, "xyaxes y axis");
    const Vec3 z = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2],
                    x[0] * y[1] - x[1] * y[0]};
    return FrameToQuat(x, y, z);
  }
  if (e.Has("zaxis")) {
    auto v = Values(e, "zaxis", 3);
    Normalized({v[0], v[1], v[2]}, e, "zaxis");
    return QuatZ2Vec({v[0], v[1], v[2]});
  }
  return std::nullopt;
}

std::string EffectiveClass(const Element& e) {
  if (const std::string* c = e.Get("class")) return *c;
  for (const Element* p = e.parent(); p; p = p->parent()) {
    if (const std::string* c = p->Get("childclass")) return *c;
  }
  return "main";
}

const std::string* ResolveAttribute(const Document& doc, const Element& e, std::string_view name) {
  if (const std::string* v = e.Get(name)) return v;
  for (const Element* d = FindDefaultClass(doc, EffectiveClass(e)); d && d->tag() == "default";
       d = d->parent()) {
    if (const std::string* v = TemplateValue(*d, e.tag(), name)) return v;
  }
  return nullptr;
}

InheritedPose InheritedDefaultPose(const Document& doc, const Element& e) {
  InheritedPose pose;
  const CompilerSettings compiler = doc.Compiler();
  for (const Element* d = FindDefaultClass(doc, EffectiveClass(e)); d && d->tag() == "default";
       d = d->parent()) {
    for (const auto& c : d->children()) {
      if (c->tag() != e.tag()) continue;
      if (!e.Has("pos") && c->Has("pos") && !pose.any) {
        auto v = Values(*c, "pos", 3);
        pose.pos = {v[0], v[1], v[2]};
        pose.any = true;
      }
      if (auto q = OwnOrientation(*c, compiler)) {
        pose.quat = *q;
        pose.any = true;
      }
    }
    if (pose.any) break;  // the nearest class that sets a pose wins
  }
  return pose;
}

std::optional<FromTo> ResolveFromTo(const Document& doc, const Element& e) {
  const std::string* text = ResolveAttribute(doc, e, "fromto");
  if (!text) return std::nullopt;
  auto v = ParseReals(*text);
  if (!v || v->size() != 6) throw InputError(e.location(), "fromto needs 6 numbers");
  const Vec3 a = {(*v)[0], (*v)[1], (*v)[2]}, b = {(*v)[3], (*v)[4], (*v)[5]};
  // MuJoCo 2.2.2 orients the frame's +Z from the second point towards the first (its manual
  // says the opposite; the engine wins, tests/document/normalization_test.cc checks it).
  const Vec3 d = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  FromTo f;
  f.pos = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
  f.quat = QuatZ2Vec(d);
  f.half_length = Norm(d.data(), 3) / 2;
  const std::string* type = ResolveAttribute(doc, e, "type");
  const std::string t = type ? *type : (e.tag() == "geom" ? "sphere" : "sphere");
  f.slot = (t == "box" || t == "ellipsoid") ? 2 : 1;
  return f;
}

bool NormalizeFromTo(const Document& doc, Element& e) {
  const std::optional<FromTo> f = ResolveFromTo(doc, e);
  if (!f) return false;
  std::vector<double> size;
  if (const std::string* s = ResolveAttribute(doc, e, "size")) size = *ParseReals(*s);
  if (size.empty()) size.push_back(e.tag() == "site" ? 0.005 : 0.0);
  size.resize(static_cast<size_t>(f->slot) + 1, size[0]);
  size[static_cast<size_t>(f->slot)] = f->half_length;
  e.Unset("fromto");
  for (const char* o : {"quat", "axisangle", "euler", "xyaxes", "zaxis"}) e.Unset(o);
  e.SetReals("pos", f->pos);
  e.SetReals("quat", f->quat);
  e.SetReals("size", size);
  return true;
}

}  // namespace urlab::document
