#include "urlab/replay/frame_sampler.h"

#include <algorithm>
#include <cmath>

namespace urlab::replay {

namespace {

// Slack for positions summed from recorded times.
constexpr double kSlack = 1e-9;

void CopyIfGiven(const std::vector<double>& from, std::vector<mjtNum>& to) {
  if (!from.empty()) to.assign(from.begin(), from.end());
}

}  // namespace

FrameSampler::FrameSampler(const RecordingReader& reader) : reader_(reader) {
  const ModelTables& t = reader.info().tables;
  dt_ = t.timestep > 0 ? t.timestep : 0.002;
  frame_.qpos.assign(static_cast<std::size_t>(t.nq), 0);
  frame_.qvel.assign(static_cast<std::size_t>(t.nv), 0);
  frame_.act.assign(static_cast<std::size_t>(t.na), 0);
  frame_.ctrl.assign(static_cast<std::size_t>(t.nu), 0);
  frame_.mocap_pos.assign(static_cast<std::size_t>(3 * t.nmocap), 0);
  frame_.mocap_quat.assign(static_cast<std::size_t>(4 * t.nmocap), 0);
  frame_.qfrc_applied.assign(static_cast<std::size_t>(t.nv), 0);
  frame_.xfrc_applied.assign(static_cast<std::size_t>(6 * t.nbody), 0);
  Cursor scan;
  while (Next(scan)) scan.have_pending = false;
  duration_ = scan.have_axis ? scan.last_pos : 0;
}

std::uint64_t FrameSampler::FrameCount(double fps) const {
  const double n = std::ceil(duration_ * fps - 1e-6);
  return n < 1 ? 1 : static_cast<std::uint64_t>(n);
}

bool FrameSampler::Next(Cursor& c) const {
  const std::vector<ChunkInfo>& chunks = reader_.chunks();
  while (true) {
    if (!c.loaded) {
      if (c.chunk >= chunks.size()) return false;
      c.records = reader_.ReadChunk(c.chunk);
      c.next = 0;
      c.loaded = true;
    }
    if (c.next >= c.records.size()) {
      ++c.chunk;
      c.loaded = false;
      continue;
    }
    Record& r = c.records[c.next++];
    if (auto* f = std::get_if<Frame>(&r)) {
      double pos = 0;
      if (c.have_axis) {
        const double delta = f->time - c.last_time;
        pos = c.last_pos + ((!c.jumped && delta > 0) ? delta : dt_);
      } else if (c.have_start) {
        const double delta = f->time - c.start.time;
        pos = delta > 0 ? delta : dt_;
      }
      c.have_axis = true;
      c.jumped = false;
      c.last_time = f->time;
      c.last_pos = pos;
      c.pending = std::move(*f);
      c.have_pending = true;
      return true;
    }
    if (auto* s = std::get_if<StateRecord>(&r)) {
      if (!c.have_axis && !c.have_start) {
        c.start = std::move(s->state);
        c.have_start = true;
      }
    } else if (std::holds_alternative<Marker>(r)) {
      c.jumped = c.have_axis;
    }
  }
}

void FrameSampler::Take(const Frame& f) {
  frame_.time = f.time;
  frame_.step = f.step;
  CopyIfGiven(f.qpos, frame_.qpos);
  CopyIfGiven(f.qvel, frame_.qvel);
  CopyIfGiven(f.act, frame_.act);
  CopyIfGiven(f.ctrl, frame_.ctrl);
  CopyIfGiven(f.mocap_pos, frame_.mocap_pos);
  CopyIfGiven(f.mocap_quat, frame_.mocap_quat);
  CopyIfGiven(f.qfrc_applied, frame_.qfrc_applied);
  CopyIfGiven(f.xfrc_applied, frame_.xfrc_applied);
}

void FrameSampler::TakeState(const physics::PhysicsState& s) {
  frame_.time = s.time;
  CopyIfGiven(s.qpos, frame_.qpos);
  CopyIfGiven(s.qvel, frame_.qvel);
  CopyIfGiven(s.act, frame_.act);
  CopyIfGiven(s.ctrl, frame_.ctrl);
  CopyIfGiven(s.mocap_pos, frame_.mocap_pos);
  CopyIfGiven(s.mocap_quat, frame_.mocap_quat);
  CopyIfGiven(s.qfrc_applied, frame_.qfrc_applied);
  CopyIfGiven(s.xfrc_applied, frame_.xfrc_applied);
}

const physics::StateFrame& FrameSampler::At(double position) {
  Cursor& c = cursor_;
  if (!started_) {
    started_ = true;
    Next(c);  // finds the start state on the way to the first step
    if (c.have_start) {
      TakeState(c.start);
      if (c.have_pending) frame_.step = c.pending.step > 0 ? c.pending.step - 1 : 0;
    } else if (c.have_pending) {
      Take(c.pending);  // no keyframe: the first step is position 0
      c.have_pending = false;
    }
  }
  while (c.have_pending || Next(c)) {
    if (c.last_pos > position + kSlack) break;
    Take(c.pending);
    c.have_pending = false;
  }
  return frame_;
}

}  // namespace urlab::replay
