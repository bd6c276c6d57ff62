#pragma once
// Replay sessions: recordings loaded for playback on the live engine ("r1", "r2", ..., each owned
// by the client that loaded it), the active one, and the one playing through a replay::Player in
// the engine's custom step handler, shown on the viewer's timeline through a PlaybackSlot when
// there is one. The operations replay_load, replay_list_sessions, replay_set_active,
// replay_start, replay_stop, replay_status and replay_unload of the step server are these
// methods; the step server only resolves file names, checks its step mode and writes replies.
// Refusals are ops::OpError with the wire code (replay_limit, replay_session_not_found,
// path_not_readable, bad_value); a file that cannot be read throws replay::RecordingError, which
// the caller maps (the step server: bad_value for another model, else path_not_readable).
//
// Threading contract: one thread calls every method (the network's I/O thread); the player runs
// in the engine's step handler, and the slot is shared with the viewer under its own mutex. The
// slot lets go of a playback before its player and reader are destroyed.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "urlab/ops/error.h"
#include "urlab/replay/playback.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recording.h"
#include "urlab/world/session.h"

namespace urlab::ops {

class ReplaySessions {
 public:
  // At most `max_sessions` recordings loaded at once (beyond: replay_limit).
  ReplaySessions(world::Session& session, std::size_t max_sessions);
  ~ReplaySessions();
  ReplaySessions(const ReplaySessions&) = delete;
  ReplaySessions& operator=(const ReplaySessions&) = delete;

  // Where a started replay is shown (the viewer's timeline); nullptr: nowhere.
  void SetPlayback(std::shared_ptr<replay::PlaybackSlot> slot) { playback_ = std::move(slot); }

  // Opens the recording at `path` for `owner` (it must record this engine's model). A load
  // releases the owner's earlier recordings except the one playing; the newest becomes active.
  const replay::RecordingReader& Load(const std::string& owner, const std::string& path,
                                      std::string* id);

  struct Entry {
    std::string id, path;
    std::uint64_t frames = 0;
    bool active = false;
  };
  std::vector<Entry> List() const;
  const std::string& active() const { return active_; }
  void SetActive(const std::string& id);  // replay_session_not_found

  struct StartRequest {
    std::string session;             // "": the active one
    std::string mode = "kinematic";  // or "resimulate" (bad_value otherwise)
    double speed = 1.0;              // checked by the caller's range table
    bool loop = false;
  };
  struct Started {
    std::string id, mode, path;
    double speed = 1;
    bool loop = false;
    std::uint64_t frames = 0;
  };
  // Plays a loaded recording from its start, replacing the one playing.
  Started Start(const StartRequest& request);
  // Stops the playback (the engine steps on its own again); returns the session that played ("":
  // none).
  std::string Stop();

  struct Status {
    bool active = false;  // a replay plays (or finished, still shown)
    std::string session, mode;
    replay::PlayerStatus player;
  };
  Status GetStatus() const;

  // Releases session `id` ("": the active one); returns its id. replay_session_not_found.
  std::string Unload(const std::string& id);
  // Releases the sessions `owner` loaded ("": any owner) except `keep`; stops the playback of a
  // released one. Returns how many.
  std::size_t Release(const std::string& owner, const std::string& keep = {});
  // The sessions `from` loaded belong to `to` from now on (a client that renewed its session).
  void Transfer(const std::string& from, const std::string& to);

 private:
  struct Loaded {
    std::string id, owner;
    std::unique_ptr<replay::RecordingReader> reader;
  };
  std::size_t ReleaseIf(const std::function<bool(const Loaded&)>& which);
  std::vector<Loaded>::iterator Find(const std::string& id);

  world::Session& session_;
  std::size_t max_sessions_;
  std::vector<Loaded> loaded_;  // in load order
  std::uint64_t next_ = 1;
  std::string active_;
  std::string playing_;                     // the session player_ plays
  std::string mode_;                        // kinematic | resimulate
  std::unique_ptr<replay::Player> player_;  // declared after loaded_: destroyed first
  std::shared_ptr<replay::PlaybackSlot> playback_;
  std::unique_ptr<replay::Playback> shown_;  // what playback_ points at (player_, its reader)
};

}  // namespace urlab::ops
