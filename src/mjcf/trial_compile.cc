#include "mjcf/trial_compile.h"

#include <cstring>

namespace urlab::mjcf {

mjModel* TrialCompile(const std::string& xml, std::string* error) {
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  const char* name = "urlab_bridge_trial.xml";
  if (mj_makeEmptyFileVFS(&vfs, name, static_cast<int>(xml.size())) != 0) {
    *error = "could not allocate the in-memory model";
    return nullptr;
  }
  std::memcpy(vfs.filedata[mj_findFileVFS(&vfs, name)], xml.data(), xml.size());
  char buf[1024] = "";
  mjModel* m = mj_loadXML(name, &vfs, buf, sizeof(buf));
  mj_deleteVFS(&vfs);
  if (!m) *error = buf;
  return m;
}

}  // namespace urlab::mjcf
