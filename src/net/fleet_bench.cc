#include "urlab/net/fleet_bench.h"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <vector>
#include <zmq.hpp>

#include "core/spin_wait.h"
#include "net/bench_util.h"
#include "net/fleet_context.h"
#include "net/msgpack_codec.h"
#include "urlab/core/error.h"
#include "urlab/net/network.h"
#include "urlab/physics/model.h"
#include "urlab/world/manager.h"
#include "wire/shm_channel.h"
#include "wire/shm_wait.h"

namespace urlab::net {

namespace {

using bench::Format;
using bench::Median;
using Clock = std::chrono::steady_clock;

// The bare loop's spread (its fastest round over its slowest) above which a run's ratios are not
// to be trusted. Even idle it moves a little: the humanoid's state, and its step's cost with it,
// moves between rounds (1.04 in an idle run on this project's 2-core test machine; 1.46 to 1.66
// while another guest of the host took a virtual CPU).
constexpr double kBusySpread = 1.15;

double Micros(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

double P50(std::vector<double> us) { return Median(std::move(us)); }

// The op of a msgpack reply map ("" when there is none).
std::string_view ReplyOp(const msgpack::object& map) {
  if (map.type != msgpack::type::MAP) return {};
  for (std::uint32_t i = 0; i < map.via.map.size; ++i) {
    const msgpack::object_kv& kv = map.via.map.ptr[i];
    if (kv.key.type == msgpack::type::STR &&
        std::string_view(kv.key.via.str.ptr, kv.key.via.str.size) == "op" &&
        kv.val.type == msgpack::type::STR) {
      return {kv.val.via.str.ptr, kv.val.via.str.size};
    }
  }
  return {};
}

// A lean C++ step-server client over ZeroMQ REQ or, after hello, a shared-memory channel: a step
// reply is parsed (msgpack) and its op checked, not turned into a tree (that would measure the
// client's JSON library, not the transport).
class LeanClient {
 public:
  LeanClient(zmq::context_t& ctx, const std::string& endpoint, bool shm)
      : socket_(ctx, zmq::socket_type::req) {
    socket_.set(zmq::sockopt::rcvtimeo, 20000);
    socket_.set(zmq::sockopt::linger, 0);
    socket_.connect(endpoint);
    Json hello{{"op", "hello"}, {"observations", "standard"}, {"arrays", "binary"}};
    if (shm) hello["shm"] = true;
    const Json h = Call(hello);
    session_ = h.at("session_id").get<std::string>();
    if (shm) {
      if (!h.contains("shm")) throw Error("bench fleet: the step server offered no shared memory");
      channel_.emplace(wire::ShmChannel::Attach(h["shm"]["path"].get<std::string>(),
                                                h["shm"]["generation"].get<std::uint64_t>()));
    }
  }
  ~LeanClient() {
    try {
      Call(Json{{"op", "bye"}});
    } catch (const std::exception&) {
    }
  }
  Json Call(Json request) {
    Exchange(std::move(request));
    std::string why;
    return DecodeMsgpack(reply_, reply_size_, &why).value_or(Json());
  }
  // One request; throws unless the reply's op is a non-error one.
  void Exchange(Json request) {
    if (!session_.empty()) request["session_id"] = session_;
    writer_.Clear();
    writer_.Value(request);
    Transfer(wire::RequestSteps(request.value("op", ""), request.value("n_steps", 1)));
  }
  // A step request of n steps, written straight into the encoder as a lean client would (no
  // tree of the request first).
  void Step(int n) {
    writer_.Clear();
    writer_.Map(3);
    writer_.Key("op");
    writer_.Str("step");
    writer_.Key("n_steps");
    writer_.Int(n);
    writer_.Key("session_id");
    writer_.Str(session_);
    Transfer(n);
  }

 private:
  // Sends the encoded request (which runs `steps` steps) and checks the reply's op.
  void Transfer(int steps) {
    if (channel_) {
      // The client's wait policy (as urlab::client::StepClient's): spin about as long as the
      // server is expected to take, then sleep.
      const auto t0 = Clock::now();
      channel_->SendRequest(
          {reinterpret_cast<const std::uint8_t*>(writer_.data()), writer_.size()});
      const auto reply =
          channel_->WaitReply(std::chrono::seconds(20),
                              wire::SpinBudget(round_trips_.Expected(steps), wire::SpareCore));
      round_trips_.Took(steps, Clock::now() - t0);
      reply_ = reply.data();
      reply_size_ = reply.size();
    } else {
      socket_.send(zmq::buffer(writer_.data(), writer_.size()));
      if (!socket_.recv(message_)) throw Error("bench fleet: the step server did not answer");
      reply_ = static_cast<const std::uint8_t*>(message_.data());
      reply_size_ = message_.size();
    }
    // Strings and packed arrays stay views into the reply (as a client reading observations
    // straight from the channel would), not copies.
    const msgpack::object_handle h =
        msgpack::unpack(reinterpret_cast<const char*>(reply_), reply_size_,
                        [](msgpack::type::object_type, std::size_t, void*) { return true; });
    const std::string_view op = ReplyOp(h.get());
    if (op.empty() || op == "error") {
      std::string why;
      throw Error("bench fleet: the step server refused a request: " +
                  DecodeMsgpack(reply_, reply_size_, &why).value_or(Json()).dump());
    }
  }

  zmq::socket_t socket_;
  std::optional<wire::ShmChannel> channel_;
  std::string session_;
  MsgpackWriter writer_;
  zmq::message_t message_;
  const std::uint8_t* reply_ = nullptr;
  std::size_t reply_size_ = 0;
  wire::ShmRoundTrips round_trips_;
};

// Lockstep steps per second with n steps per request.
double LockstepRate(LeanClient& client, int steps, int n) {
  const int requests = std::max(1, steps / n);
  const auto t0 = Clock::now();
  for (int i = 0; i < requests; ++i) client.Step(n);
  return requests * n / std::chrono::duration<double>(Clock::now() - t0).count();
}

// The lockstep figures of one transport: n=1 and n=10 ratios, the step round trip and the round
// trip of a request the server answers without the physics thread (get_counters).
void LockstepFigures(FleetContext& ctx, bool shm, std::vector<FleetFigure>* out) {
  zmq::context_t zctx(1);
  LeanClient client(zctx, ctx.rpc(), shm);
  client.Exchange(Json{{"op", "set_mode"}, {"mode", "direct"}});
  const std::string name = shm ? "shm" : "zmq";
  for (int i = 0; i < 200; ++i) client.Step(1);  // warm
  for (const int n : {1, 10}) {
    const double ratio =
        ctx.MedianRatio([&] { return LockstepRate(client, ctx.steps_per_round(), n); });
    out->push_back({name + "_n" + std::to_string(n), ratio});
    ctx.Report(Format("%s lockstep n=%d: %.3f of bare (median of %d rounds)", name.c_str(), n,
                      ratio, ctx.options().rounds));
  }
  std::vector<double> step_us, rtt_us;
  const Json counters{{"op", "get_counters"}};
  for (int i = 0; i < ctx.options().samples; ++i) {
    auto t0 = Clock::now();
    client.Step(1);
    step_us.push_back(Micros(Clock::now() - t0));
    t0 = Clock::now();
    client.Exchange(counters);
    rtt_us.push_back(Micros(Clock::now() - t0));
  }
  out->push_back({name + "_step_rtt_p50_us", P50(step_us)});
  out->push_back({name + "_rtt_p50_us", P50(rtt_us)});
  ctx.Report(Format("%s round trips: step n=1 p50 %.1f us, get_counters p50 %.2f us", name.c_str(),
                    P50(step_us), P50(rtt_us)));
}

// Raw ping-pongs: an echo thread answers each ping. ZeroMQ REQ/REP, the echo in its own
// context; shared memory through the same channel and wait strategy as the step server (the
// echo spins for a millisecond as the server's I/O thread spins for a shared-memory request:
// SpinWait::SpinTight, pause instructions and a yield every few turns; then it sleeps in poll on
// its wake socket).
void RawFigures(FleetContext& ctx, std::vector<FleetFigure>* out) {
  const std::vector<std::uint8_t> ping(64, 7);
  {
    zmq::context_t ctx_a(1), ctx_b(1);
    zmq::socket_t req(ctx_a, zmq::socket_type::req), rep(ctx_b, zmq::socket_type::rep);
    rep.set(zmq::sockopt::linger, 0);
    req.set(zmq::sockopt::linger, 0);
    rep.set(zmq::sockopt::rcvtimeo, 100);
    rep.bind("tcp://127.0.0.1:*");
    req.connect(rep.get(zmq::sockopt::last_endpoint));
    std::atomic<bool> stop{false};
    std::thread echo([&] {
      while (!stop.load()) {
        zmq::message_t m;
        if (rep.recv(m)) rep.send(m, zmq::send_flags::none);
      }
    });
    std::vector<double> us;
    for (int i = 0; i < ctx.options().samples + 50; ++i) {
      const auto t0 = Clock::now();
      req.send(zmq::buffer(ping));
      zmq::message_t m;
      (void)req.recv(m);
      if (i >= 50) us.push_back(Micros(Clock::now() - t0));
    }
    stop = true;
    echo.join();
    out->push_back({"raw_zmq_rtt_p50_us", P50(us)});
  }
  {
    char tmpl[] = "/tmp/urlab-bench-XXXXXX";
    if (!mkdtemp(tmpl)) throw Error("bench fleet: no temporary folder");
    const std::string dir = tmpl;
    wire::ShmWakeSocket wake;
    wire::ShmChannel server =
        wire::ShmChannel::Create(dir + "/" + wire::NewShmName(), 4096, 4096, wake.name());
    wire::ShmChannel client = wire::ShmChannel::Attach(server.path(), server.generation());
    server.Unlink();
    rmdir(dir.c_str());
    std::atomic<bool> stop{false};
    std::thread echo([&] {
      SpinWait spin;
      while (!stop.load(std::memory_order_relaxed)) {
        if (auto r = server.TakeRequest()) {
          server.WriteReply(*r);
          continue;
        }
        if (spin.SpinTight(std::chrono::milliseconds(1), [&] {
              return server.request_waiting() || stop.load(std::memory_order_relaxed);
            })) {
          continue;
        }
        server.Sleeping(true);
        if (!server.request_waiting()) {
          pollfd p{wake.fd(), POLLIN, 0};
          poll(&p, 1, 50);
        }
        server.Sleeping(false);
        wake.Drain();
      }
    });
    std::vector<double> us;
    for (int i = 0; i < ctx.options().samples + 50; ++i) {
      const auto t0 = Clock::now();
      client.SendRequest(ping);
      (void)client.WaitReply(std::chrono::seconds(10), std::chrono::milliseconds(2));
      if (i >= 50) us.push_back(Micros(Clock::now() - t0));
    }
    stop = true;
    echo.join();
    out->push_back({"raw_shm_rtt_p50_us", P50(us)});
  }
  ctx.Report(Format("raw ping-pong p50: ZeroMQ REQ/REP %.1f us, shared memory %.2f us",
                    out->at(out->size() - 2).value, out->back().value));
}

// A Python client (urlab_client.StepClient) in its own process, n=1 lockstep.
constexpr const char* kPythonScript = R"PY(
import sys, time
sys.path.insert(0, sys.argv[1])
from urlab_client import StepClient
endpoint, shm, steps = sys.argv[2], sys.argv[3] == "1", int(sys.argv[4])
c = StepClient(endpoint, shared_memory=shm)
if c.transport != ("shm" if shm else "zmq"):
    print("transport=" + c.transport)
    sys.exit(2)
c.set_mode("direct")
for i in range(200):
    c.step(1)
t0 = time.perf_counter()
for i in range(steps):
    c.step(1)
print("rate=%f" % (steps / (time.perf_counter() - t0)))
c.close()
)PY";

double PythonRate(FleetContext& ctx, bool shm) {
  const std::string steps = std::to_string(ctx.steps_per_round());
  int out[2];
  if (pipe(out) != 0) throw Error("bench fleet: no pipe");
  const pid_t child = fork();
  if (child < 0) throw Error("bench fleet: cannot start Python");
  if (child == 0) {
    dup2(out[1], 1);
    close(out[0]);
    close(out[1]);
    const std::string& py = ctx.options().python;
    execl(py.c_str(), py.c_str(), "-c", kPythonScript, ctx.options().python_client.c_str(),
          ctx.rpc().c_str(), shm ? "1" : "0", steps.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(out[1]);
  std::string text;
  char buf[256];
  ssize_t n = 0;
  while ((n = read(out[0], buf, sizeof(buf))) > 0) text.append(buf, static_cast<std::size_t>(n));
  close(out[0]);
  int status = 0;
  waitpid(child, &status, 0);
  const auto at = text.find("rate=");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || at == std::string::npos) {
    throw Error("bench fleet: the Python client failed (" + text + ")");
  }
  return std::stod(text.substr(at + 5));
}

void PythonFigures(FleetContext& ctx, std::vector<FleetFigure>* out) {
  if (ctx.options().python_client.empty() || access(ctx.options().python.c_str(), X_OK) != 0) {
    ctx.Report("no Python client (--python-client): Python figures left out");
    return;
  }
  for (const bool shm : {false, true}) {
    const double ratio = ctx.MedianRatio([&] { return PythonRate(ctx, shm); });
    out->push_back({shm ? "shm_python_n1" : "zmq_python_n1", ratio});
    ctx.Report(Format("Python lockstep n=1 over %s: %.3f of bare", shm ? "shared memory" : "ZeroMQ",
                      ratio));
  }
}

}  // namespace

double FleetContext::BareRate(int steps) {
  const auto t0 = Clock::now();
  for (int i = 0; i < steps; ++i) mj_step(m_, d_);
  bare_rates_.push_back(steps / std::chrono::duration<double>(Clock::now() - t0).count());
  return bare_rates_.back();
}

double FleetContext::CeilingRate(int threads, int steps, int copies) {
  std::vector<physics::DataPtr> datas;
  for (int k = 0; k < threads * copies; ++k) {
    datas.push_back(physics::MakeData(m_));
    mj_copyData(datas.back().get(), m_, d_);
  }
  std::atomic<bool> go{false};
  std::vector<std::thread> workers;
  for (int k = 0; k < threads; ++k) {
    workers.emplace_back([&, k] {
      while (!go.load(std::memory_order_acquire)) std::this_thread::yield();
      for (int i = 0; i < steps; ++i) {
        mj_step(m_, datas[static_cast<std::size_t>(k * copies + i % copies)].get());
      }
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(5));  // the threads reach the start
  const auto t0 = Clock::now();
  go.store(true, std::memory_order_release);
  for (std::thread& t : workers) t.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return static_cast<double>(threads) * steps / seconds;
}

double FleetContext::MedianRatio(const std::function<double()>& measure) {
  std::vector<double> ratios;
  for (int round = 0; round < options_.rounds; ++round) {
    if (sync_bare) sync_bare(d_);
    const double bare = BareRate(steps_per_round());
    ratios.push_back(measure() / bare);
  }
  return Median(ratios);
}

std::vector<std::pair<std::string, FigureProducer>> FleetFigureProducers() {
  return {
      {"bare",
       [](FleetContext& ctx, std::vector<FleetFigure>* out) {
         std::vector<double> rates;
         for (int i = 0; i < ctx.options().rounds; ++i) {
           rates.push_back(ctx.BareRate(ctx.steps_per_round()));
         }
         out->push_back({"bare_steps_per_s", Median(rates)});
       }},
      {"ceiling",
       [](FleetContext& ctx, std::vector<FleetFigure>* out) {
         // What kFleetBatchThreads cores give at all: independent threads over the bare loop.
         const int k = kFleetBatchThreads;
         const double ratio =
             ctx.MedianRatio([&] { return ctx.CeilingRate(k, ctx.steps_per_round()); });
         out->push_back({"parallel_ceiling", ratio});
         ctx.Report(
             Format("%d independent threads, each its own mjData, no synchronisation: "
                    "%.3f of the bare single-thread loop (the ceiling of a batch on %d "
                    "threads)",
                    k, ratio, k));
         // The same with 64 simulations (32 per thread, each stepped in turn): the ceiling of a
         // batch of 64, where every simulation's data has left the caches by its next step.
         const double ratio64 =
             ctx.MedianRatio([&] { return ctx.CeilingRate(k, ctx.steps_per_round(), 64 / k); });
         out->push_back({"parallel_ceiling64", ratio64});
         ctx.Report(
             Format("%d independent threads stepping %d mjData each in turn: %.3f of the "
                    "bare loop (the ceiling of a batch of 64)",
                    k, 64 / k, ratio64));
       }},
      {"raw", RawFigures},
      {"zmq",
       [](FleetContext& ctx, std::vector<FleetFigure>* out) { LockstepFigures(ctx, false, out); }},
      {"shm",
       [](FleetContext& ctx, std::vector<FleetFigure>* out) { LockstepFigures(ctx, true, out); }},
      {"python", PythonFigures},
      {"batch", BatchFigures},
      {"inproc", InProcessFigures},
      {"dask", DaskFigures},
      {"rollout", RolloutFigures},
  };
}

std::vector<FleetFigure> RunFleetBench(world::SceneConfig scene, const FleetBenchOptions& options) {
  if (scene.articulations.empty()) throw Error("bench fleet: the scene has no articulation");
  if (options.rounds < 1 || options.steps < 1 || options.samples < 1) {
    throw Error("bench fleet: steps, rounds and samples must be >= 1");
  }
  scene.articulations.resize(1);
  world::ArticulationConfig& art = scene.articulations.front();
  art.controller = world::ControllerConfig{};  // passthrough: the transport's cost alone
  art.hold_keyframe = false;
  art.control_source = control::ControlSource::kNetwork;
  scene.save_debug_xml.clear();

  NetworkOptions no;
  no.state = no.control = no.info = no.rpc = "tcp://127.0.0.1:*";
  no.full_state = "";
  // Lockstep from the start (and again whenever a client leaves): the physics thread waits for
  // step requests, so it never competes with the bare loop.
  no.step_mode = "direct";
  world::ManagerOptions mo;
  mo.as_fast_as_possible = true;
  world::Manager manager(mo);
  auto& net =
      static_cast<NetworkSubsystem&>(manager.AddSubsystem(std::make_unique<NetworkSubsystem>(no)));
  manager.BeginPlay(scene);
  physics::PhysicsEngine& engine = manager.session().engine();
  const physics::Model bare_model = engine.CopyModel();  // with the model's extensions
  const physics::DataPtr bare_data = physics::MakeData(bare_model.get());
  mj_forward(bare_model.get(), bare_data.get());
  FleetContext ctx(options, net.endpoints().rpc, manager.session().articulations().front().name(),
                   bare_model.get(), bare_data.get());
  ctx.scene_path = scene.path;
  ctx.sync_bare = [&engine, &bare_model](mjData* bare) {
    engine.WithLockedData([&](mjModel*, mjData* d) { mj_copyData(bare, bare_model.get(), d); });
  };
  ctx.reset_state = manager.session().InitialStateReset();  // a batched server's reset state
  ctx.Report(Format("scene %s: articulation '%s', timestep %.4f s; %d rounds of %d steps",
                    scene.path.c_str(), ctx.articulation().c_str(), engine.timestep(),
                    options.rounds, ctx.steps_per_round()));
  std::vector<FleetFigure> figures;
  for (const auto& [name, produce] : FleetFigureProducers()) {
    if (options.only.empty() ||
        std::find(options.only.begin(), options.only.end(), name) != options.only.end()) {
      produce(ctx, &figures);
    }
  }
  // How steady the machine was: every ratio above divides by a bare loop timed just before, so a
  // busy machine (another process, a shared host's other guests taking a virtual CPU) shows as
  // that loop's speed moving from round to round.
  if (const std::vector<double>& rates = ctx.bare_rates(); rates.size() >= 2) {
    const auto [lo, hi] = std::minmax_element(rates.begin(), rates.end());
    const double spread = *hi / *lo;
    figures.push_back({"bare_spread", spread});
    ctx.Report(
        Format("the bare loop over this run: %.0f to %.0f steps/s in %zu rounds (median "
               "%.0f), a spread of %.2f%s",
               *lo, *hi, rates.size(), Median(rates), spread,
               spread > kBusySpread ? ": the machine was busy, the ratios are unreliable" : ""));
  }
  manager.EndPlay();
  return figures;
}

}  // namespace urlab::net
