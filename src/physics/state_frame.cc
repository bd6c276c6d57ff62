#include "urlab/physics/state_frame.h"

#include <algorithm>
#include <limits>

#include "core/gcc_workarounds.h"
#include "urlab/core/error.h"
#include "urlab/physics/observation_delay.h"

namespace urlab::physics {

namespace {

void CopyArray(std::vector<mjtNum>* out, const mjtNum* src, int n) {
  out->assign(src, src + n);  // no allocation once sized
}

void CopyCommands(AppliedCommands* out, const AppliedCommands& in) {
  out->targets.assign(in.targets.begin(), in.targets.end());  // no allocation once sized
  out->kp.assign(in.kp.begin(), in.kp.end());
  out->kv.assign(in.kv.begin(), in.kv.end());
  out->seq.assign(in.seq.begin(), in.seq.end());
  out->source.assign(in.source.begin(), in.source.end());
  out->raw.assign(in.raw.begin(), in.raw.end());
}

void ApplyMeta(StateFrame* f, const FrameMeta& meta) {
  if (meta.commands) CopyCommands(&f->commands, *meta.commands);
  f->step = meta.step;
  f->frame = meta.frame;
  f->command_seq = meta.command_seq;
  f->discontinuity = meta.discontinuity;
  f->epoch = meta.epoch;
  f->paused = meta.paused;
  f->stepped = meta.stepped;
}

}  // namespace

std::string DiscontinuityString(std::uint32_t flags) {
  static constexpr struct {
    std::uint32_t flag;
    const char* name;
  } kNames[] = {{kDiscontinuityReset, "reset"},
                {kDiscontinuityRestore, "restore"},
                {kDiscontinuitySetState, "set_state"},
                {kDiscontinuityOptions, "options"}};
  std::string s;
  for (const auto& n : kNames) {
    // -O3: a false -Wrestrict inside std::string's operator+ (GCC PR 105329 / 105651).
    URLAB_GCC_IGNORE("-Wrestrict")
    if (flags & n.flag) s += (s.empty() ? "" : "|") + std::string(n.name);
    URLAB_GCC_RESTORE
  }
  return s;
}

AppliedCommands AppliedCommands::SizedFor(const std::vector<CommandGroupLayout>& layout) {
  AppliedCommands c;
  std::size_t n = 0;
  for (const CommandGroupLayout& g : layout) n += g.actuators.size();
  c.targets.assign(n, 0.0);
  c.kp.assign(n, std::numeric_limits<double>::quiet_NaN());
  c.kv.assign(n, std::numeric_limits<double>::quiet_NaN());
  c.seq.assign(layout.size(), 0);
  c.source.assign(layout.size(), 0);
  c.raw.assign(layout.size(), 0);
  return c;
}

StateFrame StateFrame::SizedFor(const mjModel* m, const std::vector<CommandGroupLayout>& layout) {
  StateFrame f;
  f.commands = AppliedCommands::SizedFor(layout);
  const auto z = [](int n) { return std::vector<mjtNum>(static_cast<std::size_t>(n), 0); };
  f.qpos = z(m->nq);
  f.qvel = z(m->nv);
  f.act = z(m->na);
  f.ctrl = z(m->nu);
  f.qacc = z(m->nv);
  f.sensordata = z(m->nsensordata);
  f.actuator_force = z(m->nu);
  f.xpos = z(3 * m->nbody);
  f.xquat = z(4 * m->nbody);
  f.mocap_pos = z(3 * m->nmocap);
  f.mocap_quat = z(4 * m->nmocap);
  f.qfrc_applied = z(m->nv);
  f.xfrc_applied = z(6 * m->nbody);
  return f;
}

void StateFrame::CopyFrom(const mjModel* m, const mjData* d, const mjtNum* xfrc) {
  time = d->time;
  ncon = d->ncon;
  CopyArray(&qpos, d->qpos, m->nq);
  CopyArray(&qvel, d->qvel, m->nv);
  CopyArray(&act, d->act, m->na);
  CopyArray(&ctrl, d->ctrl, m->nu);
  CopyArray(&qacc, d->qacc, m->nv);
  CopyArray(&sensordata, d->sensordata, m->nsensordata);
  CopyArray(&actuator_force, d->actuator_force, m->nu);
  CopyArray(&xpos, d->xpos, 3 * m->nbody);
  CopyArray(&xquat, d->xquat, 4 * m->nbody);
  CopyArray(&mocap_pos, d->mocap_pos, 3 * m->nmocap);
  CopyArray(&mocap_quat, d->mocap_quat, 4 * m->nmocap);
  CopyArray(&qfrc_applied, d->qfrc_applied, m->nv);
  CopyArray(&xfrc_applied, xfrc ? xfrc : d->xfrc_applied, 6 * m->nbody);
}

StateSubscription::StateSubscription(std::string name, const mjModel* m,
                                     const std::vector<CommandGroupLayout>& layout)
    : name_(std::move(name)), buffer_(StateFrame::SizedFor(m, layout)) {}

StateRing::StateRing(std::string name, const mjModel* m, std::size_t capacity,
                     const std::vector<CommandGroupLayout>& layout)
    : name_(std::move(name)), ring_(capacity, StateFrame::SizedFor(m, layout)) {
  if (capacity == 0) throw Error("StateRing '" + name_ + "': capacity must be at least 1");
}

std::shared_ptr<StateSubscription> StatePublisher::SubscribeLatest(std::string name,
                                                                   bool observed) {
  auto s = std::make_shared<StateSubscription>(std::move(name), model_, layout_);
  s->observed_ = observed;
  latest_.push_back(s);
  return s;
}

std::shared_ptr<StateRing> StatePublisher::SubscribeEveryStep(std::string name,
                                                              std::size_t capacity, bool observed) {
  auto r = std::make_shared<StateRing>(std::move(name), model_, capacity, layout_);
  r->observed_ = observed;
  rings_.push_back(r);
  return r;
}

bool StatePublisher::Unsubscribe(const void* subscription) {
  const auto before = latest_.size() + rings_.size();
  std::erase_if(latest_, [&](const auto& s) { return s.get() == subscription; });
  std::erase_if(rings_, [&](const auto& r) { return r.get() == subscription; });
  return latest_.size() + rings_.size() != before;
}

int StatePublisher::num_subscribers() const {
  return static_cast<int>(latest_.size() + rings_.size());
}

void StatePublisher::PublishTo(StateSubscription& s, const mjModel* m, const mjData* d,
                               const FrameMeta& meta) {
  StateFrame& f = s.buffer_.Back();
  f.CopyFrom(m, d, meta.xfrc_applied);
  ApplyMeta(&f, meta);
  s.buffer_.Publish();
}

void StatePublisher::Publish(const mjModel* m, const mjData* d, const FrameMeta& meta) {
  // The observed frame, once per publication (the delay lines tick here, observers or not).
  const bool delayed = observation_delay_ && observation_delay_->active();
  if (delayed) {
    if (observed_.qpos.size() != static_cast<std::size_t>(m->nq)) {
      observed_ = StateFrame::SizedFor(m, layout_);
    }
    observed_.CopyFrom(m, d, meta.xfrc_applied);
    ApplyMeta(&observed_, meta);
    observation_delay_->Apply(&observed_);
  }
  for (const auto& s : latest_) {
    if (delayed && s->observed_) {
      s->buffer_.Back() = observed_;  // copy-assignment: no allocation once sized
      s->buffer_.Publish();
    } else {
      PublishTo(*s, m, d, meta);
    }
  }
  for (const auto& r : rings_) {
    if (!r->active()) continue;
    if (StateFrame* f = r->ring_.BeginPush()) {
      if (delayed && r->observed_) {
        *f = observed_;
      } else {
        f->CopyFrom(m, d, meta.xfrc_applied);
        ApplyMeta(f, meta);
      }
      r->ring_.CommitPush();
    }
  }
}

}  // namespace urlab::physics
