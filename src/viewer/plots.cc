#include "viewer/plots.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

namespace urlab::viewer::internal {

namespace {
// Line colours (the figure's defaults repeat after a few).
constexpr float kColours[Plots::kMaxChosen][3] = {
    {0.95f, 0.35f, 0.30f}, {0.35f, 0.75f, 0.95f}, {0.45f, 0.90f, 0.40f}, {0.95f, 0.80f, 0.30f},
    {0.80f, 0.45f, 0.95f}, {0.95f, 0.55f, 0.80f}, {0.60f, 0.95f, 0.85f}, {0.85f, 0.85f, 0.85f}};

std::string Name(const mjModel* m, int type, int id, const char* fallback) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : fmt::format("{} {}", fallback, id);
}
}  // namespace

Plots::Plots() : figure_(std::make_unique<mjvFigure>()) { mjv_defaultFigure(figure_.get()); }
Plots::~Plots() = default;

void Plots::Configure(const mjModel* m) {
  available_.clear();
  lines_.clear();
  for (int j = 0; j < m->njnt; ++j) {
    const int t = m->jnt_type[j];
    if (t != mjJNT_HINGE && t != mjJNT_SLIDE) continue;
    available_.push_back({SignalKind::kJoint, m->jnt_qposadr[j], Name(m, mjOBJ_JOINT, j, "joint")});
  }
  for (int s = 0; s < m->nsensor; ++s) {
    const std::string n = Name(m, mjOBJ_SENSOR, s, "sensor");
    for (int k = 0; k < m->sensor_dim[s]; ++k) {
      available_.push_back({SignalKind::kSensor, m->sensor_adr[s] + k,
                            m->sensor_dim[s] == 1 ? n : fmt::format("{}[{}]", n, k)});
    }
  }
  for (int a = 0; a < m->nu; ++a) {
    available_.push_back(
        {SignalKind::kActuatorForce, a, Name(m, mjOBJ_ACTUATOR, a, "actuator") + " force"});
  }
}

bool Plots::chosen(int signal) const {
  return std::any_of(lines_.begin(), lines_.end(),
                     [signal](const Line& l) { return l.signal == signal; });
}

bool Plots::Choose(int signal, bool on) {
  if (signal < 0 || signal >= static_cast<int>(available_.size())) return false;
  const auto it = std::find_if(lines_.begin(), lines_.end(),
                               [signal](const Line& l) { return l.signal == signal; });
  if (!on) {
    if (it != lines_.end()) lines_.erase(it);
    return true;
  }
  if (it != lines_.end()) return true;
  if (num_chosen() >= kMaxChosen) return false;
  lines_.push_back({signal, {}, {}});
  Clear();  // all lines share their sample times
  return true;
}

void Plots::Clear() {
  for (Line& l : lines_) {
    l.t.clear();
    l.v.clear();
  }
  points_ = 0;
}

double Plots::last(int line) const {
  const Line& l = lines_.at(static_cast<std::size_t>(line));
  return l.v.empty() ? 0.0 : l.v.back();
}

void Plots::Sample(const physics::StateFrame& f) {
  if (f.frame == last_frame_) return;
  last_frame_ = f.frame;
  if (f.time < last_time_) Clear();  // a reset: the plot starts again
  last_time_ = f.time;
  if (lines_.empty()) return;
  for (Line& l : lines_) {
    const Signal& s = available_[static_cast<std::size_t>(l.signal)];
    const std::vector<mjtNum>* src = &f.qpos;
    if (s.kind == SignalKind::kSensor) src = &f.sensordata;
    if (s.kind == SignalKind::kActuatorForce) src = &f.actuator_force;
    const auto i = static_cast<std::size_t>(s.index);
    const double v = i < src->size() ? (*src)[i] : 0.0;
    if (static_cast<int>(l.t.size()) >= kMaxPoints) {
      l.t.erase(l.t.begin());
      l.v.erase(l.v.begin());
    }
    l.t.push_back(static_cast<float>(f.time));
    l.v.push_back(static_cast<float>(v));
  }
  points_ = static_cast<int>(lines_.front().t.size());
}

void Plots::Draw(const mjrRect& viewport, const mjrContext* con) {
  mjvFigure& fig = *figure_;
  mjv_defaultFigure(&fig);
  std::strncpy(fig.title, "Plots (F4; choose signals in the panel)", sizeof fig.title - 1);
  std::strncpy(fig.xlabel, "time (s)", sizeof fig.xlabel - 1);
  fig.flg_legend = 1;
  fig.figurergba[3] = 0.8f;
  fig.gridsize[0] = 5;
  fig.gridsize[1] = 5;
  fig.legendrgba[3] = 0.6f;
  for (std::size_t i = 0; i < lines_.size() && i < static_cast<std::size_t>(mjMAXLINE); ++i) {
    const Line& l = lines_[i];
    const int n = std::min(static_cast<int>(l.t.size()), mjMAXLINEPNT);
    fig.linepnt[i] = n;
    for (int k = 0; k < n; ++k) {
      fig.linedata[i][2 * k] = l.t[static_cast<std::size_t>(k)];
      fig.linedata[i][2 * k + 1] = l.v[static_cast<std::size_t>(k)];
    }
    std::strncpy(fig.linename[i], available_[static_cast<std::size_t>(l.signal)].name.c_str(),
                 sizeof fig.linename[i] - 1);
    std::copy_n(kColours[i % kMaxChosen], 3, fig.linergb[i]);
  }
  if (lines_.empty()) std::strncpy(fig.linename[0], "(nothing chosen)", sizeof fig.linename[0] - 1);
  mjr_figure(viewport, &fig, con);
}

}  // namespace urlab::viewer::internal
