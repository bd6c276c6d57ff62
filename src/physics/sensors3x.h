#pragma once
// MuJoCo 3.x sensors computed from MuJoCo 2.2.2's mjData (internal to the physics module, used by
// software_sensors.cc): `insidesite` (is an object's position inside a site's volume) and
// `contact` (matching, reduction and extraction of mjData.contact into fixed slots), with the
// layouts of the 3.x XML reference.
//
// Thread: pure functions of (model, data); called on the thread that steps the model.
#include <mujoco/mujoco.h>

#include <map>
#include <string>

namespace urlab::physics {

struct InsideSiteSensor {
  int site = -1;
  mjtObj objtype = mjOBJ_BODY;  // body (centre of mass), xbody, geom, site, camera
  int objid = -1;
};

struct ContactSensor {
  // Matching: -1 = no criterion. Side 1 and side 2 (geom, body, subtree root) and a site.
  int geom[2] = {-1, -1};
  int body[2] = {-1, -1};
  int subtree[2] = {-1, -1};
  int site = -1;
  int num = 1;
  enum class Reduce { kNone, kMinDist, kMaxForce } reduce = Reduce::kNone;
  // Fields in 3.x's order: found, force, torque, dist, pos, normal, tangent.
  bool fields[7] = {true, false, false, false, false, false, false};
  int SlotSize() const;
};

// Parse the 3.x attributes (names as in MJCF, values as written) against the compiled model.
// Throw urlab::Error naming `what` and the attribute for unknown names or values.
InsideSiteSensor ParseInsideSite(const mjModel* m, const std::map<std::string, std::string>& a,
                                 const std::string& what);
ContactSensor ParseContactSensor(const mjModel* m, const std::map<std::string, std::string>& a,
                                 const std::string& what);

// 3.x e_potential (gravity and joint/tendon springs, respecting the gravity and passive flags)
// and e_kinetic (0.5 qvel' M qvel). 2.2.2's mj_energyPos/Vel compute only with the energy flag.
mjtNum PotentialEnergy(const mjModel* m, const mjData* d);
mjtNum KineticEnergy(const mjModel* m, const mjData* d);

// 1 when the object's position is inside the site's volume, else 0 (position stage).
mjtNum InsideSiteValue(const mjModel* m, const mjData* d, const InsideSiteSensor& s);

// num * SlotSize() values into `out` (acceleration stage: contact forces are known).
void ContactSensorValues(const mjModel* m, const mjData* d, const ContactSensor& s, mjtNum* out);

}  // namespace urlab::physics
