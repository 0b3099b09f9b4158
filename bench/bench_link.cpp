// Benchmark of the robot link on loopback: prints figures, asserts nothing.
//
//   build/bench/bench_link [--quick]
//
// The stand-in robot (twin + server) runs in this process on its own
// threads; a blocking controlling client on a real TCP socket measures
// - command round trip: COMMAND sent -> REPLY received, 1000 times;
// - heartbeat round trip: the robot's echo of our HEARTBEAT;
// - telemetry: arrival rate and the spread of the gaps between frames
//   (the robot sends at 50 Hz from a 2 ms timer);
// - telemetry latency: how much older than the freshest frame each frame's
//   state is on arrival (state published at 100 Hz, so up to 10 ms of it is
//   the publishing period).
// Then the same controller again, under load that must not starve it
// (ratios against the first, unloaded run):
// - 500 idle monitors: authenticated, subscribed to telemetry, never reading;
// - 2000 connect / HELLO / close cycles from another thread, with 200
//   connections open at a time that never send HELLO.

#include <asio.hpp>

#include <algorithm>
#include <atomic>
#include <memory>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

#include "app/robot/twin_host.h"
#include "net/auth.h"
#include "net/robot_server.h"
#include "sim/model_loader.h"

using namespace sp;
using namespace sp::net;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

double now() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

struct Client {
  asio::io_context io;
  asio::ip::tcp::socket socket{io};
  FrameDecoder decoder;
  explicit Client(uint16_t port) {
    socket.connect({asio::ip::make_address("127.0.0.1"), port});
    socket.set_option(asio::ip::tcp::no_delay(true));
  }
  void send(const Message& m) {
    std::string error;
    asio::write(socket, asio::buffer(*encodeMessage(m, error)));
  }
  Message next() {
    while (true) {
      if (auto f = decoder.next()) {
        std::string error;
        if (auto m = decodeMessage(*f, error)) return *m;
      }
      char buf[8192];
      const size_t n = socket.read_some(asio::buffer(buf));
      decoder.feed(buf, n);
    }
  }
  // HELLO with the proof over the robot's CHALLENGE.
  void hello(const std::string& name, Role role) {
    while (true) {
      const Message m = next();
      if (const auto* c = std::get_if<ChallengeMsg>(&m))
        return send(HelloMsg{name, {}, role, helloProof(kToken, c->nonce, name, role)});
    }
  }
};

struct Summary {
  double median = 0, p99 = 0, max = 0;
};

Summary printStats(const char* what, std::vector<double> v) {
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))]; };
  std::printf("  %-34s n=%zu  median %.1f us  p99 %.1f us  max %.1f us\n", what, v.size(), at(0.5) * 1e6,
              at(0.99) * 1e6, v.back() * 1e6);
  return {at(0.5), at(0.99), v.back()};
}

struct Run {
  Summary command, heartbeat;
  double telemetryHz = 0;
  double maxGap = 0;
};

// The controller's figures: n command and heartbeat round trips, then
// telemetry alone for `listen` seconds.
Run measure(Client& c, int n, double listen, uint64_t& seq) {
  std::vector<double> commandRtt, heartbeatRtt, gaps, age;
  double lastTelemetry = 0;
  auto collect = [&](const Message& m) {
    if (const auto* tm = std::get_if<TelemetryMsg>(&m)) {
      const double t = now();
      if (lastTelemetry > 0) gaps.push_back(t - lastTelemetry);
      lastTelemetry = t;
      // The twin runs at 1x, so wall time minus twin time is a constant
      // plus the telemetry's age; its minimum over the run is taken as 0.
      age.push_back(t - tm->time);
    } else if (const auto* h = std::get_if<HeartbeatMsg>(&m); h && h->seq >= (uint64_t{1} << 62)) {
      c.send(*h);  // echo the robot's heartbeats, as a client must
    }
  };
  for (int i = 1; i <= n; ++i) {
    const uint64_t s = ++seq;
    const double t0 = now();
    c.send(CommandMsg{s, 1000, "stop"});
    while (true) {
      Message m = c.next();
      if (const auto* r = std::get_if<ReplyMsg>(&m); r && r->seq == s) break;
      collect(m);
    }
    commandRtt.push_back(now() - t0);
    const double t1 = now();
    c.send(HeartbeatMsg{s, t1});
    while (true) {
      Message m = c.next();
      if (const auto* h = std::get_if<HeartbeatMsg>(&m); h && h->seq == s) break;
      collect(m);
    }
    heartbeatRtt.push_back(now() - t1);
  }
  const double until = now() + listen;
  while (now() < until) collect(c.next());

  Run run;
  run.command = printStats("command -> reply round trip", commandRtt);
  run.heartbeat = printStats("heartbeat echo round trip", heartbeatRtt);
  printStats("gap between telemetry frames", gaps);
  const double fresh = *std::min_element(age.begin(), age.end());
  for (double& a : age) a -= fresh;
  printStats("telemetry age beyond the freshest", age);
  double mean = 0;
  for (double g : gaps) mean += g / static_cast<double>(gaps.size());
  run.telemetryHz = 1.0 / mean;
  run.maxGap = *std::max_element(gaps.begin(), gaps.end());
  std::printf("  telemetry rate %.1f Hz, longest gap %.1f ms\n", run.telemetryHz, run.maxGap * 1e3);
  return run;
}

// Reads (echoing the robot's heartbeats) for `seconds`: the backlog the
// controller did not read while the load was set up is not measured.
void drain(Client& c, double seconds) {
  const double until = now() + seconds;
  while (now() < until) {
    const Message m = c.next();
    if (const auto* h = std::get_if<HeartbeatMsg>(&m); h && h->seq >= (uint64_t{1} << 62)) c.send(*h);
  }
}

void compare(const Run& base, const Run& loaded) {
  std::printf("  ratio to unloaded: command rtt median x%.2f p99 x%.2f, heartbeat median x%.2f, telemetry rate x%.3f\n",
              loaded.command.median / base.command.median, loaded.command.p99 / base.command.p99,
              loaded.heartbeat.median / base.heartbeat.median, loaded.telemetryHz / base.telemetryHz);
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  Diagnostics diag;
  auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
  if (!model) return 1;
  TwinHost host(World::create(*model, SimParams{}, diag), 1.0);
  asio::io_context io;
  RobotServerConfig config;
  config.port = 0;
  config.link.token = kToken;
  config.maxConnections = 1000;  // room for the idle crowd below
  RobotServer server(io, config, host);
  if (!server.start().empty()) return 1;
  host.start();
  std::thread serverThread([&] { io.run(); });

  Client c(server.port());
  c.hello("bench", Role::Control);
  c.send(LeaseAcquireMsg{});
  const int n = quick ? 200 : 1000;
  const double listen = quick ? 1.0 : 4.0;
  uint64_t seq = 0;

  std::printf("SimPartner link benchmark: stand-in robot on loopback, one controlling client\n");
  std::printf("unloaded:\n");
  const Run base = measure(c, n, listen, seq);

  // 500 monitors that authenticate and then never read: the robot's
  // queues for them fill and it drops their telemetry, never the
  // controller's.
  const int idle = 500;
  std::vector<std::unique_ptr<Client>> monitors;
  for (int i = 0; i < idle; ++i) {
    monitors.push_back(std::make_unique<Client>(server.port()));
    monitors.back()->hello("idle" + std::to_string(i), Role::Monitor);
  }
  drain(c, 1.0);
  std::printf("with %d idle monitors (authenticated, never reading):\n", idle);
  compare(base, measure(c, n, listen, seq));
  monitors.clear();

  // Connect / HELLO / close cycles from another thread, plus 200 silent
  // connections (no HELLO) held open.
  const int cycles = 2000;
  std::vector<std::unique_ptr<Client>> silent;
  for (int i = 0; i < 200; ++i) silent.push_back(std::make_unique<Client>(server.port()));
  // The churn runs for the whole measurement and at least `cycles` times.
  std::atomic<int> done{0};
  std::atomic<bool> measuring{true};
  std::thread churn([&] {
    while (measuring || done < cycles) {
      Client k(server.port());
      k.hello("churn", Role::Monitor);
      k.socket.close();
      ++done;
    }
  });
  drain(c, 1.0);
  const double t0 = now();
  std::printf("during connect/HELLO/close cycles (at least %d), 200 silent connections open:\n", cycles);
  compare(base, measure(c, n, listen, seq));
  measuring = false;
  churn.join();
  std::printf("  %d cycles in %.2f s (%.0f per second)\n", done.load(), now() - t0, done.load() / (now() - t0));

  asio::post(io, [&] {
    server.stop();
    io.stop();
  });
  serverThread.join();
  host.stop();
  std::printf("server: %llu connections refused at the cap, %llu closed for no HELLO\n",
              static_cast<unsigned long long>(server.stats().refusedConnections),
              static_cast<unsigned long long>(server.stats().helloTimeouts));
  return 0;
}
