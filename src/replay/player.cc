#include "urlab/replay/player.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>

#include "urlab/physics/step_core.h"

namespace urlab::replay {

namespace {

using Reason = RecordingError::Reason;

bool SameBits(const double* a, const std::vector<double>& b) {
  return b.empty() || std::memcmp(a, b.data(), b.size() * sizeof(double)) == 0;
}

// The first element whose bits differ, -1 when none.
int FirstDifference(const double* a, const std::vector<double>& b) {
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (std::memcmp(a + i, &b[i], sizeof(double)) != 0) return static_cast<int>(i);
  }
  return -1;
}

std::string JointAt(const ModelTables& t, int index, bool qpos) {
  for (const JointEntry& j : t.joints) {
    const int adr = qpos ? j.qposadr : j.dofadr;
    const int n = qpos ? j.nq : j.nv;
    if (index >= adr && index < adr + n) {
      return n == 1 ? j.name : fmt::format("{}[{}]", j.name, index - adr);
    }
  }
  return {};
}

void Copy(const std::vector<double>& from, double* to) {
  if (!from.empty()) std::memcpy(to, from.data(), from.size() * sizeof(double));
}

// Writes a frame's inputs (what mj_step reads besides the state).
void ApplyInputs(const Frame& f, mjData* d) {
  Copy(f.ctrl, d->ctrl);
  Copy(f.mocap_pos, d->mocap_pos);
  Copy(f.mocap_quat, d->mocap_quat);
  Copy(f.qfrc_applied, d->qfrc_applied);
  Copy(f.xfrc_applied, d->xfrc_applied);
}

// Compares the state after a re-simulated step with the recorded frame; fills `r` on the first
// difference.
bool Matches(const ModelTables& t, const Frame& f, const mjData* d, ResimReport* r) {
  const struct {
    const char* field;
    const double* now;
    const std::vector<double>* rec;
    bool qpos;
  } fields[] = {{"qpos", d->qpos, &f.qpos, true},
                {"qvel", d->qvel, &f.qvel, false},
                {"act", d->act, &f.act, false}};
  if (std::memcmp(&d->time, &f.time, sizeof(double)) != 0) {
    r->field = "time";
    r->index = 0;
    r->recorded = f.time;
    r->simulated = d->time;
    return false;
  }
  for (const auto& x : fields) {
    if (SameBits(x.now, *x.rec)) continue;
    const int i = FirstDifference(x.now, *x.rec);
    r->field = x.field;
    r->index = i;
    r->recorded = (*x.rec)[static_cast<std::size_t>(i)];
    r->simulated = x.now[i];
    r->element = std::string(x.field) == "act" ? std::string()
                                               : JointAt(t, i, std::string(x.field) == "qpos");
    return false;
  }
  return true;
}

void ApplyOptions(const OptionsRecord& o, mjOption* opt) {
  std::memcpy(opt, o.option.data(), sizeof(mjOption));
}

}  // namespace

std::string ResimReport::str() const {
  if (identical) {
    return fmt::format("re-simulation identical: {} of {} steps bit for bit{}", steps_checked,
                       frames, stopped.empty() ? "" : " (" + stopped + ")");
  }
  if (diverged) {
    return fmt::format(
        "re-simulation DIVERGED at step {} (frame {}, t={:.6f} s): {}[{}]{} recorded {:.17g}, "
        "re-simulated {:.17g} ({} steps matched before it)",
        divergent_step, divergent_index, divergent_time, field, index,
        element.empty() ? "" : " (" + element + ")", recorded, simulated, steps_checked);
  }
  return fmt::format("re-simulation stopped after {} steps: {}", steps_checked, stopped);
}

physics::Model LoadRecordedModel(const RecordingReader& reader) {
  const RecordingInfo& info = reader.info();
  if (info.mjb.empty()) {
    throw RecordingError(Reason::kCorrupt, reader.path(), "the recording holds no model");
  }
  if (physics::ContentHash(info.mjb) != info.model_hash) {
    throw RecordingError(Reason::kCorrupt, reader.path(),
                         "the recorded model does not match the header's model hash");
  }
  try {
    return physics::Model::FromMjb(info.mjb);
  } catch (const Error& e) {
    throw RecordingError(Reason::kCorrupt, reader.path(),
                         fmt::format("the recorded model (MuJoCo {}) cannot be loaded by MuJoCo "
                                     "{}: {}",
                                     info.mujoco_version, physics::MujocoVersion(), e.what()));
  }
}

void CheckSameModel(const RecordingReader& reader, const physics::Model& m, bool compare_options) {
  const RecordingInfo& info = reader.info();
  std::uint64_t h = 0;
  if (compare_options) {
    h = m.Hash();
  } else {
    // `m` with the recorded options (read from the recorded MJB) hashes as the recorded model
    // when it is that model, whatever options it runs with now.
    physics::ModelPtr recorded;
    try {
      recorded = physics::LoadMjbBytes(info.mjb);
    } catch (const Error& e) {
      throw RecordingError(Reason::kCorrupt, reader.path(),
                           std::string("the recorded model cannot be loaded: ") + e.what());
    }
    physics::ModelPtr probe(mj_copyModel(nullptr, m.get()));
    if (!probe) throw Error("MuJoCo could not copy the model");
    probe->opt = recorded->opt;
    h = physics::ContentHash(physics::MjbBytes(probe.get()));
  }
  if (h != info.model_hash) {
    throw RecordingError(
        Reason::kWrongModel, reader.path(),
        fmt::format("recorded with another model (recording model hash {}, this model {}): "
                    "play it without --scene to use the model it carries",
                    HashText(info.model_hash), HashText(h)));
  }
}

namespace {

// The recorded inputs of the frame being re-simulated are the controls of a step core's iteration:
// Resimulate and the Player's re-simulation advance the same StepCore::Advance the engine does.
struct Resimulator {
  explicit Resimulator(physics::Model model)
      : core(std::move(model), physics::StepCore::Options{.reset_on_divergence = false,
                                                          .log_command_failures = false}) {
    core.SetApplyControlsHook([this](const mjModel*, mjData* d) { ApplyInputs(*frame, d); });
  }
  // Re-runs the step behind recorded frame `f` (its inputs, then one iteration).
  void Step(const Frame& f) {
    frame = &f;
    core.Advance({.force_step = true, .honour_error_latch = false});
    frame = nullptr;
  }
  mjModel* model() { return core.mutable_model(); }
  mjData* data() { return core.data(); }

  physics::StepCore core;
  const Frame* frame = nullptr;
};

}  // namespace

ResimReport Resimulate(const RecordingReader& reader, const physics::Model* given,
                       const ResimOptions& options) {
  physics::Model owned;
  if (given) {
    CheckSameModel(reader, *given);
    owned = given->Copy();
  } else {
    owned = LoadRecordedModel(reader);
  }
  Resimulator sim(std::move(owned));
  mjModel* m = sim.model();
  mjData* d = sim.data();
  const ModelTables& t = reader.info().tables;
  ResimReport r;
  r.frames = reader.frame_count();
  bool have_state = false;
  bool need_state = false;  // after a gap or an uncaptured jump: wait for the next keyframe
  std::uint64_t index = 0;
  for (std::size_t c = 0; c < reader.chunks().size(); ++c) {
    for (Record& rec : reader.ReadChunk(c)) {
      if (auto* s = std::get_if<StateRecord>(&rec)) {
        if (!have_state || need_state || s->jump != 0) {
          physics::RestoreState(m, d, s->state);
          have_state = true;
          need_state = false;
        }
      } else if (auto* o = std::get_if<OptionsRecord>(&rec)) {
        ApplyOptions(*o, &m->opt);
      } else if (auto* mk = std::get_if<Marker>(&rec)) {
        if (IsUncapturedJump(*mk)) {
          need_state = true;
          if (r.stopped.empty()) {
            r.stopped = fmt::format(
                "a jump the recorder could not capture at step {} was "
                "skipped to the next keyframe",
                mk->step);
          }
        }
      } else if (auto* g = std::get_if<Gap>(&rec)) {
        need_state = true;
        if (r.stopped.empty()) {
          r.stopped = fmt::format("{} frames were lost after step {}; resumed at the next keyframe",
                                  g->dropped, g->after_step);
        }
      } else if (auto* f = std::get_if<Frame>(&rec)) {
        if (have_state && !need_state) {
          sim.Step(*f);
          if (!Matches(t, *f, d, &r)) {
            r.diverged = true;
            r.divergent_step = f->step;
            r.divergent_index = index;
            r.divergent_time = f->time;
            if (options.stop_at_first_divergence) return r;
          } else {
            ++r.steps_checked;
          }
        }
        ++index;
        if (options.progress && options.progress_every && index % options.progress_every == 0) {
          options.progress(index, r.frames);
        }
      }
    }
  }
  r.identical = !r.diverged && r.steps_checked > 0;
  return r;
}

// ---- Player ----

struct Player::Impl {
  physics::PhysicsEngine& engine;
  const RecordingReader& reader;
  ModelTables tables;

  mutable std::mutex mutex;  // the controls and the status
  PlayerOptions options;
  bool playing = false;
  std::optional<double> seek_time;
  std::optional<std::uint64_t> seek_step;
  std::optional<std::uint64_t> seek_frame;
  PlayerStatus status;

  // Physics thread only.
  std::size_t chunk = 0;
  std::vector<Record> records;
  std::size_t next = 0;  // next record in `records`
  bool loaded = false;
  double clock = 0;            // playback position, recorded seconds since the start
  double shown_pos = 0;        // position of the frame shown
  double last_frame_time = 0;  // recorded time of the last frame consumed
  bool have_last = false;
  bool jumped = false;  // a marker since the last frame
  std::uint64_t frame_index = 0;
  bool have_state = false;
  bool seeking = false;  // a seek is under way
  // Re-simulation mode: the recorded model re-simulated by its own step core; each iteration
  // shows its state on the engine.
  std::unique_ptr<Resimulator> sim;

  Impl(physics::PhysicsEngine& e, const RecordingReader& r) : engine(e), reader(r) {}

  void Load(std::size_t c) {
    chunk = c;
    records = reader.ReadChunk(c);
    next = 0;
    loaded = true;
  }
  // The next frame (applying states and options to the re-simulation on the way in resimulate
  // mode); nullptr at the end of the recording.
  const Frame* NextFrame(bool resim);
  void Rewind(std::size_t c);
  void Step(const mjModel* m, mjData* d);
  // Re-simulates frame `f` when a state to start from is known.
  void Resimulate(const Frame& f) {
    if (have_state) sim->Step(f);
  }
};

void Player::Impl::Rewind(std::size_t c) {
  Load(c);
  have_last = false;
  have_state = false;
  frame_index = 0;
  for (std::size_t i = 0; i < c; ++i) frame_index += reader.chunks()[i].frames;
}

const Frame* Player::Impl::NextFrame(bool resim) {
  while (true) {
    if (!loaded) Load(0);
    if (next >= records.size()) {
      if (chunk + 1 >= reader.chunks().size()) return nullptr;
      Load(chunk + 1);
      continue;
    }
    Record& rec = records[next++];
    if (auto* f = std::get_if<Frame>(&rec)) return f;
    if (auto* s = std::get_if<StateRecord>(&rec)) {
      if (resim && (!have_state || s->jump != 0)) {
        physics::RestoreState(sim->model(), sim->data(), s->state);
        have_state = true;
      }
    } else if (auto* o = std::get_if<OptionsRecord>(&rec)) {
      if (resim) ApplyOptions(*o, &sim->model()->opt);
    } else if (std::holds_alternative<Marker>(rec) || std::holds_alternative<Gap>(rec)) {
      jumped = true;
      if (std::holds_alternative<Gap>(rec)) have_state = false;
    }
  }
}

void Player::Impl::Step(const mjModel* m, mjData* d) {
  PlayerOptions opt;
  bool play = false;
  {
    std::lock_guard<std::mutex> lock(mutex);
    opt = options;
    play = playing;
    if (seek_time || seek_step || seek_frame) {
      if (!seeking) {
        const std::size_t c = seek_time ? reader.ChunkAt(*seek_time) : [&] {
          std::size_t best = 0;
          std::uint64_t first = 0;  // index of the chunk's first frame
          for (std::size_t i = 0; i < reader.chunks().size(); ++i) {
            const ChunkInfo& ci = reader.chunks()[i];
            if (ci.frames && (seek_step ? ci.first_step <= *seek_step : first <= *seek_frame)) {
              best = i;
            }
            first += ci.frames;
          }
          return best;
        }();
        // Re-simulation starts from a keyframe: the nearest chunk at or before that has one
        // (a chunk flushed while a keyframe request was late starts without).
        std::size_t from = c;
        if (opt.mode == PlayMode::kResimulate) {
          while (from > 0 && !reader.chunks()[from].starts_with_state) --from;
        }
        Rewind(from);
        seeking = true;
      }
      // Skip (re-simulating silently in dynamic mode) to the target frame.
      const bool resim = opt.mode == PlayMode::kResimulate;
      while (true) {
        const Frame* f = NextFrame(resim);
        if (!f) break;
        if ((seek_time && f->time >= *seek_time) || (seek_step && f->step >= *seek_step) ||
            (seek_frame && frame_index >= *seek_frame)) {
          --next;  // NextFrame returned records[next - 1]: show it next
          break;
        }
        if (resim) Resimulate(*f);
        last_frame_time = f->time;
        ++frame_index;
      }
      seeking = false;
      have_last = false;
      shown_pos = 0;
      clock = 0;
      seek_time.reset();
      seek_step.reset();
      seek_frame.reset();
      status.finished = false;
      play = true;  // show the frame sought, also while paused
    }
  }
  if (!play) return;
  const bool resim = opt.mode == PlayMode::kResimulate;
  // How many recorded frames this iteration shows: the playback clock advances by speed times
  // the engine's step; frames are taken while the next one is due.
  const double dt = tables.timestep > 0 ? tables.timestep : m->opt.timestep;
  const double target = clock;
  clock += opt.speed * m->opt.timestep;
  const Frame* shown = nullptr;
  while (!have_last || shown_pos + dt <= target + 1e-9) {
    const Frame* f = NextFrame(resim);
    if (!f) {
      std::lock_guard<std::mutex> lock(mutex);
      if (opt.loop) {
        Rewind(0);
        clock = opt.speed * m->opt.timestep;
        shown_pos = 0;
        ++status.loops;
        if (status.loops > 1 && !shown) break;  // an empty recording
        continue;
      }
      status.finished = true;
      playing = false;
      break;
    }
    // Position on the recorded time axis (a jump, e.g. a reset back to t=0, counts one step).
    if (have_last) {
      const double delta = f->time - last_frame_time;
      shown_pos += (!jumped && delta > 0) ? delta : dt;
    }
    jumped = false;
    last_frame_time = f->time;
    have_last = true;
    if (resim && have_state) {
      Resimulate(*f);
      std::lock_guard<std::mutex> lock(mutex);
      if (!status.resim.diverged) {
        if (Matches(tables, *f, sim->data(), &status.resim)) {
          ++status.resim.steps_checked;
        } else {
          status.resim.diverged = true;
          status.resim.divergent_step = f->step;
          status.resim.divergent_index = frame_index;
          status.resim.divergent_time = f->time;
        }
      }
    }
    shown = f;
    ++frame_index;
  }
  if (!shown) return;
  // Shown kinematically: the recorded frame, or the re-simulated state (bit for bit what the
  // re-simulation reached) with the frame's inputs.
  if (resim && have_state) {
    const mjData* r = sim->data();
    mju_copy(d->qpos, r->qpos, m->nq);
    mju_copy(d->qvel, r->qvel, m->nv);
    mju_copy(d->act, r->act, m->na);
    ApplyInputs(*shown, d);
    d->time = r->time;
    mj_forward(m, d);
    mju_copy(d->qpos, r->qpos, m->nq);  // mj_forward normalised the quaternions in place
  } else {
    Copy(shown->qpos, d->qpos);
    Copy(shown->qvel, d->qvel);
    Copy(shown->act, d->act);
    ApplyInputs(*shown, d);
    d->time = shown->time;
    mj_forward(m, d);
    Copy(shown->qpos, d->qpos);  // mj_forward normalised the quaternions in place
  }
  std::lock_guard<std::mutex> lock(mutex);
  status.time = shown->time;
  status.step = shown->step;
  status.frame = frame_index - 1;
}

Player::Player(physics::PhysicsEngine& engine, const RecordingReader& reader, PlayerOptions options)
    : impl_(std::make_unique<Impl>(engine, reader)) {
  physics::Model model = engine.CopyModel();
  CheckSameModel(reader, model);
  if (!(options.speed > 0) || !std::isfinite(options.speed)) {
    throw Error("playback speed must be a finite number > 0");
  }
  if (options.mode == PlayMode::kResimulate) {
    impl_->sim = std::make_unique<Resimulator>(std::move(model));
  }
  impl_->tables = reader.info().tables;
  impl_->options = options;
  impl_->playing = !options.start_paused;
  impl_->status.frames = reader.frame_count();
  impl_->status.speed = options.speed;
  impl_->status.loop = options.loop;
  Impl* impl = impl_.get();
  engine.SetCustomStepHandler([impl](const mjModel* m, mjData* d) {
    try {
      impl->Step(m, d);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(impl->mutex);
      impl->status.error = e.what();
      impl->playing = false;
    }
  });
}

Player::~Player() { impl_->engine.SetCustomStepHandler({}); }

void Player::Play() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (impl_->status.finished) {
    impl_->seek_step = 0;
    impl_->seek_time.reset();
    impl_->seek_frame.reset();
    impl_->status.finished = false;
  }
  impl_->playing = true;
}

void Player::Pause() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->playing = false;
}

void Player::SetSpeed(double speed) {
  if (!(speed > 0) || !std::isfinite(speed)) {
    throw Error("playback speed must be a finite number > 0");
  }
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->options.speed = speed;
  impl_->status.speed = speed;
}

void Player::SetLoop(bool loop) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->options.loop = loop;
  impl_->status.loop = loop;
}

void Player::SeekTime(double t) {
  if (!std::isfinite(t)) throw Error("seek time must be finite");
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->seek_time = t;
  impl_->seek_step.reset();
  impl_->seek_frame.reset();
}

void Player::SeekStep(std::uint64_t step) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->seek_step = step;
  impl_->seek_time.reset();
  impl_->seek_frame.reset();
}

void Player::SeekFrame(std::uint64_t index) {
  const std::uint64_t frames = impl_->reader.frame_count();
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->seek_frame = frames > 0 ? std::min(index, frames - 1) : 0;
  impl_->seek_time.reset();
  impl_->seek_step.reset();
}

TimelineMarks ScanTimeline(const RecordingReader& reader) {
  TimelineMarks out;
  out.frames = reader.frame_count();
  out.first_time = reader.first_time();
  out.last_time = reader.last_time();
  std::uint64_t index = 0;
  for (std::size_t c = 0; c < reader.chunks().size(); ++c) {
    const ChunkInfo& ci = reader.chunks()[c];
    if (ci.starts_with_state && ci.frames) {
      out.keyframes.push_back({index, ci.first_step, ci.first_time, {}});
    }
    for (const Record& rec : reader.ReadChunk(c)) {
      if (std::holds_alternative<Frame>(rec)) {
        ++index;
      } else if (const auto* m = std::get_if<Marker>(&rec)) {
        out.jumps.push_back({index, m->step, m->time, m->text});
      }
    }
  }
  return out;
}

PlayerStatus Player::status() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  PlayerStatus s = impl_->status;
  s.playing = impl_->playing;
  return s;
}

}  // namespace urlab::replay
