#include "urlab/net/broadcast_bench.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
#include <zmq.hpp>

#include "net/bench_util.h"
#include "urlab/core/error.h"
#include "urlab/net/network.h"
#include "urlab/world/manager.h"

namespace urlab::net {

namespace {

using bench::Format;
using bench::Median;
using Clock = std::chrono::steady_clock;

struct Trial {
  double rate = 0;  // physics steps per second
  double messages_per_step = 0;
};

// Plays `scene` as fast as possible for `seconds` (after a warm-up) and counts steps; with
// `network`, every topic goes to a subscriber thread that receives all of it.
Trial RunTrial(const world::SceneConfig& scene, bool network, const BroadcastBenchOptions& o) {
  world::ManagerOptions mo;
  mo.as_fast_as_possible = true;
  world::Manager manager(mo);
  NetworkSubsystem* net = nullptr;
  if (network) {
    NetworkOptions no;
    no.state = no.control = no.info = "tcp://127.0.0.1:*";
    no.rpc = "";
    no.full_state = o.full_state;
    net = &static_cast<NetworkSubsystem&>(
        manager.AddSubsystem(std::make_unique<NetworkSubsystem>(no)));
  }
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> received{0};
  std::thread reader;
  zmq::context_t ctx(1);
  manager.BeginPlay(scene);
  if (net) {
    if (net->endpoints().state.empty()) throw Error("bench loop --network: no state socket");
    const std::string endpoint = net->endpoints().state;
    reader = std::thread([&ctx, &stop, &received, endpoint, &o] {
      // The subscriber stands in for a client on another host: on a shared 2-core machine it
      // would otherwise take the physics thread's core (its own ZeroMQ thread is created by
      // the context, before this one, and keeps the default priority).
      if (o.subscriber_nice > 0) {
        setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), o.subscriber_nice);
      }
      zmq::socket_t sub(ctx, zmq::socket_type::sub);
      sub.set(zmq::sockopt::subscribe, "");
      sub.set(zmq::sockopt::rcvhwm, 100000);
      sub.set(zmq::sockopt::rcvtimeo, 50);
      sub.connect(endpoint);
      zmq::message_t m;
      while (!stop.load(std::memory_order_relaxed)) {
        if (sub.recv(m)) received.fetch_add(1, std::memory_order_relaxed);
      }
    });
  }
  physics::PhysicsEngine& engine = manager.session().engine();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // warm-up; subscription joins
  const std::uint64_t steps0 = engine.step_count();
  const std::uint64_t received0 = received.load();
  const auto t0 = Clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(o.seconds));
  const std::uint64_t steps1 = engine.step_count();
  const std::uint64_t received1 = received.load();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  stop = true;
  if (reader.joinable()) reader.join();
  manager.EndPlay();
  Trial t;
  const double steps = static_cast<double>(steps1 - steps0);
  t.rate = steps / elapsed;
  t.messages_per_step = steps > 0 ? static_cast<double>(received1 - received0) / steps : 0;
  return t;
}

}  // namespace

BroadcastBenchResult RunBroadcastBench(world::SceneConfig scene,
                                       const BroadcastBenchOptions& options) {
  if (options.trials < 1 || !(options.seconds > 0)) {
    throw Error("bench loop --network: trials and seconds must be positive");
  }
  const auto report = [&](const std::string& line) {
    if (options.report) options.report(line);
  };
  scene.save_debug_xml.clear();
  BroadcastBenchResult r;
  std::vector<double> messages;
  for (int i = 0; i < options.trials; ++i) {
    const Trial bare = RunTrial(scene, false, options);
    const Trial net = RunTrial(scene, true, options);
    r.bare_rates.push_back(bare.rate);
    r.network_rates.push_back(net.rate);
    messages.push_back(net.messages_per_step);
    report(
        Format("trial %d: loop %.0f steps/s, with network %.0f steps/s (%.1f messages per "
               "step received), ratio %.3f",
               i + 1, bare.rate, net.rate, net.messages_per_step, net.rate / bare.rate));
  }
  r.messages_per_step = Median(messages);
  r.ratio = Median(r.network_rates) / Median(r.bare_rates);
  report(Format("median loop %.0f steps/s, with network %.0f steps/s: ratio %.4f",
                Median(r.bare_rates), Median(r.network_rates), r.ratio));
  return r;
}

}  // namespace urlab::net
