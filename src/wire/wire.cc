#include "urlab/wire/wire.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "wire/request_limits.h"

namespace urlab::wire {

namespace {

void PutU32(std::string* out, std::uint32_t v) {
  const char b[4] = {static_cast<char>(v & 0xff), static_cast<char>((v >> 8) & 0xff),
                     static_cast<char>((v >> 16) & 0xff), static_cast<char>((v >> 24) & 0xff)};
  out->append(b, 4);
}
void PutI32(std::string* out, std::int32_t v) { PutU32(out, static_cast<std::uint32_t>(v)); }
void PutF32(std::string* out, double v) {
  PutU32(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)));
}

std::uint32_t GetU32(std::string_view in, std::size_t at) {
  const auto b = [&](std::size_t i) {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(in[at + i]));
  };
  return b(0) | (b(1) << 8) | (b(2) << 16) | (b(3) << 24);
}
std::int32_t GetI32(std::string_view in, std::size_t at) {
  return static_cast<std::int32_t>(GetU32(in, at));
}
float GetF32(std::string_view in, std::size_t at) { return std::bit_cast<float>(GetU32(in, at)); }

std::string Join(std::string_view art, std::string_view kind, std::string_view name) {
  std::string s;
  s.reserve(art.size() + kind.size() + name.size() + 2);
  s.append(art).append("/").append(kind);
  if (!name.empty()) s.append("/").append(name);
  return s;
}

constexpr const char* kDropNames[] = {
    "unknown_topic",    "truncated",     "bad_size",    "negative_count", "too_many",
    "foreign_actuator", "non_finite",    "bad_json",    "unknown_name",   "bad_number",
    "unknown_field",    "no_controller", "bad_framing", "too_large"};
static_assert(std::size(kDropNames) == kNumDrops, "one name per Drop reason");

}  // namespace

const char* DropName(Drop d) {
  const int i = static_cast<int>(d);
  return i >= 0 && i < kNumDrops ? kDropNames[i] : "?";
}

std::string JointTopic(std::string_view art, std::string_view joint) {
  return Join(art, "joint", joint);
}
std::string BaseStateTopic(std::string_view art, std::string_view joint) {
  return Join(art, "base_state", joint);
}
std::string SensorTopic(std::string_view art, std::string_view sensor) {
  return Join(art, "sensor", sensor);
}
std::string TwistTopic(std::string_view art) { return Join(art, "twist", ""); }
std::string ActionsTopic(std::string_view art) { return Join(art, "actions", ""); }
std::string ControlTopic(std::string_view art) { return Join(art, "control ", ""); }
std::string SetGainsTopic(std::string_view art) { return Join(art, "set_gains ", ""); }

void AppendJoint(std::string* out, std::int32_t joint_id, double qpos, double qvel, double qacc) {
  PutI32(out, joint_id);
  PutF32(out, qpos);
  PutF32(out, qvel);
  PutF32(out, qacc);
}

void AppendBallJoint(std::string* out, std::int32_t joint_id, const double* qpos4,
                     const double* qvel3, const double* qacc3) {
  PutI32(out, joint_id);
  for (int i = 0; i < 4; ++i) PutF32(out, qpos4[i]);
  for (int i = 0; i < 3; ++i) PutF32(out, qvel3[i]);
  for (int i = 0; i < 3; ++i) PutF32(out, qacc3[i]);
}

void AppendBaseState(std::string* out, const double* qpos7, const double* qvel6) {
  for (int i = 0; i < 3; ++i) PutF32(out, qpos7[i]);
  for (int i : {4, 5, 6, 3}) PutF32(out, qpos7[i]);  // x y z w on the wire
  for (int i = 0; i < 6; ++i) PutF32(out, qvel6[i]);
}

void AppendSensor(std::string* out, std::int32_t sensor_id, std::span<const double> values) {
  PutI32(out, sensor_id);
  PutI32(out, static_cast<std::int32_t>(values.size()));
  for (double v : values) PutF32(out, v);
}

void AppendTwist(std::string* out, double vx, double vy, double yaw_rate) {
  PutF32(out, vx);
  PutF32(out, vy);
  PutF32(out, yaw_rate);
}

void AppendActions(std::string* out, std::int32_t mask) { PutI32(out, mask); }

void AppendControl(std::string* out, std::span<const std::pair<std::int32_t, float>> values) {
  PutI32(out, static_cast<std::int32_t>(values.size()));
  for (const auto& [id, v] : values) {
    PutI32(out, id);
    PutF32(out, v);
  }
}

std::optional<Drop> DecodeControl(std::string_view payload,
                                  std::vector<std::pair<std::int32_t, float>>* out) {
  out->clear();
  if (payload.size() > kMaxInboundPayloadBytes) return Drop::kTooLarge;
  if (payload.size() < 4) return Drop::kTruncated;
  const std::int32_t n = GetI32(payload, 0);
  if (n < 0) return Drop::kNegativeCount;
  if (n > kMaxControlCount) return Drop::kTooMany;
  const std::size_t expected = 4 + 8 * static_cast<std::size_t>(n);
  if (payload.size() < expected) return Drop::kTruncated;
  if (payload.size() != expected) return Drop::kBadSize;
  out->reserve(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    const float v = GetF32(payload, 8 + 8 * i);
    if (!std::isfinite(v)) {
      out->clear();
      return Drop::kNonFinite;
    }
    out->emplace_back(GetI32(payload, 4 + 8 * i), v);
  }
  return std::nullopt;
}

std::optional<Drop> DecodeSetGains(std::string_view payload, std::vector<GainPatch>* out) {
  out->clear();
  if (payload.size() > kMaxInboundPayloadBytes) return Drop::kTooLarge;
  if (!JsonDepthWithin(payload, kMaxSetGainsDepth)) return Drop::kBadJson;
  const auto j = nlohmann::ordered_json::parse(payload, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) return Drop::kBadJson;
  for (const auto& [name, fields] : j.items()) {
    if (!fields.is_object()) return out->clear(), Drop::kBadJson;
    GainPatch p;
    p.name = name;
    for (const auto& [field, value] : fields.items()) {
      std::optional<double>* slot = field == "kp"             ? &p.kp
                                    : field == "kv"           ? &p.kv
                                    : field == "torque_limit" ? &p.torque_limit
                                                              : nullptr;
      if (!slot) return out->clear(), Drop::kUnknownField;
      if (!value.is_number()) return out->clear(), Drop::kBadNumber;
      const double v = value.get<double>();
      if (!std::isfinite(v) || v < 0) return out->clear(), Drop::kBadNumber;
      *slot = v;
    }
    out->push_back(std::move(p));
  }
  return std::nullopt;
}

std::optional<JointMessage> DecodeJoint(std::string_view payload) {
  if (payload.size() != kJointBytes && payload.size() != kBallJointBytes) return std::nullopt;
  JointMessage m;
  m.joint_id = GetI32(payload, 0);
  const bool ball = payload.size() == kBallJointBytes;
  const std::size_t nq = ball ? 4 : 1, nv = ball ? 3 : 1;
  std::size_t at = 4;
  for (auto [vec, n] : {std::pair{&m.qpos, nq}, std::pair{&m.qvel, nv}, std::pair{&m.qacc, nv}}) {
    for (std::size_t i = 0; i < n; ++i, at += 4) vec->push_back(GetF32(payload, at));
  }
  return m;
}

std::optional<BaseStateMessage> DecodeBaseState(std::string_view payload) {
  if (payload.size() != kBaseStateBytes) return std::nullopt;
  BaseStateMessage m;
  for (std::size_t i = 0; i < 3; ++i) m.pos[i] = GetF32(payload, 4 * i);
  m.quat_wxyz = {GetF32(payload, 24), GetF32(payload, 12), GetF32(payload, 16),
                 GetF32(payload, 20)};
  for (std::size_t i = 0; i < 3; ++i) m.linvel[i] = GetF32(payload, 28 + 4 * i);
  for (std::size_t i = 0; i < 3; ++i) m.angvel[i] = GetF32(payload, 40 + 4 * i);
  return m;
}

std::optional<SensorMessage> DecodeSensor(std::string_view payload) {
  if (payload.size() < 8) return std::nullopt;
  SensorMessage m;
  m.sensor_id = GetI32(payload, 0);
  const std::int32_t dim = GetI32(payload, 4);
  if (dim < 0 || payload.size() != 8 + 4 * static_cast<std::size_t>(dim)) return std::nullopt;
  for (std::int32_t i = 0; i < dim; ++i) {
    m.values.push_back(GetF32(payload, 8 + 4 * static_cast<std::size_t>(i)));
  }
  return m;
}

}  // namespace urlab::wire
