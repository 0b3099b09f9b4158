#include "app/ghost/ghost.h"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "app/ghost/hold_policy.h"
#include "sim/kinematics.h"
#include "sim/readout.h"
#include "sim/runner.h"

namespace sp {

struct Ghost::Base {
  std::shared_ptr<const Twin> twin;  // what the snapshot is of
  Snapshot snapshot;
  double time = 0;       // robot time of the snapshot
  uint64_t nextSeq = 0;  // the first command not in it
  double made = 0;       // robot time of the telemetry it was anchored on
  bool latched = false;  // that telemetry reported an e-stop or failsafe
};

struct Ghost::TrailRequest {
  std::shared_ptr<const Twin> twin;
  Snapshot snapshot;
  double time = 0;
  uint64_t nextSeq = 0;
  bool latched = false;
  bool urgent = false;  // commands changed: the trail running now is wrong
};

namespace {

constexpr double kTrailPeriod = 0.25; // [s] between trails while nothing changes

// Seconds as the steady clock's duration (Ghost::now() counts from its epoch).
std::chrono::steady_clock::duration steady(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

// The calling thread yields to the rest of the process: re-anchoring and
// the trail are best effort, and must not take the cores the robot's twin
// and the window's frames need (Linux: a thread's nice value is its own).
void yieldToOthers() { setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10); }
// Names the calling thread (top -H, gdb): at most 15 characters.
void nameThread(const char* name) { pthread_setname_np(pthread_self(), name); }

}  // namespace

double Ghost::now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
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
  SimParams profile = params;
  profile.step = params.ghostStep;
  profile.iterations = params.ghostIterations;
  std::unique_ptr<Ghost> g(new Ghost(world, profile, options));
  const RobotModel& robot = world.robots[0].model;
  std::vector<int> drive;  // the wheels and the articulation keep turning in a held subtree
  if (robot.drive) {
    drive.assign(robot.drive->wheels.begin(), robot.drive->wheels.end());
    drive.push_back(robot.drive->articulation);
  }
  for (const std::string& name : splitNames(params.ghostHold)) {
    const std::vector<int> subtree = subtreeJoints(robot, name);
    if (subtree.empty()) {
      error = "ghost.hold: the robot has no joint '" + name + "'";
      return nullptr;
    }
    if (std::find(drive.begin(), drive.end(), robot.findJoint(name)) != drive.end()) {
      error = "ghost.hold: joint '" + name + "' drives the robot and cannot be held";
      return nullptr;
    }
    for (int j : subtree)
      if (std::find(drive.begin(), drive.end(), j) == drive.end() &&
          std::find(g->held_.begin(), g->held_.end(), j) == g->held_.end())
        g->held_.push_back(j);
  }
  std::sort(g->held_.begin(), g->held_.end());
  // The worlds are built on the first telemetry (the pose to weld at);
  // what could fail is checked now, in the robot's initial pose.
  const std::shared_ptr<const Twin> twin =
      g->makeTwin(std::vector<double>(robot.joints.size(), 0.0), !g->held_.empty(), error);
  if (!twin) return nullptr;
  if (!g->buildWorld(*twin, &error)) return nullptr;
  g->anchorThread_ = std::thread([raw = g.get()] { raw->anchorLoop(); });
  g->presentThread_ = std::thread([raw = g.get()] { raw->presentLoop(); });
  g->trailThread_ = std::thread([raw = g.get()] { raw->trailLoop(); });
  return g;
}

Ghost::~Ghost() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  anchorWake_.notify_all();
  presentWake_.notify_all();
  trailWake_.notify_all();
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
  std::lock_guard lock(mutex_);
  return clock_.ghostTime(wall);
}

std::optional<GhostError> Ghost::anchor(const RobotFrame& frame, double roundTrip) {
  std::optional<GhostError> error;
  {
    std::lock_guard lock(mutex_);
    if (clock_.frame(frame.time, now(), roundTrip)) {
      // The robot's clock went back (it was reset): what was shown and
      // sent belongs to the old run.
      record_.clear();
      commands_.clear();
      ++epoch_;
    }
    // Commands long in effect are in the anchor world's set-points already.
    commands_.forgetBefore(frame.time - PredictionRecord::kErrorWindow);
    error = record_.compare(frame);
    frame_ = frame;
    ++frameVersion_;
  }
  anchorWake_.notify_one();
  return error;
}

void Ghost::commandSent(const Command& command) {
  {
    std::lock_guard lock(mutex_);
    commands_.add(command, clock_.ghostTime(now()));
  }
  presentWake_.notify_one();
}

GhostView Ghost::view() const {
  std::lock_guard lock(mutex_);
  return view_;
}

uint64_t Ghost::commandsSent() const {
  std::lock_guard lock(mutex_);
  return commands_.sent();
}

int64_t Ghost::viewVersion() const {
  std::lock_guard lock(mutex_);
  return view_.version;
}

std::optional<std::pair<double, double>> Ghost::errorMedian() const {
  std::lock_guard lock(mutex_);
  return record_.median();
}

GhostStats Ghost::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void Ghost::setProblem(const std::string& problem) {
  std::lock_guard lock(mutex_);
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

void Ghost::anchorLoop() {
  nameThread("ghost-anchor");
  yieldToOthers();
  std::shared_ptr<const Twin> twin;
  std::unique_ptr<World> world;
  Snapshot anchored;  // the last anchored state, commands in effect included
  uint64_t seen = 0, applied = 0, epoch = 0;
  HoldPolicy policy(held_, model_.robots[0].model);
  double lastStart = -1e9;
  for (;;) {
    RobotFrame frame;
    std::vector<SentCommand> effective, pending;
    double target = 0;
    {
      std::unique_lock lock(mutex_);
      anchorWake_.wait(lock, [&] { return stop_ || frameVersion_ != seen; });
      // At most ghost.anchor_rate re-anchorings a second: the newest frame
      // when the time comes.
      anchorWake_.wait_until(lock, std::chrono::steady_clock::time_point(steady(lastStart + 1 / params_.ghostAnchorRate)),
                             [&] { return stop_; });
      if (stop_) return;
      seen = frameVersion_;
      frame = *frame_;
      if (epoch != epoch_) {  // the robot restarted: weld and build anew
        epoch = epoch_;
        world.reset();
        policy.reset();
        applied = commands_.sent();
      }
      for (SentCommand& c : commands_.from(applied)) (c.time <= frame.time ? effective : pending).push_back(std::move(c));
      target = options_.runAhead ? clock_.ghostTime(now()) : frame.time;
    }
    lastStart = now();
    const size_t joints = model_.robots[0].model.joints.size();
    if (frame.jointPositions.size() != joints || frame.jointRates.size() != joints) {
      setProblem("telemetry at " + std::to_string(frame.time) + " s has " +
                 std::to_string(frame.jointPositions.size()) + " joint positions and " +
                 std::to_string(frame.jointRates.size()) + " rates; the robot has " + std::to_string(joints) +
                 " joints");
      continue;
    }
    const bool latched = frame.estop || frame.failsafe;
    const HoldDecision decision =
        policy.decide(frame, effective, pending, world && twin->rigid ? &*twin->rigid : nullptr, world != nullptr);
    const bool hold = decision.hold;
    if (decision.rebuild) {
      std::string error;
      std::shared_ptr<const Twin> next = makeTwin(frame.jointPositions, hold, error);
      std::unique_ptr<World> built = next ? buildWorld(*next, &error) : nullptr;
      if (!built) {
        setProblem(error);
        continue;
      }
      // The set-points of the commands in effect carry over.
      if (world) carryControl(*world, *twin, *built, *next, frame.jointPositions);
      twin = std::move(next);
      world = std::move(built);
      anchored = world->snapshot();
      std::lock_guard lock(mutex_);
      ++stats_.twins;
      stats_.held = hold;
    }
    World& w = *world;
    if (!effective.empty()) applied = effective.back().seq + 1;
    if (latched) {
      // The robot holds still and refuses what it is sent meanwhile.
      if (!pending.empty()) applied = pending.back().seq + 1;
      effective.assign(1, SentCommand{0, frame.time, StopCmd{}});
      pending.clear();
    }
    if (!options_.inFlight) pending.clear();
    for (const SentCommand& c : effective) w.submit(c.command);
    if (!effective.empty() && !w.step()) {
      w.restore(anchored);
      setProblem("the ghost diverged applying the commands in effect: " + w.health().message());
      continue;
    }
    std::vector<std::pair<std::string, Pose>> objects;
    for (const ObjectReadout& o : frame.objects) objects.emplace_back(o.name, o.pose);
    const std::vector<double> positions = twin->rigid ? rigidJoints(*twin->rigid, frame.jointPositions) : frame.jointPositions;
    const std::vector<double> rates = twin->rigid ? rigidJoints(*twin->rigid, frame.jointRates) : frame.jointRates;
    const std::string error = w.setRobotMotion(
        0,
        linkMotions(w.robotModel(0), frame.base, frame.hasBaseVelocity ? frame.baseLinearVelocity : Vec3{},
                    frame.hasBaseVelocity ? frame.baseAngularVelocity : Vec3{}, positions, rates),
        objects);
    if (!error.empty()) {
      w.restore(anchored);
      setProblem("telemetry at " + std::to_string(frame.time) + " s does not fit the robot: " + error);
      continue;
    }
    anchored = w.snapshot();
    double t = frame.time;
    size_t next = 0;
    const bool ok = advance(w, t, target, pending, next);
    auto base = std::make_shared<Base>();
    base->twin = twin;
    base->time = t;
    base->nextSeq = next < pending.size() ? pending[next].seq : (pending.empty() ? applied : pending.back().seq + 1);
    base->made = frame.time;
    base->latched = latched;
    if (ok) base->snapshot = w.snapshot();
    const std::string health = ok ? "" : w.health().message();
    w.restore(anchored);
    if (!ok) {
      setProblem("the ghost diverged predicting from " + std::to_string(frame.time) + " s: " + health);
      continue;
    }
    {
      std::lock_guard lock(mutex_);
      if (epoch != epoch_) continue;  // a reset came meanwhile
      base_ = std::move(base);
      ++baseVersion_;
      ++stats_.anchors;
      stats_.anchorMs = (now() - lastStart) * 1000;
      stats_.anchorSpan = t - frame.time;
    }
    presentWake_.notify_one();
  }
}

void Ghost::presentLoop() {
  nameThread("ghost-present");
  std::shared_ptr<const Twin> twin;
  std::unique_ptr<World> world;
  std::shared_ptr<const Base> base;
  uint64_t seenBase = 0, seenCommands = 0, next = 0;
  double t = 0, lastTrail = -1e9;
  const auto period = steady(options_.frameInterval);
  for (;;) {
    std::vector<SentCommand> commands;
    double target = 0;
    bool newBase = false, newCommands = false;
    {
      std::unique_lock lock(mutex_);
      presentWake_.wait_for(lock, period,
                            [&] { return stop_ || baseVersion_ != seenBase || commands_.sent() != seenCommands; });
      if (stop_) return;
      if (baseVersion_ != seenBase) {
        seenBase = baseVersion_;
        base = base_;
        newBase = true;
        next = base->nextSeq;
      }
      newCommands = commands_.sent() != seenCommands;
      seenCommands = commands_.sent();
      if (!base) continue;
      if (!base->latched && options_.inFlight) commands = commands_.from(next);
      target = options_.runAhead ? clock_.ghostTime(now()) : clock_.newest();
    }
    if (newBase && base->twin != twin) {
      twin = base->twin;
      world = buildWorld(*twin);  // the anchor thread built one from it: it builds
    }
    if (!world) continue;
    if (newBase) {
      world->restore(base->snapshot);
      t = base->time;
    }
    World& w = *world;
    size_t applied = 0;
    if (!advance(w, t, target, commands, applied)) {
      const std::string health = w.health().message();
      w.restore(base->snapshot);
      t = base->time;
      next = base->nextSeq;
      setProblem("the ghost diverged: " + health);
      continue;
    }
    if (applied > 0) next = commands[applied - 1].seq + 1;
    const RobotReadout r = readRobot(w);
    const double wall = now();
    std::shared_ptr<TrailRequest> trail;
    if (newCommands || wall - lastTrail >= kTrailPeriod) {
      trail = std::make_shared<TrailRequest>(TrailRequest{twin, w.snapshot(), t, next, base->latched, newCommands});
      lastTrail = wall;
    }
    {
      std::lock_guard lock(mutex_);
      GhostView& v = view_;
      ++v.version;
      v.time = t;
      v.span = t - clock_.newest();
      v.base = r.base;
      v.jointPositions = fullPositions(*twin, r.jointPositions, frame_ ? &frame_->jointPositions : nullptr);
      v.objects = r.objects;
      v.problem.clear();
      v.commands = next;
      ++stats_.views;
      record_.shown(t, base->made, r.base);
      if (trail) {
        trailRequest_ = trail;
        ++trailVersion_;
      }
    }
    if (trail) trailWake_.notify_one();
  }
}

void Ghost::trailLoop() {
  nameThread("ghost-trail");
  yieldToOthers();
  std::shared_ptr<const Twin> twin;
  std::unique_ptr<World> world;
  uint64_t seen = 0;
  for (;;) {
    std::shared_ptr<const TrailRequest> request;
    std::vector<SentCommand> commands;
    {
      std::unique_lock lock(mutex_);
      trailWake_.wait(lock, [&] { return stop_ || trailVersion_ != seen; });
      if (stop_) return;
      seen = trailVersion_;
      request = trailRequest_;
      if (!request->latched && options_.inFlight) commands = commands_.from(request->nextSeq);
    }
    const double start = now();
    if (request->twin != twin) {
      twin = request->twin;
      world = buildWorld(*twin);
    }
    if (!world) continue;
    World& w = *world;
    w.restore(request->snapshot);
    double t = request->time;
    size_t next = 0;
    // The base's path on the ground: seen from behind the robot, a line at
    // base height would run straight away from the eye and shrink to a dot.
    const auto groundPoint = [&w] {
      const Vec3 p = w.linkPose(0, 0).p;
      return Vec3{p.x, p.y, w.terrainHeight(p.x, p.y)};
    };
    std::vector<Vec3> points{groundPoint()};
    // Given up when the commands changed meanwhile; a newer request that
    // only starts from a fresher state waits for this one to finish.
    const auto superseded = [&] {
      std::lock_guard lock(mutex_);
      return stop_ || (trailVersion_ != seen && trailRequest_->urgent);
    };
    const int count = static_cast<int>(std::floor(params_.ghostHorizon / options_.trailSpacing + 1e-9));
    bool complete = true;
    for (int k = 1; k <= count && complete; ++k) {
      complete = advance(w, t, request->time + k * options_.trailSpacing, commands, next, superseded);
      if (complete) points.push_back(groundPoint());
    }
    if (!complete && superseded()) continue;
    std::lock_guard lock(mutex_);
    view_.trail = std::move(points);  // up to where it diverged, if it did
    view_.trailTime = request->time;
    ++view_.version;
    ++stats_.trails;
    stats_.trailMs = (now() - start) * 1000;
  }
}

}  // namespace sp
