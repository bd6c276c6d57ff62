#pragma once
// Owning handles for MuJoCo's mjModel/mjData and compilation of MJCF text from an in-memory
// virtual file system. All functions may be called from any thread, but a given mjModel/mjData
// is owned by whoever holds the handle (see engine.h for the physics thread's contract).
#include <mujoco/mujoco.h>

#include <memory>
#include <string>
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

// The same compile for a trial whose result only informs a later compile (the dialect bridge's):
// nullptr and MuJoCo's message in `error` when MuJoCo refuses the model; compiler warnings are
// not reported (the real compile reports them).
ModelPtr TryCompileXmlString(const std::string& xml, std::string* error);

// Loads an MJCF file from disk with MuJoCo's own mj_loadXML (baseline for comparisons).
// Throws CompileError.
ModelPtr LoadXmlFile(const std::string& path);

// Allocates mjData for `m`. Throws MujocoError when MuJoCo cannot allocate it.
DataPtr MakeData(const mjModel* m);

// Saves a compiled model as MuJoCo binary (.mjb). Throws Error on I/O failure.
void SaveMjb(const mjModel* m, const std::string& path);

// The version of the MuJoCo library actually loaded, e.g. "2.2.2".
std::string MujocoVersion();

}  // namespace urlab::physics
