// simpartner-robot: the stand-in robot. Runs the twin headless and speaks
// the robot's side of the link protocol (docs/protocol.md) on TCP, exactly as
// a real robot's adapter would, so that everything can be tested without
// hardware.

#include <asio.hpp>

#include <iostream>
#include <string>
#include <vector>

#include "app/headless_runner.h"
#include "app/twin_host.h"
#include "net/robot_server.h"
#include "sim/model_loader.h"

namespace {

constexpr const char* kUsage = R"(usage:
  simpartner-robot --world FILE [options]
      Runs the twin as a robot on the link protocol (docs/protocol.md).
      --port N          TCP port (default: port.robot of the parameters; 0 = any free port)
      --bind ADDRESS    address to listen on (default 127.0.0.1); any other
                        address needs --token
      --token HEX       shared secret, >= 32 hex digits; without it on
                        loopback a random one is made and printed
      --params FILE     parameters file; --set KEY=VALUE overrides (repeatable)
      --rtf X|max       real-time factor (default: realtime.factor)
      --delay S         emulate a slow link: one-way delay [s] in both directions
      --jitter S        and +- this much jitter [s]
      --loss P          and lose each frame with probability P
  Prints `listening on ADDRESS:PORT` when ready; stops on SIGINT or SIGTERM.
)";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string world, params, bind = "127.0.0.1", token;
  std::vector<std::string> overrides;
  std::optional<int> port;
  std::optional<double> rtf;
  sp::net::LinkEmulatorConfig emulation;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      std::cout << kUsage;
      return 0;
    }
    if (i + 1 >= args.size()) {
      std::cerr << "<command line>: error: unknown option or missing value '" << a << "'\n" << kUsage;
      return 2;
    }
    const std::string& v = args[++i];
    if (a == "--world") world = v;
    else if (a == "--params") params = v;
    else if (a == "--set") overrides.push_back(v);
    else if (a == "--bind") bind = v;
    else if (a == "--token") token = v;
    else if (a == "--port") port = std::atoi(v.c_str());
    else if (a == "--rtf") rtf = v == "max" ? 0.0 : std::atof(v.c_str());
    else if (a == "--delay" || a == "--jitter" || a == "--loss") {
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(x >= 0) || (a == "--loss" && x > 1)) {
        std::cerr << "<command line>: error: " << a << ": expected a number " << (a == "--loss" ? "in [0, 1]" : ">= 0")
                  << ", got '" << v << "'\n";
        return 2;
      }
      (a == "--delay" ? emulation.delay : a == "--jitter" ? emulation.jitter : emulation.loss) = x;
    }
    else {
      std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (world.empty()) {
    std::cerr << "<command line>: error: --world FILE is required\n" << kUsage;
    return 2;
  }
  const bool loopback = bind == "127.0.0.1" || bind == "::1" || bind == "localhost";
  if (token.empty() && !loopback) {
    std::cerr << "<command line>: error: refusing to listen on " << bind
              << " without --token: only loopback may run with a generated token\n";
    return 2;
  }
  sp::Diagnostics diag;
  auto simParams = sp::loadRunParams(params, overrides, diag);
  auto model = sp::loadWorld(world, diag);
  std::cerr << diag.format();
  if (!simParams || !model) return 1;
  if (model->robots.empty()) {
    std::cerr << world << ": error: the world has no <robot>\n";
    return 1;
  }
  if (rtf) simParams->realTimeFactor = *rtf;
  auto twin = sp::World::create(*model, *simParams, diag);
  if (!twin) {
    std::cerr << diag.format();
    return 1;
  }
  const bool generated = token.empty();
  if (generated) token = sp::net::randomToken();

  sp::TwinHost host(std::move(twin), simParams->realTimeFactor);
  asio::io_context io;
  sp::net::RobotServerConfig config;
  config.address = bind;
  config.port = static_cast<uint16_t>(port.value_or(simParams->robotPort));
  config.link.robotName = model->robots[0].name;
  config.link.token = token;
  config.link.telemetryRate = simParams->telemetryRate;
  config.emulation = emulation;
  config.log = [](const std::string& line) { std::cerr << "simpartner-robot: " << line << "\n"; };
  sp::net::RobotServer server(io, config, host);
  if (const std::string error = server.start(); !error.empty()) {
    std::cerr << "error: " << error << "\n";
    return 1;
  }
  host.start();
  if (generated) std::cout << "token " << token << "\n";
  if (emulation.active())
    std::cout << "emulating a link with " << emulation.delay << " s delay, +-" << emulation.jitter << " s jitter, "
              << emulation.loss * 100 << " % loss\n";
  std::cout << "listening on " << bind << ":" << server.port() << std::endl;
  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const asio::error_code&, int) {
    server.stop();
    io.stop();
  });
  io.run();
  host.stop();
  std::cout << "stopped: " << server.stats().clientsAccepted << " clients, " << server.stats().framesIn
            << " frames in, " << server.stats().badFrames << " closed for bad frames, "
            << server.stats().telemetryDropped << " telemetry frames dropped for slow clients\n";
  return 0;
}
