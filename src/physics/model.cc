#include "urlab/physics/model.h"

#include <cstdio>
#include <cstring>
#include <filesystem>

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

// mj_loadXML reports compiler warnings through its error buffer with a non-null model.
ModelPtr FinishLoad(mjModel* m, const char* error) {
  if (!m) throw CompileError(error[0] ? error : "MuJoCo could not compile the model");
  if (error[0]) ReportMujocoWarning(error);
  return ModelPtr(m);
}

// mj_loadXML of `xml` from an in-memory VFS holding only that text (the VFS is 2 MB: on the
// heap). `error` receives the compiler's message (or warning when the model compiled).
mjModel* LoadFromMemory(const std::string& xml, char* error) {
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), kVirtualName, static_cast<int>(xml.size())) != 0) {
    throw CompileError("could not allocate the in-memory model file");
  }
  const int index = mj_findFileVFS(vfs.get(), kVirtualName);
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());
  return mj_loadXML(kVirtualName, vfs.get(), error, kErrorSize);
}

}  // namespace

ModelPtr CompileXmlString(const std::string& xml) {
  char error[kErrorSize] = "";
  mjModel* m = LoadFromMemory(xml, error);
  return FinishLoad(m, error);
}

ModelPtr TryCompileXmlString(const std::string& xml, std::string* error) {
  char buf[kErrorSize] = "";
  ModelPtr m(LoadFromMemory(xml, buf));
  if (!m) *error = buf[0] ? buf : "MuJoCo could not compile the model";
  return m;
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

void SaveMjb(const mjModel* m, const std::string& path) {
  const int size = mj_sizeModel(m);
  std::vector<unsigned char> buf(static_cast<size_t>(size));
  mj_saveModel(m, nullptr, buf.data(), size);
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw Error(path + ": cannot open for writing");
  const bool written = std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) throw Error(path + ": write failed");
}

std::string MujocoVersion() {
  const int v = mj_version();
  return std::to_string(v / 100) + "." + std::to_string(v / 10 % 10) + "." + std::to_string(v % 10);
}

}  // namespace urlab::physics
