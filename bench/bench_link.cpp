// Benchmark of the robot link on loopback: prints figures, asserts nothing.
//
//   build/bench/bench_link [--quick]
//
// The stand-in robot (twin + server) runs in this process on its own
// threads; a blocking client on a real TCP socket measures
// - command round trip: COMMAND sent -> REPLY received, 1000 times;
// - heartbeat round trip: the robot's echo of our HEARTBEAT;
// - telemetry: arrival rate and the spread of the gaps between frames
//   (the robot sends at 50 Hz from a 2 ms timer);
// - telemetry latency: how much older than the freshest frame each frame's
//   state is on arrival (state published at 100 Hz, so up to 10 ms of it is
//   the publishing period).

#include <asio.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

#include "app/twin_host.h"
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
};

void printStats(const char* what, std::vector<double> v) {
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))]; };
  std::printf("%-34s n=%zu  median %.1f us  p99 %.1f us  max %.1f us\n", what, v.size(), at(0.5) * 1e6,
              at(0.99) * 1e6, v.back() * 1e6);
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
  RobotServer server(io, config, host);
  if (!server.start().empty()) return 1;
  host.start();
  std::thread serverThread([&] { io.run(); });

  Client c(server.port());
  c.send(HelloMsg{"bench", kToken, Role::Control});
  c.send(LeaseAcquireMsg{});
  const int n = quick ? 200 : 1000;
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
    const double t0 = now();
    c.send(CommandMsg{static_cast<uint64_t>(i), 1000, "stop"});
    while (true) {
      Message m = c.next();
      if (const auto* r = std::get_if<ReplyMsg>(&m); r && r->seq == static_cast<uint64_t>(i)) break;
      collect(m);
    }
    commandRtt.push_back(now() - t0);
    const double t1 = now();
    c.send(HeartbeatMsg{static_cast<uint64_t>(i), t1});
    while (true) {
      Message m = c.next();
      if (const auto* h = std::get_if<HeartbeatMsg>(&m); h && h->seq == static_cast<uint64_t>(i)) break;
      collect(m);
    }
    heartbeatRtt.push_back(now() - t1);
  }
  // Then only telemetry for a while.
  const double until = now() + (quick ? 1.0 : 4.0);
  while (now() < until) collect(c.next());

  std::printf("SimPartner link benchmark: stand-in robot on loopback, one controlling client\n");
  printStats("command -> reply round trip", commandRtt);
  printStats("heartbeat echo round trip", heartbeatRtt);
  printStats("gap between telemetry frames", gaps);
  const double fresh = *std::min_element(age.begin(), age.end());
  for (double& a : age) a -= fresh;
  printStats("telemetry age beyond the freshest", age);
  double mean = 0;
  for (double g : gaps) mean += g / static_cast<double>(gaps.size());
  std::printf("telemetry rate %.1f Hz (configured %.0f Hz)\n", 1.0 / mean, config.link.telemetryRate);
  asio::post(io, [&] {
    server.stop();
    io.stop();
  });
  serverThread.join();
  host.stop();
  return 0;
}
