// Pacing benchmark (not part of ctest: 2 x 20 s by default). Runs the physics loop at 500 Hz and
// at 1 kHz, speed 100 %, and prints the real-time-factor error and the step-period jitter
// (|period - target|) at p50/p99/max, plus how often the schedule was far off.
//
// Usage: bench_pacing [seconds_per_rate=20]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/model.h"

namespace {

using Clock = std::chrono::steady_clock;

std::string Pendulum(double timestep) {
  return R"(<mujoco><option timestep=")" + std::to_string(timestep) + R"("/>
  <worldbody><body pos="0 0 1"><joint type="hinge" axis="0 1 0" damping="0.01"/>
  <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/></body></worldbody>
  </mujoco>)";
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(p * (v.size() - 1) + 0.5));
  return v[i];
}

void Run(double hz, double seconds) {
  const double dt = 1.0 / hz;
  urlab::physics::PhysicsEngine engine(urlab::physics::CompileXmlString(Pendulum(dt)));
  std::vector<Clock::time_point> stamps;
  stamps.reserve(static_cast<std::size_t>(hz * seconds * 1.2) + 16);
  engine.AddOnPostStep([&](const mjModel*, mjData*) {
    if (stamps.size() < stamps.capacity()) stamps.push_back(Clock::now());
  });
  const auto w0 = Clock::now();
  engine.Start();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  engine.Stop();
  const double wall = std::chrono::duration<double>(Clock::now() - w0).count();
  double sim = 0;
  engine.WithLockedData([&](mjModel*, mjData* d) { sim = d->time; });

  std::vector<double> jitter_us;
  int late_1ms = 0;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    const double period = std::chrono::duration<double>(stamps[i] - stamps[i - 1]).count();
    jitter_us.push_back(std::abs(period - dt) * 1e6);
    if (period - dt > 1e-3) ++late_1ms;
  }
  const double rtf = sim / wall;
  std::printf(
      "%5.0f Hz, %.0f s: steps=%zu rtf=%.4f rtf_error=%+.2f%% (engine-measured rtf %.4f, "
      "step rate %.1f/s)\n",
      hz, seconds, stamps.size(), rtf, (rtf - 1) * 100, engine.real_time_factor(),
      engine.step_rate());
  std::printf(
      "        period jitter |period-%.0fus|: p50=%.1fus p99=%.1fus max=%.1fus, "
      "periods >1ms late: %d\n",
      dt * 1e6, Percentile(jitter_us, 0.5), Percentile(jitter_us, 0.99), Percentile(jitter_us, 1.0),
      late_1ms);
}

}  // namespace

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  const double seconds = argc > 1 ? std::atof(argv[1]) : 20.0;
  Run(500, seconds);
  Run(1000, seconds);
  return 0;
}
