#include "urlab/physics/observation_delay.h"

#include <cmath>
#include <cstddef>

#include "urlab/core/error.h"

namespace urlab::physics {

int ObservationDelay::AddGroup(std::string name, ObservedSlice slice) {
  Group g;
  g.name = std::move(name);
  g.slice = std::move(slice);
  groups_.push_back(std::move(g));
  return static_cast<int>(groups_.size()) - 1;
}

int ObservationDelay::Find(const std::string& name) const {
  for (std::size_t i = 0; i < groups_.size(); ++i) {
    if (groups_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void ObservationDelay::Configure(int group, const DelaySpec& spec, const mjData* d) {
  if (group < 0 || group >= num_groups()) throw Error("ObservationDelay: bad group");
  Group& g = groups_[static_cast<std::size_t>(group)];
  g.line.Configure(spec);
  g.noise_state = g.noise_seed;
  if (d && g.line.active()) {
    GatherData(g.slice, d, &g.scratch);
    if (g.noise > 0) AddNoise(g);
    g.line.Push(g.scratch);
  }
}

void ObservationDelay::GatherData(const ObservedSlice& s, const mjData* d,
                                  std::vector<mjtNum>* out) {
  out->clear();  // the layout of Gather
  for (int a : s.qpos) out->push_back(d->qpos[a]);
  for (int a : s.dof) out->push_back(d->qvel[a]);
  for (int a : s.dof) out->push_back(d->qacc[a]);
  for (int a : s.act) out->push_back(d->act[a]);
  for (int a : s.sensor) out->push_back(d->sensordata[a]);
  for (int a : s.actuator) out->push_back(d->actuator_force[a]);
  for (int b : s.body) {
    for (int k = 0; k < 3; ++k) out->push_back(d->xpos[3 * b + k]);
    for (int k = 0; k < 4; ++k) out->push_back(d->xquat[4 * b + k]);
  }
}

const DelaySpec& ObservationDelay::spec(int group) const {
  return groups_.at(static_cast<std::size_t>(group)).line.spec();
}

void ObservationDelay::SetNoise(int group, double stddev, std::uint64_t seed) {
  if (group < 0 || group >= num_groups()) throw Error("ObservationDelay: bad group");
  Group& g = groups_[static_cast<std::size_t>(group)];
  g.noise = stddev > 0 ? stddev : 0;
  g.noise_seed = g.noise_state = seed;
  g.line.Restart();
}

bool ObservationDelay::active() const {
  for (const Group& g : groups_) {
    if (g.line.active() || g.noise > 0) return true;
  }
  return false;
}

void ObservationDelay::AddNoise(Group& g) {
  const auto normal = [&g] {  // Box-Muller; u1 in (0, 1]
    const double u1 = 1.0 - UnitDouble(&g.noise_state);
    const double u2 = UnitDouble(&g.noise_state);
    return g.noise * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  };
  const std::size_t nq = g.slice.qpos.size(), nv = g.slice.dof.size();
  for (std::size_t i = 0; i < nq + nv; ++i) g.scratch[i] += normal();  // qpos, qvel
  const std::size_t sensors = nq + 2 * nv + g.slice.act.size();
  for (std::size_t i = 0; i < g.slice.sensor.size(); ++i) g.scratch[sensors + i] += normal();
}

int ObservationDelay::last_jitter(int group) const {
  return groups_.at(static_cast<std::size_t>(group)).line.last_jitter();
}

std::int64_t ObservationDelay::ticks(int group) const {
  return groups_.at(static_cast<std::size_t>(group)).line.ticks();
}

void ObservationDelay::Gather(const ObservedSlice& s, const StateFrame& f,
                              std::vector<mjtNum>* out) {
  out->clear();  // keeps its capacity
  for (int a : s.qpos) out->push_back(f.qpos[static_cast<std::size_t>(a)]);
  for (int a : s.dof) out->push_back(f.qvel[static_cast<std::size_t>(a)]);
  for (int a : s.dof) out->push_back(f.qacc[static_cast<std::size_t>(a)]);
  for (int a : s.act) out->push_back(f.act[static_cast<std::size_t>(a)]);
  for (int a : s.sensor) out->push_back(f.sensordata[static_cast<std::size_t>(a)]);
  for (int a : s.actuator) out->push_back(f.actuator_force[static_cast<std::size_t>(a)]);
  for (int b : s.body) {
    for (int k = 0; k < 3; ++k) out->push_back(f.xpos[static_cast<std::size_t>(3 * b + k)]);
    for (int k = 0; k < 4; ++k) out->push_back(f.xquat[static_cast<std::size_t>(4 * b + k)]);
  }
}

void ObservationDelay::Scatter(const ObservedSlice& s, const std::vector<mjtNum>& in,
                               StateFrame* f) {
  std::size_t i = 0;
  for (int a : s.qpos) f->qpos[static_cast<std::size_t>(a)] = in[i++];
  for (int a : s.dof) f->qvel[static_cast<std::size_t>(a)] = in[i++];
  for (int a : s.dof) f->qacc[static_cast<std::size_t>(a)] = in[i++];
  for (int a : s.act) f->act[static_cast<std::size_t>(a)] = in[i++];
  for (int a : s.sensor) f->sensordata[static_cast<std::size_t>(a)] = in[i++];
  for (int a : s.actuator) f->actuator_force[static_cast<std::size_t>(a)] = in[i++];
  for (int b : s.body) {
    for (int k = 0; k < 3; ++k) f->xpos[static_cast<std::size_t>(3 * b + k)] = in[i++];
    for (int k = 0; k < 4; ++k) f->xquat[static_cast<std::size_t>(4 * b + k)] = in[i++];
  }
}

void ObservationDelay::Apply(StateFrame* frame) {
  for (Group& g : groups_) {
    if (!g.line.active() && g.noise == 0) continue;
    if (frame->discontinuity != 0) {
      g.line.Restart();
      g.noise_state = g.noise_seed;
    }
    Gather(g.slice, *frame, &g.scratch);
    const std::vector<mjtNum>* out = g.line.output();
    if (frame->stepped || !out) {
      if (g.noise > 0) AddNoise(g);
      out = &g.line.Push(g.scratch);
    }
    Scatter(g.slice, *out, frame);
  }
}

}  // namespace urlab::physics
