#include "app/console/console_session.h"

#include "app/state/robot_shapes.h"
#include "app/console/terrain_editor.h"
#include "app/console/telemetry_tap.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "app/state/run_params.h"
#include "app/log/log_player.h"
#include "app/log/resimulation.h"
#include "app/log/session_recorder.h"
#include "app/robot/stand_in.h"
#include "app/log/telemetry_recorder.h"
#include "sim/calibration_table.h"
#include "sim/model_loader.h"
#include "sim/perturbation.h"
#include "sim/terrain_brush.h"
#include "sim/text.h"

namespace sp {
namespace {

/// The diagnostics as one text without the final newline (for a dialog).
std::string text(const Diagnostics& diag) {
  const std::string all = diag.format();
  return all.substr(0, all.find_last_not_of('\n') + 1);
}

}  // namespace

ConsoleSession::ConsoleSession(ConsoleSessionOptions options) : options_(std::move(options)) {}

ConsoleSession::~ConsoleSession() {
  tap_->unbind();  // the link's worker may outlive the session
  recorder_.reset();
  if (standIn_) standIn_->stop();
}

const RobotModel* ConsoleSession::robot() const {
  return world_ && !world_->robots.empty() ? &world_->robots[0].model : nullptr;
}

void ConsoleSession::bindTap() {
  tap_->bind({robot(), ghost_.get(), calibrator_.get(), recorder_.get(), standIn_.get()});
}

namespace {

// `m` (the ghost's: its world's geometry and terrain) with the deviations
// of what the twin knows of the robot: a fitted value's deviation, else
// the prior's (the ranges a robot may differ from its files by).
ErrorModel withDeviations(ErrorModel m, const CalibrationState* calibration) {
  const auto deviation = [&](CalParam p) {
    const auto i = static_cast<size_t>(p);
    return calibration && calibration->observed[i] ? calibration->sigma[i] : calParam(p).scale;
  };
  m.speed = std::hypot(deviation(CalParam::WheelRadius), deviation(CalParam::MotorGain));
  m.curvature = deviation(CalParam::WheelRadiusSide) / m.track;
  m.arrival = deviation(CalParam::Delay);
  return m;
}

}  // namespace

void ConsoleSession::setWorld(WorldModel world) {
  const TapRebind rebind(*this);
  terrain_.reset();  // its history is of the old world's heights
  world_ = std::move(world);
  if (world_->terrain.kind == TerrainSpec::Kind::Heightfield)
    terrain_ = std::make_unique<TerrainEditor>(world_->terrain.grid);
  ++worldVersion_;
  calibrator_.reset();
  ghost_.reset();
  ghostError_.clear();
  calibrationSeen_ = calibrationFitsLogged_ = 0;
  if (options_.ghost) ghost_ = Ghost::create(*world_, params_, options_.ghostOptions, ghostError_);
  if (ghost_) ghost_->setErrorModel(withDeviations(ghost_->errorModel(), nullptr));
  ghostCalibration_ = calValues(params_);
  // The calibration fits the ghost's own twin.
  if (ghost_ && options_.calibrate) {
    LiveCalibrator::Options o = options_.calibration;
    if (!o.full) o.full = params_;  // the rehearsals' physics checks what they are given
    calibrator_ = std::make_unique<LiveCalibrator>(*world_, Ghost::profile(params_), ghostCalibration_, o);
  }
}

SimParams ConsoleSession::twinParams() const {
  return calibrator_ ? withCalValues(params_, calibrator_->fullPhysics()) : params_;
}

std::optional<RobotEstimate> ConsoleSession::twinEstimate() const {
  if (!calibrator_) return std::nullopt;
  const CalibrationState s = calibrator_->state();
  RobotEstimate e;
  e.sigma = s.sigma;
  e.observed = s.observed;
  return e;
}

void ConsoleSession::takeCalibration() {
  if (!calibrator_ || calibrator_->version() == calibrationSeen_) return;
  const CalibrationState s = calibrator_->state();
  // The ghost rebuilds its twin for a new calibration: only when the values
  // changed (a refused or frozen fit, a freeze, count as versions too).
  if (ghost_ && s.applied != ghostCalibration_) {
    const SimParams calibrated = withCalValues(params_, s.applied);
    ghost_->setCalibration(calibratedWorld(*world_, calibrated), calibrated.calDelay);
    ghostCalibration_ = s.applied;
  }
  if (ghost_) ghost_->setErrorModel(withDeviations(ghost_->errorModel(), &s));
  calibrationSeen_ = s.version;
  // The fits since the last call, one row per parameter (the history keeps the newest).
  const int fresh = std::min<int>(s.fits - calibrationFitsLogged_, static_cast<int>(s.history.size()));
  for (size_t k = s.history.size() - static_cast<size_t>(fresh); k < s.history.size(); ++k) {
    const CalibrationFit& fit = s.history[k];
    const std::string status = !fit.refused.empty() ? "refused: " + fit.refused : s.frozen ? "frozen" : "applied";
    for (size_t i = 0; i < kCalParams; ++i) {
      const LogCalibration row{fit.to, calParams()[i].key, fit.value[i], fit.sigma[i], fit.observed[i], status};
      if (standIn_) standIn_->logCalibration(row);
      if (recorder_) recorder_->calibration(row);
    }
  }
  calibrationFitsLogged_ = s.fits;
}

std::string ConsoleSession::start() {
  Diagnostics paramDiag;
  std::optional<SimParams> params = loadRunParams(options_.params, options_.overrides, paramDiag);
  if (!params) return text(paramDiag);
  params_ = *params;
  if (!remote()) return startStandIn(options_.world, {});
  // A remote robot: the world file only tells what to draw.
  Diagnostics diag;
  std::optional<WorldModel> world = loadWorld(options_.world, diag);
  if (!world) return text(diag);
  if (world->robots.empty()) return options_.world + ": error: the world has no <robot>";
  std::string error;
  const std::optional<RobotEndpoint> endpoint = parseEndpoint(options_.connectTo, options_.token, error);
  if (!endpoint) return "--connect: " + error;
  endpoint_ = *endpoint;
  worldFile_ = options_.world;
  setWorld(std::move(*world));
  openRemoteLog();
  return {};
}

std::optional<RobotEndpoint> parseEndpoint(const std::string& hostPort, const std::string& token, std::string& error) {
  const size_t colon = hostPort.rfind(':');
  uint32_t port = 0;
  bool ok = colon != std::string::npos && colon > 0 && colon + 1 < hostPort.size();
  for (size_t i = colon + 1; ok && i < hostPort.size(); ++i) {
    const char c = hostPort[i];
    ok = c >= '0' && c <= '9' && port <= 65535;
    port = port * 10 + static_cast<uint32_t>(c - '0');
  }
  if (!ok || port == 0 || port > 65535) {
    error = "expected HOST:PORT, got '" + hostPort + "'";
    return std::nullopt;
  }
  const bool hex = token.find_first_not_of("0123456789abcdefABCDEF") == std::string::npos;
  if (!hex || token.size() < 32) {
    error = "the token must have at least 32 hex digits (128 bits), got " +
            (hex ? std::to_string(token.size()) + " digits" : std::string("other characters"));
    return std::nullopt;
  }
  return RobotEndpoint{hostPort.substr(0, colon), static_cast<uint16_t>(port), token, hostPort};
}

std::string ConsoleSession::connectTo(const std::string& hostPort, const std::string& token) {
  std::string error;
  const std::optional<RobotEndpoint> endpoint = parseEndpoint(hostPort, token, error);
  if (!endpoint) return error;
  const TapRebind rebind(*this);
  // The stand-in goes (its log complete); the drawing stays until the
  // operator opens the remote robot's world.
  if (standIn_) standIn_->stop();
  standIn_.reset();
  options_.connectTo = hostPort;
  options_.token = token;
  endpoint_ = *endpoint;
  openRemoteLog();
  return {};
}

std::string ConsoleSession::useStandIn() {
  const std::string world = worldFile_.empty() ? options_.world : worldFile_;
  const std::string previous = options_.connectTo;
  options_.connectTo.clear();
  if (std::string error = startStandIn(world, {}); !error.empty()) {
    options_.connectTo = previous;
    return error;
  }
  const TapRebind rebind(*this);
  recorder_.reset();
  return {};
}

std::string ConsoleSession::startStandIn(const std::string& worldFile, const std::string& robotFile,
                                         const Snapshot* startState, std::map<std::string, std::string> logMeta) {
  StandInOptions o;
  if (startState) o.startState = *startState;
  o.logMeta = std::move(logMeta);
  o.worldFile = worldFile;
  o.robotFile = robotFile;
  o.paramsFile = options_.params;
  o.overrides = options_.overrides;
  o.port = uint16_t{0};  // any free port: several consoles may run on one machine
  o.token = options_.token;
  if (options_.rtf >= 0) o.realTimeFactor = options_.rtf;
  o.log = options_.log;
  o.logDir = options_.logDir;
  o.perturbSeed = options_.perturbSeed;
  o.wheelTorque = options_.wheelTorque;
  o.change = options_.change;
  o.groundFile = options_.ground;
  o.emulation.delay = options_.delay;
  o.emulation.jitter = options_.jitter;
  Diagnostics diag;
  std::unique_ptr<StandInRobot> standIn = StandInRobot::create(o, diag);
  if (!standIn) return text(diag);
  if (std::string error = standIn->start(); !error.empty()) return error;
  // Only now that the new robot runs is the old one replaced.
  const TapRebind rebind(*this);
  if (standIn_) standIn_->stop();
  standIn_ = std::move(standIn);
  worldFile_ = worldFile;
  robotFile_ = robotFile;
  endpoint_ = {"127.0.0.1", standIn_->port(), standIn_->token(),
               "127.0.0.1:" + std::to_string(standIn_->port()) + " (stand-in, " +
                   std::filesystem::path(worldFile).filename().string() + ")"};
  setWorld(standIn_->world());
  pruneLogs();
  return {};
}

void ConsoleSession::pruneLogs() {
  // log.keep: the newest logs stay, the current one always.
  if (options_.log && params_.logKeep > 0) pruneSessionLogs(options_.logDir, params_.logKeep, logPath());
}

std::string ConsoleSession::openWorld(const std::string& path) {
  Diagnostics diag;
  std::optional<WorldModel> world = loadWorld(path, diag);
  if (!world) return text(diag);
  if (world->robots.empty()) return path + ": error: the world has no <robot> to control";
  if (!remote()) return startStandIn(path, {});
  worldFile_ = path;
  setWorld(std::move(*world));  // the remote robot runs in its own world: only the drawing changes
  return {};
}

std::string ConsoleSession::openRobot(const std::string& path) {
  Diagnostics diag;
  std::optional<RobotModel> robot = loadRobot(path, diag);
  if (!robot) return text(diag);
  if (!remote()) return startStandIn(worldFile_, path);
  if (world_ && !world_->robots.empty()) {
    WorldModel world = *world_;
    world.robots[0].model = std::move(*robot);
    setWorld(std::move(world));
  }
  return {};
}

void ConsoleSession::openRemoteLog() {
  const TapRebind rebind(*this);
  recorder_.reset();
  recorderError_.clear();
  if (!options_.log || !world_) return;
  const std::string path = newSessionLogPath(options_.logDir, recorderError_);
  if (path.empty()) return;
  recorder_ = TelemetryRecorder::open(path, *world_, endpoint_.label, recorderError_);
  pruneLogs();
}

std::string ConsoleSession::logPath() const {
  if (standIn_) return standIn_->logPath();
  return recorder_ ? recorder_->path() : std::string();
}

std::string ConsoleSession::logError() const {
  if (standIn_) return standIn_->logError();
  if (recorder_ && recorder_->writer().failed()) return recorder_->writer().errorMessage();
  return recorderError_;
}

RobotFrame ConsoleSession::telemetry(const net::TelemetryMsg& t, double wall, double roundTrip) {
  RobotFrame f = tap_->telemetry(t, wall, roundTrip).frame;
  takeCalibration();
  return f;
}

LaserFrame ConsoleSession::laser(const net::LaserMsg& m) {
  tap_->laser(m);
  return laserFromMessage(m);
}

std::optional<GhostError> ConsoleSession::lastPrediction() const { return tap_->lastPrediction(); }

double ConsoleSession::realTimeFactor() const { return tap_->realTimeFactor(); }

std::string ConsoleSession::commandRefusal(bool leaseHeld) const {
  if (!leaseHeld) return "Not sent: take control first (Robot ▸ Take control)";
  return {};
}

void ConsoleSession::commandSent(const Command& command) {
  // When it will act on the robot, by the ghost's clock (before the
  // calibrated delay: a fit adds its own).
  const std::optional<double> arrival = ghost_ ? std::optional(ghost_->ghostTime(Ghost::now())) : std::nullopt;
  if (recorder_) recorder_->command(command, robot(), arrival);
  if (ghost_) {
    if (calibrator_) calibrator_->command(command, *arrival);
    ghost_->commandSent(command);
  }
}

void ConsoleSession::linkDown(const std::string& why) {
  if (ghost_) ghost_->halt("the robot link is down (" + why + "): no prediction until it is back");
}

void ConsoleSession::estopSent() {
  // The robot's e-stop stops every motor as `stop` does, when it lands: the
  // ghost and the fit see it arrive then, as any command (not logged as
  // one: the log has the e-stop's event).
  if (!ghost_) return;
  if (calibrator_) calibrator_->command(StopCmd{}, ghost_->ghostTime(Ghost::now()));
  ghost_->commandSent(StopCmd{});
}

bool ConsoleSession::terrainEdited(const TerrainPatchCmd& patch) {
  if (!terrain_ || !patchFits(&world_->terrain.grid, patch).empty()) return false;
  commandSent(patch);
  return true;
}

std::string ConsoleSession::branchFrom(const std::string& logPath, double time) {
  if (remote()) return "a branch runs on the stand-in: switch to it first (Robot > Use the stand-in)";
  std::string error;
  std::unique_ptr<LogPlayer> player = LogPlayer::open(logPath, error);
  if (!player) return error;
  std::optional<BranchPoint> b = player->branchAt(time, error);
  if (!b) return error;
  return branchFrom(logPath, *b);
}

std::string ConsoleSession::branchFrom(const std::string& logPath, const BranchPoint& b) {
  if (remote()) return "a branch runs on the stand-in: switch to it first (Robot > Use the stand-in)";
  const auto meta = [&](const char* key) {
    const auto it = b.meta.find(key);
    return it == b.meta.end() ? std::string() : it->second;
  };
  // The new session runs the files on disk: they must be the logged ones,
  // or the state would be put into another robot or world. (A remote
  // robot's telemetry log holds no parameters: the console's apply.)
  const std::string worldFile = meta("world_file");
  const std::string robotFile = meta("replaced_robot_file").empty() ? std::string() : meta("robot_file");
  std::vector<std::pair<std::string, std::string>> files{{worldFile, meta("world_contents")},
                                                         {meta("robot_file"), meta("robot_contents")}};
  if (b.meta.count("params_contents")) files.emplace_back(options_.params, meta("params_contents"));
  for (const auto& [file, contents] : files)
    if (readWholeFile(file) != contents)
      return (file.empty() ? std::string("the parameters") : file) +
             ": differs from what the log was written with; a branch needs the logged files";
  const std::string at = shortestText(static_cast<double>(b.step) * b.logged.params.step);
  std::map<std::string, std::string> parent{{"parent_log", logPath}, {"parent_time", at}};
  if (b.reconstructed) parent["parent_state"] = "reconstructed from telemetry";
  if (std::string e = startStandIn(worldFile, robotFile, &b.state, parent); !e.empty()) return e;
  standIn_->addNote("branch of " + logPath + " at t = " + at + " s (state hash " + hashHex(b.hash) +
                    (b.reconstructed ? ", reconstructed from telemetry: contacts and controllers start afresh)" : ")"));
  return {};
}

std::string ConsoleSession::resetRobot() {
  if (remote() || !standIn_) return "a robot elsewhere is put back by hand: Reset restarts the stand-in only";
  const std::string oldLog = standIn_->logPath();
  standIn_->addNote("reset: the robot goes back to its start; the session continues in a new log");
  if (std::string error = startStandIn(worldFile_, robotFile_); !error.empty()) return error;
  standIn_->addNote(oldLog.empty() ? std::string("reset: the robot is back at its start")
                                   : "reset: the robot is back at its start; the session before is in " + oldLog);
  return {};
}

std::string ConsoleSession::filesMismatch(const std::string& worldHash, const std::string& robotHash) const {
  if (!world_ || world_->robots.empty()) return {};
  std::string differs;
  const auto check = [&](const std::string& announced, const std::string& file, const char* what) {
    if (announced.empty()) return;
    const std::string here = fileHash(file);
    if (announced == here) return;
    if (!differs.empty()) differs += "; ";
    differs += std::string("its ") + what + " file differs from " + file + " (robot " + announced + ", here " +
               (here.empty() ? "unreadable" : here) + ")";
  };
  check(worldHash, world_->file, "world");
  check(robotHash, world_->robots[0].model.file, "robot");
  if (differs.empty()) return {};
  return "The robot runs other files than this console's twin: " + differs +
         ". The ghost predicts from the console's files; open the robot's with File > Open world.";
}

std::optional<double> ConsoleSession::edgeDistance(const Pose& base) const {
  if (!world_ || world_->terrain.kind != TerrainSpec::Kind::Heightfield) return std::nullopt;
  const TerrainSpec& t = world_->terrain;
  // The grid is centred on the terrain's pose and turned by its yaw only.
  const double yaw = std::atan2(2 * (t.pose.q.w * t.pose.q.z + t.pose.q.x * t.pose.q.y),
                                1 - 2 * (t.pose.q.y * t.pose.q.y + t.pose.q.z * t.pose.q.z));
  const double dx = base.p.x - t.pose.p.x, dy = base.p.y - t.pose.p.y;
  const double x = std::cos(yaw) * dx + std::sin(yaw) * dy, y = -std::sin(yaw) * dx + std::cos(yaw) * dy;
  return std::min(t.grid.width / 2 - std::abs(x), t.grid.depth / 2 - std::abs(y));
}

void ConsoleSession::note(const std::string& text) {
  if (standIn_) standIn_->addNote(text);
  if (recorder_) recorder_->event("note", text);
}

// What a robot sent is stored escaped: a terminal escape in an EVENT or an
// ERROR must not reach a terminal that prints the log.
void ConsoleSession::logEvent(const std::string& kind, const std::string& text) {
  const std::string safe = net::escapeText(text);
  if (standIn_) standIn_->logEvent(kind, safe);
  if (recorder_) recorder_->event(kind, safe);
}

void ConsoleSession::event(const std::string& kind, const std::string& text) {
  if (recorder_) recorder_->event(kind, net::escapeText(text));
}

net::RobotClientConfig ConsoleSession::clientConfig(const std::string& name) const {
  net::RobotClientConfig config;
  config.host = endpoint_.host;
  config.port = endpoint_.port;
  config.token = endpoint_.token;
  config.name = name;
  config.keepaliveInterval = params_.linkKeepalive;
  config.commandExpiryMs = static_cast<uint64_t>(std::llround(params_.linkCommandExpiry * 1000));
  config.helloTimeout = params_.linkHelloTimeout;
  if (const RobotModel* model = robot()) config.bounds = net::telemetryBounds(*model);
  return config;
}

}  // namespace sp
