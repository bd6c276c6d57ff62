// libFuzzer target for the network's decoders of untrusted bytes (include/urlab/wire/wire.h):
// the control topic's binary payload and set_gains' JSON, resolved against a real articulation's
// table (net::BuildTopicTables over a built Session) and applied as the network's I/O thread
// does (ops::CheckTargets/ApplyTargets, ops::SetGains), then one physics step consumes them.
//
// Input: the first byte picks the message kind (even: control, odd: set_gains); the rest is the
// payload, up to wire::kMaxInboundPayloadBytes (tools/fuzz.sh's -max_len, asked from this target).
// Invariants checked beyond "no crash": an accepted control message is exactly 4 + 8 n bytes of
// finite values and re-encodes to the same bytes; an accepted set_gains has only finite gains >= 0.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fuzz_support.h"
#include "net/topic_table.h"
#include "urlab/control/controllers.h"
#include "urlab/core/error.h"
#include "urlab/ops/controllers.h"
#include "urlab/ops/targets.h"
#include "urlab/physics/commands.h"
#include "urlab/wire/wire.h"

namespace {

using urlab::net::ArticulationTopics;
namespace wire = urlab::wire;

struct Fixture {
  std::shared_ptr<urlab::world::Session> session = urlab::fuzz::MakeArmSession();
  std::vector<ArticulationTopics> tables = urlab::net::BuildTopicTables(*session);
  std::vector<urlab::control::PdGains> gains = Gains();  // as built, restored for each input

  urlab::control::PdController& pd() {
    auto* pd = dynamic_cast<urlab::control::PdController*>(tables.at(0).control->controller());
    if (!pd) __builtin_trap();  // the fixture's articulation is under PD
    return *pd;
  }
  std::vector<urlab::control::PdGains> Gains() {
    std::vector<urlab::control::PdGains> g;
    for (std::size_t i = 0; i < tables.at(0).actuator_ids.size(); ++i) {
      g.push_back(pd().gains(static_cast<int>(i)));
    }
    return g;
  }
};

Fixture& F() {
  static Fixture f;
  return f;
}

void Control(urlab::world::Session& session, ArticulationTopics& t, std::string_view payload) {
  std::vector<std::pair<std::int32_t, float>> values;
  if (wire::DecodeControl(payload, &values)) return;  // refused, with a reason
  if (payload.size() != 4 + 8 * values.size()) __builtin_trap();
  for (const auto& [id, v] : values) {
    if (!std::isfinite(v)) __builtin_trap();
  }
  std::string again;
  wire::AppendControl(&again, values);
  if (again != payload) __builtin_trap();
  // As the I/O thread: the targets operation checks the ids and values whole, then patches.
  urlab::ops::TargetsRequest request;
  urlab::ops::ArticulationTargets& a = request.articulations.emplace_back();
  a.articulation = t.name;
  a.by_id.assign(values.begin(), values.end());
  urlab::ops::CheckedTargets checked;
  try {
    urlab::ops::CheckTargets(session, request, &checked);
  } catch (const urlab::ops::TargetsError&) {
    return;  // dropped whole, with a reason
  }
  urlab::ops::ApplyTargets(session, checked);
  // The last value given for an actuator is the one in the frame.
  const auto& patch = checked.patches.at(0).values;
  auto& channel = t.control->channel(urlab::control::ControlSource::kNetwork);
  if (!patch.empty() && channel.Get(patch.back().first) != patch.back().second) __builtin_trap();
}

void SetGains(urlab::world::Session& session, ArticulationTopics& t, std::string_view payload) {
  std::vector<wire::GainPatch> patches;
  if (wire::DecodeSetGains(payload, &patches)) return;
  for (const wire::GainPatch& p : patches) {
    for (const auto& g : {p.kp, p.kv, p.torque_limit}) {
      if (g && !(std::isfinite(*g) && *g >= 0)) __builtin_trap();
    }
  }
  // As the I/O thread: the gains operation resolves the names, all or nothing.
  urlab::ops::GainsRequest request;
  for (const wire::GainPatch& p : patches) {
    request.named.push_back({p.name, {p.kp, p.kv, p.torque_limit}});
  }
  try {
    urlab::ops::SetGains(session, t.name, request);
  } catch (const urlab::ops::OpError&) {
  }
}

}  // namespace

// The fixture is built before the first input (its allocations are not the input's).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  urlab::fuzz::AnswerMaxLenQuery(1 + wire::kMaxInboundPayloadBytes);  // the kind byte, a payload
  (void)F();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Fixture& f = F();
  ArticulationTopics& t = f.tables.at(0);
  const std::string_view payload(reinterpret_cast<const char*>(data) + 1, size - 1);
  urlab::physics::PhysicsEngine& engine = f.session->engine();
  try {
    (void)f.session->ResetToInitialState();
    for (std::size_t i = 0; i < f.gains.size(); ++i)
      f.pd().SetGains(static_cast<int>(i), f.gains[i]);
    const std::vector<double> zeros(t.actuator_ids.size(), 0.0);
    (void)t.control->channel(urlab::control::ControlSource::kNetwork).Publish(zeros);
    if (data[0] % 2 == 0) {
      Control(*f.session, t, payload);
    } else {
      SetGains(*f.session, t, payload);
    }
    // The controller consumes the new targets and gains in one step (engine not running: the
    // step runs here).
    (void)engine.Submit(urlab::physics::cmd::Step{1});
  } catch (const urlab::Error&) {
  }
  (void)engine.DrainEvents();  // nobody else delivers them (a leak to libFuzzer otherwise)
  return 0;
}
