// The dialect bridge's sensor passes: actuator-force sensors and the sensors the runtime
// computes (energies, insidesite, contact) as <user> sensors.
#include <mujoco/mujoco.h>

#include <map>
#include <sstream>

#include "mjcf/bridge_pass.h"
#include "urlab/document/orientation.h"

namespace urlab::mjcf::bridge {

namespace {

using document::Element;
using Kind = BridgeChange::Kind;

class SensorsPasses : public Pass {
 public:
  using Pass::Pass;

  // ---- sensors ----
  void Sensors() {
    for (Element* s : Find({"jointactuatorfrc", "tendonactuatorfrc"})) {
      const bool joint = s->tag() == "jointactuatorfrc";
      const std::string* target = s->Get(joint ? "joint" : "tendon");
      if (!target) {
        Note("sensor.refused", *s, Tag(*s) + " needs a " + (joint ? "joint" : "tendon"));
        continue;
      }
      const std::string tname = *target;
      std::string name = s->Name();
      if (name.empty()) {
        name = s->tag() + "_" + tname;
        Note("sensor.unnamed", *s, Tag(*s) + " is unnamed; named '" + name + "'");
      }
      Element& u = Retag(*s, "user");
      u.Unset(joint ? "joint" : "tendon");
      u.Set("name", name);
      u.Set("objtype", joint ? "joint" : "tendon");
      u.Set("objname", tname);
      u.Set("datatype", "real");
      u.Set("needstage", "acc");
      u.Set("dim", "1");
      report_.software_sensors.push_back({name,
                                          joint ? BridgedSensor::Kind::kJointActuatorForce
                                                : BridgedSensor::Kind::kTendonActuatorForce,
                                          tname});
      Note("sensor.actuatorfrc", u,
           "<" + std::string(joint ? "jointactuatorfrc" : "tendonactuatorfrc") + " name='" + name +
               "'> -> <user> sensor of the same name, computed by the runtime from " +
               (joint ? "qfrc_actuator at the joint's dof"
                      : "the actuator forces of the tendon's actuators"));
    }
  }

  // 3.x sensors the runtime computes from 2.2.2's mjData (physics/software_sensors.h): energies,
  // insidesite and contact, as <user> sensors with the 3.x layout and stage.
  void ComputedSensors() {
    int unnamed = 0;
    for (Element* s : Find({"e_kinetic", "e_potential", "insidesite", "contact"})) {
      if (!s->parent() || s->parent()->tag() != "sensor") continue;
      const std::string tag = s->tag();
      std::map<std::string, std::string> params;
      for (const char* a : {"site", "objtype", "objname", "geom1", "geom2", "body1", "body2",
                            "subtree1", "subtree2", "num", "data", "reduce"}) {
        if (const std::string* v = s->Get(a)) params[a] = *v;
      }
      int dim = 1;
      const std::string stage = tag == "e_kinetic" ? "vel" : tag == "contact" ? "acc" : "pos";
      const BridgedSensor::Kind kind = tag == "e_kinetic" ? BridgedSensor::Kind::kKineticEnergy
                                       : tag == "e_potential"
                                           ? BridgedSensor::Kind::kPotentialEnergy
                                       : tag == "insidesite" ? BridgedSensor::Kind::kInsideSite
                                                             : BridgedSensor::Kind::kContact;
      if (tag == "insidesite" &&
          (!params.count("site") || !params.count("objtype") || !params.count("objname"))) {
        Note("sensor.refused", *s, Tag(*s) + " needs site, objtype and objname (3.x too)");
        continue;
      }
      if (tag == "contact") {
        if (params.count("reduce") && params["reduce"] == "netforce") {
          Note("sensor.contact.netforce", *s,
               Tag(*s) +
                   " reduce=\"netforce\" (the net wrench of all matched contacts about their "
                   "centroid) is not computed by the runtime; nearest: reduce=\"maxforce\"");
          continue;
        }
        static const std::pair<const char*, int> kFields[] = {
            {"found", 1}, {"force", 3},  {"torque", 3}, {"dist", 1},
            {"pos", 3},   {"normal", 3}, {"tangent", 3}};
        int slot = 0, last = -1;
        bool bad = false;
        std::istringstream words(params.count("data") ? params["data"] : "found");
        for (std::string w; words >> w;) {
          int i = 0;
          while (i < 7 && w != kFields[i].first) ++i;
          bad = bad || i == 7 || i <= last;
          if (i < 7) slot += kFields[i].second;
          last = i;
        }
        const int num = params.count("num") ? std::atoi(params["num"].c_str()) : 1;
        if (bad || num < 1) {
          Note("sensor.refused", *s,
               Tag(*s) +
                   " data/num invalid (3.x refuses it too: fields are found force torque "
                   "dist pos normal tangent, in that order; num >= 1)");
          continue;
        }
        dim = num * slot;
      }
      std::string name = s->Name();
      if (name.empty()) name = tag + "_sensor" + std::to_string(unnamed++);
      Element& u = Retag(*s, "user");
      for (const auto& kv : params) u.Unset(kv.first);
      u.Set("name", name);
      // 2.2.2 requires an object: the site for insidesite, otherwise the world body.
      u.Set("objtype", tag == "insidesite" ? "site" : "body");
      u.Set("objname", tag == "insidesite" ? params["site"] : "world");
      u.Set("datatype", "real");
      u.Set("needstage", stage);
      u.SetInt("dim", dim);
      report_.software_sensors.push_back({name, kind, "", params});
      Note("sensor.computed", u,
           "<" + tag + " name='" + name + "'> -> <user> sensor of the same name (dim " +
               std::to_string(dim) + ", stage " + stage +
               ") computed by the runtime through mjcb_sensor with the 3.x layout");
    }
  }
};

}  // namespace

void Sensors(State& s) { SensorsPasses(s).Sensors(); }
void ComputedSensors(State& s) { SensorsPasses(s).ComputedSensors(); }

}  // namespace urlab::mjcf::bridge
