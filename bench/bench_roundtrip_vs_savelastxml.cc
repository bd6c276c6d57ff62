// Comparison: URLab's import/export round trip versus MuJoCo 2.2.2's own mj_saveLastXML on every
// model under tests/data/mjcf/corpus (or the folders given). For each model the output is
// reloaded from another working directory and its 1000-step zero-control trajectory compared
// bit for bit with the original's. Prints counts for both and the ratio of bit-identical models.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"
#include "urlab/physics/trajectory_compare.h"

namespace fs = std::filesystem;

namespace {

enum class Outcome { kIdentical, kDiffers, kNoReload };

Outcome Check(const mjModel* original, const std::string& out_file) {
  const fs::path old = fs::current_path();
  fs::current_path(fs::temp_directory_path());
  urlab::physics::ModelPtr again;
  try {
    again = urlab::physics::LoadXmlFile(out_file);
  } catch (const urlab::Error&) {
    fs::current_path(old);
    return Outcome::kNoReload;
  }
  fs::current_path(old);
  if (!urlab::physics::CompareSizes(original, again.get()).empty()) return Outcome::kDiffers;
  return urlab::physics::CompareTrajectories(original, again.get(), 1000).empty()
             ? Outcome::kIdentical
             : Outcome::kDiffers;
}

}  // namespace

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  urlab::SetLogLevel("off");
  std::vector<std::string> dirs;
  for (int i = 1; i < argc; ++i) dirs.push_back(argv[i]);
  if (dirs.empty()) dirs.push_back(URLAB_SOURCE_DIR "/tests/data/mjcf/corpus");
  std::vector<std::string> files;
  for (const auto& d : dirs) {
    for (const auto& e : fs::recursive_directory_iterator(d)) {
      if (e.path().extension() == ".xml") files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  const fs::path tmp = fs::temp_directory_path() / ("urlab_rt_cmp_" + std::to_string(getpid()));
  fs::create_directories(tmp);
  int total = 0, ours[3] = {0, 0, 0}, theirs[3] = {0, 0, 0};
  for (const std::string& f : files) {
    urlab::physics::ModelPtr original;
    try {
      original = urlab::physics::LoadXmlFile(f);
    } catch (const urlab::Error&) {
      continue;  // an include-only part, not a model
    }
    ++total;
    const std::string stem = fs::path(f).stem().string();
    const std::string mj_out = (tmp / (stem + "_mj.xml")).string();
    char err[1000] = "";
    mj_saveLastXML(mj_out.c_str(), original.get(), err, sizeof(err));
    const Outcome t = Check(original.get(), mj_out);
    const std::string our_out = (tmp / (stem + "_urlab.xml")).string();
    urlab::mjcf::WriteFile(urlab::mjcf::ReadFile(f), our_out);
    const Outcome o = Check(original.get(), our_out);
    ++theirs[static_cast<int>(t)];
    ++ours[static_cast<int>(o)];
    const char* names[] = {"identical", "differs", "does not reload"};
    std::printf("%-60s mj_saveLastXML: %-16s urlab: %s\n", f.c_str(), names[static_cast<int>(t)],
                names[static_cast<int>(o)]);
  }
  fs::remove_all(tmp);
  std::printf("models=%d\n", total);
  std::printf("mj_saveLastXML: bit_identical=%d differs=%d no_reload=%d\n", theirs[0], theirs[1],
              theirs[2]);
  std::printf("urlab:          bit_identical=%d differs=%d no_reload=%d\n", ours[0], ours[1],
              ours[2]);
  std::printf("ratio=%.3f (urlab bit-identical models / all models)\n",
              total ? static_cast<double>(ours[0]) / total : 0.0);
  return ours[0] == total ? 0 : 1;
}
