#include "app/robot/stand_in.h"

#include <asio.hpp>

#include <algorithm>
#include <chrono>
#include <thread>

#include "app/state/run_params.h"
#include "app/log/session_recorder.h"
#include "app/robot/twin_host.h"
#include "net/auth.h"
#include "net/robot_server.h"
#include "sim/text.h"
#include "net/thread_priority.h"
#include "sim/model_loader.h"
#include "sim/perturbation.h"

namespace sp {

struct StandInRobot::Server {
  asio::io_context io;
  std::unique_ptr<net::RobotServer> server;
  std::thread thread;
};

namespace {

bool isLoopback(const std::string& address) {
  return address == "127.0.0.1" || address == "::1" || address == "localhost";
}

}  // namespace

std::unique_ptr<StandInRobot> StandInRobot::create(const StandInOptions& options, Diagnostics& diag) {
  if (options.worldFile.empty()) diag.error("<options>", 0, "no world file given");
  if (options.token.empty() && !isLoopback(options.bind))
    diag.error("<options>", 0,
               "refusing to listen on " + options.bind + " without a token: only loopback may run with a generated one");
  std::optional<SimParams> params = loadRunParams(options.paramsFile, options.overrides, diag);
  std::optional<WorldModel> model;
  std::string replacedRobotFile;
  if (!options.worldFile.empty()) model = loadWorld(options.worldFile, diag);
  if (model && model->robots.empty()) diag.error(options.worldFile, 0, "the world has no <robot>");
  if (model && !model->robots.empty() && !options.robotFile.empty()) {
    std::optional<RobotModel> robot = loadRobot(options.robotFile, diag);
    if (robot) {
      replacedRobotFile = model->robots[0].model.file;
      model->robots[0].model = std::move(*robot);
    }
  }
  std::optional<WorldModel> ground;
  if (!options.groundFile.empty()) ground = loadWorld(options.groundFile, diag);
  if (diag.hasErrors() || !params || !model || (!options.groundFile.empty() && !ground)) return nullptr;
  if (options.realTimeFactor) params->realTimeFactor = *options.realTimeFactor;
  // A robot that is not its twin runs perturbed physics; what it announces
  // and logs as its files stays the files.
  std::optional<Perturbation> perturbation;
  if (options.perturbSeed) perturbation = drawPerturbation(*options.perturbSeed, model->robots[0].model);
  if (options.wheelTorque != std::array<double, 4>{1, 1, 1, 1}) {
    if (!perturbation) perturbation = Perturbation{};
    perturbation->wheelTorque = options.wheelTorque;
  }
  // A twin calibrated by the parameters (calibration.*) is calibrated here too.
  WorldModel physics = calibratedWorld(*model, *params);
  if (ground) physics.terrain = ground->terrain;  // the ground as it is, not as the map has it
  std::unique_ptr<World> world = World::create(perturbation ? perturbWorld(physics, *perturbation) : physics, *params, diag);
  if (!world) return nullptr;
  if (options.startState) {
    if (std::string why = world->restore(*options.startState); !why.empty()) {
      diag.error(options.worldFile, 0, "cannot start from the given state: " + why);
      return nullptr;
    }
  }
  if (options.change)
    if (const std::string why = options.change->check(); !why.empty()) {
      diag.error("change", 0, why);
      return nullptr;
    }
  auto host = std::make_unique<TwinHost>(std::move(world), params->realTimeFactor);
  if (options.change) host->scheduleChange(*options.change);
  if (perturbation || params->calDelay > 0)
    host->setDeviations((perturbation ? perturbation->delay : 0) + params->calDelay,
                        perturbation ? perturbation->rollBias : 0, perturbation ? perturbation->pitchBias : 0);
  return std::unique_ptr<StandInRobot>(new StandInRobot(options, std::move(*model), std::move(host), *params, std::move(replacedRobotFile)));
}

StandInRobot::StandInRobot(StandInOptions options, WorldModel world, std::unique_ptr<TwinHost> host,
                           SimParams params, std::string replacedRobotFile)
    : options_(std::move(options)),
      replacedRobotFile_(std::move(replacedRobotFile)),
      world_(std::move(world)),
      params_(std::move(params)),
      token_(options_.token.empty() ? net::randomToken() : options_.token),
      host_(std::move(host)) {}

StandInRobot::~StandInRobot() { stop(); }

std::map<std::string, std::string> StandInRobot::logMeta() const {
  std::map<std::string, std::string> meta = options_.logMeta;
  if (options_.perturbSeed) {
    meta["perturbation_seed"] = std::to_string(*options_.perturbSeed);
    meta["perturbation"] = drawPerturbation(*options_.perturbSeed, world_.robots[0].model).report(world_.robots[0].model);
  }
  if (options_.wheelTorque != std::array<double, 4>{1, 1, 1, 1}) {
    std::string text;
    for (double f : options_.wheelTorque) text += (text.empty() ? "" : " ") + shortestText(f);
    meta["perturbation_wheel_torque"] = text;
  }
  if (options_.change) meta["perturbation_change"] = options_.change->describe();
  return meta;
}

std::string StandInRobot::chooseLogPath(std::string& error) const {
  if (!options_.logPath.empty()) return options_.logPath;
  return newSessionLogPath(options_.logDir, error);
}

std::string StandInRobot::start() {
  if (started_) return "the stand-in robot was started already";
  started_ = true;

  auto server = std::make_unique<Server>();
  net::RobotServerConfig config;
  config.address = options_.bind;
  config.port = options_.port.value_or(static_cast<uint16_t>(params_.robotPort));
  config.link.robotName = world_.robots[0].name;
  config.link.token = token_;
  config.link.telemetryRate = params_.telemetryRate;
  config.link.worldHash = fileHash(world_.file);
  config.link.robotHash = fileHash(world_.robots[0].model.file);
  if (options_.terrainEdits) config.link.capabilities = "terrain_edit";
  host_->acceptTerrainEdits(options_.terrainEdits);
  config.link.deadman = params_.linkDeadman;
  config.link.leaseConfirm = params_.linkLeaseConfirm;
  config.maxConnections = static_cast<size_t>(params_.linkMaxConnections);
  config.helloTimeout = params_.linkHelloTimeout;
  config.emulation = options_.emulation;
  // Both run on the server's thread; the host queues log events for the
  // physics thread, which stamps them with the twin's step and time.
  TwinHost& host = *host_;
  config.log = [&host, lineLog = options_.lineLog](const std::string& line) {
    host.logEvent("link", line);
    if (lineLog) lineLog(line);
  };
  config.events = [&host, lineLog = options_.lineLog](const std::string& kind, const std::string& text) {
    host.logEvent(kind, text);
    if (lineLog) lineLog(kind == "link" ? text : kind + ": " + text);
  };
  server->server = std::make_unique<net::RobotServer>(server->io, config, host);
  if (std::string error = server->server->start(); !error.empty()) return error;

  if (options_.log) {
    std::string error;
    const std::string path = chooseLogPath(error);
    std::unique_ptr<SessionLogWriter> writer;
    if (!path.empty())
      writer = openSessionLog(path,
                              {.worldFile = options_.worldFile,
                               .robotFile = world_.robots[0].model.file,
                               .paramsFile = options_.paramsFile,
                               .terrainFile = world_.terrain.file,
                               .commandsFile = {},
                               .overrides = options_.overrides,
                               .replacedRobotFile = replacedRobotFile_,
                               .extraMeta = logMeta()},
                              error);
    if (!writer) {
      server->server->stop();
      return error;
    }
    logPath_ = path;
    host.logTo(std::move(writer));
  }

  port_ = server->server->port();
  host.start();
  Server& s = *server;
  s.thread = std::thread([&s] {
    net::raiseLinkThreadPriority();  // the robot's deadman, above the console's other work
    s.io.run();
  });
  server_ = std::move(server);
  return {};
}

bool StandInRobot::shutdown(const std::string& reason, double maxWait) {
  using Clock = std::chrono::steady_clock;
  if (!server_) return false;
  host_->logEvent("shutdown", reason);
  asio::post(server_->io, [s = server_.get(), reason] { s->server->shutdown(reason); });
  // The stop is applied at the twin's next step; then it comes to rest. At
  // rest: the base slower than 5 mm/s and 0.01 rad/s (what telemetry
  // reports, so a real robot's adapter can wait the same way) throughout
  // `settle`: a body rocking on its tyres after braking passes through
  // zero speed on every swing.
  const Clock::time_point start = Clock::now();
  const auto until = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(maxWait));
  const auto settle = std::chrono::duration<double>(std::max(0.1, 3.0 / params_.logRate));
  Clock::time_point moving = start;  // when it was last seen moving
  bool rest = false;
  while (Clock::now() < until && !rest) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const net::RobotState s = host_->state();
    if (norm(s.baseLinearVelocity) >= 0.005 || norm(s.baseAngularVelocity) >= 0.01) moving = Clock::now();
    rest = Clock::now() - moving >= settle;
  }
  // Logged samples of it at rest (at the logging rate), then the end.
  if (rest) std::this_thread::sleep_for(settle);
  stop();
  return rest;
}

void StandInRobot::fadeLink(double seconds) {
  if (server_) asio::post(server_->io, [s = server_.get(), seconds] { s->server->fade(seconds); });
}

void StandInRobot::stop() {
  if (server_) {
    Server& s = *server_;
    asio::post(s.io, [&s] {
      s.server->stop();
      s.io.stop();
    });
    if (s.thread.joinable()) s.thread.join();
    const net::RobotServerStats& st = s.server->stats();
    stats_ = {st.clientsAccepted, st.framesIn, st.badFrames, st.telemetryDropped, st.emulatedLost};
    server_.reset();  // the server before the host it refers to
  }
  host_->stop();
}

bool StandInRobot::logFailed() const { return host_->log() && host_->log()->failed(); }

std::string StandInRobot::logError() const { return host_->log() ? host_->log()->errorMessage() : std::string(); }

int64_t StandInRobot::logDropped() const { return host_->log() ? host_->log()->dropped() : 0; }

void StandInRobot::addNote(std::string text) { host_->logEvent("note", std::move(text)); }
void StandInRobot::logEvent(std::string kind, std::string text) { host_->logEvent(std::move(kind), std::move(text)); }

void StandInRobot::logPrediction(const LogPrediction& prediction) { host_->logPrediction(prediction); }

void StandInRobot::logCalibration(const LogCalibration& row) { host_->logCalibration(row); }

}  // namespace sp
