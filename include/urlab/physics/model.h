#pragma once
// The compiled model and what runs with it.
//
// `Model` owns a compiled mjModel together with its extensions: what URLab computes for it that
// MuJoCo 2.2.2 cannot (software sensors, passive forces such as body gravity compensation and
// dead-band tendon springs, the data of equalities on sites; software_sensors.h). Constructing a
// Model writes the site equalities' data into the mjModel and registers the sensors and passive
// forces for MuJoCo's callbacks (mjcb_sensor / mjcb_passive); destroying it unregisters them
// before the mjModel is freed. Copying (Copy), loading an MJB with its extensions (FromMjb) and
// compiling text (Model(CompileXmlString(...), extensions)) all give a Model that carries them.
// Its content hash (Hash) covers the MJB bytes and, when there are any, the extensions' canonical
// text (SerializeExtensions): a model without extensions hashes as its MJB alone.
//
// An MJB file alone cannot carry the extensions: a recording stores them beside the MJB (see
// replay/recording.h); `urlab compile --save-mjb` warns that they are lost.
//
// Threading contract
// - A Model (and a ModelPtr / DataPtr) is owned by whoever holds it; a given mjModel/mjData is
//   used by one thread at a time (see engine.h for the physics thread's).
// - Construction, Copy, FromMjb and destruction may run on any thread, also while other models
//   step on other threads: the registry of extensions behind them is thread-safe
//   (software_sensors.h). Copy and Hash read the mjModel: call them where its owner allows
//   reading it (the engine's: inside WithLockedData, or PhysicsEngine::CopyModel).
// - The other functions are pure and may be called from any thread.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/core/error.h"
#include "urlab/physics/software_sensors.h"

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

// The same compile for a trial whose result only informs a later compile (the dialect bridge's):
// nullptr and MuJoCo's message in `error` when MuJoCo refuses the model; compiler warnings are
// not reported (the real compile reports them).
ModelPtr TryCompileXmlString(const std::string& xml, std::string* error);

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

// The canonical text of `extensions` (JSON, fixed key order, doubles in shortest round-trip
// form): "" when there are none. ParseExtensions reads it back; throws Error naming the field.
std::string SerializeExtensions(const SoftwareModelSpec& extensions);
SoftwareModelSpec ParseExtensions(std::string_view text);

// FNV-1a 64 over `mjb`, continued over `extensions` (the canonical text) when it is not empty.
std::uint64_t ContentHash(std::string_view mjb, std::string_view extensions);

// A compiled model that owns its extensions. Movable, not copyable (Copy makes a new one).
class Model {
 public:
  Model() = default;
  // A model without extensions (implicit: every compiled ModelPtr is one).
  Model(ModelPtr model);  // NOLINT(google-explicit-constructor)
  // Takes `model` with `extensions`: writes the site equalities' data (idempotent: a model loaded
  // from an MJB that has it already gets the same bits) and registers the sensors and passive
  // forces. Throws Error for a name that is not in the model (software_sensors.h).
  Model(ModelPtr model, SoftwareModelSpec extensions);
  // MJB bytes and the canonical text of their extensions (SerializeExtensions). Throws Error.
  static Model FromMjb(std::string_view mjb, std::string_view extensions);

  Model(Model&& o) noexcept;
  Model& operator=(Model&& o) noexcept;
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;
  ~Model();

  // mj_copyModel with the extensions registered for the copy (options included: the copy has
  // the `opt` this model has now). Throws Error when MuJoCo cannot copy it.
  Model Copy() const;

  mjModel* get() const { return model_.get(); }
  mjModel* operator->() const { return model_.get(); }
  explicit operator bool() const { return model_ != nullptr; }
  const SoftwareModelSpec& extensions() const { return *extensions_; }

  std::string Mjb() const { return MjbBytes(model_.get()); }
  // SerializeExtensions(extensions()).
  const std::string& extension_text() const { return extension_text_; }
  // ContentHash(Mjb(), extension_text()).
  std::uint64_t Hash() const;

 private:
  ModelPtr model_;
  std::shared_ptr<const SoftwareModelSpec> extensions_ = std::make_shared<SoftwareModelSpec>();
  std::string extension_text_;
  SoftwareSensorRegistration registration_;  // released before model_ (see the destructor)
};

// The version of the MuJoCo library actually loaded, e.g. "3.17.0".
std::string MujocoVersion();

}  // namespace urlab::physics
