#include "viewer/timeline.h"

#include <GLFW/glfw3.h>
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <iterator>
#include <vector>

namespace urlab::viewer::internal {

namespace {

constexpr TimelineKey kTimelineKeys[] = {
    {GLFW_KEY_SPACE, "Space", TimelineAction::kPlayPause, "play / pause the replay"},
    {GLFW_KEY_LEFT, "Left", TimelineAction::kStepBack, "one recorded step back (pauses)"},
    {GLFW_KEY_RIGHT, "Right", TimelineAction::kStepForward, "one recorded step on (pauses)"},
    {GLFW_KEY_HOME, "Home", TimelineAction::kStart, "first frame"},
    {GLFW_KEY_END, "End", TimelineAction::kEnd, "last frame"},
    {GLFW_KEY_PAGE_UP, "PgUp", TimelineAction::kPrevKeyframe, "previous keyframe"},
    {GLFW_KEY_PAGE_DOWN, "PgDn", TimelineAction::kNextKeyframe, "next keyframe"},
    {GLFW_KEY_LEFT_BRACKET, "[", TimelineAction::kPrevJump, "previous reset (recorded jump)"},
    {GLFW_KEY_RIGHT_BRACKET, "]", TimelineAction::kNextJump, "next reset (recorded jump)"},
    {GLFW_KEY_DOWN, "Down", TimelineAction::kSlower, "half the speed"},
    {GLFW_KEY_UP, "Up", TimelineAction::kFaster, "twice the speed"},
    {GLFW_KEY_L, "L", TimelineAction::kToggleLoop, "loop on / off"},
};

constexpr double kMinSpeed = 1.0 / 64, kMaxSpeed = 64;

// The mark before (or after) `frame`, nullptr when none.
const replay::TimelineMark* Before(const std::vector<replay::TimelineMark>& marks,
                                   std::uint64_t frame) {
  const replay::TimelineMark* found = nullptr;
  for (const replay::TimelineMark& m : marks) {
    if (m.frame < frame) found = &m;
  }
  return found;
}

const replay::TimelineMark* After(const std::vector<replay::TimelineMark>& marks,
                                  std::uint64_t frame) {
  for (const replay::TimelineMark& m : marks) {
    if (m.frame > frame) return &m;
  }
  return nullptr;
}

std::string SeekTo(replay::Player& player, const replay::TimelineMark* mark, const char* what) {
  if (!mark) return fmt::format("replay: no {} there", what);
  player.SeekFrame(mark->frame);
  return fmt::format("replay: {} at frame {} (t={:.3f} s{})", what, mark->frame, mark->time,
                     mark->text.empty() ? "" : ", " + mark->text);
}

void Text(const std::string& s) { ImGui::TextUnformatted(s.c_str()); }

}  // namespace

std::span<const TimelineKey> TimelineKeys() { return kTimelineKeys; }

std::optional<TimelineAction> TimelineActionOfKey(int key) {
  const auto* it = std::find_if(std::begin(kTimelineKeys), std::end(kTimelineKeys),
                                [key](const TimelineKey& k) { return k.key == key; });
  if (it == std::end(kTimelineKeys)) return std::nullopt;
  return it->action;
}

std::string Timeline::Perform(const replay::Playback& p, TimelineAction action) {
  replay::Player& player = *p.player;
  const replay::PlayerStatus st = player.status();
  const std::uint64_t last = st.frames > 0 ? st.frames - 1 : 0;
  switch (action) {
    case TimelineAction::kPlayPause:
      if (st.playing) {
        player.Pause();
        return fmt::format("replay: paused at frame {} (t={:.3f} s)", st.frame, st.time);
      }
      player.Play();
      return "replay: playing";
    case TimelineAction::kStepBack:
      player.Pause();
      player.SeekFrame(st.frame > 0 ? st.frame - 1 : 0);
      return {};
    case TimelineAction::kStepForward:
      player.Pause();
      player.SeekFrame(std::min(st.frame + 1, last));
      return {};
    case TimelineAction::kStart:
      player.SeekFrame(0);
      return "replay: first frame";
    case TimelineAction::kEnd:
      player.Pause();
      player.SeekFrame(last);
      return "replay: last frame";
    case TimelineAction::kPrevKeyframe:
      return SeekTo(player, Before(p.marks.keyframes, st.frame), "keyframe");
    case TimelineAction::kNextKeyframe:
      return SeekTo(player, After(p.marks.keyframes, st.frame), "keyframe");
    case TimelineAction::kPrevJump:
      return SeekTo(player, Before(p.marks.jumps, st.frame), "reset");
    case TimelineAction::kNextJump:
      return SeekTo(player, After(p.marks.jumps, st.frame), "reset");
    case TimelineAction::kSlower:
    case TimelineAction::kFaster: {
      const double speed = std::clamp(
          action == TimelineAction::kFaster ? st.speed * 2 : st.speed / 2, kMinSpeed, kMaxSpeed);
      player.SetSpeed(speed);
      return fmt::format("replay: speed {:g}x", speed);
    }
    case TimelineAction::kToggleLoop:
      player.SetLoop(!st.loop);
      return fmt::format("replay: loop {}", st.loop ? "off" : "on");
  }
  return {};
}

void Timeline::Draw(const replay::Playback& p, float x, float y, float width) {
  replay::Player& player = *p.player;
  const replay::PlayerStatus st = player.status();
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(width, kHeight), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.85f);
  ImGui::Begin("Replay", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoScrollbar);
  auto button = [&](const char* label, TimelineAction a, const char* tip) {
    if (ImGui::Button(label)) Perform(p, a);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tip);
    ImGui::SameLine();
  };
  button("|<", TimelineAction::kStart, "first frame (Home)");
  button("<K", TimelineAction::kPrevKeyframe, "previous keyframe (PgUp)");
  button("<R", TimelineAction::kPrevJump, "previous reset ([)");
  button("<", TimelineAction::kStepBack, "one step back (Left)");
  button(st.playing ? " Pause " : " Play  ", TimelineAction::kPlayPause, "Space");
  button(">", TimelineAction::kStepForward, "one step on (Right)");
  button("R>", TimelineAction::kNextJump, "next reset (])");
  button("K>", TimelineAction::kNextKeyframe, "next keyframe (PgDn)");
  button(">|", TimelineAction::kEnd, "last frame (End)");
  bool loop = st.loop;
  if (ImGui::Checkbox("loop (L)", &loop)) player.SetLoop(loop);
  ImGui::SameLine();
  button("-", TimelineAction::kSlower, "half the speed (Down)");
  Text(fmt::format("{:g}x", st.speed));
  ImGui::SameLine();
  button("+", TimelineAction::kFaster, "twice the speed (Up)");
  ImGui::NewLine();

  // The scrub bar: one position per recorded frame; keyframes and resets marked under it.
  const int frames = static_cast<int>(std::max<std::uint64_t>(st.frames, 1));
  int frame =
      static_cast<int>(std::min<std::uint64_t>(st.frame, static_cast<std::uint64_t>(frames - 1)));
  ImGui::SetNextItemWidth(-1);
  const std::string label = fmt::format("t {:.3f} s   frame %d", st.time);
  if (ImGui::SliderInt("##scrub", &frame, 0, frames - 1, label.c_str())) {
    player.SeekFrame(static_cast<std::uint64_t>(frame));
  }
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  scrub_ = {a.x, a.y, b.x, b.y};
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const float span = b.x - a.x;
  auto tick = [&](std::uint64_t at, ImU32 colour, float height) {
    const float tx =
        a.x + span * static_cast<float>(static_cast<double>(at) / static_cast<double>(frames));
    draw->AddLine(ImVec2(tx, b.y), ImVec2(tx, b.y + height), colour, 2.0f);
  };
  for (const replay::TimelineMark& m : p.marks.keyframes)
    tick(m.frame, IM_COL32(170, 170, 170, 255), 5);
  for (const replay::TimelineMark& m : p.marks.jumps) tick(m.frame, IM_COL32(240, 70, 60, 255), 9);
  ImGui::Dummy(ImVec2(0, 8));

  std::string state = st.finished ? "end" : st.playing ? "playing" : "paused";
  if (!st.error.empty()) state = "error: " + st.error;
  std::string resim;
  if (p.mode == "resimulate") {
    resim = st.resim.diverged ? fmt::format("   DIVERGED at step {}", st.resim.divergent_step)
                              : fmt::format("   {} steps identical", st.resim.steps_checked);
  }
  Text(fmt::format("{}   {}   step {}   frame {}/{}   {} keyframes, {} resets   {}{}", p.label,
                   state, st.step, st.frame + 1, st.frames, p.marks.keyframes.size(),
                   p.marks.jumps.size(), p.mode, resim));
  ImGui::End();
}

}  // namespace urlab::viewer::internal
