// The predictive ghost's interface and its twins (app/ghost/ghost.h); its
// threads are in ghost_threads.cpp.
#include "app/ghost/ghost.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "app/ghost/ghost_impl.h"
#include "app/ghost/hold_policy.h"
#include "sim/perturbation.h"
#include "sim/terrain_brush.h"
#include "sim/runner.h"

namespace sp {

double Ghost::now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

SimParams Ghost::profile(const SimParams& params) {
  SimParams p = params;
  p.step = params.ghostStep;
  p.iterations = params.ghostIterations;
  return p;
}

namespace {

ConformalLayer::Options layerOptions(const SimParams& p, bool conformal = true) {
  ConformalLayer::Options o;
  if (!conformal) o.minScores = std::numeric_limits<int>::max();
  o.levels = {p.ghostRegionInner, p.ghostRegionOuter, p.ghostRegionDeparture};
  o.window = p.ghostRegionWindow;
  o.gamma = p.ghostRegionGamma;
  return o;
}

}  // namespace

Ghost::Ghost(const WorldModel& world, const SimParams& params, const Options& options)
    : model_(world),
      robot_(world.robots.at(0).model),
      params_(params),
      options_(options),
      region_(layerOptions(params, options.conformal)),
      vertical_([&] {
        ConformalLayer::Options o = layerOptions(params, options.conformal);
        o.levels = {params.ghostRegionDeparture};
        return o;
      }()) {
  DepartureWatch::Options o;
  o.hold = params.ghostRegionHold;
  watch_ = DepartureWatch(o);
  ground_ = world.terrain;
  givenModel_ = errorModelFor(world);
  errorModel_ = asOptioned(givenModel_);
}

ErrorModel Ghost::asOptioned(ErrorModel m) const {
  // (The link's jitter, measured, is scaled in sourcesOf.)
  if (!options_.sources) m.speed = m.curvature = m.arrival = m.terrain = 0;
  for (double* d : {&m.floor, &m.speed, &m.curvature, &m.arrival, &m.terrain}) *d *= options_.modelFactor;
  return m;
}

std::unique_ptr<Ghost> Ghost::create(const WorldModel& world, const SimParams& params, std::string& error) {
  return create(world, params, Options{}, error);
}

std::unique_ptr<Ghost> Ghost::create(const WorldModel& world, const SimParams& params, const Options& options,
                                     std::string& error) {
  if (world.robots.empty()) {
    error = "the world has no robot to predict";
    return nullptr;
  }
  if (!ConformalLayer::checkLevels(layerOptions(params).levels).empty()) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "ghost.region.inner (%g), ghost.region.outer (%g) and ghost.region.departure (%g) must ascend",
                  params.ghostRegionInner, params.ghostRegionOuter, params.ghostRegionDeparture);
    error = text;
    return nullptr;
  }
  std::unique_ptr<Ghost> g(new Ghost(calibratedWorld(world, params), profile(params), options));
  g->delay_ = params.calDelay;
  const RobotModel& robot = world.robots[0].model;
  std::optional<std::vector<int>> held = holdableJoints(robot, params.ghostHold, "ghost.hold", error);
  if (!held) return nullptr;
  g->held_ = std::move(*held);
  // The worlds are built on the first telemetry (the pose to weld at);
  // what could fail is checked now, in the robot's initial pose.
  const std::shared_ptr<const Twin> twin =
      g->makeTwin(std::vector<double>(robot.joints.size(), 0.0), !g->held_.empty(), error);
  if (!twin) return nullptr;
  if (!g->buildWorld(*twin, &error)) return nullptr;
  g->anchorThread_ = std::thread([raw = g.get()] { raw->guarded("anchor", &Ghost::anchorLoop); });
  g->presentThread_ = std::thread([raw = g.get()] { raw->guarded("present", &Ghost::presentLoop); });
  g->trailThread_ = std::thread([raw = g.get()] { raw->guarded("trail", &Ghost::trailLoop); });
  return g;
}

void Ghost::guarded(const char* name, void (Ghost::*loop)()) {
  // What a thread throws (ODE's errors are thrown: sim/world.h) must not
  // reach std::terminate and end the console: the view says so and the
  // loop starts over with worlds built anew, a second later.
  for (;;) {
    try {
      (this->*loop)();
      return;
    } catch (const std::exception& e) {
      setProblem(std::string("the ghost's ") + name + " thread failed: " + e.what() + "; it starts again");
    } catch (...) {
      setProblem(std::string("the ghost's ") + name + " thread failed; it starts again");
    }
    if (!anchorBell_.sleepUntil(std::chrono::steady_clock::now() + std::chrono::seconds(1))) return;
  }
}

Ghost::~Ghost() {
  stop_ = true;
  for (ghost_detail::Doorbell* bell : {&anchorBell_, &presentBell_, &trailBell_}) bell->close();
  for (std::thread* t : {&anchorThread_, &presentThread_, &trailThread_})
    if (t->joinable()) t->join();
}

std::shared_ptr<const Ghost::Twin> Ghost::makeTwin(const std::vector<double>& positions, bool hold,
                                                   std::string& error) const {
  auto twin = std::make_shared<Twin>();
  twin->world = model_;
  if (hold && !held_.empty()) {
    twin->rigid = holdRigid(model_.robots[0].model, positions, held_, error);
    if (!twin->rigid) {
      error = "ghost.hold: " + error;
      return nullptr;
    }
    twin->world.robots[0].model = twin->rigid->model;
    twin->held = held_;
  }
  return twin;
}

std::unique_ptr<World> Ghost::buildWorld(const Twin& twin, std::string* error) const {
  WorldOptions options;
  options.sensors = false;  // the ghost draws the robot; the laser is the robot's
  Diagnostics diag;
  std::unique_ptr<World> world = World::create(twin.world, params_, diag, options);
  if (!world && error) *error = "the ghost's world: " + diag.format();
  return world;
}

void Ghost::carryControl(const World& from, const Twin& fromTwin, World& to, const Twin& toTwin,
                         const std::vector<double>& positions) const {
  const RobotModel& a = fromTwin.world.robots[0].model;
  const RobotModel& b = toTwin.world.robots[0].model;
  const Snapshot before = from.snapshot();  // kept: `was` refers into it
  const RobotControlState& was = before.robots[0];
  Snapshot s = to.snapshot();
  RobotControlState& now = s.robots[0];
  const RobotControlState fresh = now;
  now = was;
  now.actuators = fresh.actuators;
  now.resistance = fresh.resistance;  // per link: the two twins' links differ
  now.resistanceShare = fresh.resistanceShare;
  now.resistanceHold = fresh.resistanceHold;
  for (size_t i = 0; i < b.actuators.size(); ++i) {
    const ActuatorSpec& spec = b.actuators[i];
    const auto same = std::find_if(a.actuators.begin(), a.actuators.end(),
                                   [&](const ActuatorSpec& x) { return x.name == spec.name; });
    if (same != a.actuators.end()) {
      now.actuators[i] = was.actuators[static_cast<size_t>(same - a.actuators.begin())];
    } else if (spec.hasPid && spec.kp > 0) {
      // It was held, so the robot kept it still: it holds where it is.
      const int full = toTwin.rigid ? toTwin.rigid->jointOf[static_cast<size_t>(spec.joint)] : spec.joint;
      now.actuators[i].mode = JointMode::Position;
      now.actuators[i].target = positions[static_cast<size_t>(full)];
      now.actuators[i].integral = 0;
    }
  }
  to.restore(s);
}

std::vector<double> Ghost::fullPositions(const Twin& twin, const std::vector<double>& joints,
                                         const std::vector<double>* reported) const {
  if (!twin.rigid) return joints;
  std::vector<double> full = fullJoints(*twin.rigid, joints);
  if (reported && reported->size() == full.size())
    for (int j : twin.held) full[static_cast<size_t>(j)] = (*reported)[static_cast<size_t>(j)];
  return full;
}

double Ghost::ghostTime(double wall) const {
  std::lock_guard lock(timelineMutex_);
  return clock_.ghostTime(wall);
}

std::optional<GhostError> Ghost::anchor(const RobotFrame& frame, double roundTrip) {
  bool reset = false;
  {
    std::lock_guard lock(timelineMutex_);
    // The robot's clock went back (it was reset): what was shown and sent
    // belongs to the old run.
    reset = clock_.frame(frame.time, now(), roundTrip);
    if (reset) {
      commands_.clear();
      ++epoch_;
    }
    // Commands long in effect are in the anchor world's set-points already.
    commands_.forgetBefore(frame.time - PredictionRecord::kErrorWindow);
  }
  std::optional<GhostError> error;
  {
    std::lock_guard lock(recordMutex_);
    if (reset) {
      record_.clear();
      region_.clear();
      vertical_.clear();
      learnt_.clear();
      watch_.clear();
      departures_.clear();
      pending_.clear();
    }
    error = record_.compare(frame);
    if (error) judge(*error, frame);
  }
  frames_.publish(std::make_shared<const RobotFrame>(frame));
  {
    std::lock_guard lock(viewMutex_);
    halted_.clear();
  }
  anchorBell_.ring();
  return error;
}

void Ghost::judge(GhostError& e, const RobotFrame& frame) {
  if (!(e.scale > 0)) return;
  e.inner = region_.multiplier(0) * e.scale;
  e.outer = region_.multiplier(1) * e.scale;
  e.limit = region_.multiplier(2) * e.scale;
  const double score = e.position / e.scale;
  const double vscale = verticalScale(e.scale, errorModel_);
  while (!groundEdits_.empty() && groundEdits_.front().first <= frame.time) {
    if (ground_.kind == TerrainSpec::Kind::Heightfield && patchFits(&ground_.grid, groundEdits_.front().second).empty())
      applyPatch(ground_.grid, groundEdits_.front().second);
    groundEdits_.pop_front();
  }
  std::array<Vec3, 4> hubs{};
  const WheelClearances actual = wheelClearances(
      robot_, [this](double x, double y) { return groundHeight(ground_, x, y); }, frame.base, frame.jointPositions,
      &hubs);
  // A wheel that carries nothing is off the ground, wherever the ground
  // is (a bounce on rough ground): only wheels telemetry has loaded are
  // judged, when it reports the loads at all.
  WheelClearances loaded = actual;
  if (std::any_of(frame.wheelNormal.begin(), frame.wheelNormal.end(), [](double n) { return n > 0; }))
    for (size_t k = 0; k < loaded.size(); ++k)
      if (frame.wheelNormal[k] < kLoadedWheel) loaded[k] = kNoClearance;
  int wheel = -1;
  e.vertical = groundDiscrepancy(e.clearance, loaded, &wheel);
  const std::optional<Vec3> wheelAt =
      wheel >= 0 ? std::optional<Vec3>(hubs[static_cast<size_t>(wheel)]) : std::nullopt;
  e.verticalLimit = vertical_.multiplier(0) * vscale;
  const double vscore = e.vertical / vscale;
  region_.judge(score);
  vertical_.judge(vscore);
  const DepartureWatch::Change change =
      watch_.judge(frame.time, frame.base.p, e.position, e.limit, e.vertical, e.verticalLimit, wheelAt);
  if (change == DepartureWatch::Change::Began) {
    departures_.push_back(*watch_.last());
    e.departure = 1;
    pending_.clear();  // the run outside was the departure's
  } else if (change == DepartureWatch::Change::Ended) {
    e.departure = -1;
    pending_.clear();  // frames of its clearing
  }
  if (watch_.last() && !departures_.empty()) departures_.back() = *watch_.last();
  const bool lasting = watch_.departing() && frame.time - watch_.last()->time > kLasting;
  // Only a departure under the wheels is a place the calibration must not
  // fit. One of the base alone, the wheels on the map's ground, is the
  // robot (bench_region bumpy seed 24, a motor gain +19 %: 17 cm off at
  // 2 s, departing again and again); were its frames left out, the fit
  // that brings the twin back could never land.
  e.suspect = watch_.departing() && watch_.last()->ground;
  // A lasting departure's frames teach the position's layer (the robot
  // differs: the region must widen to it), never the ground's: ground that
  // is not the map's stays a departure wherever the robot meets it.
  const Judged judged{frame.time, e.position, e.vertical, e.sources,
                      !watch_.departing() && e.vertical <= kUnlearntGround};
  if (watch_.suspect() && !lasting) {
    pending_.push_back(judged);
    return;
  }
  for (const Judged& p : pending_) learn(p);  // a run outside that was no departure
  pending_.clear();
  learn(judged);
}

void Ghost::learn(const Judged& j) {
  const double scale = errorScale(j.sources, errorModel_);
  region_.learn(j.time, j.position / scale);
  if (j.ground) vertical_.learn(j.time, j.vertical / verticalScale(scale, errorModel_));
  learnt_.push_back(j);
  while (learnt_.front().time < j.time - params_.ghostRegionWindow) learnt_.pop_front();
}

ErrorSources Ghost::sourcesOf(double t, double made, double speed,
                              const std::vector<std::pair<double, Command>>& timeline, double spread) const {
  return {t - made, speed, commandTiming(timeline, made, t, speed, errorModel_.wheelbase), options_.sources ? spread * options_.modelFactor : 0};
}

void Ghost::setErrorModel(const ErrorModel& given) {
  const ErrorModel model = asOptioned(given);
  std::lock_guard lock(recordMutex_);
  givenModel_ = given;
  if (model == errorModel_) return;
  errorModel_ = model;
  // The window's scores meant the old scale: each rescored under the new
  // one, from the errors and sources it was learnt with (both layers keep
  // the same frames in the same order as learnt_).
  size_t k = 0, v = 0;
  region_.rescore([&](double, double) {
    const Judged& j = learnt_[std::min(k++, learnt_.size() - 1)];
    return j.position / errorScale(j.sources, errorModel_);
  });
  vertical_.rescore([&](double, double) {
    while (v + 1 < learnt_.size() && !learnt_[v].ground) ++v;  // frames the ground's layer did not learn
    const Judged& j = learnt_[std::min(v++, learnt_.size() - 1)];
    return j.vertical / verticalScale(errorScale(j.sources, errorModel_), errorModel_);
  });
}

ErrorModel Ghost::errorModel() const {
  std::lock_guard lock(recordMutex_);
  return givenModel_;
}

std::vector<Departure> Ghost::departures() const {
  std::lock_guard lock(recordMutex_);
  return departures_;
}

size_t Ghost::departureCount() const {
  std::lock_guard lock(recordMutex_);
  return departures_.size();
}

std::optional<Departure> Ghost::departing() const {
  std::lock_guard lock(recordMutex_);
  if (!watch_.departing()) return std::nullopt;
  return watch_.last();
}

Ghost::Coverage Ghost::coverage() const {
  std::lock_guard lock(recordMutex_);
  Coverage c;
  c.judged = region_.judged();
  for (size_t i = 0; i < c.share.size(); ++i) c.share[i] = region_.coverage(i).value_or(0);
  return c;
}

void Ghost::commandSent(const Command& command) {
  double effect = 0;
  {
    std::lock_guard lock(timelineMutex_);
    effect = clock_.ghostTime(now()) + delay_;
    commands_.add(command, effect);
  }
  if (const auto* patch = std::get_if<TerrainPatchCmd>(&command)) {
    std::lock_guard lock(recordMutex_);
    groundEdits_.emplace_back(effect, *patch);
  }
  presentBell_.ring();
}

void Ghost::setCalibration(WorldModel world, double delay) {
  {
    std::lock_guard lock(calibrationMutex_);
    nextModel_ = std::move(world);
  }
  {
    std::lock_guard lock(timelineMutex_);
    delay_ = delay;
  }
  anchorBell_.ring();
}

GhostView Ghost::view() const {
  std::lock_guard lock(viewMutex_);
  return view_;
}

uint64_t Ghost::commandsSent() const {
  std::lock_guard lock(timelineMutex_);
  return commands_.sent();
}

int64_t Ghost::viewVersion() const {
  std::lock_guard lock(viewMutex_);
  return view_.version;
}

std::optional<std::pair<double, double>> Ghost::errorMedian() const {
  std::lock_guard lock(recordMutex_);
  return record_.median();
}

std::optional<double> Ghost::errorWorst() const {
  std::lock_guard lock(recordMutex_);
  return record_.worstPosition();
}

GhostStats Ghost::stats() const {
  std::lock_guard lock(statsMutex_);
  return stats_;
}

void Ghost::halt(const std::string& why) {
  std::lock_guard lock(viewMutex_);
  if (halted_ == why) return;
  halted_ = why;
  view_.problem = why;
  ++view_.version;
}

void Ghost::setProblem(const std::string& problem) {
  std::lock_guard lock(viewMutex_);
  view_.problem = problem;
  ++view_.version;
}

bool Ghost::advance(World& world, double& t, double target, const std::vector<SentCommand>& commands, size_t& next,
                    const std::function<bool()>& abort) const {
  // Robot time t is the world's step boundary `start`; a command acts from
  // the first boundary at or after its arrival, as on the robot.
  const double h = world.params().step;
  const int64_t start = world.stepCount();
  const auto steps = static_cast<int64_t>(std::floor((target - t) / h + 0.5));
  if (steps <= 0) return true;
  Runner runner(world);
  // In the order sent: one that falls due earlier than the one before it
  // (the clock estimate moved) waits for it, as it would on the robot.
  int64_t due = 0;
  for (size_t i = next; i < commands.size(); ++i) {
    due = std::max(due, static_cast<int64_t>(std::ceil((commands[i].time - t - 1e-9) / h)));
    if (due >= steps) break;  // after this advance
    runner.schedule(ScheduledCommand{commands[i].command, 0, start + due});
  }
  size_t submitted = 0;
  runner.setSubmitHook([&](const ScheduledCommand&, const std::string&) { ++submitted; });
  int64_t taken = 0;
  if (abort) runner.setMonitor([&](const World&) { return ++taken % 64 != 0 || !abort(); });
  const RunOutcome out = runner.advanceBy(steps);
  t += static_cast<double>(out.steps) * h;
  next += submitted;
  return out.stop == RunOutcome::Stop::Reached;
}

}  // namespace sp
