#include "viewer/profiler.h"

#include <algorithm>
#include <cstring>

namespace urlab::viewer::internal {

namespace {

constexpr std::size_t kHistory = 200;
constexpr auto kPeriod = std::chrono::milliseconds(100);

// MuJoCo's timer clock (milliseconds), as simulate installs it.
mjtNum TimerMs() {
  using namespace std::chrono;
  static const auto start = steady_clock::now();
  return duration<double, std::milli>(steady_clock::now() - start).count();
}

void Fill(mjvFigure& fig, const char* title, const std::deque<ProfileSample>& h,
          std::initializer_list<std::pair<const char*, double ProfileSample::*>> doubles,
          std::initializer_list<std::pair<const char*, int ProfileSample::*>> ints) {
  mjv_defaultFigure(&fig);
  std::strncpy(fig.title, title, sizeof fig.title - 1);
  std::strncpy(fig.xlabel, "time (s)", sizeof fig.xlabel - 1);
  fig.flg_legend = 1;
  fig.figurergba[3] = 0.8f;
  fig.legendrgba[3] = 0.6f;
  fig.gridsize[0] = 5;
  fig.gridsize[1] = 4;
  int line = 0;
  const auto n = static_cast<int>(std::min<std::size_t>(h.size(), mjMAXLINEPNT));
  const auto put = [&](const char* name, auto get) {
    std::strncpy(fig.linename[line], name, sizeof fig.linename[line] - 1);
    fig.linepnt[line] = n;
    for (int k = 0; k < n; ++k) {
      const ProfileSample& s =
          h[h.size() - static_cast<std::size_t>(n) + static_cast<std::size_t>(k)];
      fig.linedata[line][2 * k] = static_cast<float>(s.time);
      fig.linedata[line][2 * k + 1] = static_cast<float>(get(s));
    }
    ++line;
  };
  for (const auto& [name, field] : doubles)
    put(name, [f = field](const ProfileSample& s) { return s.*f; });
  for (const auto& [name, field] : ints)
    put(name, [f = field](const ProfileSample& s) { return s.*f; });
}

}  // namespace

Profiler::Profiler()
    : shared_(std::make_shared<Shared>()),
      timing_(std::make_unique<mjvFigure>()),
      size_(std::make_unique<mjvFigure>()) {}

Profiler::~Profiler() = default;

void Profiler::Request(physics::PhysicsEngine& engine) {
  const auto now = std::chrono::steady_clock::now();
  if (now - last_request_ < kPeriod) return;
  last_request_ = now;
  engine.Submit(physics::cmd::Inspect{[s = shared_](const mjModel*, const mjData* d) {
                                        if (!mjcb_time)
                                          mjcb_time = TimerMs;  // this thread reads it: set it here
                                        ProfileSample p;
                                        p.time = d->time;
                                        const int n = d->timer[mjTIMER_STEP].number;
                                        const int steps = std::max(1, n - s->prev_n);
                                        const auto per_step = [&](int t) {
                                          const double v =
                                              (d->timer[t].duration - s->prev[t]) / steps;
                                          return std::max(0.0, v);
                                        };
                                        p.step_ms = per_step(mjTIMER_STEP);
                                        p.forward_ms = per_step(mjTIMER_FORWARD);
                                        p.collision_ms = per_step(mjTIMER_POS_COLLISION);
                                        p.solver_ms = per_step(mjTIMER_CONSTRAINT);
                                        p.steps =
                                            static_cast<std::uint64_t>(std::max(0, n - s->prev_n));
                                        for (int t = 0; t < mjNTIMER; ++t)
                                          s->prev[t] = d->timer[t].duration;
                                        s->prev_n = n;
                                        p.ncon = d->ncon;
                                        p.nefc = d->nefc;
                                        p.iterations = 0;  // the most any island took
                                        for (int i = 0; i < std::min(d->nisland, mjNISLAND); ++i)
                                          p.iterations = std::max(p.iterations, d->solver_niter[i]);
                                        std::lock_guard<std::mutex> lock(s->mutex);
                                        s->fresh.push_back(p);
                                        if (s->fresh.size() > kHistory) s->fresh.pop_front();
                                      },
                                      "viewer profiler"});
}

std::optional<ProfileSample> Profiler::Latest() {
  {
    std::lock_guard<std::mutex> lock(shared_->mutex);
    for (const ProfileSample& p : shared_->fresh) {
      if (!history_.empty() && p.time < history_.back().time) history_.clear();  // a reset
      history_.push_back(p);
    }
    shared_->fresh.clear();
  }
  while (history_.size() > kHistory) history_.pop_front();
  if (history_.empty()) return std::nullopt;
  return history_.back();
}

void Profiler::Draw(const mjrRect& vp, const mjrContext* con) {
  Fill(*timing_, "CPU time per step (ms)", history_,
       {{"step", &ProfileSample::step_ms},
        {"forward", &ProfileSample::forward_ms},
        {"collision", &ProfileSample::collision_ms},
        {"constraint", &ProfileSample::solver_ms}},
       {});
  Fill(*size_, "Dimensions", history_, {},
       {{"contacts", &ProfileSample::ncon},
        {"constraints", &ProfileSample::nefc},
        {"iterations", &ProfileSample::iterations}});
  const int h = vp.height / 2;
  mjr_figure({vp.left, vp.bottom + h, vp.width, vp.height - h}, timing_.get(), con);
  mjr_figure({vp.left, vp.bottom, vp.width, h}, size_.get(), con);
}

}  // namespace urlab::viewer::internal
