// The panel's sections for what MuJoCo's simulate offers: the menu bar (File, Simulation, View,
// Render, Physics), files and keyframes, the model's cameras, visualisation and rendering flags,
// frames and labels, geom/site/joint/tendon/actuator groups, physics flags, and the choice of
// plotted signals. Flags of the simulation go through ViewerCore::SetOptions (a queued command);
// visual ones change only the viewer's mjvOption and mjvScene.
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <string>

#include "urlab/core/error.h"
#include "viewer/panel.h"
#include "viewer/viewer_core.h"

namespace urlab::viewer::internal {

namespace {

// A menu item that does what its hotkey does.
void Item(ViewerCore& core, const char* label, Action action, bool enabled = true) {
  if (ImGui::MenuItem(label, KeyLabel(action), false, enabled)) core.Perform(action);
}

void Toggle(ViewerCore& core, const char* label, Action action, bool on) {
  if (ImGui::MenuItem(label, KeyLabel(action), on)) core.Perform(action);
}

// Disable flags are shown as what they enable ("contact" on = contacts computed).
void PhysicsFlagItems(ViewerCore& core, bool menu) {
  const mjOption& opt = core.view().model()->opt;
  for (int i = 0; i < mjNDISABLE; ++i) {
    bool on = (opt.disableflags & (1 << i)) == 0;
    const bool changed = menu ? ImGui::MenuItem(mjDISABLESTRING[i], nullptr, &on)
                              : ImGui::Checkbox(mjDISABLESTRING[i], &on);
    if (changed) core.SetDisableFlag(i, !on);
  }
  for (int i = 0; i < mjNENABLE; ++i) {
    bool on = (opt.enableflags & (1 << i)) != 0;
    const std::string label = fmt::format("{} (enable)", mjENABLESTRING[i]);
    const bool changed =
        menu ? ImGui::MenuItem(label.c_str(), nullptr, &on) : ImGui::Checkbox(label.c_str(), &on);
    if (changed) core.SetEnableFlag(i, on);
  }
}

void VisFlagItems(ViewerCore& core, bool menu) {
  mjvOption& opt = core.view().option();
  for (int i = 0; i < mjNVISFLAG; ++i) {
    bool on = opt.flags[i] != 0;
    const char* key = mjVISSTRING[i][2];
    const std::string shortcut = key[0] ? fmt::format("Shift+{}", key) : "";
    const std::string label =
        menu ? std::string(mjVISSTRING[i][0])
             : fmt::format("{}{}##vis", mjVISSTRING[i][0], key[0] ? " (" + shortcut + ")" : "");
    if (menu ? ImGui::MenuItem(label.c_str(), shortcut.c_str(), &on)
             : ImGui::Checkbox(label.c_str(), &on)) {
      opt.flags[i] = on;
    }
  }
}

void RenderFlagItems(ViewerCore& core, bool menu) {
  mjvScene& scn = core.view().scene();
  for (int i = 0; i < mjNRNDFLAG; ++i) {
    bool on = scn.flags[i] != 0;
    const std::string label = fmt::format("{}##rnd", mjRNDSTRING[i][0]);
    if (menu ? ImGui::MenuItem(label.c_str(), nullptr, &on) : ImGui::Checkbox(label.c_str(), &on)) {
      scn.flags[i] = on;
    }
  }
}

}  // namespace

void Panel::DrawMenuBar(ViewerCore& core) {
  if (!ImGui::BeginMenuBar()) return;
  if (ImGui::SmallButton("<")) core.layout().SetCollapsed(true);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("hide the panel (H)");
  if (ImGui::BeginMenu("File")) {
    Item(core, "Save XML", Action::kSaveXml);
    Item(core, "Save MJB", Action::kSaveMjb);
    Item(core, "Print model", Action::kPrintModel);
    Item(core, "Print data", Action::kPrintData);
    Item(core, "Reload", Action::kReload);
    Item(core, "Screenshot", Action::kScreenshot);
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Simulation")) {
    const bool paused = core.session().engine().paused();
    Item(core, paused ? "Run" : "Pause", Action::kTogglePause);
    Item(core, "Step", Action::kStep, paused);
    Item(core, "Reset", Action::kReset);
    ImGui::Separator();
    const int nkey = core.view().model()->nkey;
    Item(core, "Load key", Action::kLoadKey, nkey > 0);
    Item(core, "Save key", Action::kSaveKey, nkey > 0);
    Item(core, "Copy pose", Action::kCopyPose);
    ImGui::Separator();
    Item(core, "Fire launchers", Action::kFireLaunchers, !core.session().launchers().empty());
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("View")) {
    ViewerCore::Overlays& o = core.overlays();
    Toggle(core, "Help", Action::kToggleHelp, o.help);
    Toggle(core, "Info", Action::kToggleInfo, o.info);
    Toggle(core, "Profiler", Action::kToggleProfiler, o.profiler);
    Toggle(core, "Plots", Action::kTogglePlots, o.plots);
    ImGui::Separator();
    Item(core, "Frame the scene", Action::kFrameScene);
    Item(core, "Free camera", Action::kFreeCamera);
    Item(core, "Next camera", Action::kNextCamera);
    Item(core, "Previous camera", Action::kPrevCamera);
    Item(core, "Cinematic camera", Action::kToggleCinematic);
    Item(core, "Hide the panel", Action::kTogglePanel);
    if (ImGui::BeginMenu("Visualisation flags")) {
      VisFlagItems(core, true);
      ImGui::EndMenu();
    }
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Render")) {
    RenderFlagItems(core, true);
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Physics")) {
    PhysicsFlagItems(core, true);
    ImGui::EndMenu();
  }
  ImGui::EndMenuBar();
}

void Panel::DrawFileAndKeys(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("File and keyframes")) return;
  const auto button = [&](const char* label, Action a) {
    if (ImGui::Button(label)) core.Perform(a);
    if (ImGui::IsItemHovered() && KeyLabel(a)[0]) ImGui::SetTooltip("%s", KeyLabel(a));
  };
  button("Save XML", Action::kSaveXml);
  ImGui::SameLine();
  button("Save MJB", Action::kSaveMjb);
  ImGui::SameLine();
  button("Reload", Action::kReload);
  button("Print model", Action::kPrintModel);
  ImGui::SameLine();
  button("Print data", Action::kPrintData);
  const mjModel* m = core.view().model();
  if (m->nkey > 0) {
    int key = core.key();
    const char* name = mj_id2name(m, mjOBJ_KEY, key);
    if (ImGui::SliderInt("key", &key, 0, m->nkey - 1, name ? name : "%d")) core.SetKey(key);
    button("Load key", Action::kLoadKey);
    ImGui::SameLine();
    button("Save key", Action::kSaveKey);
    ImGui::SameLine();
  } else {
    ImGui::TextDisabled("no keyframes in the model");
  }
  button("Copy pose", Action::kCopyPose);
  ImGui::TextDisabled("drop a scene (.yaml) or model (.xml) on the window to open it");
}

void Panel::DrawCameras(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Cameras")) return;
  const mjModel* m = core.view().model();
  std::vector<std::string> names = {"free"};
  for (int c = 0; c < m->ncam; ++c) {
    const char* n = mj_id2name(m, mjOBJ_CAMERA, c);
    names.push_back(n ? n : fmt::format("camera {}", c));
  }
  std::vector<const char*> ptrs;
  for (const std::string& n : names) ptrs.push_back(n.c_str());
  int choice = core.camera() + 1;
  if (ImGui::Combo("camera ([ ])", &choice, ptrs.data(), static_cast<int>(ptrs.size()))) {
    core.SetCamera(choice - 1);
  }
  if (ImGui::Button("Frame the scene (Ctrl+A)")) core.Perform(Action::kFrameScene);
  mjvOption& opt = core.view().option();
  int frame = opt.frame;
  if (ImGui::Combo("frames", &frame, mjFRAMESTRING, mjNFRAME)) opt.frame = frame;
  int label = opt.label;
  if (ImGui::Combo("labels", &label, mjLABELSTRING, mjNLABEL)) opt.label = label;
}

void Panel::DrawVisualisation(ViewerCore& core) {
  if (ImGui::CollapsingHeader("Visualisation flags")) VisFlagItems(core, false);
  if (ImGui::CollapsingHeader("Render flags")) {
    RenderFlagItems(core, false);
    float scale = static_cast<float>(core.quality().scale);
    if (ImGui::SliderFloat("render scale", &scale, 0.25f, 2.0f, "%.2f")) {
      core.quality().scale = scale;
    }
  }
}

void Panel::DrawGroups(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Groups")) return;
  mjvOption& opt = core.view().option();
  const std::pair<const char*, mjtByte*> rows[] = {{"geom (Alt+0-5)", opt.geomgroup},
                                                   {"site (Alt+Shift+0-5)", opt.sitegroup},
                                                   {"joint", opt.jointgroup},
                                                   {"tendon", opt.tendongroup},
                                                   {"actuator", opt.actuatorgroup},
                                                   {"flex", opt.flexgroup},
                                                   {"skin", opt.skingroup}};
  for (const auto& [name, groups] : rows) {
    ImGui::PushID(name);
    for (int g = 0; g < mjNGROUP; ++g) {
      bool on = groups[g] != 0;
      if (ImGui::Checkbox(fmt::format("{}##{}", g, g).c_str(), &on)) groups[g] = on;
      ImGui::SameLine();
    }
    ImGui::TextUnformatted(name);
    ImGui::PopID();
  }
}

void Panel::DrawPhysicsFlags(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Physics flags")) return;
  PhysicsFlagItems(core, false);
}

void Panel::DrawPlotChoice(ViewerCore& core) {
  if (!ImGui::CollapsingHeader("Plots")) return;
  Plots& plots = core.plots();
  bool shown = core.overlays().plots;
  if (ImGui::Checkbox("show the plots (F4)", &shown)) core.overlays().plots = shown;
  ImGui::SameLine();
  if (ImGui::SmallButton("clear")) plots.Clear();
  ImGui::TextDisabled("%d of at most %d chosen", plots.num_chosen(), Plots::kMaxChosen);
  const auto& all = plots.available();
  ImGui::BeginChild("signals", ImVec2(0, std::min(220.0f, 24.0f * all.size() + 8)), true);
  for (int i = 0; i < static_cast<int>(all.size()); ++i) {
    bool on = plots.chosen(i);
    const char* kind = all[static_cast<std::size_t>(i)].kind == SignalKind::kJoint    ? "joint"
                       : all[static_cast<std::size_t>(i)].kind == SignalKind::kSensor ? "sensor"
                                                                                      : "force";
    const std::string label =
        fmt::format("{}  ({})##sig{}", all[static_cast<std::size_t>(i)].name, kind, i);
    if (ImGui::Checkbox(label.c_str(), &on)) {
      if (plots.Choose(i, on) && on) core.overlays().plots = true;
    }
  }
  ImGui::EndChild();
}

}  // namespace urlab::viewer::internal
