#include "viewer/panel.h"

#include <fmt/format.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "urlab/ops/controllers.h"
#include "urlab/ops/error.h"
#include "urlab/ops/recording.h"
#include "urlab/ops/simulation.h"
#include "urlab/ops/state.h"
#include "urlab/ops/targets.h"
#include "urlab/replay/recorder.h"
#include "urlab/world/manager.h"
#include "viewer/viewer_core.h"

namespace urlab::viewer::internal {

namespace {

// The sources a user may pick for an articulation (hold and replay are set by their features).
constexpr std::array<const char*, 4> kSourceChoices = {"scene default", "network", "ui", "input"};
constexpr std::array<control::ControlSource, 3> kSources = {
    control::ControlSource::kNetwork, control::ControlSource::kUi, control::ControlSource::kInput};

void Text(const std::string& s) { ImGui::TextUnformatted(s.c_str()); }

}  // namespace

void Panel::Draw(ViewerCore& core) {
  int iw = 0, ih = 0;
  core.WindowSize(&iw, &ih);
  const auto w = static_cast<float>(iw), h = static_cast<float>(ih);
  Layout& layout = core.layout();
  const WindowRect r = layout.Panel(w, h);
  constexpr ImGuiWindowFlags kFixed = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                                      ImGuiWindowFlags_NoCollapse |
                                      ImGuiWindowFlags_NoBringToFrontOnFocus;
  ImGui::SetNextWindowPos(ImVec2(r.x, r.y), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(r.w, r.h), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(1.0f);  // docked beside the viewport, not over it
  if (layout.collapsed()) {
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(2, 6));
    ImGui::Begin("##collapsed", nullptr, kFixed | ImGuiWindowFlags_NoDecoration);
    if (ImGui::Button(">", ImVec2(r.w - 4, 0))) layout.SetCollapsed(false);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("show the panel (H)");
    ImGui::End();
    ImGui::PopStyleVar();
    return;
  }
  ImGui::Begin("URLab simulate", nullptr,
               kFixed | ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_MenuBar);
  DrawMenuBar(core);
  if (!core.status().empty()) ImGui::TextWrapped("%s", core.status().c_str());
  DrawSimulation(core);
  DrawFileAndKeys(core);
  DrawLaunchers(core);
  DrawOptions(core);
  DrawArticulation(core);
  DrawDebug(core);
  DrawRendering(core);
  DrawCameras(core);
  DrawVisualisation(core);
  DrawGroups(core);
  DrawPhysicsFlags(core);
  DrawPlotChoice(core);
  DrawRecording(core);
  DrawSubsystems(core);
  DrawHelp(core);
  ImGui::End();
  DrawSplitter(core, w, h);
}

void Panel::DrawSplitter(ViewerCore& core, float w, float h) {
  Layout& layout = core.layout();
  const WindowRect s = layout.Splitter(w, h);
  if (s.w <= 0) return;
  ImGui::SetNextWindowPos(ImVec2(s.x, s.y), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(s.w, s.h), ImGuiCond_Always);
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowBorderSize, 0);
  ImGui::PushStyleVar(ImGuiStyleVar_WindowMinSize, ImVec2(1, 1));
  ImGui::Begin("##splitter", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus);
  ImGui::InvisibleButton("##split", ImVec2(s.w, s.h));
  const bool hot = ImGui::IsItemHovered() || ImGui::IsItemActive();
  if (hot) ImGui::SetMouseCursor(ImGuiMouseCursor_ResizeEW);
  if (ImGui::IsItemActive()) {
    // Follows the mouse: the panel's right edge where the pointer is.
    const float x = ImGui::GetIO().MousePos.x - s.w / 2;
    layout.SetWidth(x);
    layout.SetWidth(layout.Panel(w, h).w);  // clamped
  }
  ImGui::GetWindowDrawList()->AddRectFilled(
      ImVec2(s.x, s.y), ImVec2(s.x + s.w, s.y + s.h),
      ImGui::GetColorU32(hot ? ImGuiCol_SeparatorActive : ImGuiCol_Separator));
  ImGui::End();
  ImGui::PopStyleVar(3);
}

void Panel::DrawSimulation(ViewerCore& core) {
  physics::PhysicsEngine& engine = core.session().engine();
  if (!ImGui::CollapsingHeader("Simulation", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const physics::StateFrame* f = core.frame();
  Text(fmt::format("time {:.3f} s   step {}", f ? f->time : 0.0, f ? f->step : 0));
  Text(fmt::format("RTF {:.3f}   {:.0f} steps/s   {:.0f} fps{}", engine.real_time_factor(),
                   engine.step_rate(), core.fps(), engine.paused() ? "   PAUSED" : ""));
  if (ImGui::Button(engine.paused() ? "Run (P)" : "Pause (P)")) core.Perform(Action::kTogglePause);
  ImGui::SameLine();
  ImGui::BeginDisabled(!engine.paused());
  if (ImGui::Button("Step (Right)")) core.Perform(Action::kStep);
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Reset (R)")) core.Perform(Action::kReset);
  int speed = engine.speed_percent();
  if (ImGui::SliderInt("speed %", &speed, 5, 100)) ops::SetSpeed(core.session(), speed);
  bool fast = engine.as_fast_as_possible();
  if (ImGui::Checkbox("as fast as possible", &fast)) engine.SetAsFastAsPossible(fast);
}

void Panel::DrawLaunchers(ViewerCore& core) {
  const std::vector<world::LauncherLayout>& launchers = core.session().launchers();
  fire_buttons_.clear();
  if (launchers.empty() ||
      !ImGui::CollapsingHeader("Launchers (F fires all)", ImGuiTreeNodeFlags_DefaultOpen)) {
    return;
  }
  for (std::size_t i = 0; i < launchers.size(); ++i) {
    ImGui::PushID(static_cast<int>(i));
    if (ImGui::Button("Fire")) ops::FireLauncher(core.session(), launchers[i].name);
    const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
    fire_buttons_.push_back({(a.x + b.x) / 2, (a.y + b.y) / 2});
    ImGui::SameLine();
    Text(fmt::format("{}   {:.1f} m/s, {} projectiles", launchers[i].name, launchers[i].speed,
                     launchers[i].bodies.size()));
    ImGui::PopID();
  }
}

void Panel::DrawOptions(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Physics options")) return;
  const mjOption& opt = core.view().model()->opt;  // the viewer's copy follows what it sets
  // What set_sim_options also changes goes through the same operation (ops::SetOptions).
  double timestep = opt.timestep;
  if (ImGui::InputDouble("timestep", &timestep, 0.0005, 0.001, "%.5f",
                         ImGuiInputTextFlags_EnterReturnsTrue)) {
    core.SetOptions(ops::OptionsChange{.timestep = timestep});
  }
  const auto names = [](const std::vector<const char*>& n) { return static_cast<int>(n.size()); };
  int integrator = std::clamp(opt.integrator, 0, names(ops::IntegratorNames()) - 1);
  if (ImGui::Combo("integrator", &integrator, ops::IntegratorNames().data(),
                   names(ops::IntegratorNames()))) {
    core.SetOptions(ops::OptionsChange{.integrator = integrator});
  }
  int solver = std::clamp(opt.solver, 0, names(ops::SolverNames()) - 1);
  if (ImGui::Combo("solver", &solver, ops::SolverNames().data(), names(ops::SolverNames()))) {
    core.SetOptions(ops::OptionsChange{.solver = solver});
  }
  int iterations = opt.iterations;
  if (ImGui::SliderInt("iterations", &iterations, 1, 200)) {
    core.SetOptions(ops::OptionsChange{.iterations = iterations});
  }
  int cone = std::clamp(opt.cone, 0, names(ops::ConeNames()) - 1);
  if (ImGui::Combo("cone", &cone, ops::ConeNames().data(), names(ops::ConeNames()))) {
    core.SetOptions(ops::OptionsChange{.cone = cone});
  }
  int jacobian = std::clamp(opt.jacobian, 0, 2);
  constexpr std::array<const char*, 3> kJacobians = {"dense", "sparse", "auto"};
  if (ImGui::Combo("jacobian", &jacobian, kJacobians.data(), static_cast<int>(kJacobians.size()))) {
    core.SetOptions([jacobian](mjOption& o) { o.jacobian = jacobian; }, "jacobian");
  }
  int noslip = opt.noslip_iterations;
  if (ImGui::SliderInt("noslip iterations", &noslip, 0, 100)) {
    core.SetOptions([noslip](mjOption& o) { o.noslip_iterations = noslip; }, "noslip_iterations");
  }
  // MuJoCo 3's solver settings simulate shows: line search, convex collision (CCD) and SDF
  // collision iterations.
  const auto whole = [&](const char* label, int value, int low, int high, int mjOption::*field,
                         const char* name) {
    if (ImGui::SliderInt(label, &value, low, high)) {
      core.SetOptions([value, field](mjOption& o) { o.*field = value; }, name);
    }
  };
  whole("ls iterations", opt.ls_iterations, 0, 100, &mjOption::ls_iterations, "ls_iterations");
  whole("ccd iterations", opt.ccd_iterations, 1, 200, &mjOption::ccd_iterations, "ccd_iterations");
  whole("sdf iterations", opt.sdf_iterations, 1, 100, &mjOption::sdf_iterations, "sdf_iterations");
  whole("sdf initpoints", opt.sdf_initpoints, 1, 100, &mjOption::sdf_initpoints, "sdf_initpoints");
  const auto tolerance = [&](const char* label, mjtNum value, mjtNum mjOption::*field,
                             const char* name) {
    double v = value;
    if (ImGui::InputDouble(label, &v, 0, 0, "%.3g", ImGuiInputTextFlags_EnterReturnsTrue) &&
        std::isfinite(v) && v >= 0) {
      core.SetOptions([v, field](mjOption& o) { o.*field = v; }, name);
    }
  };
  tolerance("ls tolerance", opt.ls_tolerance, &mjOption::ls_tolerance, "ls_tolerance");
  tolerance("noslip tolerance", opt.noslip_tolerance, &mjOption::noslip_tolerance,
            "noslip_tolerance");
  tolerance("ccd tolerance", opt.ccd_tolerance, &mjOption::ccd_tolerance, "ccd_tolerance");
  // Numbers take effect on Enter (a half-typed value never reaches the simulation).
  const auto number = [&](const char* label, double value, const char* format,
                          std::optional<double> ops::OptionsChange::*field) {
    if (ImGui::InputDouble(label, &value, 0, 0, format, ImGuiInputTextFlags_EnterReturnsTrue)) {
      ops::OptionsChange change;
      change.*field = value;
      core.SetOptions(change);
    }
  };
  number("tolerance", opt.tolerance, "%.3g", &ops::OptionsChange::tolerance);
  number("impratio", opt.impratio, "%.3g", &ops::OptionsChange::impratio);
  number("density", opt.density, "%.4g", &ops::OptionsChange::density);
  number("viscosity", opt.viscosity, "%.4g", &ops::OptionsChange::viscosity);
  const auto vector = [&](const char* label, const mjtNum* v,
                          std::optional<std::array<double, 3>> ops::OptionsChange::*field) {
    double xyz[3] = {v[0], v[1], v[2]};
    if (ImGui::InputScalarN(label, ImGuiDataType_Double, xyz, 3, nullptr, nullptr, "%.3g",
                            ImGuiInputTextFlags_EnterReturnsTrue)) {
      ops::OptionsChange change;
      change.*field = std::array<double, 3>{xyz[0], xyz[1], xyz[2]};
      core.SetOptions(change);
    }
  };
  vector("gravity", opt.gravity, &ops::OptionsChange::gravity);
  vector("wind", opt.wind, &ops::OptionsChange::wind);
  vector("magnetic", opt.magnetic, &ops::OptionsChange::magnetic);
}

void Panel::DrawArticulation(ViewerCore& core) {
  sliders_.clear();
  world::Session& session = core.session();
  const auto& arts = session.articulations();
  if (arts.empty() || !ImGui::CollapsingHeader("Articulation", ImGuiTreeNodeFlags_DefaultOpen)) {
    return;
  }
  int selected = core.selected_articulation();
  std::vector<const char*> names;
  for (const world::Articulation& a : arts) names.push_back(a.name().c_str());
  if (ImGui::Combo("articulation", &selected, names.data(), static_cast<int>(names.size()))) {
    core.SelectArticulation(selected);
    keyframe_ = 0;
  }
  const world::Articulation& art = arts[static_cast<std::size_t>(core.selected_articulation())];
  control::ArticulationControl& ctl = *art.control;
  const control::ControlSource global = session.controls().global_source();
  // Control source: the scene's default, or an override.
  int choice = 0;
  if (const auto o = ctl.source_override()) {
    const auto* it = std::find(kSources.begin(), kSources.end(), *o);
    if (it != kSources.end()) choice = 1 + static_cast<int>(it - kSources.begin());
  }
  if (ImGui::Combo("control source", &choice, kSourceChoices.data(),
                   static_cast<int>(kSourceChoices.size()))) {
    ctl.SetSourceOverride(
        choice == 0 ? std::nullopt : std::optional(kSources[static_cast<std::size_t>(choice - 1)]));
  }
  const control::ControlSource active = ctl.EffectiveSource(global);
  Text(fmt::format("active: {}", control::ToString(active)));

  // Actuator sliders: the UI source's targets; locked and showing what another source sends.
  const mjModel* m = core.view().model();
  const control::Controller* controller = ctl.controller();
  const bool editable = active == control::ControlSource::kUi;
  if (ImGui::TreeNodeEx("actuators", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::BeginDisabled(!editable);
    for (int i = 0; i < ctl.num_actuators(); ++i) {
      const int id = ctl.actuator_ids()[static_cast<std::size_t>(i)];
      double lo = -1, hi = 1;
      if (controller && static_cast<std::size_t>(i) < controller->bindings().size()) {
        // The range of the target the controller takes (the step server's hello reports it too).
        const control::ActuatorBinding& b = controller->bindings()[static_cast<std::size_t>(i)];
        double range[2];
        if (b.TargetRange(controller->TargetsArePositions(), range)) lo = range[0], hi = range[1];
      } else if (m->actuator_ctrllimited[id]) {
        lo = m->actuator_ctrlrange[2 * id], hi = m->actuator_ctrlrange[2 * id + 1];
      }
      double value = ctl.GetTarget(editable ? control::ControlSource::kUi : active, i);
      const char* full = mj_id2name(m, mjOBJ_ACTUATOR, id);
      std::string label = full ? full : fmt::format("actuator {}", id);
      if (label.starts_with(art.prefix)) label.erase(0, art.prefix.size());
      const float frame_width = ImGui::CalcItemWidth();
      if (ImGui::SliderScalar(label.c_str(), ImGuiDataType_Double, &value, &lo, &hi, "%.3f") &&
          editable) {
        // The operation the step server and the control topic use (one validation: a value
        // typed out of range, Ctrl+click, is refused with its message).
        try {
          ops::SetTargets(
              session, {.source = control::ControlSource::kUi,
                        .articulations = {{.articulation = art.name(), .by_id = {{id, value}}}}});
        } catch (const ops::OpError& e) {
          message_ = e.what();
        }
      }
      const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
      sliders_.push_back({a.x, a.x + frame_width, (a.y + b.y) / 2});
    }
    ImGui::EndDisabled();
    ImGui::TreePop();
  }

  // Keyframes of this articulation.
  const std::vector<int>& keys = art.bindings->keyframes();
  if (!keys.empty()) {
    std::vector<std::string> key_names;
    for (int k : keys) {
      const char* n = mj_id2name(m, mjOBJ_KEY, k);
      std::string s = n ? n : fmt::format("key {}", k);
      if (s.starts_with(art.prefix)) s.erase(0, art.prefix.size());
      key_names.push_back(std::move(s));
    }
    std::vector<const char*> ptrs;
    for (const std::string& s : key_names) ptrs.push_back(s.c_str());
    keyframe_ = std::clamp(keyframe_, 0, static_cast<int>(keys.size()) - 1);
    ImGui::Combo("keyframe", &keyframe_, ptrs.data(), static_cast<int>(ptrs.size()));
    if (ImGui::Button("Reset##key")) {
      try {
        ops::ResetArticulation(session, art.name(), key_names[static_cast<std::size_t>(keyframe_)]);
      } catch (const ops::OpError& e) {
        message_ = e.what();
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("Hold")) ctl.HoldKeyframe(keys[static_cast<std::size_t>(keyframe_)]);
    ImGui::SameLine();
    if (ImGui::Button("Stop")) ctl.StopHold();
    if (ctl.holding()) {
      ImGui::SameLine();
      ImGui::TextUnformatted("holding");
    }
  }

  // Readouts from the viewer's copy of the state.
  const mjData* d = core.view().data();
  if (ImGui::TreeNode("joints")) {
    for (const physics::JointView& j : art.bindings->joints().all()) {
      if (j.qpos_size == 1) {
        Text(fmt::format("{:<20} {:+.4f}", j.name.substr(art.prefix.size()), d->qpos[j.qpos_adr]));
      }
    }
    ImGui::TreePop();
  }
  const physics::StateFrame* f = core.frame();
  if (f && !f->sensordata.empty() && ImGui::TreeNode("sensors")) {
    for (const physics::SensorView& s : art.bindings->sensors().all()) {
      std::string values;
      for (int k = 0; k < std::min(s.dim, 4); ++k) {
        values += fmt::format(" {:+.3f}", f->sensordata[static_cast<std::size_t>(s.adr + k)]);
      }
      Text(fmt::format("{:<18}{}", s.name.substr(art.prefix.size()), values));
    }
    ImGui::TreePop();
  }
  const Possession& possession = core.possession();
  if (possession.active()) {
    const control::Twist t = possession.twist();
    Text(fmt::format("driving '{}': vx {:+.2f} vy {:+.2f} yaw {:+.2f} actions {:#x}",
                     arts[static_cast<std::size_t>(possession.articulation())].name(), t.vx, t.vy,
                     t.yaw_rate, possession.actions()));
    if (ImGui::Button("Release (Tab)")) core.Perform(Action::kTogglePossess);
  } else if (const std::string why =
                 WhyNotPossessable(core.view().model(), ctl.twist(), ctl.num_actuators());
             !why.empty()) {
    ImGui::TextDisabled("%s", why.c_str());  // a fixed articulation, a static prop
  } else if (ImGui::Button("Possess (Tab)")) {
    core.Perform(Action::kTogglePossess);
  }
}

void Panel::DrawDebug(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Debug drawing", ImGuiTreeNodeFlags_DefaultOpen)) return;
  DebugSettings& s = core.debug();
  ImGui::TextUnformatted("global");
  for (int i = 0; i < kNumDebugLayers; ++i) {
    const auto layer = static_cast<DebugLayer>(i);
    const std::string label =
        i < 5 ? fmt::format("{} ({})", DebugLayerName(layer), i + 1) : DebugLayerName(layer);
    ImGui::Checkbox(label.c_str(), &s.global[static_cast<std::size_t>(i)]);
  }
  const auto sel = static_cast<std::size_t>(core.selected_articulation());
  if (sel < s.articulation.size()) {
    Text(fmt::format("articulation '{}'", core.session().articulations()[sel].name()));
    for (DebugLayer layer : {DebugLayer::kContacts, DebugLayer::kVisual, DebugLayer::kCollision,
                             DebugLayer::kJoints, DebugLayer::kSites}) {
      const std::string label = fmt::format("{}##art", DebugLayerName(layer));
      ImGui::Checkbox(label.c_str(), &s.articulation[sel][static_cast<std::size_t>(layer)]);
    }
  }
}

void Panel::DrawRendering(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Rendering")) return;
  mjvScene& scn = core.view().scene();
  bool shadow = scn.flags[mjRND_SHADOW] != 0, reflection = scn.flags[mjRND_REFLECTION] != 0;
  if (ImGui::Checkbox("shadows", &shadow)) scn.flags[mjRND_SHADOW] = shadow;
  if (ImGui::Checkbox("reflections", &reflection)) scn.flags[mjRND_REFLECTION] = reflection;
  if (ImGui::Button("Free camera (Esc)")) core.Perform(Action::kFreeCamera);
}

void Panel::DrawRecording(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Record and snapshot")) return;
  world::Session& session = core.session();
  // The operations the step server's snapshot and recording requests use (ops/recording.h); a
  // refusal (or a file that cannot be written) is shown below the buttons.
  const auto act = [this](const auto& op) {
    try {
      op();
    } catch (const std::exception& e) {
      message_ = e.what();
    }
  };
  if (ImGui::Button("Snapshot")) {
    act([&] {
      snapshot_ = ops::TakeState(session);
      message_ = fmt::format("snapshot at t={:.3f} s", snapshot_->time);
    });
  }
  ImGui::SameLine();
  ImGui::BeginDisabled(!snapshot_);
  if (ImGui::Button("Restore")) act([&] { ops::RestoreState(session, *snapshot_); });
  ImGui::EndDisabled();
  replay::RecorderSubsystem* recorder = core.recorder();
  if (recorder && recorder->recorder()) {
    ImGui::InputText("file", &record_path_);
    if (!recorder->recorder()->active()) {
      if (ImGui::Button("Record")) {
        act([&] {
          message_ = "recording " + ops::StartRecording(recorder, {.path = record_path_});
        });
      }
    } else if (ImGui::Button("Stop recording")) {
      act([&] {
        const replay::RecorderStatus st = ops::StopRecording(recorder);
        message_ = fmt::format("{}: {} steps", st.path, st.frames);
      });
    }
  } else {
    ImGui::TextUnformatted("(no recorder in this run)");
  }
  if (!message_.empty()) Text(message_);
}

void Panel::DrawSubsystems(ViewerCore& core) {
  if (!core.manager() || !ImGui::CollapsingHeader("Subsystems")) return;
  for (const auto& s : core.manager()->subsystems()) {
    const std::vector<world::StatusLine> lines = s->Status();
    Text(std::string(s->name()));
    for (const world::StatusLine& l : lines) Text(fmt::format("  {}: {}", l.key, l.value));
  }
}

void Panel::DrawHelp(ViewerCore& /*core*/) {
  if (!ImGui::CollapsingHeader("Keys and mouse")) return;
  for (const Hotkey& h : Hotkeys()) {
    Text(fmt::format("{:<4} {}", h.label, h.help));
  }
  ImGui::TextWrapped(
      "left drag: rotate, right drag: move, wheel: zoom; double-click: select, Ctrl+right "
      "double-click: track; Ctrl+left/right drag: push the selected body");
}

}  // namespace urlab::viewer::internal
