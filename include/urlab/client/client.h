#pragma once
// The C++ client of a running URLab (`urlab run` / `urlab view`): the same capabilities as the
// Python client. StreamClient speaks the streaming topics (discovery, decoded joint, base and
// sensor state by name, control by actuator name, gains); StepClient speaks the step server
// (hello, step in lockstep, reset, modes, any other operation by name). ZeroMQ and the message
// encoding stay inside the library.
//
// Threading: each client object is used by one thread at a time (it owns ZeroMQ sockets).
#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/wire/wire.h"

namespace urlab::client {

// Where the simulator serves (docs/protocol.md's defaults on `host`).
struct Endpoints {
  std::string state = "tcp://127.0.0.1:5555";
  std::string control = "tcp://127.0.0.1:5556";
  std::string info = "tcp://127.0.0.1:5557";
  std::string rpc = "tcp://127.0.0.1:5559";
  static Endpoints OnHost(const std::string& host);
};

// One articulation as discovery describes it.
struct Robot {
  std::string name;
  std::vector<std::string> actuator_names;  // short names, as in the robot's MJCF
  std::vector<int> actuator_ids;            // global ids
  std::vector<double> mins, maxs;
  // The global id of an actuator by short or full name; throws std::out_of_range.
  int ActuatorId(std::string_view name) const;
};

class StreamClient {
 public:
  explicit StreamClient(Endpoints endpoints = {});
  ~StreamClient();
  StreamClient(const StreamClient&) = delete;
  StreamClient& operator=(const StreamClient&) = delete;

  // Waits for discovery until every robot in `expect` is known (or, with none, one second
  // after the first); throws std::runtime_error after `timeout` without it.
  const std::map<std::string, Robot>& Discover(std::chrono::milliseconds timeout,
                                               const std::vector<std::string>& expect = {});
  const std::map<std::string, Robot>& robots() const;
  // Reads every waiting state message (waiting up to `timeout` for the first); returns the
  // number read. The newest values are kept by robot and name.
  int Poll(std::chrono::milliseconds timeout = std::chrono::milliseconds(0));
  std::optional<wire::JointMessage> Joint(const std::string& robot, const std::string& joint) const;
  std::optional<wire::BaseStateMessage> Base(const std::string& robot,
                                             const std::string& joint) const;
  std::optional<std::vector<float>> Sensor(const std::string& robot,
                                           const std::string& sensor) const;
  // One control message: {actuator short/full name: value}; throws std::out_of_range for an
  // unknown robot or actuator (call Discover first).
  void SendControl(const std::string& robot, const std::map<std::string, double>& targets);
  // A set_gains patch, as docs/protocol.md's JSON text ({"knee": {"kp": 50}}).
  void SetGains(const std::string& robot, const std::string& json);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// An error reply of the step server (code as in docs/protocol.md).
class StepError : public std::runtime_error {
 public:
  StepError(std::string code, const std::string& message)
      : std::runtime_error(code + ": " + message), code_(std::move(code)) {}
  const std::string& code() const { return code_; }

 private:
  std::string code_;
};

struct ArticulationObservation {
  std::vector<double> qpos, qvel, ctrl, act;
  std::map<std::string, std::vector<double>> sensors;
};
struct Observation {
  double time = 0;
  std::uint64_t step = 0;
  std::map<std::string, ArticulationObservation> per_articulation;
};

// Puppet mode input for one articulation (joint and actuator order of discovery); an empty
// vector leaves that part of the state as it is.
struct PuppetState {
  std::vector<double> qpos, qvel, ctrl;
};

// One active contact (get_contacts); force in the contact frame (normal first).
struct Contact {
  std::string geom1, geom2, body1, body2;
  std::array<double, 3> pos{}, normal{};
  double dist = 0;
  std::array<double, 6> force{};
};

class StepClient {
 public:
  // Connects and says hello (observation level minimal, standard or full). With
  // `shared_memory`, hello asks for a shared-memory channel, which a server on the same host
  // offers: every later request goes over it (the same messages; docs/network.md, "Shared
  // memory"); a channel that cannot be attached leaves the client on ZeroMQ. A server that dies
  // or closes the channel is a std::runtime_error within `timeout`.
  explicit StepClient(const std::string& endpoint = "tcp://127.0.0.1:5559",
                      const std::string& observations = "standard",
                      std::chrono::milliseconds timeout = std::chrono::milliseconds(10000),
                      bool shared_memory = true);
  ~StepClient();  // says bye
  StepClient(const StepClient&) = delete;
  StepClient& operator=(const StepClient&) = delete;

  const std::string& session_id() const;
  // "shm" once the session moved to shared memory, else "zmq".
  std::string transport() const;
  // The hello reply (articulation tables and more) as JSON text.
  const std::string& hello_json() const;
  // Any operation: `fields` is a JSON object text; returns the reply as JSON text. Throws
  // StepError for an error reply, std::runtime_error when no reply comes in time.
  std::string Call(const std::string& op, const std::string& fields = "{}");
  void SetMode(const std::string& mode);  // live | direct | puppet
  // n steps with controls {articulation: one value per actuator}.
  Observation Step(int n_steps = 1,
                   const std::map<std::string, std::vector<double>>& controls = {});
  // To a keyframe (full name) or, with none, the scene's initial state.
  Observation Reset(const std::string& keyframe = "");
  // Puppet mode (SetMode("puppet") first): writes the given state, runs mj_forward.
  Observation Puppet(const std::map<std::string, PuppetState>& per_articulation,
                     std::optional<double> time = std::nullopt);
  // The active contacts (at most max_contacts; *truncated says whether more exist).
  std::vector<Contact> Contacts(int max_contacts = 64, bool* truncated = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace urlab::client
