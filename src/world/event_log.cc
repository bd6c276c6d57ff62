#include "urlab/world/event_log.h"

#include <spdlog/spdlog.h>

#include <string>

namespace urlab::world {

namespace {

using physics::EngineEventKind;

const char* KindName(EngineEventKind k) {
  switch (k) {
    case EngineEventKind::kReset:
      return "reset";
    case EngineEventKind::kRestored:
      return "restore";
    case EngineEventKind::kDivergence:
      return "divergence";
    case EngineEventKind::kError:
      return "error";
  }
  return "event";
}

std::string HeldBack(long n, EngineEventKind k) {
  return n > 0 ? " (" + std::to_string(n) + " more " + KindName(k) +
                     " event(s) since the last report)"
               : std::string();
}

}  // namespace

EventLog::EventLog(Clock::duration interval, std::function<Clock::time_point()> now)
    : interval_(interval), now_(std::move(now)) {}

void EventLog::OnEvent(const physics::EngineEvent& e) {
  PerKind& k = kinds_[static_cast<std::size_t>(e.kind)];
  const Clock::time_point now = now_();
  if (k.logged && now - k.last < interval_) {
    ++k.held_back;
    ++held_back_total_;
    return;
  }
  const std::string more = HeldBack(k.held_back, e.kind);
  k.logged = true;
  k.last = now;
  k.held_back = 0;
  ++lines_;
  switch (e.kind) {
    case EngineEventKind::kReset:
    case EngineEventKind::kRestored:
      spdlog::info("physics: {} (at t={:.4f} s){}", e.message, e.sim_time, more);
      break;
    case EngineEventKind::kDivergence:
      spdlog::warn("physics: {} in articulation '{}', joint '{}'{}{}", e.message,
                   e.articulation.empty() ? "?" : e.articulation,
                   e.joint_name.empty() ? "?" : e.joint_name,
                   e.auto_reset ? "; reset to the initial state" : "", more);
      break;
    case EngineEventKind::kError:
      spdlog::error("physics: {}; simulation paused at t={:.4f} s{}", e.message, e.sim_time, more);
      break;
  }
}

void EventLog::Flush() {
  for (std::size_t i = 0; i < kinds_.size(); ++i) {
    PerKind& k = kinds_[i];
    if (k.held_back == 0) continue;
    const auto kind = static_cast<EngineEventKind>(i);
    spdlog::info("physics: {} more {} event(s) were not logged one by one", k.held_back,
                 KindName(kind));
    ++lines_;
    k.held_back = 0;
  }
}

}  // namespace urlab::world
