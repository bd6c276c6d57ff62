#pragma once
// The streaming topics' byte layouts (docs/protocol.md, "Streaming topics"): little-endian, packed,
// no padding; int32 ids and f32 values. Encoders for what the simulator publishes, decoders for
// what clients send, both over plain byte strings, so the server, the C++ client and the tests
// share one definition. Decoders never read past their input and report why they refuse it.
//
// Threading: pure functions; any thread.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace urlab::wire {

// Payload sizes of the fixed-size topics.
inline constexpr std::size_t kJointBytes = 16;      // int32 id, f32 qpos, qvel, qacc
inline constexpr std::size_t kBallJointBytes = 44;  // int32 id, f32 qpos[4], qvel[3], qacc[3]
inline constexpr std::size_t kBaseStateBytes = 52;  // f32 pos[3], quat xyzw, linvel[3], angvel[3]
inline constexpr std::size_t kTwistBytes = 12;      // f32 vx, vy, yaw_rate
inline constexpr std::size_t kActionsBytes = 4;     // int32 bitmask
// Largest control message accepted: 4 + 8 n bytes for n actuators.
inline constexpr std::int32_t kMaxControlCount = 1 << 16;
// Largest payload of an inbound topic (control, set_gains): the largest control message. Larger
// payloads are dropped as too_large before they are decoded. fuzz/net_control_fuzz.cc takes
// inputs of up to one byte more (its kind byte), so fuzzing reaches this limit.
inline constexpr std::size_t kMaxInboundPayloadBytes =
    4 + 8 * static_cast<std::size_t>(kMaxControlCount);
// set_gains is an object of objects of numbers: JSON nested deeper is dropped as bad_json
// before it is parsed.
inline constexpr std::size_t kMaxSetGainsDepth = 2;

// ---- Topic names ----
std::string JointTopic(std::string_view art, std::string_view joint);      // {art}/joint/{joint}
std::string BaseStateTopic(std::string_view art, std::string_view joint);  // {art}/base_state/..
std::string SensorTopic(std::string_view art, std::string_view sensor);    // {art}/sensor/{s}
std::string TwistTopic(std::string_view art);                              // {art}/twist
std::string ActionsTopic(std::string_view art);                            // {art}/actions
std::string ControlTopic(std::string_view art);   // "{art}/control " (trailing space)
std::string SetGainsTopic(std::string_view art);  // "{art}/set_gains " (trailing space)
inline constexpr std::string_view kFullStateTopic = "state/full";

// ---- Encoders (append to *out) ----
void AppendJoint(std::string* out, std::int32_t joint_id, double qpos, double qvel, double qacc);
// qpos as MuJoCo stores it (w x y z), qvel/qacc the three angular components.
void AppendBallJoint(std::string* out, std::int32_t joint_id, const double* qpos4,
                     const double* qvel3, const double* qacc3);
// pos and quaternion from a free joint's qpos (w x y z in MuJoCo; the wire puts w last), linear
// and angular velocity from its qvel.
void AppendBaseState(std::string* out, const double* qpos7, const double* qvel6);
void AppendSensor(std::string* out, std::int32_t sensor_id, std::span<const double> values);
void AppendTwist(std::string* out, double vx, double vy, double yaw_rate);
void AppendActions(std::string* out, std::int32_t mask);
// A control message: int32 n, then n x (int32 actuator_id, f32 value).
void AppendControl(std::string* out, std::span<const std::pair<std::int32_t, float>> values);

// ---- Decoders ----
// Why an inbound message was dropped (counted per reason).
enum class Drop {
  kUnknownTopic,     // the topic names no articulation (or no known message kind)
  kTruncated,        // shorter than its header says
  kBadSize,          // size is not exactly what the header implies
  kNegativeCount,    // n < 0
  kTooMany,          // n beyond kMaxControlCount or the articulation's actuator count
  kForeignActuator,  // an id that is not an actuator of this articulation
  kNonFinite,        // NaN or infinity
  kBadJson,          // not well-formed JSON, or not an object of objects
  kUnknownName,      // a set_gains name that is neither an actuator nor a joint
  kBadNumber,        // a gain that is not a finite number >= 0, a control value out of range
  kUnknownField,     // a set_gains field other than kp, kv, torque_limit
  kNoController,     // set_gains for an articulation whose controller has no gains
  kBadFraming,       // not exactly two frames [topic][payload]
  kTooLarge,         // a payload larger than kMaxInboundPayloadBytes
  kCount_,           // number of reasons (not a reason)
};
inline constexpr int kNumDrops = static_cast<int>(Drop::kCount_);
// "unknown_topic", "truncated", ... (stable names for counters and logs).
const char* DropName(Drop d);

// Decodes a control payload's structure (count, size, finite values). Ids are checked by the
// caller against the articulation. On success *out holds the pairs in message order.
std::optional<Drop> DecodeControl(std::string_view payload,
                                  std::vector<std::pair<std::int32_t, float>>* out);

// One entry of a set_gains message: a name (actuator or joint, short or prefixed) and the fields
// given (absent fields stay as they are).
struct GainPatch {
  std::string name;
  std::optional<double> kp, kv, torque_limit;
};
// Decodes a set_gains JSON payload (the names are resolved by the caller).
std::optional<Drop> DecodeSetGains(std::string_view payload, std::vector<GainPatch>* out);

// ---- Decoders for clients of the state topics (the C++ client and tests) ----
struct JointMessage {
  std::int32_t joint_id = -1;
  std::vector<float> qpos, qvel, qacc;  // 1/1/1 (hinge, slide) or 4/3/3 (ball)
};
std::optional<JointMessage> DecodeJoint(std::string_view payload);
struct BaseStateMessage {
  std::array<float, 3> pos{};
  std::array<float, 4> quat_wxyz{};  // reordered from the wire's x y z w
  std::array<float, 3> linvel{}, angvel{};
};
std::optional<BaseStateMessage> DecodeBaseState(std::string_view payload);
struct SensorMessage {
  std::int32_t sensor_id = -1;
  std::vector<float> values;
};
std::optional<SensorMessage> DecodeSensor(std::string_view payload);

}  // namespace urlab::wire
