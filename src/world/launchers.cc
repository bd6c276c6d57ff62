#include "urlab/world/launchers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "urlab/core/error.h"

namespace urlab::world {

namespace {

// Collision bits: the tray (bit 2) touches only projectiles (bits 1 and 2), which also touch
// everything on the default bit 1.
constexpr int kTrayBits = 2;
constexpr int kProjectileBits = 3;
constexpr double kTrayHalfThickness = 0.01;
constexpr double kTrayMargin = 0.03;   // tray beyond the parked projectiles, each side
constexpr double kBelowMuzzle = 0.05;  // gap between the parked row and a launch

// The extents of one projectile lying on the tray (a capsule lies with its axis along x).
struct Extents {
  double radius = 0;  // bounding sphere
  double half_x = 0, half_y = 0, half_z = 0;
};

Extents ExtentsOf(const std::string& shape, const std::vector<double>& s) {
  if (shape == "box") return {std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]), s[0], s[1], s[2]};
  if (shape == "capsule") return {s[0] + s[1], s[0] + s[1], s[0], s[0]};
  return {s[0], s[0], s[0], s[0]};
}

std::vector<double> SizeOf(const LauncherSpec& spec, const ProjectileShape& shape) {
  if (spec.size.empty()) {
    return std::vector<double>(shape.default_size.begin(),
                               shape.default_size.begin() + shape.size_count);
  }
  if (static_cast<int>(spec.size.size()) != shape.size_count) {
    throw InputError(
        {}, fmt::format("{}: a {} needs {} size number(s) ({}), not {}", spec.name, shape.name,
                        shape.size_count, shape.size_help, spec.size.size()));
  }
  for (double v : spec.size) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw InputError({}, spec.name + ": size values must be > 0 and finite");
    }
  }
  return spec.size;
}

const ProjectileShape& ShapeOf(const LauncherSpec& spec) {
  const ProjectileShape* shape = FindProjectileShape(spec.shape);
  if (!shape) {
    throw InputError(
        {}, spec.name + ": unknown projectile shape '" + spec.shape + "' (sphere, box or capsule)");
  }
  return *shape;
}

// The barrel marker's length: the muzzle is this far ahead of the launcher, plus a radius.
double BarrelLength(const Extents& e) { return std::max(0.1, 2 * e.radius); }

// Where projectile i rests: a row along world y centred under the launcher.
struct Parking {
  double spacing = 0, top = 0;  // distance between centres; the tray's top surface (z)
  std::array<double, 3> At(const LauncherSpec& spec, const Extents& e, int i) const {
    const double y0 = spec.pos[1] - 0.5 * spacing * (spec.pool - 1);
    return {spec.pos[0], y0 + spacing * i, top + e.half_z};
  }
};

Parking ParkingOf(const LauncherSpec& spec, const Extents& e) {
  Parking p;
  p.spacing = 2 * e.half_y + std::max(0.02, e.half_y);
  p.top = spec.pos[2] - e.radius - kBelowMuzzle - 2 * e.half_z;
  return p;
}

// A capsule lies on its side, its axis along x (and flies along it); other shapes as they are.
std::array<double, 4> LyingQuat(const std::string& shape) {
  if (shape != "capsule") return {1, 0, 0, 0};
  const double h = std::numbers::sqrt2 / 2;
  return {h, 0, h, 0};
}

}  // namespace

const ProjectileShape* FindProjectileShape(std::string_view name) {
  for (const ProjectileShape& s : kProjectileShapes) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

document::Document BuildLauncherDocument(const LauncherSpec& spec) {
  const ProjectileShape& shape = ShapeOf(spec);
  const std::vector<double> size = SizeOf(spec, shape);
  const Extents e = ExtentsOf(spec.shape, size);
  const Parking park = ParkingOf(spec, e);

  document::Document doc(spec.name);
  document::Element& world = doc.Section("worldbody");
  document::Element& tray = world.AddChild("geom");
  tray.Set("name", "tray");
  tray.Set("type", "box");
  const double half_y = 0.5 * park.spacing * spec.pool + kTrayMargin;
  tray.SetReals("size", std::vector<double>{e.half_x + kTrayMargin, half_y, kTrayHalfThickness});
  tray.SetReals("pos",
                std::vector<double>{spec.pos[0], spec.pos[1], park.top - kTrayHalfThickness});
  tray.SetInt("contype", kTrayBits);
  tray.SetInt("conaffinity", kTrayBits);
  tray.SetReals("rgba", std::vector<double>{0.35, 0.35, 0.4, 1});

  // The barrel: where the launcher is and which way it fires (drawn only).
  mjtNum dir[3];
  const mjtNum x[3] = {1, 0, 0};
  mju_rotVecQuat(dir, x, spec.quat.data());
  const double length = BarrelLength(e);
  document::Element& barrel = world.AddChild("geom");
  barrel.Set("name", "barrel");
  barrel.Set("type", "capsule");
  barrel.SetReals(
      "fromto",
      std::vector<double>{spec.pos[0], spec.pos[1], spec.pos[2], spec.pos[0] + length * dir[0],
                          spec.pos[1] + length * dir[1], spec.pos[2] + length * dir[2]});
  barrel.SetReal("size", std::max(0.01, 0.5 * e.half_z));
  barrel.SetInt("contype", 0);
  barrel.SetInt("conaffinity", 0);
  barrel.SetReals("rgba", std::vector<double>{0.2, 0.2, 0.25, 1});

  const std::array<double, 4> lying = LyingQuat(spec.shape);
  for (int i = 0; i < spec.pool; ++i) {
    const std::string name = fmt::format("projectile{}", i);
    document::Element& body = world.AddChild("body");
    body.Set("name", name);
    const std::array<double, 3> at = park.At(spec, e, i);
    body.SetReals("pos", std::vector<double>(at.begin(), at.end()));
    body.SetReals("quat", std::vector<double>(lying.begin(), lying.end()));
    body.AddChild("freejoint").Set("name", name);
    document::Element& g = body.AddChild("geom");
    g.Set("name", name);
    g.Set("type", shape.name);
    g.SetReals("size", size);
    g.SetReal("mass", spec.mass);
    g.SetInt("contype", kProjectileBits);
    g.SetInt("conaffinity", kProjectileBits);
    g.SetReals("rgba", std::vector<double>(spec.rgba.begin(), spec.rgba.end()));
  }
  return doc;
}

LauncherLayout LauncherLayoutOf(const mjModel* m, const LauncherSpec& spec) {
  const Extents e = ExtentsOf(spec.shape, SizeOf(spec, ShapeOf(spec)));
  LauncherLayout l;
  l.name = spec.name;
  l.pos = spec.pos;
  l.quat = spec.quat;
  const std::array<double, 4> lying = LyingQuat(spec.shape);
  mju_mulQuat(l.launch_quat.data(), spec.quat.data(), lying.data());
  l.speed = spec.speed;
  const mjtNum x[3] = {1, 0, 0};
  mju_rotVecQuat(l.direction.data(), x, spec.quat.data());
  const double ahead = BarrelLength(e) + e.radius + 0.01;
  for (int k = 0; k < 3; ++k) l.muzzle[k] = spec.pos[k] + ahead * l.direction[k];
  for (int i = 0; i < spec.pool; ++i) {
    const std::string name = fmt::format("{}_projectile{}", spec.name, i);
    const int body = mj_name2id(m, mjOBJ_BODY, name.c_str());
    const int joint = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    if (body < 0 || joint < 0 || m->jnt_type[joint] != mjJNT_FREE) {
      throw Error("launcher '" + spec.name + "': the compiled model has no free body " + name);
    }
    l.bodies.push_back(body);
    l.qpos_adr.push_back(m->jnt_qposadr[joint]);
    l.qvel_adr.push_back(m->jnt_dofadr[joint]);
  }
  return l;
}

void CheckTrayAboveGround(const mjModel* m, const LauncherSpec& spec) {
  const int tray = mj_name2id(m, mjOBJ_GEOM, (spec.name + "_tray").c_str());
  if (tray < 0) return;
  const double top = m->geom_pos[3 * tray + 2] + m->geom_size[3 * tray + 2];
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] != mjGEOM_PLANE || m->geom_bodyid[g] != 0) continue;
    const mjtNum* q = m->geom_quat + 4 * g;
    const double normal_z = 1 - 2 * (q[1] * q[1] + q[2] * q[2]);  // the plane's z axis, up part
    if (normal_z < 0.999) continue;
    const double ground = m->geom_pos[3 * g + 2];
    if (top >= ground) continue;
    const char* plane = mj_id2name(m, mjOBJ_GEOM, g);
    throw InputError(
        {}, fmt::format("{}: its projectiles rest on a tray {:.3f} m below the launcher, at z = "
                        "{:.3f}, under the ground plane {}(z = {:.3f}); place the launcher at z "
                        ">= {:.3f}",
                        spec.name, spec.pos[2] - top, top,
                        plane ? fmt::format("'{}' ", plane) : std::string(), ground,
                        spec.pos[2] + ground - top));
  }
}

LaunchState LaunchStateOf(const LauncherLayout& l) {
  LaunchState s;
  std::copy(l.muzzle.begin(), l.muzzle.end(), s.qpos.begin());
  std::copy(l.launch_quat.begin(), l.launch_quat.end(), s.qpos.begin() + 3);
  for (int k = 0; k < 3; ++k) s.qvel[k] = l.speed * l.direction[k];
  return s;
}

}  // namespace urlab::world
