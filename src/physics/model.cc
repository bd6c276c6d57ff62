#include "urlab/physics/model.h"

#include <cstdio>
#include <cstring>
#include <filesystem>

#include "urlab/core/files.h"
#include "urlab/core/mujoco_handlers.h"

namespace urlab::physics {

namespace {

constexpr int kErrorSize = 2048;
constexpr const char* kVirtualName = "urlab_model.xml";

struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};
using VfsPtr = std::unique_ptr<mjVFS, VfsDeleter>;

// A VFS holding one file `name` with `bytes`; nullptr when MuJoCo cannot allocate it.
VfsPtr VfsWith(const char* name, std::string_view bytes) {
  VfsPtr vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  if (mj_addBufferVFS(vfs.get(), name, bytes.data(), static_cast<int>(bytes.size())) != 0) {
    return nullptr;
  }
  return vfs;
}

// mj_loadXML reports compiler warnings through its error buffer with a non-null model.
ModelPtr FinishLoad(mjModel* m, const char* error) {
  if (!m) throw CompileError(error[0] ? error : "MuJoCo could not compile the model");
  if (error[0]) ReportMujocoWarning(error);
  return ModelPtr(m);
}

// mj_loadXML of `xml` from an in-memory VFS holding only that text (the VFS on the
// heap). `error` receives the compiler's message (or warning when the model compiled).
mjModel* LoadFromMemory(const std::string& xml, char* error) {
  VfsPtr vfs = VfsWith(kVirtualName, xml);
  if (!vfs) throw CompileError("could not allocate the in-memory model file");
  return mj_loadXML(kVirtualName, vfs.get(), error, kErrorSize);
}

}  // namespace

ModelPtr CompileXmlString(const std::string& xml) {
  char error[kErrorSize] = "";
  mjModel* m = LoadFromMemory(xml, error);
  return FinishLoad(m, error);
}

ModelPtr LoadXmlFile(const std::string& path) {
  if (!std::filesystem::exists(path)) throw CompileError(path + ": file not found");
  char error[kErrorSize] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, kErrorSize);
  return FinishLoad(m, error);
}

DataPtr MakeData(const mjModel* m) {
  mjData* d = mj_makeData(m);
  if (!d) throw MujocoError("mj_makeData failed");
  return DataPtr(d);
}

std::string MjbBytes(const mjModel* m) {
  const int size = mj_sizeModel(m);
  std::string bytes(static_cast<size_t>(size), '\0');
  mj_saveModel(m, nullptr, bytes.data(), size);
  return bytes;
}

ModelPtr LoadMjbBytes(std::string_view mjb) {
  if (mjb.empty()) throw Error("no model (empty MJB)");
  constexpr const char* kName = "urlab_model.mjb";
  VfsPtr vfs = VfsWith(kName, mjb);
  if (!vfs) throw Error("the MJB does not fit in memory");
  mjModel* m = nullptr;
  std::string error;
  try {
    m = mj_loadModel(kName, vfs.get());  // our handler turns mju_error into an exception
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!m) {
    throw Error("MuJoCo cannot load the MJB" + (error.empty() ? std::string() : ": " + error));
  }
  return ModelPtr(m);
}

std::uint64_t ContentHash(std::string_view mjb) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : mjb) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// ---- Model

Model::Model(ModelPtr model) : model_(std::move(model)) {}

Model Model::FromMjb(std::string_view mjb) { return Model(LoadMjbBytes(mjb)); }

Model Model::Copy() const {
  if (!model_) throw Error("copy of an empty model");
  ModelPtr copy(mj_copyModel(nullptr, model_.get()));
  if (!copy) throw Error("MuJoCo could not copy the model");
  return Model(std::move(copy));
}

std::uint64_t Model::Hash() const { return ContentHash(Mjb()); }

std::string MujocoVersion() { return mj_versionString(); }

}  // namespace urlab::physics
