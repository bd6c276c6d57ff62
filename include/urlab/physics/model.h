#pragma once
// The compiled model: owning pointers for mjModel/mjData, compiling and loading helpers, and
// `Model`, a compiled mjModel with its copy and content hash (recordings identify a model by
// ContentHash of its MJB).
//
// Threading contract
// - A Model (and a ModelPtr / DataPtr) is owned by whoever holds it; a given mjModel/mjData is
//   used by one thread at a time (see engine.h for the physics thread's).
// - Construction, Copy and destruction may run on any thread, also while other models step on
//   other threads. Copy and Hash read the mjModel: call them where its owner allows reading it
//   (the engine's: inside WithLockedData, or PhysicsEngine::CopyModel).
// - The other functions are pure and may be called from any thread.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::physics {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

// MuJoCo refused to compile a model. what() carries MuJoCo's message.
class CompileError : public Error {
 public:
  using Error::Error;
};

// Compiles MJCF text with mj_loadXML from an in-memory VFS holding only that text; asset files
// named with absolute paths are read from disk by MuJoCo. Compiler warnings are reported through
// ReportMujocoWarning. Throws CompileError.
ModelPtr CompileXmlString(const std::string& xml);

// Loads an MJCF file from disk with MuJoCo's own mj_loadXML (baseline for comparisons).
// Throws CompileError.
ModelPtr LoadXmlFile(const std::string& path);

// Allocates mjData for `m`. Throws MujocoError when MuJoCo cannot allocate it.
DataPtr MakeData(const mjModel* m);

// A compiled model as MuJoCo binary (.mjb) bytes.
std::string MjbBytes(const mjModel* m);

// A model from MJB bytes (mj_loadModel through an in-memory VFS). Throws Error with MuJoCo's
// reason when it refuses them.
ModelPtr LoadMjbBytes(std::string_view mjb);

// FNV-1a 64 over `mjb`.
std::uint64_t ContentHash(std::string_view mjb);

// A compiled model. Movable, not copyable (Copy makes a new one).
class Model {
 public:
  Model() = default;
  Model(ModelPtr model);  // NOLINT(google-explicit-constructor): every compiled ModelPtr is one
  // A model from MJB bytes (LoadMjbBytes). Throws Error.
  static Model FromMjb(std::string_view mjb);

  // mj_copyModel (options included: the copy has the `opt` this model has now). Throws Error
  // when MuJoCo cannot copy it.
  Model Copy() const;

  mjModel* get() const { return model_.get(); }
  mjModel* operator->() const { return model_.get(); }
  explicit operator bool() const { return model_ != nullptr; }

  std::string Mjb() const { return MjbBytes(model_.get()); }
  // ContentHash(Mjb()).
  std::uint64_t Hash() const;

 private:
  ModelPtr model_;
};

// Replacing a running model's values in place (a scene edited through its spec, or read again
// from its files; world::Session::EditModel, ReloadKeepingState). MuJoCo's mj_recompile frees and
// reallocates the buffers of the model and data it is given, which would leave every view,
// binding and controller address into them dangling; URLab instead compiles a new model and
// copies its values into the running one, whose buffers (and so every address into them) and
// mjData (the whole state) stay as they are.
//
// Why `fresh` cannot take `running`'s place ("" when it can), naming the first difference: a
// size ("nbody 12 -> 13"), an element's name, or a value URLab resolved once when it bound the
// scene (joint types, addresses and ranges, actuator transmissions, kinds, control ranges and
// gears, a motor's gain, sensor addresses, parent bodies, mocap ids, keyframe poses). Reads only
// what never changes in a running model (its sizes, names and those values), so it may run on
// any thread while the model steps.
std::string InPlaceDifference(const mjModel* running, const mjModel* fresh);

// Copies into `dest` the options, visual settings, statistics, flags and every array of `src`
// that differs (arrays that are equal are not written), keeping dest's buffer. Precondition:
// InPlaceDifference(dest, src) is "". Thread: dest's owner, with its data not in use.
void CopyModelValuesInPlace(mjModel* dest, const mjModel* src);

// The version of the MuJoCo library actually loaded, e.g. "3.17.0".
std::string MujocoVersion();

}  // namespace urlab::physics
