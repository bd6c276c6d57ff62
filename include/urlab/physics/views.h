#pragma once
// Typed views over a compiled mjModel/mjData: each caches raw pointers into MuJoCo's arrays for
// one element so that runtime access costs nothing. Bound after compile: by id first (with a
// bounds check and, when a name is given, a check that the id still carries that name), by the
// prefixed name as fallback.
//
// Threading: views are plain pointers. Binding only reads the model and may run on any thread.
// Reading or writing through a view touches mjData, so it follows the engine's contract
// (physics thread inside callbacks, or under PhysicsEngine::WithLockedData). A view is valid as
// long as its mjModel/mjData live.
#include <mujoco/mujoco.h>

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::physics {

// Neither the id nor the name resolved to an element.
class BindError : public Error {
 public:
  using Error::Error;
};

// Fields every view has.
struct ViewBase {
  int id = -1;               // MuJoCo id, -1 when unbound
  std::string name;          // full (prefixed) MuJoCo name
  mjModel* model = nullptr;  // the model and data the pointers point into
  mjData* data = nullptr;
  bool valid() const { return id >= 0; }
};

struct BodyView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_BODY;
  mjtNum* xpos = nullptr;          // 3
  mjtNum* xquat = nullptr;         // 4
  mjtNum* xfrc_applied = nullptr;  // 6
  mjtNum* mass = nullptr;
  int mocap_id = -1;  // index into mocap_pos/quat, -1 when not a mocap body
  int parent_id = -1;
  // Ids of the direct child bodies, of this body's geoms and of its joints.
  std::vector<int> Bodies() const;
  std::vector<int> Geoms() const;
  std::vector<int> Joints() const;
  void Init(mjModel* m, mjData* d, int i);
};

struct GeomView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_GEOM;
  mjtNum* xpos = nullptr;  // 3
  mjtNum* xmat = nullptr;  // 9
  mjtNum* size = nullptr;  // 3
  int* type = nullptr;
  int* contype = nullptr;
  int* conaffinity = nullptr;
  int* dataid = nullptr;
  int body_id = -1;
  void Init(mjModel* m, mjData* d, int i);
};

struct JointView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_JOINT;
  mjtNum* qpos = nullptr;     // qpos_size values
  mjtNum* qvel = nullptr;     // dof_size values
  mjtNum* qacc = nullptr;     // dof_size values
  mjtNum* xanchor = nullptr;  // 3
  mjtNum* xaxis = nullptr;    // 3
  mjtNum* range = nullptr;    // 2
  mjtNum* stiffness = nullptr;
  mjtNum* damping = nullptr;  // dof_size values (per dof in MuJoCo 2.2.2)
  int type = mjJNT_HINGE;
  bool limited = false;
  int qpos_adr = -1;
  int dof_adr = -1;
  int qpos_size = 0;
  int dof_size = 0;
  void Init(mjModel* m, mjData* d, int i);
};

struct ActuatorView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_ACTUATOR;
  mjtNum* ctrl = nullptr;
  mjtNum* force = nullptr;
  mjtNum* length = nullptr;
  mjtNum* ctrlrange = nullptr;  // 2
  mjtNum* gainprm = nullptr;    // mjNGAIN
  mjtNum* biasprm = nullptr;    // mjNBIAS
  mjtNum* gear = nullptr;       // 6
  mjtNum* act = nullptr;        // activation, nullptr for actuators without dynamics
  int act_adr = -1;             // index into d->act, -1 when none
  int trntype = mjTRN_JOINT;
  int trnid = -1;  // joint/tendon/site id of the transmission
  void Init(mjModel* m, mjData* d, int i);
};

struct SensorView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_SENSOR;
  mjtNum* values = nullptr;  // dim values in sensordata
  int dim = 0;
  int adr = 0;
  int type = 0;
  void Init(mjModel* m, mjData* d, int i);
};

struct TendonView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_TENDON;
  mjtNum* length = nullptr;
  mjtNum* velocity = nullptr;
  mjtNum* stiffness = nullptr;
  mjtNum* damping = nullptr;
  mjtNum* range = nullptr;  // 2
  void Init(mjModel* m, mjData* d, int i);
};

struct SiteView : ViewBase {
  static constexpr mjtObj kObjType = mjOBJ_SITE;
  mjtNum* xpos = nullptr;  // 3
  mjtNum* xmat = nullptr;  // 9
  mjtNum* size = nullptr;  // 3
  int* type = nullptr;
  int body_id = -1;
  void Init(mjModel* m, mjData* d, int i);
};

// Number of elements of `type` in `m` (bodies, geoms, joints, actuators, sensors, tendons, sites,
// keyframes); 0 for other types.
int ElementCount(const mjModel* m, mjtObj type);

// Id of `prefix + name`: `id_hint` first when it is in range and names that element (any
// element when `name` is empty), else a name lookup. -1 when neither resolves.
int ResolveId(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name,
              int id_hint = -1);

// Binds a view (see ResolveId). Returns std::nullopt when the element does not exist.
template <typename View>
std::optional<View> TryBind(mjModel* m, mjData* d, std::string_view prefix, std::string_view name,
                            int id_hint = -1) {
  const int id = ResolveId(m, View::kObjType, prefix, name, id_hint);
  if (id < 0) return std::nullopt;
  View v;
  v.Init(m, d, id);
  return v;
}

// Binds a view or throws BindError naming the element that was not found.
template <typename View>
View Bind(mjModel* m, mjData* d, std::string_view prefix, std::string_view name, int id_hint = -1) {
  std::optional<View> v = TryBind<View>(m, d, prefix, name, id_hint);
  if (!v) {
    throw BindError("no " + std::string(mju_type2Str(View::kObjType)) + " '" + std::string(prefix) +
                    std::string(name) + "' (id hint " + std::to_string(id_hint) + ") in the model");
  }
  return *std::move(v);
}

// All elements of one kind belonging to an articulation, with constant-time lookup by short name
// (the name without the prefix) and by MuJoCo id.
template <typename View>
class ElementSet {
 public:
  // Views in increasing MuJoCo id order.
  const std::vector<View>& all() const { return views_; }
  std::size_t size() const { return views_.size(); }
  // nullptr when absent.
  const View* Find(std::string_view short_name) const {
    auto it = by_name_.find(short_name);
    return it == by_name_.end() ? nullptr : &views_[static_cast<std::size_t>(it->second)];
  }
  const View* ById(int id) const {
    if (id < 0 || id >= static_cast<int>(by_id_.size())) return nullptr;
    const int i = by_id_[static_cast<std::size_t>(id)];
    return i < 0 ? nullptr : &views_[static_cast<std::size_t>(i)];
  }
  // Position of an element in all(), -1 when absent.
  int IndexOfId(int id) const {
    return id < 0 || id >= static_cast<int>(by_id_.size()) ? -1
                                                           : by_id_[static_cast<std::size_t>(id)];
  }
  // Short names in all() order.
  const std::vector<std::string>& short_names() const { return short_names_; }

  // Collects every element of the view's type whose name starts with `prefix`.
  void Build(mjModel* m, mjData* d, std::string_view prefix);

 private:
  struct Hash {
    using is_transparent = void;
    std::size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
  };
  std::vector<View> views_;
  std::vector<std::string> short_names_;
  std::unordered_map<std::string, int, Hash, std::equal_to<>> by_name_;
  std::vector<int> by_id_;
};

// Every named element of one articulation (all names starting with `prefix`), bound to one
// mjModel/mjData. Built after compile on the main thread; read-only afterwards, so lookups are
// safe from any thread (what you do with the pointers follows the engine's contract).
class ArticulationBindings {
 public:
  ArticulationBindings(mjModel* m, mjData* d, std::string prefix);

  const std::string& prefix() const { return prefix_; }
  mjModel* model() const { return model_; }
  mjData* data() const { return data_; }

  const ElementSet<BodyView>& bodies() const { return bodies_; }
  const ElementSet<GeomView>& geoms() const { return geoms_; }
  const ElementSet<JointView>& joints() const { return joints_; }
  const ElementSet<ActuatorView>& actuators() const { return actuators_; }
  const ElementSet<SensorView>& sensors() const { return sensors_; }
  const ElementSet<TendonView>& tendons() const { return tendons_; }
  const ElementSet<SiteView>& sites() const { return sites_; }
  // Ids of the keyframes whose names start with the prefix (articulation-defined keyframes).
  const std::vector<int>& keyframes() const { return keyframes_; }

  // True when `full_name` starts with this articulation's prefix.
  bool Owns(std::string_view full_name) const { return full_name.starts_with(prefix_); }

 private:
  std::string prefix_;
  mjModel* model_;
  mjData* data_;
  ElementSet<BodyView> bodies_;
  ElementSet<GeomView> geoms_;
  ElementSet<JointView> joints_;
  ElementSet<ActuatorView> actuators_;
  ElementSet<SensorView> sensors_;
  ElementSet<TendonView> tendons_;
  ElementSet<SiteView> sites_;
  std::vector<int> keyframes_;
};

}  // namespace urlab::physics
