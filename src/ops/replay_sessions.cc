// Replay sessions (urlab/ops/replay_sessions.h).
#include "urlab/ops/replay_sessions.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "urlab/physics/model.h"

namespace urlab::ops {

ReplaySessions::ReplaySessions(world::Session& session, std::size_t max_sessions)
    : session_(session), max_sessions_(max_sessions) {}

ReplaySessions::~ReplaySessions() { Stop(); }

std::vector<ReplaySessions::Loaded>::iterator ReplaySessions::Find(const std::string& id) {
  return std::find_if(loaded_.begin(), loaded_.end(),
                      [&id](const Loaded& s) { return s.id == id; });
}

const replay::RecordingReader& ReplaySessions::Load(const std::string& owner,
                                                    const std::string& path, std::string* id) {
  // A new load releases this owner's earlier recordings (except one playing); the total is
  // bounded too.
  Release(owner, playing_);
  if (loaded_.size() >= max_sessions_) {
    Fail("replay_limit", std::to_string(loaded_.size()) +
                             " recordings are loaded (the limit); replay_unload one first");
  }
  auto reader = std::make_unique<replay::RecordingReader>(
      replay::RecordingReader::Open(path, {.allow_partial = true}));
  replay::CheckSameModel(*reader, session_.engine().CopyModel());
  if (reader->info().kind != "recording") {
    Fail("path_not_readable", path + ": not a recording (a " + reader->info().kind + ")");
  }
  // fmt, not "r" + std::to_string: GCC 12 -O3 raises a false -Wrestrict on the latter.
  Loaded s{fmt::format("r{}", next_++), owner, std::move(reader)};
  active_ = s.id;  // the newest recording is the one Start plays by default
  *id = s.id;
  loaded_.push_back(std::move(s));
  return *loaded_.back().reader;
}

std::vector<ReplaySessions::Entry> ReplaySessions::List() const {
  std::vector<Entry> out;
  for (const Loaded& s : loaded_) {
    out.push_back({s.id, s.reader->path(), s.reader->frame_count(), s.id == active_});
  }
  return out;
}

void ReplaySessions::SetActive(const std::string& id) {
  if (Find(id) == loaded_.end()) {
    Fail("replay_session_not_found", "no replay session '" + id + "' (see replay_list_sessions)");
  }
  active_ = id;
}

ReplaySessions::Started ReplaySessions::Start(const StartRequest& request) {
  const std::string id = request.session.empty() ? active_ : request.session;
  const auto s = Find(id);
  if (s == loaded_.end()) {
    Fail("replay_session_not_found",
         id.empty() ? std::string("no recording loaded (replay_load first)")
                    : "no replay session '" + id + "' (see replay_list_sessions)");
  }
  replay::PlayerOptions o;
  if (request.mode == "kinematic") {
    o.mode = replay::PlayMode::kKinematic;
  } else if (request.mode == "resimulate") {
    o.mode = replay::PlayMode::kResimulate;
  } else {
    Fail("bad_value", "mode must be kinematic or resimulate");
  }
  o.speed = request.speed;
  o.loop = request.loop;
  Stop();  // one replay at a time: a new start replaces it
  try {
    player_ = std::make_unique<replay::Player>(session_.engine(), *s->reader, o);
  } catch (const replay::RecordingError& e) {
    Fail(e.reason() == replay::RecordingError::Reason::kWrongModel ? "bad_value"
                                                                   : "path_not_readable",
         e.what());
  }
  playing_ = id;
  mode_ = request.mode;
  if (playback_) {  // a running viewer shows it on its timeline
    auto shown = std::make_unique<replay::Playback>();
    shown->player = player_.get();
    shown->reader = s->reader.get();
    try {
      shown->marks = replay::ScanTimeline(*s->reader);
    } catch (const replay::RecordingError& e) {
      spdlog::warn("replay: the timeline shows no keyframes or resets: {}", e.what());
    }
    shown->label = id + ": " + s->reader->path();
    shown->mode = request.mode;
    shown_ = std::move(shown);
    playback_->Set(shown_.get());
  }
  return {id, request.mode, s->reader->path(), o.speed, o.loop, s->reader->frame_count()};
}

std::string ReplaySessions::Stop() {
  const std::string was = player_ ? playing_ : std::string();
  if (playback_) playback_->Set(nullptr);  // the viewer's timeline lets go first
  shown_.reset();
  player_.reset();  // removes the custom step handler: the engine steps on its own again
  playing_.clear();
  return was;
}

ReplaySessions::Status ReplaySessions::GetStatus() const {
  if (!player_) return {};
  return {true, playing_, mode_, player_->status()};
}

std::string ReplaySessions::Unload(const std::string& id) {
  const std::string which = id.empty() ? active_ : id;
  if (ReleaseIf([&which](const Loaded& s) { return s.id == which; }) == 0) {
    Fail("replay_session_not_found",
         which.empty() ? std::string("no recording loaded")
                       : "no replay session '" + which + "' (see replay_list_sessions)");
  }
  return which;
}

std::size_t ReplaySessions::Release(const std::string& owner, const std::string& keep) {
  return ReleaseIf([&](const Loaded& s) {
    return (owner.empty() || s.owner == owner) && (keep.empty() || s.id != keep);
  });
}

void ReplaySessions::Transfer(const std::string& from, const std::string& to) {
  for (Loaded& s : loaded_) {
    if (s.owner == from) s.owner = to;
  }
}

std::size_t ReplaySessions::ReleaseIf(const std::function<bool(const Loaded&)>& which) {
  std::size_t n = 0;
  for (auto it = loaded_.begin(); it != loaded_.end();) {
    if (!which(*it)) {
      ++it;
      continue;
    }
    if (it->id == playing_) Stop();  // the reader it plays goes away
    if (it->id == active_) active_.clear();
    it = loaded_.erase(it);
    ++n;
  }
  if (active_.empty() && !loaded_.empty()) active_ = loaded_.back().id;
  return n;
}

}  // namespace urlab::ops
