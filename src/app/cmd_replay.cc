// `urlab replay`: information about a recording, its exports (CSV, .npz), a bit-for-bit
// re-simulation check, and playback through a physics thread (kinematic or re-simulating) at a
// chosen speed, with loop; headless, or with --view in the viewer with the replay timeline.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>

#include "app/commands.h"
#include "app/signals.h"
#include "urlab/core/files.h"
#include "urlab/physics/engine.h"
#include "urlab/replay/csv.h"
#include "urlab/replay/npz.h"
#include "urlab/replay/playback.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recording.h"
#include "urlab/replay/trajectory.h"
#include "urlab/viewer/viewer.h"
#include "urlab/world/manager.h"
#include "urlab/world/scene_checks.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using replay::RecordingReader;

struct ReplayArgs {
  std::string file;
  std::string scene;
  double speed = 1;
  bool loop = false;
  bool resimulate = false;
  bool check = false;
  bool info = false;
  bool fast = false;
  std::string export_csv;
  std::string export_npz;
  bool short_names = false;
  std::size_t segment = 0;  // 0: the recording must be one segment
  double duration = 0;
  bool view = false;  // the viewer window with the replay timeline
  bool paused = false;
  viewer::ViewerOptions viewer;
};

// Opens a recording, keeping the readable prefix of a damaged or unfinished one (with a warning).
RecordingReader OpenRecording(const std::string& path) {
  RecordingReader r = RecordingReader::Open(path, {true});
  if (!r.problem().empty()) {
    spdlog::warn("{}: {}; using the {} readable chunk(s)", path, r.problem(), r.chunks().size());
  }
  return r;
}

int Info(const RecordingReader& r) {
  const replay::RecordingInfo& i = r.info();
  const replay::ModelTables& t = i.tables;
  std::printf("file:        %s (%llu bytes)\n", r.path().c_str(),
              static_cast<unsigned long long>(fs::file_size(r.path())));
  std::printf("kind:        %s, format %u, written by URLab %s on MuJoCo %s, %s\n", i.kind.c_str(),
              i.format_version, i.urlab_version.c_str(), i.mujoco_version.c_str(),
              i.created.c_str());
  std::printf("scene:       %s\n", i.scene.empty() ? "(not recorded)" : i.scene.c_str());
  std::printf(
      "model:       hash %s, nq %d, nv %d, na %d, nu %d, nbody %d, nmocap %d, "
      "nsensordata %d, timestep %g\n",
      replay::HashText(i.model_hash).c_str(), t.nq, t.nv, t.na, t.nu, t.nbody, t.nmocap,
      t.nsensordata, t.timestep);
  std::string arts;
  for (const std::string& a : t.articulations) arts += (arts.empty() ? "" : ", ") + a;
  std::printf("articulations: %s; %zu joints, %zu actuators, %zu sensors\n",
              arts.empty() ? "(none)" : arts.c_str(), t.joints.size(), t.actuators.size(),
              t.sensors.size());
  for (const physics::CommandGroupLayout& g : t.command_groups) {
    std::string names;
    for (int a : g.actuators) {
      names += (names.empty() ? "" : " ") +
               (a < static_cast<int>(t.actuators.size()) ? t.actuators[a].name : "?");
    }
    std::printf("commands:    %s: %zu targets (%s)\n", g.name.c_str(), g.actuators.size(),
                names.c_str());
  }
  std::printf(
      "content:     %llu steps, t %.6f .. %.6f s, %zu chunks, compression %s, "
      "sensordata %s, keyframe every %g s\n",
      static_cast<unsigned long long>(r.frame_count()), r.first_time(), r.last_time(),
      r.chunks().size(), i.compression.c_str(), i.sensordata ? "yes" : "no", i.keyframe_interval);
  std::uint64_t payload = 0;
  for (const replay::ChunkInfo& c : r.chunks()) payload += c.stored_size;
  if (r.frame_count()) {
    std::printf("size:        %.1f bytes per step in data chunks\n",
                static_cast<double>(payload) / static_cast<double>(r.frame_count()));
  }
  std::printf("finished:    %s\n", r.finished() ? "yes" : ("NO: " + r.problem()).c_str());
  std::uint64_t markers = 0, gaps = 0, dropped = 0;
  // Per command group: the steps whose command frame was raw (control_mode raw).
  std::vector<std::uint64_t> raw_steps(t.command_groups.size(), 0);
  for (std::size_t c = 0; c < r.chunks().size(); ++c) {
    try {
      for (const replay::Record& rec : r.ReadChunk(c)) {
        if (const auto* f = std::get_if<replay::Frame>(&rec)) {
          for (std::size_t g = 0; g < f->commands.raw.size() && g < raw_steps.size(); ++g) {
            raw_steps[g] += f->commands.raw[g];
          }
        } else if (const auto* m = std::get_if<replay::Marker>(&rec)) {
          ++markers;
          std::printf("  jump at step %llu, t=%.6f: %s\n", static_cast<unsigned long long>(m->step),
                      m->time, m->text.c_str());
        } else if (const auto* g = std::get_if<replay::Gap>(&rec)) {
          ++gaps;
          dropped += g->dropped;
        }
      }
    } catch (const replay::RecordingError& e) {
      std::printf("checked:     chunks 1..%zu fine; %s\n", c, e.what());
      return 1;
    }
  }
  std::printf(
      "checked:     every chunk's checksum and records; %llu jumps, %llu gaps (%llu "
      "frames lost)\n",
      static_cast<unsigned long long>(markers), static_cast<unsigned long long>(gaps),
      static_cast<unsigned long long>(dropped));
  // A damaged or forged chunk ends the readable prefix: reported above, and a failure (a
  // recorder that died leaves an unfinished file, which is not).
  const bool damaged =
      !r.problem().empty() && r.problem_reason() == replay::RecordingError::Reason::kCorrupt;
  if (!t.command_groups.empty()) {
    std::string raw;
    for (std::size_t g = 0; g < raw_steps.size(); ++g) {
      raw += fmt::format("{}{} {} steps", g ? ", " : "", t.command_groups[g].name, raw_steps[g]);
    }
    std::printf("raw control: %s\n", raw.c_str());
  }
  return damaged ? 1 : 0;
}

// What an export writes: one segment of the frames (a segment ends where the recorded time goes
// back, at a reset) as a trajectory, with the ctrl and the applied command targets of each row.
struct ExportRows {
  replay::Trajectory traj;
  std::vector<double> ctrl;        // rows x nu
  std::vector<double> targets;     // rows x (command targets), empty without command groups
  std::vector<double> sensordata;  // rows x nsensordata, empty unless recorded
  std::size_t segments = 0;        // in the whole recording
};

// Segment `segment` (1-based; 0: the recording must have a single segment) of the recording.
ExportRows ToRows(const RecordingReader& r, std::size_t segment) {
  ExportRows out;
  replay::Trajectory& t = out.traj;
  t.nq = r.info().tables.nq;
  t.nv = r.info().tables.nv;
  double last = 0;
  bool any = false;
  std::uint64_t first_back_step = 0;
  std::size_t current = 0;
  for (std::size_t c = 0; c < r.chunks().size(); ++c) {
    for (const replay::Record& rec : r.ReadChunk(c)) {
      const auto* f = std::get_if<replay::Frame>(&rec);
      if (!f) continue;
      if (!any || !(f->time > last)) {
        if (any && current == 1) first_back_step = f->step;
        ++current;
      }
      any = true;
      last = f->time;
      if (current != (segment == 0 ? 1 : segment)) continue;
      t.time.push_back(f->time);
      t.qpos.insert(t.qpos.end(), f->qpos.begin(), f->qpos.end());
      t.qvel.insert(t.qvel.end(), f->qvel.begin(), f->qvel.end());
      out.ctrl.insert(out.ctrl.end(), f->ctrl.begin(), f->ctrl.end());
      out.targets.insert(out.targets.end(), f->commands.targets.begin(), f->commands.targets.end());
      out.sensordata.insert(out.sensordata.end(), f->sensordata.begin(), f->sensordata.end());
    }
  }
  out.segments = current;
  if (segment == 0 && current > 1) {
    throw InputError({r.path(), 0},
                     fmt::format("time goes back at step {} (a reset): the recording has {} "
                                 "segments of increasing time; export one with --segment 1..{}",
                                 first_back_step, current, current));
  }
  if (segment > current) {
    throw InputError({r.path(), 0}, fmt::format("--segment {}: the recording has {} segment(s)",
                                                segment, current));
  }
  return out;
}

// Re-simulates on the recorded model, or with --scene on that scene's (checked to be the same).
int Check(const ReplayArgs& args, const RecordingReader& r) {
  world::CompiledScene scene;
  if (!args.scene.empty()) {
    CurrentInput() = args.scene;
    scene = world::BuildCheckedScene(world::LoadSceneOrModel(args.scene));
  }
  replay::ResimOptions o;
  o.progress = [](std::uint64_t done, std::uint64_t total) {
    spdlog::info("re-simulated {} of {} steps", done, total);
  };
  o.progress_every = 20000;
  const auto start = Clock::now();
  const replay::ResimReport rep =
      replay::Resimulate(r, args.scene.empty() ? nullptr : &scene.model, o);
  std::printf("%s (%.2f s)\n", rep.str().c_str(),
              std::chrono::duration<double>(Clock::now() - start).count());
  return rep.identical ? 0 : 3;
}

int Play(const ReplayArgs& args, const RecordingReader& r) {
  std::shared_ptr<world::Session> session;
  std::unique_ptr<physics::PhysicsEngine> own;
  physics::PhysicsEngine* engine = nullptr;
  if (!args.scene.empty()) {
    CurrentInput() = args.scene;
    session = world::Session::Create(world::LoadSceneOrModel(args.scene));
    engine = &session->engine();
  } else {
    own = std::make_unique<physics::PhysicsEngine>(replay::LoadRecordedModel(r));
    engine = own.get();
  }
  replay::PlayerOptions po;
  po.mode = args.resimulate ? replay::PlayMode::kResimulate : replay::PlayMode::kKinematic;
  po.speed = args.fast ? 1 : args.speed;
  po.loop = args.loop;
  replay::Player player(*engine, r, po);
  engine->SetAsFastAsPossible(args.fast);
  engine->Start();
  SetImmediateExit(false);
  const auto start = Clock::now();
  auto next_log = start + std::chrono::seconds(1);
  spdlog::info("playing {} ({} steps, {}{}{})", r.path(), r.frame_count(),
               args.resimulate ? "re-simulating" : "kinematic",
               args.fast ? ", as fast as possible" : fmt::format(", speed {}", args.speed),
               args.loop ? ", loop" : "");
  replay::PlayerStatus st;
  while (StopSignal() == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    st = player.status();
    if (!st.error.empty()) break;
    if (st.finished && !args.loop) break;
    const auto now = Clock::now();
    if (args.duration > 0 && now - start >= std::chrono::duration<double>(args.duration)) break;
    if (now >= next_log) {
      spdlog::info("t={:.3f} s  step {}  frame {}/{}{}", st.time, st.step, st.frame + 1, st.frames,
                   st.loop ? fmt::format("  loops {}", st.loops) : "");
      next_log += std::chrono::seconds(1);
    }
  }
  engine->Stop();
  st = player.status();
  std::printf("played: frame %llu of %llu, t=%.6f s, step %llu%s\n",
              static_cast<unsigned long long>(st.frame + 1),
              static_cast<unsigned long long>(st.frames), st.time,
              static_cast<unsigned long long>(st.step), st.finished ? " (end)" : "");
  if (!st.error.empty()) {
    std::fprintf(stderr, "urlab: error: %s\n", st.error.c_str());
    return 1;
  }
  if (args.resimulate) {
    st.resim.frames = st.frames;
    st.resim.identical = !st.resim.diverged && st.resim.steps_checked > 0;
    std::printf("%s\n", st.resim.str().c_str());
    if (st.resim.diverged) return 3;
  }
  const int signal = StopSignal();
  return signal ? ExitCodeForSignal(signal) : 0;
}

// The scene a viewed replay runs on: --scene, else the scene the recording names when it is
// still there, else the composed MJCF the recording carries (written to a temporary file, with
// the asset paths it resolved when recorded). The player checks that the model is the recorded
// one (same hash).
world::SceneConfig SceneForView(const ReplayArgs& args, const RecordingReader& r,
                                std::string* temporary) {
  std::string path = args.scene;
  if (path.empty() && !r.info().scene.empty() && fs::is_regular_file(r.info().scene)) {
    path = r.info().scene;
  }
  if (path.empty()) {
    if (r.info().mjcf.empty()) {
      throw InputError({r.path(), 0},
                       "the recording names no scene and carries no MJCF: give --scene");
    }
    *temporary = (fs::temp_directory_path() / fmt::format("urlab-replay-{}-{}.xml", ::getpid(),
                                                          replay::HashText(r.info().model_hash)))
                     .string();
    WriteFileAtomic(*temporary, r.info().mjcf);
    path = *temporary;
  }
  spdlog::info("replay: viewing on {}",
               path == *temporary ? "the MJCF the recording carries" : path);
  CurrentInput() = path;
  return world::LoadSceneOrModel(path);
}

// `replay FILE --view`: the scene in the viewer, the recording played through its engine's step
// handler, the timeline driving the player. `reopen` gets the file the viewer asks to open next
// (one dropped on its window), "" when none.
int View(const ReplayArgs& args, const RecordingReader& r, std::string* reopen) {
  // A shot past the last frame would wait for a time the timeline never reaches.
  if (!args.viewer.screenshot.empty() && args.viewer.screenshot_at > r.last_time() + 1e-9) {
    throw InputError({r.path(), 0},
                     fmt::format("--at {}: past the recording's last frame "
                                 "(it holds {} to {} s)",
                                 args.viewer.screenshot_at, r.first_time(), r.last_time()));
  }
  std::string temporary;
  const world::SceneConfig scene = SceneForView(args, r, &temporary);
  world::Manager manager;
  const auto slot = std::make_shared<replay::PlaybackSlot>();
  auto view = std::make_unique<viewer::ViewerSubsystem>(args.viewer);
  viewer::ViewerSubsystem* viewer = view.get();
  view->SetManager(&manager);
  view->SetPlayback(slot);
  manager.AddSubsystem(std::move(view));
  manager.BeginPlay(scene);
  if (!temporary.empty()) fs::remove(temporary);
  CurrentInput() = args.file;
  replay::PlayerOptions po;
  po.mode = args.resimulate ? replay::PlayMode::kResimulate : replay::PlayMode::kKinematic;
  po.speed = args.speed;
  po.loop = args.loop;
  po.start_paused = args.paused;
  std::unique_ptr<replay::Player> player;
  try {
    player = std::make_unique<replay::Player>(manager.session().engine(), r, po);
  } catch (const replay::RecordingError& e) {
    manager.EndPlay();
    if (temporary.empty() || e.reason() != replay::RecordingError::Reason::kWrongModel) throw;
    throw InputError({r.path(), 0},
                     fmt::format("the MJCF the recording carries compiles to another model here "
                                 "({}); give the scene it was recorded from with --scene",
                                 e.what()));
  } catch (...) {
    manager.EndPlay();
    throw;
  }
  replay::Playback shown;
  shown.player = player.get();
  shown.reader = &r;
  shown.marks = replay::ScanTimeline(r);
  shown.label = r.path();
  shown.mode = args.resimulate ? "resimulate" : "kinematic";
  slot->Set(&shown);
  spdlog::info(
      "replay: {} frames, {} keyframes, {} resets; Space plays/pauses, Left/Right step, "
      "PgUp/PgDn keyframes, [ ] resets, Up/Down speed, L loop",
      shown.marks.frames, shown.marks.keyframes.size(), shown.marks.jumps.size());
  SetImmediateExit(false);
  const auto start = Clock::now();
  auto next = start;
  while (StopSignal() == 0 && !manager.StopRequested()) {
    manager.Tick();
    const auto now = Clock::now();
    if (args.duration > 0 && now - start >= std::chrono::duration<double>(args.duration)) break;
    next += std::chrono::microseconds(16667);
    if (next < now) next = now;
    std::this_thread::sleep_until(next);
  }
  const replay::PlayerStatus st = player->status();
  slot->Set(nullptr);
  player.reset();
  manager.EndPlay();
  *reopen = viewer->reload_request();
  std::printf("viewed: frame %llu of %llu, t=%.6f s\n",
              static_cast<unsigned long long>(st.frame + 1),
              static_cast<unsigned long long>(st.frames), st.time);
  if (!st.error.empty()) {
    std::fprintf(stderr, "urlab: error: %s\n", st.error.c_str());
    return 1;
  }
  const int signal = StopSignal();
  return signal ? ExitCodeForSignal(signal) : 0;
}

int Replay(const ReplayArgs& args) {
  CurrentInput() = args.file;
  const RecordingReader r = OpenRecording(args.file);
  if (args.info) return Info(r);
  if (!args.export_csv.empty() || !args.export_npz.empty()) {
    const ExportRows rows = ToRows(r, args.segment);
    const replay::Trajectory& t = rows.traj;
    const std::string which =
        rows.segments > 1 ? fmt::format(" (segment {} of {})", args.segment, rows.segments) : "";
    if (!args.export_csv.empty()) {
      CheckOutputs({{args.export_csv, "--export-csv"}}, {args.file});
      replay::CsvExportOptions o;
      o.short_names = args.short_names;
      if (!rows.sensordata.empty()) o.sensordata = &rows.sensordata;
      replay::ExportCsv(args.export_csv, r.info().tables, t, o);
      std::printf("wrote %s: %zu rows%s\n", args.export_csv.c_str(), t.rows(), which.c_str());
    }
    if (!args.export_npz.empty()) {
      CheckOutputs({{args.export_npz, "--export-npz"}}, {args.file});
      const replay::ModelTables& tables = r.info().tables;
      replay::NpzExtras extras;
      extras.ctrl = rows.ctrl;
      if (t.rows() > 0) {
        extras.targets = rows.targets;
        extras.sensordata = rows.sensordata;
      }
      replay::ExportNpz(args.export_npz, tables, t, replay::ExportArrays(tables, t.rows(), extras));
      std::printf("wrote %s: %zu rows%s\n", args.export_npz.c_str(), t.rows(), which.c_str());
    }
    return 0;
  }
  if (args.check) return Check(args, r);
  if (args.view) {
    std::string reopen;
    const int code = View(args, r, &reopen);
    if (reopen.empty() || StopSignal() != 0) return code;
    spdlog::info("viewer: opening {}", reopen);
    return ViewFiles(reopen, args.viewer);
  }
  return Play(args, r);
}

}  // namespace

bool IsRecordingPath(const std::string& path) {
  return path.ends_with(".urrec") || path.ends_with(".urrec.part");
}

int ViewRecording(const std::string& file, const viewer::ViewerOptions& viewer,
                  std::string* reopen) {
  ReplayArgs args;
  args.file = file;
  args.view = true;
  args.viewer = viewer;
  CurrentInput() = file;
  const RecordingReader r = OpenRecording(file);
  return View(args, r, reopen);
}

void RegisterReplayCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Play a recording made by `urlab record` (or the step server's recording_start) with the "
      "model it carries: kinematic (every recorded frame shown exactly, on the recorded time "
      "axis) or --resimulate (the recorded controls, forces and jumps re-applied to the physics, "
      "each step checked bit for bit). --check re-simulates as fast as possible without a "
      "physics thread and reports the first divergent step (exit 3). --info describes the file "
      "and checks every chunk; --export-csv writes qpos and qvel per step, --export-npz also ctrl "
      "and the applied command targets. A "
      "damaged or unfinished file is played up to its last readable chunk, with a warning.");
  static ReplayArgs args;
  cmd->add_option("FILE", args.file, "the recording (.urrec)")->required();
  cmd->add_option("--scene", args.scene,
                  "play (or --check) on this scene's model instead of the recorded one (it must "
                  "be the same model: the hashes are compared, the "
                  "physics options apart, which the recording re-applies)");
  cmd->add_option("--speed", args.speed, "recorded seconds per second of wall time (default 1)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--fast", args.fast, "play as fast as possible (ignores --speed)");
  cmd->add_flag("--loop", args.loop, "start again at the end");
  cmd->add_flag("--resimulate", args.resimulate,
                "re-simulate the physics from the recorded inputs and check each step");
  cmd->add_option("--duration", args.duration, "stop after this many wall-clock seconds")
      ->check(CLI::PositiveNumber);
  CLI::Option* check =
      cmd->add_flag("--check", args.check,
                    "re-simulate the whole recording offline and report whether every step is "
                    "bit-identical (exit 0) or the first divergent step (exit 3)");
  CLI::Option* info = cmd->add_flag("--info", args.info, "describe the file and check every chunk");
  CLI::Option* csv = cmd->add_option("--export-csv", args.export_csv,
                                     "write time, qpos and qvel per step as CSV (columns by "
                                     "joint name, name[i] for multi-value joints; /dev/stdout "
                                     "writes to standard output)");
  csv->check(OutputPath());
  CLI::Option* npz =
      cmd->add_option("--export-npz", args.export_npz,
                      "write time, qpos, qvel, ctrl and the applied command targets (rows x "
                      "targets, groups as --info lists them) as a NumPy .npz");
  npz->check(OutputPath());
  CLI::Option* segment = cmd->add_option(
      "--segment", args.segment,
      "export this segment (1, 2, ...) of a recording whose time goes back at resets; --info "
      "lists the jumps");
  segment->check(CLI::PositiveNumber);
  cmd->add_flag("--short-names", args.short_names,
                "CSV columns without the articulation prefix where unambiguous");
  CLI::Option* view = cmd->add_flag(
      "--view", args.view,
      "watch it in the viewer with the replay timeline: play/pause (Space), speed (Up/Down), "
      "scrub, single steps (Left/Right), loop (L), keyframes (PgUp/PgDn) and resets ([ ]); runs "
      "on --scene, the recorded scene when it is still there, or the MJCF the recording carries");
  cmd->add_flag("--paused", args.paused, "with --view: start paused on the first frame");
  cmd->add_option("--width", args.viewer.width, "with --view: window width (default 1280)")
      ->check(CLI::Range(64, 8192));
  cmd->add_option("--height", args.viewer.height, "with --view: window height (default 720)")
      ->check(CLI::Range(64, 8192));
  CLI::Option* shot = cmd->add_option(
      "--screenshot", args.viewer.screenshot,
      "with --view: write a PNG of the window (timeline included) showing the first frame at "
      "recorded time --at, then stop");
  cmd->add_option("--at", args.viewer.screenshot_at, "recorded time of --screenshot (default 0)")
      ->check(CLI::NonNegativeNumber)
      ->needs(shot);
  shot->needs(view);
  AddRenderQualityOptions(cmd, args.viewer);
  info->excludes(view);
  check->excludes(view);
  csv->excludes(view);
  npz->excludes(view);
  info->excludes(check)->excludes(csv)->excludes(npz);
  check->excludes(csv)->excludes(npz);
  info->excludes(segment);
  check->excludes(segment);
  cmd->callback([&exit_code] { exit_code = Replay(args); });
}

}  // namespace urlab::app
