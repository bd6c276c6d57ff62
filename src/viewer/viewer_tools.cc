// ViewerCore: what MuJoCo's simulate offers beyond our own viewer: single steps, the model's
// cameras, keyframes (load, save, copy pose), saving and printing the model, reload and
// drag-and-drop, and the overlays (help, info, profiler, plots). Everything that changes the
// simulation is a queued command; the files follow the output rule (core/files.h).
#include <GLFW/glfw3.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/mjcf/writer.h"
#include "urlab/ops/scene_export.h"
#include "urlab/ops/simulation.h"
#include "urlab/replay/recorder.h"
#include "viewer/viewer_core.h"

namespace urlab::viewer::internal {

namespace fs = std::filesystem;

namespace {

std::string Numbers(const mjtNum* v, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += fmt::format("{}{:.6g}", i ? " " : "", v[i]);
  return s;
}

// Runs a MuJoCo print function into a temporary file and returns what it wrote.
template <typename Fn>
std::string PrintToString(Fn print) {
  char tmpl[] = "/tmp/urlab-print-XXXXXX";
  const int fd = mkstemp(tmpl);
  if (fd < 0) throw Error("viewer: cannot make a temporary file to print into");
  close(fd);
  print(tmpl);
  std::ifstream in(tmpl, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  fs::remove(tmpl);
  return text.str();
}

bool EndsWith(const std::string& s, const char* suffix) {
  const std::string x = suffix;
  return s.size() >= x.size() && s.compare(s.size() - x.size(), x.size(), x) == 0;
}

}  // namespace

void ViewerCore::SetStatus(std::string text) {
  spdlog::info("viewer: {}", text);
  status_ = std::move(text);
}

std::string ViewerCore::OutputPath(const std::string& name) const {
  return options_.files_dir.empty() ? name : (fs::path(options_.files_dir) / name).string();
}

void ViewerCore::SetCamera(int id) {
  const mjModel* m = view_->model();
  if (id < -1 || id >= m->ncam) return;
  camera_ = id;
  mjvCamera& cam = view_->camera();
  if (id < 0) {
    cam.type = mjCAMERA_FREE;
    cam.fixedcamid = -1;
    return;
  }
  if (possession_.active()) TogglePossess();
  cinematic_.Stop();
  cam.type = mjCAMERA_FIXED;
  cam.fixedcamid = id;
}

void ViewerCore::SetKey(int k) {
  const int nkey = view_->model()->nkey;
  key_ = nkey > 0 ? std::clamp(k, 0, nkey - 1) : 0;
}

void ViewerCore::SetDisableFlag(int i, bool disabled) {
  if (i < 0 || i >= mjNDISABLE) return;
  SetOptions(
      [i, disabled](mjOption& o) {
        if (disabled) {
          o.disableflags |= 1 << i;
        } else {
          o.disableflags &= ~(1 << i);
        }
      },
      fmt::format("{} {}", mjDISABLESTRING[i], disabled ? "off" : "on"));
}

void ViewerCore::SetEnableFlag(int i, bool enabled) {
  if (i < 0 || i >= mjNENABLE) return;
  SetOptions(
      [i, enabled](mjOption& o) {
        if (enabled) {
          o.enableflags |= 1 << i;
        } else {
          o.enableflags &= ~(1 << i);
        }
      },
      fmt::format("{} {}", mjENABLESTRING[i], enabled ? "on" : "off"));
}

void ViewerCore::Step() {
  physics::PhysicsEngine& engine = session_->engine();
  if (replay_mode()) {
    PerformTimeline(TimelineAction::kStepForward);
    return;
  }
  if (!engine.paused()) {
    SetStatus("single steps while paused (P pauses)");
    return;
  }
  ops::Step(*session_, 1);
}

std::string ViewerCore::SaveXml() {
  const std::string path = OutputPath("urlab_scene.xml");
  std::vector<std::string> changed;  // asset paths relative to the output folder
  WriteFileAtomic(
      path, ops::SceneXml(*session_, fs::absolute(path).parent_path().lexically_normal().string(),
                          &changed));
  SetStatus("saved the composed scene to " + path +
            (changed.empty() ? ""
                             : fmt::format(" with the options changed at run time ({})",
                                           fmt::join(changed, ", "))));
  return path;
}

std::string ViewerCore::SaveMjb() {
  const std::string path = OutputPath("urlab_scene.mjb");
  const physics::Model model = session_->engine().CopyModel();  // under the step mutex
  WriteFileAtomic(path, model.Mjb());
  SetStatus("saved the model to " + path);
  return path;
}

std::string ViewerCore::PrintModel() {
  const std::string path = OutputPath("urlab_model.txt");
  const physics::Model model = session_->engine().CopyModel();
  WriteFileAtomic(path, PrintToString([&](const char* f) { mj_printModel(model.get(), f); }));
  SetStatus("printed the model to " + path);
  return path;
}

std::string ViewerCore::PrintData() {
  const std::string path = OutputPath("urlab_data.txt");
  WriteFileAtomic(
      path, PrintToString([&](const char* f) { mj_printData(view_->model(), view_->data(), f); }));
  SetStatus(fmt::format("printed the data at t={:.3f} s to {}", view_->data()->time, path));
  return path;
}

std::string ViewerCore::CopyPose() {
  const mjModel* m = view_->model();
  const mjData* d = view_->data();
  std::string key =
      fmt::format("<key time=\"{:.6g}\" qpos=\"{}\"", d->time, Numbers(d->qpos, m->nq));
  if (m->nv) key += fmt::format(" qvel=\"{}\"", Numbers(d->qvel, m->nv));
  if (m->na) key += fmt::format(" act=\"{}\"", Numbers(d->act, m->na));
  if (m->nu) key += fmt::format(" ctrl=\"{}\"", Numbers(d->ctrl, m->nu));
  if (m->nmocap) {
    key += fmt::format(" mpos=\"{}\" mquat=\"{}\"", Numbers(d->mocap_pos, 3 * m->nmocap),
                       Numbers(d->mocap_quat, 4 * m->nmocap));
  }
  key += "/>";
  window_->SetClipboard(key);
  SetStatus(
      fmt::format("copied the pose at t={:.3f} s ({} values) to the clipboard", d->time, m->nq));
  return key;
}

void ViewerCore::LoadKey() {
  const mjModel* m = view_->model();
  if (m->nkey == 0) {
    SetStatus("the model has no keyframes");
    return;
  }
  const int k = key_;
  physics::cmd::SetState s;
  s.qpos.push_back(
      {0, std::vector<mjtNum>(m->key_qpos + k * m->nq, m->key_qpos + (k + 1) * m->nq)});
  s.qvel.push_back(
      {0, std::vector<mjtNum>(m->key_qvel + k * m->nv, m->key_qvel + (k + 1) * m->nv)});
  if (m->nu) {
    s.ctrl.push_back(
        {0, std::vector<mjtNum>(m->key_ctrl + k * m->nu, m->key_ctrl + (k + 1) * m->nu)});
  }
  s.time = m->key_time[k];
  physics::PhysicsEngine& engine = session_->engine();
  for (int b = 0; b < m->nmocap; ++b) {
    physics::cmd::SetMocap mc;
    mc.mocap_id = b;
    std::copy_n(m->key_mpos + k * 3 * m->nmocap + 3 * b, 3, mc.pos.begin());
    std::copy_n(m->key_mquat + k * 4 * m->nmocap + 4 * b, 4, mc.quat.begin());
    engine.Submit(std::move(mc));
  }
  engine.Submit(std::move(s));
  const char* name = mj_id2name(m, mjOBJ_KEY, k);
  SetStatus(fmt::format("loaded keyframe {} ({})", k, name ? name : "unnamed"));
}

void ViewerCore::SaveKey() {
  mjModel* m = view_->model();
  if (m->nkey == 0) {
    SetStatus("the model has no keyframes to save into");
    return;
  }
  const mjData* d = view_->data();
  const int k = key_;
  m->key_time[k] = d->time;
  std::copy_n(d->qpos, m->nq, m->key_qpos + k * m->nq);
  std::copy_n(d->qvel, m->nv, m->key_qvel + k * m->nv);
  std::copy_n(d->act, m->na, m->key_act + k * m->na);
  std::copy_n(d->ctrl, m->nu, m->key_ctrl + k * m->nu);
  std::copy_n(d->mocap_pos, 3 * m->nmocap, m->key_mpos + k * 3 * m->nmocap);
  std::copy_n(d->mocap_quat, 4 * m->nmocap, m->key_mquat + k * 4 * m->nmocap);
  SetStatus(fmt::format("saved the state at t={:.3f} s into keyframe {} (Load key restores it)",
                        d->time, k));
}

void ViewerCore::RequestReload(std::string path) {
  if (path.empty()) path = session_->scene_config().path;
  SetStatus("opening " + path);
  reload_request_ = std::move(path);
}

void ViewerCore::ReloadKeepingState() {
  const std::string& path = session_->scene_config().path;
  if (replay_mode()) {  // a replay shows a recorded model: Reload opens the scene itself, as before
    RequestReload("");
    return;
  }
  std::string restart_because = options_.reload_restarts_because;
  if (restart_because.empty() && recorder_ && recorder_->recorder() &&
      recorder_->recorder()->active()) {
    // Its file holds the model it began with: a replay would re-simulate the old values.
    restart_because = "a recording is being written, whose model is the one it began with";
  }
  if (!restart_because.empty()) {
    spdlog::info("viewer: reloading {} from the start; the state cannot be kept: {}", path,
                 restart_because);
    RequestReload("");
    return;
  }
  const world::Session::Reload r = session_->ReloadKeepingState();
  if (r.kept) {  // one line in the log and the panel
    SetStatus("reloaded " + path + " into the running simulation, state kept");
    return;
  }
  spdlog::info("viewer: reloading {} from the start; the state cannot be kept: {}", path, r.reason);
  RequestReload("");
}

void ViewerCore::OnDrop(const std::vector<std::string>& paths) {
  if (paths.empty()) return;
  const std::string& p = paths.front();
  if (EndsWith(p, ".yaml") || EndsWith(p, ".yml") || EndsWith(p, ".xml") || EndsWith(p, ".urrec") ||
      EndsWith(p, ".urrec.part")) {
    RequestReload(p);  // a recording plays with the replay timeline
  } else {
    SetStatus("cannot open " + p +
              ": drop a scene (.yaml), an MJCF model (.xml) or a recording (.urrec)");
  }
}

// ---------------------------------------------------------------------------------------------
// Overlays

std::pair<std::string, std::string> ViewerCore::HelpText() const {
  std::string keys, what;
  // While a replay plays, the timeline's keys come first and take over the keys they share.
  const bool replay = replay_mode();
  if (replay) {
    for (const TimelineKey& k : TimelineKeys()) {
      keys += std::string(k.label) + "\n";
      what += "replay: " + std::string(k.what) + "\n";
    }
  }
  for (const Hotkey& h : Hotkeys()) {
    if (replay && h.mods == 0 && TimelineActionOfKey(h.key)) continue;
    keys += std::string(h.label) + "\n";
    what += std::string(h.help) + "\n";
  }
  keys +=
      "Shift+letter\nAlt+0-5\nAlt+Shift+0-5\nleft drag\nright drag\nwheel\n"
      "double-click\nCtrl+drag";
  what +=
      "visualisation flag (see the panel)\ngeom group\nsite group\nrotate\nmove\nzoom\n"
      "select (right: look at)\npush the selected body";
  return {keys, what};
}

void ViewerCore::DrawOverlays(const mjrRect& vp) {
  const mjrContext* con = &view_->context();
  const bool want_profile = overlays_.profiler || overlays_.info;
  if (want_profile) profiler_.Request(session_->engine());
  const std::optional<ProfileSample> prof = want_profile ? profiler_.Latest() : std::nullopt;
  if (overlays_.help) {
    const auto [keys, what] = HelpText();
    mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, vp, keys.c_str(), what.c_str(), con);
  }
  if (overlays_.info) {
    const physics::PhysicsEngine& engine = session_->engine();
    const std::string titles = "Time\nStep\nSize\nCPU\nSolver\nFPS\nCamera";
    const char* cam = camera_ >= 0 ? mj_id2name(view_->model(), mjOBJ_CAMERA, camera_) : nullptr;
    const std::string values = fmt::format(
        "{:.3f} s{}\n{}\n{} contacts, {} constraints\n{:.3f} ms/step\n{} iterations\n{:.0f}\n{}",
        frame_ ? frame_->time : 0.0, engine.paused() ? " (paused)" : "", frame_ ? frame_->step : 0,
        prof ? prof->ncon : 0, prof ? prof->nefc : 0, prof ? prof->step_ms : 0.0,
        prof ? prof->iterations : 0, fps_,
        camera_ < 0 ? std::string("free") : std::string(cam ? cam : "camera"));
    mjr_overlay(mjFONT_NORMAL, mjGRID_BOTTOMLEFT, vp, titles.c_str(), values.c_str(), con);
  }
  const int fw = std::max(200, vp.width / 3);
  if (overlays_.profiler) {
    const int fh = std::max(200, vp.height / 2);
    profiler_.Draw({vp.left + vp.width - fw, vp.bottom + vp.height - fh, fw, fh}, con);
  }
  if (overlays_.plots) {
    const int fh = std::max(150, vp.height / 3);
    plots_.Draw({vp.left + vp.width - fw, vp.bottom, fw, fh}, con);
  }
}

}  // namespace urlab::viewer::internal
