#include "urlab/control/command_frame.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace urlab::control {

namespace {
constexpr double kKeepGain = std::numeric_limits<double>::quiet_NaN();

void Assign(std::vector<double>* out, const std::vector<double>& in) {
  out->assign(in.begin(), in.end());  // no allocation: every slot is sized at construction
}
}  // namespace

FrameChannel::FrameChannel(std::size_t n) : n_(n) {
  last_.targets.assign(n, 0);
  last_.kp.assign(n, kKeepGain);
  last_.kv.assign(n, kKeepGain);
  buffer_.slots().fill(last_);
  buffer_.Publish();
}

void FrameChannel::PublishLocked() {
  ++last_.seq;
  CommandFrame& back = buffer_.Back();
  Assign(&back.targets, last_.targets);
  Assign(&back.kp, last_.kp);
  Assign(&back.kv, last_.kv);
  back.raw = last_.raw;
  back.seq = last_.seq;
  buffer_.Publish();
}

bool FrameChannel::Publish(std::span<const double> targets, std::span<const double> kp,
                           std::span<const double> kv) {
  if (targets.size() != n_ || (!kp.empty() && kp.size() != n_) ||
      (!kv.empty() && kv.size() != n_)) {
    return false;
  }
  std::lock_guard<std::mutex> lock(writer_mutex_);
  std::copy(targets.begin(), targets.end(), last_.targets.begin());
  // A gain patch: NaN entries keep what earlier frames set.
  for (std::size_t i = 0; i < kp.size(); ++i) {
    if (!std::isnan(kp[i])) last_.kp[i] = kp[i];
  }
  for (std::size_t i = 0; i < kv.size(); ++i) {
    if (!std::isnan(kv[i])) last_.kv[i] = kv[i];
  }
  PublishLocked();
  return true;
}

bool FrameChannel::Patch(std::span<const std::pair<int, double>> values, std::optional<bool> raw) {
  for (const auto& [i, v] : values) {
    if (i < 0 || static_cast<std::size_t>(i) >= n_) return false;
  }
  std::lock_guard<std::mutex> lock(writer_mutex_);
  for (const auto& [i, v] : values) last_.targets[static_cast<std::size_t>(i)] = v;
  if (raw) last_.raw = *raw;
  PublishLocked();
  return true;
}

bool FrameChannel::Set(int index, double value) {
  const std::pair<int, double> one{index, value};
  return Patch(std::span(&one, 1));
}

double FrameChannel::Get(int index) const {
  if (index < 0 || static_cast<std::size_t>(index) >= n_) return 0;
  std::lock_guard<std::mutex> lock(writer_mutex_);
  return last_.targets[static_cast<std::size_t>(index)];
}

bool FrameChannel::PatchGains(std::span<const double> kp, std::span<const double> kv) {
  if ((!kp.empty() && kp.size() != n_) || (!kv.empty() && kv.size() != n_)) return false;
  std::lock_guard<std::mutex> lock(writer_mutex_);
  for (std::size_t i = 0; i < kp.size(); ++i) {
    if (!std::isnan(kp[i])) last_.kp[i] = kp[i];
  }
  for (std::size_t i = 0; i < kv.size(); ++i) {
    if (!std::isnan(kv[i])) last_.kv[i] = kv[i];
  }
  PublishLocked();
  return true;
}

std::pair<double, double> FrameChannel::Gains(int index) const {
  if (index < 0 || static_cast<std::size_t>(index) >= n_) return {kKeepGain, kKeepGain};
  std::lock_guard<std::mutex> lock(writer_mutex_);
  return {last_.kp[static_cast<std::size_t>(index)], last_.kv[static_cast<std::size_t>(index)]};
}

std::vector<double> FrameChannel::Targets() const {
  std::lock_guard<std::mutex> lock(writer_mutex_);
  return last_.targets;
}

std::uint64_t FrameChannel::last_seq() const {
  std::lock_guard<std::mutex> lock(writer_mutex_);
  return last_.seq;
}

}  // namespace urlab::control
