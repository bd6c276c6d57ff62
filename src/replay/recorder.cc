#include "urlab/replay/recorder.h"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>
#include <tuple>

#include "replay/format.h"
#include "replay/io.h"
#include "urlab/core/files.h"
#include "urlab/mjcf/writer.h"
#include "urlab/world/session.h"

namespace urlab::replay {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// A state the physics thread captured for the writer: after a command that made the state jump
// (seq set), or for a keyframe request (token set).
struct Capture {
  std::uint64_t seq = 0;
  std::uint64_t token = 0;
  std::uint32_t jump = 0;
  physics::PhysicsState state;
  std::vector<std::uint8_t> option;
};

std::vector<std::uint8_t> OptionBytes(const mjModel* m) {
  std::vector<std::uint8_t> b(sizeof(mjOption));
  std::memcpy(b.data(), &m->opt, sizeof(mjOption));
  return b;
}

std::string NowUtc() {
  const auto now = std::chrono::system_clock::now();
  return fmt::format("{:%Y-%m-%dT%H:%M:%S}Z",
                     fmt::gmtime(std::chrono::system_clock::to_time_t(now)));
}

// An encoded chunk kept in memory (ring mode) or about to be written.
struct HeldChunk {
  format::ChunkHeader header;
  std::string stored;
  double duration = 0;
};

void CheckOptions(const RecorderOptions& o) {
  const auto bad = [](double v, bool allow_zero) {
    return !std::isfinite(v) || v < 0 || (!allow_zero && v == 0);
  };
  if (bad(o.keyframe_interval, false)) {
    throw RecorderError("bad_value", "keyframe_interval must be a finite number > 0");
  }
  if (bad(o.chunk_seconds, false)) {
    throw RecorderError("bad_value", "chunk_seconds must be a finite number > 0");
  }
  if (bad(o.max_duration, true)) {
    throw RecorderError("bad_value", "max_duration must be a finite number >= 0");
  }
  if (bad(o.ring_seconds, true)) {
    throw RecorderError("bad_value", "ring_seconds must be a finite number >= 0");
  }
  if (o.zstd_level < 1 || o.zstd_level > 19) {
    throw RecorderError("bad_value", "zstd_level must be 1..19");
  }
}

}  // namespace

struct Recorder::Impl {
  physics::PhysicsEngine& engine;
  RecordingInfo info;
  std::shared_ptr<physics::StateRing> ring;
  physics::PhysicsEngine::CallbackId listener = 0;

  // Captures from the physics thread.
  std::atomic<bool> recording{false};
  std::mutex capture_mutex;
  std::deque<Capture> captures;
  std::atomic<std::uint64_t> next_token{1};

  // The API (Start/Stop/Save/Clear).
  mutable std::mutex api_mutex;
  std::thread writer;
  std::atomic<bool> stop_requested{false};
  RecorderOptions options;
  bool temporary = false;
  bool in_place = false;  // the recording goes straight to a device or FIFO
  std::string last_path;  // the last finished recording
  bool last_temporary = false;
  bool last_in_place = false;  // it went to a device or FIFO: nothing to copy

  // Shared with the writer thread.
  mutable std::mutex status_mutex;
  RecorderStatus status;
  std::mutex file_mutex;  // the writer appending; Save copying
  std::unique_ptr<PartFile> file;
  std::deque<HeldChunk> held;  // ring mode
  std::uint32_t next_chunk = 1;

  Impl(physics::PhysicsEngine& e) : engine(e) {}

  void Run();
  // Asks the physics thread for a full-state keyframe, captured when the command applies (into
  // `captures`). Returns its token and the command's sequence number. Any thread.
  std::pair<std::uint64_t, std::uint64_t> RequestKeyframe();
  // The start keyframe, requested by Start before the writer runs (so the recording begins with
  // the first step after Start returns, however late the writer thread gets a core).
  std::uint64_t start_token = 0, start_seq = 0;
  void WriteChunk(HeldChunk chunk);
  std::string EndChunk(std::uint32_t number) const;
  std::string FileBytesLocked();  // file_mutex held: a finished copy of what is recorded so far
};

Recorder::Recorder(physics::PhysicsEngine& engine, RecorderSource source, std::size_t ring_frames)
    : impl_(std::make_unique<Impl>(engine)) {
  Impl& s = *impl_;
  const mjModel* m = engine.model();
  DescribeModel(engine.owned_model(), &s.info);
  s.info.mjcf = std::move(source.mjcf);
  s.info.scene = std::move(source.scene);
  s.info.tables = ModelTables::Of(m, source.articulations);
  s.info.tables.command_groups = engine.command_layout();
  s.ring = engine.SubscribeEveryStep("recorder", ring_frames);
  s.ring->SetActive(false);
  Impl* impl = impl_.get();
  s.listener = engine.AddCommandListener(
      [impl](const physics::AppliedCommand& c, const mjModel* model, const mjData* d) {
        if (c.discontinuity == 0 || !c.error.empty() ||
            !impl->recording.load(std::memory_order_acquire)) {
          return;
        }
        Capture cap;
        cap.seq = c.seq;
        cap.jump = c.discontinuity;
        cap.state = physics::CaptureState(model, d);
        cap.option = OptionBytes(model);
        std::lock_guard<std::mutex> lock(impl->capture_mutex);
        impl->captures.push_back(std::move(cap));
      });
}

Recorder::~Recorder() {
  try {
    if (active()) Stop();
  } catch (const std::exception& e) {
    spdlog::error("recorder: {}", e.what());
  }
  if (impl_->writer.joinable()) impl_->writer.join();
  impl_->engine.RemoveCallback(impl_->listener);
}

const RecordingInfo& Recorder::info() const { return impl_->info; }

bool Recorder::active() const {
  std::lock_guard<std::mutex> lock(impl_->status_mutex);
  return impl_->status.active;
}

RecorderStatus Recorder::status() const {
  std::lock_guard<std::mutex> lock(impl_->status_mutex);
  return impl_->status;
}

void Recorder::Start(RecorderOptions options) {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> api(s.api_mutex);
  CheckOptions(options);
  {
    std::lock_guard<std::mutex> lock(s.status_mutex);
    if (s.status.active) {
      throw RecorderError("recording_already_active",
                          "a recording is already running (to " + s.status.path + ")");
    }
  }
  if (s.writer.joinable()) s.writer.join();  // one that stopped itself (a limit)
  s.temporary = options.path.empty();
  if (s.temporary) {
    options.path = (fs::temp_directory_path() /
                    fmt::format("urlab-{}-{}.urrec", ::getpid(), s.next_token.load()))
                       .string();
  }
  // The model as it is now: its physics options may have changed since construction (the step
  // server's set_sim_options), and the header's MJB and hash carry those in effect at the start.
  s.engine.WithLockedData(
      [&s](mjModel*, mjData*) { DescribeModel(s.engine.owned_model(), &s.info); });
  s.info.sensordata = options.sensordata;
  s.info.keyframe_interval = options.keyframe_interval;
  s.info.compression = options.compress ? "zstd" : "none";
  s.info.created = NowUtc();
  s.held.clear();
  s.next_chunk = 1;
  const std::string header = format::EncodeFileStart(
      s.info, options.compress ? format::Codec::kZstd : format::Codec::kStored, options.zstd_level);
  try {
    std::lock_guard<std::mutex> lock(s.file_mutex);
    s.file = std::make_unique<PartFile>(options.path);
    s.in_place = s.file->in_place();
    s.file->Append(header);
  } catch (const Error& e) {
    s.file.reset();
    throw RecorderError("path_not_writable", e.what());
  }
  s.options = options;
  {
    std::lock_guard<std::mutex> lock(s.status_mutex);
    s.status = RecorderStatus{};
    s.status.active = true;
    s.status.path = options.path;
    s.status.bytes = header.size();
  }
  {
    std::lock_guard<std::mutex> lock(s.capture_mutex);
    s.captures.clear();
  }
  s.stop_requested.store(false);
  s.recording.store(true, std::memory_order_release);
  s.ring->SetActive(true);
  std::tie(s.start_token, s.start_seq) = s.RequestKeyframe();
  s.writer = std::thread([&s] { s.Run(); });
  spdlog::info("recording to {}{}", options.path,
               options.ring_seconds > 0
                   ? fmt::format(" (keeping the last {} s)", options.ring_seconds)
                   : "");
}

RecorderStatus Recorder::Stop() {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> api(s.api_mutex);
  {
    std::lock_guard<std::mutex> lock(s.status_mutex);
    if (!s.status.active && !s.writer.joinable()) {
      throw RecorderError("recording_not_active", "no recording is running");
    }
  }
  s.stop_requested.store(true);
  if (s.writer.joinable()) s.writer.join();
  RecorderStatus st = status();
  s.last_path = st.path;
  s.last_temporary = s.temporary;
  s.last_in_place = s.in_place;
  return st;
}

std::string Recorder::Impl::EndChunk(std::uint32_t number) const {
  RecorderStatus st;
  {
    std::lock_guard<std::mutex> lock(status_mutex);
    st = status;
  }
  const nlohmann::json totals = {{"frames", st.frames},   {"duration", st.duration},
                                 {"dropped", st.dropped}, {"markers", st.markers},
                                 {"chunks", st.chunks},   {"stopped_because", st.stopped_because}};
  return format::EncodeEndChunk(number, totals.dump());
}

std::string Recorder::Impl::FileBytesLocked() {
  if (options.ring_seconds > 0) {
    std::string out = format::EncodeFileStart(
        info, options.compress ? format::Codec::kZstd : format::Codec::kStored, options.zstd_level);
    std::uint32_t n = 1;
    for (const HeldChunk& c : held) {
      format::ChunkHeader ch = c.header;
      ch.number = n++;
      out += format::EncodeChunk(ch, c.stored);
    }
    return out + EndChunk(n);
  }
  if (file->in_place()) {
    throw Error(options.path + " is " + file->part_path() +
                ", written in place: the recording cannot be read back to save a copy");
  }
  InputFile in(file->part_path());
  return in.Read(0, file->bytes()) + EndChunk(next_chunk);
}

std::string Recorder::Save(const std::string& path) {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> api(s.api_mutex);
  if (path.empty()) throw RecorderError("bad_value", "save needs a path");
  try {
    std::unique_lock<std::mutex> lock(s.file_mutex);
    if (s.file) {
      // Never over the file this recorder is writing (its .part, or where it will be renamed).
      const std::string target = ResolveOutput(path).file;
      if (target == ResolveOutput(s.options.path).file ||
          target == ResolveOutput(s.file->part_path()).file) {
        throw RecorderError("bad_value", path +
                                             " is the recording being written; save the copy to "
                                             "another file");
      }
      const std::string bytes = s.FileBytesLocked();
      lock.unlock();
      WriteFileAtomic(path, bytes);
      return path;
    }
    lock.unlock();
    if (s.last_path.empty()) {
      throw RecorderError("recording_not_active", "nothing recorded to save");
    }
    if (s.last_in_place) {
      throw RecorderError("recording_not_active",
                          "the last recording went straight to " + s.last_path +
                              " (a device or FIFO): there is no file to save a copy of");
    }
    std::error_code ec;
    if (fs::exists(path) && fs::equivalent(path, s.last_path, ec)) return path;
    InputFile in(s.last_path);
    WriteFileAtomic(path, in.Read(0, in.size()));
    return path;
  } catch (const RecorderError&) {
    throw;
  } catch (const Error& e) {
    throw RecorderError("path_not_writable", e.what());
  }
}

void Recorder::Clear() {
  Impl& s = *impl_;
  std::lock_guard<std::mutex> api(s.api_mutex);
  if (!s.last_path.empty() && s.last_temporary) {
    std::error_code ec;
    fs::remove(s.last_path, ec);
  }
  s.last_path.clear();
}

void Recorder::Impl::WriteChunk(HeldChunk chunk) {
  std::lock_guard<std::mutex> lock(file_mutex);
  if (options.ring_seconds > 0) {
    held.push_back(std::move(chunk));
    double kept = 0;
    for (const HeldChunk& c : held) kept += c.duration;
    // Drop whole chunks from the front while the rest still covers ring_seconds.
    while (held.size() > 1 && kept - held.front().duration >= options.ring_seconds) {
      kept -= held.front().duration;
      held.pop_front();
    }
    std::uint64_t data = 0;
    for (const HeldChunk& c : held) data += format::EncodeChunk(c.header, c.stored).size();
    std::lock_guard<std::mutex> st(status_mutex);
    status.chunks = held.size();
    status.data_bytes = data;
    return;
  }
  chunk.header.number = next_chunk++;
  const std::string bytes = format::EncodeChunk(chunk.header, chunk.stored);
  file->Append(bytes);
  std::lock_guard<std::mutex> st(status_mutex);
  status.bytes = file->bytes();
  status.data_bytes += bytes.size();
  ++status.chunks;
}

std::pair<std::uint64_t, std::uint64_t> Recorder::Impl::RequestKeyframe() {
  const std::uint64_t token = next_token.fetch_add(1);
  Impl* self = this;
  const std::uint64_t seq =
      engine.Submit(physics::cmd::Inspect{[self, token](const mjModel* m, const mjData* d) {
        Capture cap;
        cap.token = token;
        cap.state = physics::CaptureState(m, d);
        cap.option = OptionBytes(m);
        std::lock_guard<std::mutex> lock(self->capture_mutex);
        self->captures.push_back(std::move(cap));
      }});
  return {token, seq};
}

void Recorder::Impl::Run() {
  const ModelTables& tables = info.tables;
  format::ChunkEncoder enc(tables, options.sensordata);
  const format::Codec codec = options.compress ? format::Codec::kZstd : format::Codec::kStored;
  std::deque<Capture> caps;  // taken from the physics thread, in application order
  std::uint64_t pending_token = 0, pending_seq = 0;
  Clock::time_point pending_since{};
  bool started = false;
  std::uint64_t last_dropped = ring->dropped();
  const std::uint64_t dropped_at_start = last_dropped;
  std::uint64_t last_step = 0;
  double last_time = 0;
  bool have_time = false;
  double duration = 0, chunk_duration = 0;
  double chunk_first_time = 0;
  bool chunk_has_time = false;
  Clock::time_point chunk_wall = Clock::now();
  std::uint64_t frames = 0, markers = 0, raw_bytes = 0;
  std::string stopped_because = "stopped";

  const auto request_keyframe = [&]() -> std::uint64_t {
    std::tie(pending_token, pending_seq) = RequestKeyframe();
    pending_since = Clock::now();
    return pending_token;
  };
  const auto flush = [&] {
    if (enc.empty()) return;
    HeldChunk c;
    c.header = enc.Header(codec);
    c.stored = format::Compress(enc.bytes(), codec, options.zstd_level);
    c.duration = chunk_duration;
    raw_bytes += enc.bytes().size();
    WriteChunk(std::move(c));
    enc.Reset();
    chunk_duration = 0;
    chunk_has_time = false;
    chunk_wall = Clock::now();
  };
  const auto publish_status = [&] {
    std::lock_guard<std::mutex> lock(status_mutex);
    status.frames = frames;
    status.markers = markers;
    status.duration = duration;
    status.raw_bytes = raw_bytes + enc.bytes().size();
    status.dropped = ring->dropped() - dropped_at_start;
  };
  try {
    pending_token = start_token;
    pending_seq = start_seq;
    pending_since = Clock::now();
    while (true) {
      {
        std::lock_guard<std::mutex> lock(capture_mutex);
        while (!captures.empty()) {
          caps.push_back(std::move(captures.front()));
          captures.pop_front();
        }
      }
      const physics::StateFrame* f = ring->Front();
      if (!f) {
        if (stop_requested.load()) break;
        // The physics thread did not answer a keyframe request (stopped, or stuck): flush
        // without one so that a crash still loses at most about chunk_seconds.
        if (pending_token && started &&
            Clock::now() - pending_since > std::chrono::duration<double>(options.chunk_seconds)) {
          flush();
          pending_token = 0;
        }
        publish_status();
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      const std::uint64_t dropped = ring->dropped();
      if (!started) {
        // Frames published before the start keyframe was captured are not part of it.
        if (f->command_seq < start_seq) {
          ring->Pop();
          continue;
        }
        while (!caps.empty() && caps.front().token != start_token) caps.pop_front();
        if (caps.empty()) {
          throw Error("the start state was not captured before its frame");
        }
        enc.Add(StateRecord{0, std::move(caps.front().state)});
        enc.Add(OptionsRecord{std::move(caps.front().option)});
        caps.pop_front();
        pending_token = 0;
        started = true;
        last_dropped = dropped;
      } else {
        if (dropped > last_dropped) {
          enc.Add(Gap{dropped - last_dropped, last_step});
          last_dropped = dropped;
        }
        bool captured_jump = false;
        while (!caps.empty()) {
          Capture& c = caps.front();
          if (c.token != 0) {
            if (c.token != pending_token) {  // a stale request
              caps.pop_front();
              continue;
            }
            if (pending_seq > f->command_seq) break;
            flush();  // a keyframe starts the next chunk
            // With the options in effect, so that a re-simulating seek that starts here runs
            // with them even when they changed since the start.
            enc.Add(StateRecord{0, std::move(c.state)});
            enc.Add(OptionsRecord{std::move(c.option)});
            pending_token = 0;
          } else {
            if (c.seq < start_seq) {
              caps.pop_front();
              continue;
            }
            if (c.seq > f->command_seq) break;
            enc.Add(Marker{c.jump, c.state.time, f->step, physics::DiscontinuityString(c.jump)});
            enc.Add(StateRecord{c.jump, std::move(c.state)});
            if (c.jump & physics::kDiscontinuityOptions)
              enc.Add(OptionsRecord{std::move(c.option)});
            captured_jump = true;
            ++markers;
          }
          caps.pop_front();
        }
        if (f->discontinuity != 0 && !captured_jump) {
          // A jump no command made (an automatic reset after divergence): marked, and a keyframe
          // follows as soon as the physics thread takes the request.
          enc.Add(Marker{f->discontinuity | kMarkerNotCaptured, f->time, f->step,
                         physics::DiscontinuityString(f->discontinuity) + " (not captured)"});
          ++markers;
          if (!pending_token) request_keyframe();
        }
      }
      if (f->stepped) {
        if (have_time && f->time > last_time && f->discontinuity == 0) {
          duration += f->time - last_time;
          chunk_duration += f->time - last_time;
        }
        if (!chunk_has_time) {
          chunk_first_time = f->time;
          chunk_has_time = true;
        }
        enc.Add(*f);
        ++frames;
        last_step = f->step;
        last_time = f->time;
        have_time = true;
      }
      ring->Pop();
      if (!pending_token &&
          ((chunk_has_time && last_time - chunk_first_time >= options.keyframe_interval) ||
           Clock::now() - chunk_wall >= std::chrono::duration<double>(options.chunk_seconds) ||
           enc.bytes().size() > (8u << 20))) {
        request_keyframe();
      }
      // Never a chunk larger than a reader accepts (a flood of state writes while a keyframe is
      // pending): close it now, without a keyframe at its start.
      if (enc.bytes().size() >= format::kDataChunkFlushBytes) flush();
      if ((frames & 255) == 0) publish_status();
      if (options.max_duration > 0 && duration >= options.max_duration) {
        stopped_because = "max_duration";
        break;
      }
      if (options.max_bytes > 0 && status.bytes + enc.bytes().size() / 2 >= options.max_bytes) {
        stopped_because = "max_bytes";
        break;
      }
    }
    ring->SetActive(false);
    recording.store(false, std::memory_order_release);
    flush();
    publish_status();
    {
      std::lock_guard<std::mutex> lock(status_mutex);
      status.stopped_because = stopped_because;
      status.dropped = ring->dropped() - dropped_at_start;
    }
    std::lock_guard<std::mutex> lock(file_mutex);
    if (options.ring_seconds > 0) {
      file->Append(FileBytesLocked().substr(file->bytes()));
    } else {
      file->Append(EndChunk(next_chunk));
    }
    file->Finish();
    {
      std::lock_guard<std::mutex> st(status_mutex);
      status.bytes = file->bytes();
    }
    file.reset();
  } catch (const std::exception& e) {
    ring->SetActive(false);
    recording.store(false, std::memory_order_release);
    std::lock_guard<std::mutex> fl(file_mutex);
    const std::string kept =
        !file               ? std::string("nothing was kept")
        : file->in_place()  ? fmt::format("{} bytes went to {}", file->bytes(), file->part_path())
        : file->bytes() > 0 ? fmt::format(
                                  "the {} bytes written so far are kept in {} (urlab replay "
                                  "reads it up to its last whole chunk)",
                                  file->bytes(), file->part_path())
                            : "nothing was kept";
    if (file && !file->in_place() && file->bytes() == 0) file->Discard();
    spdlog::error("recorder: {}; {}", e.what(), kept);
    std::lock_guard<std::mutex> lock(status_mutex);
    status.stopped_because = std::string("error: ") + e.what() + "; " + kept;
    file.reset();
  }
  // Frames left in the ring belong to no recording.
  while (ring->Front()) ring->Pop();
  {
    std::lock_guard<std::mutex> lock(status_mutex);
    status.active = false;
  }
  spdlog::info("recording {}: {} steps, {:.3f} s simulated, {} bytes{}", options.path,
               status.frames, status.duration, status.bytes,
               status.dropped ? fmt::format(", {} frames DROPPED", status.dropped) : "");
}

// ---- RecorderSubsystem ----

RecorderSubsystem::RecorderSubsystem(std::optional<RecorderOptions> autostart)
    : autostart_(std::move(autostart)) {}

RecorderSubsystem::~RecorderSubsystem() = default;

void RecorderSubsystem::BeginPlay(world::Session& session) {
  session_ = session.shared_from_this();
  RecorderSource source;
  for (const auto& a : session.articulations()) source.articulations.push_back(a.name());
  source.mjcf = world::SceneXml(session.scene());
  source.scene = session.scene_config().path;
  recorder_ = std::make_unique<Recorder>(session.engine(), std::move(source));
  if (autostart_) recorder_->Start(*autostart_);
}

void RecorderSubsystem::Tick(world::Session&, world::TickPhase phase) {
  if (phase != world::TickPhase::kUpdate || !recorder_) return;
  const RecorderStatus st = recorder_->status();
  if (st.dropped > logged_dropped_) {
    const auto now = Clock::now();
    if (now - last_log_ >= std::chrono::seconds(1)) {
      spdlog::warn(
          "recorder: {} frames dropped so far (the writer cannot keep up; the file marks "
          "each gap)",
          st.dropped);
      logged_dropped_ = st.dropped;
      last_log_ = now;
    }
  }
}

void RecorderSubsystem::EndPlay(world::Session&) {
  if (recorder_ && recorder_->active()) {
    const RecorderStatus st = recorder_->Stop();
    spdlog::info("recorder: wrote {}", st.path);
  }
}

}  // namespace urlab::replay
