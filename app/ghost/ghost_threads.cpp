// The predictive ghost's three threads (app/ghost/ghost.h): anchor,
// present, trail. Each owns one World; each takes its input from a slot
// and publishes into the next (ghost_slots.h), copying values in and out
// under short locks, none held while another is taken.

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <tuple>

#include "app/ghost/ghost_impl.h"
#include "app/ghost/hold_policy.h"
#include "sim/kinematics.h"
#include "sim/readout.h"

namespace sp {

namespace {

constexpr double kTrailPeriod = 0.25; // [s] between trails while nothing changes

// "" or, for `w` just diverged, that a link of its robot went past the
// edge of the map (beyond it the physics has no ground: the twin falls),
// in the operator's words rather than the solver's.
std::string offTheMap(const World& w) {
  const TerrainSpec& map = w.model().terrain;
  for (int k = 0; k < static_cast<int>(w.robotModel(0).links.size()); ++k) {
    const Vec3 p = w.linkPose(0, k).p;
    if (std::isfinite(p.x) && std::isfinite(p.y) && !onTerrain(map, p.x, p.y)) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "the ghost's prediction leaves the map at (%.1f, %.1f): beyond its edge there is no ground to "
                    "predict on",
                    p.x, p.y);
      return text;
    }
  }
  return "";
}

// Seconds as the steady clock's duration (Ghost::now() counts from its epoch).
std::chrono::steady_clock::duration steady(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

// The calling thread yields to the rest of the process: re-anchoring and
// the trail are best effort, and must not take the cores the robot's twin
// and the window's frames need (Linux: a thread's nice value is its own).
void yieldToOthers() { setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10); }
// What the view says when the clock puts the robot `ahead` [s] past its
// newest telemetry, beyond Options::maxAhead.
std::string aheadProblem(double ahead) {
  return "the link's delay puts the robot " + (std::isfinite(ahead) ? std::to_string(static_cast<long long>(ahead)) + " s" : std::string("an unknown time")) +
         " past its newest telemetry: the ghost predicts no further than its limit";
}

// Names the calling thread (top -H, gdb): at most 15 characters.
void nameThread(const char* name) { pthread_setname_np(pthread_self(), name); }

}  // namespace

bool Ghost::takeAnchorInput(AnchorRun& run, AnchorInput& in) {
  while (frames_.version() == run.seen)
    if (!anchorBell_.wait(run.rung)) return false;
  // At most ghost.anchor_rate re-anchorings a second: the newest frame
  // when the time comes.
  if (!anchorBell_.sleepUntil(std::chrono::steady_clock::time_point(steady(run.lastStart + 1 / params_.ghostAnchorRate))))
    return false;
  {
    const auto [version, newest] = frames_.latest();
    run.seen = version;
    in.frame = *newest;
  }
  {
    std::lock_guard lock(calibrationMutex_);
    if (nextModel_) {  // a calibration: the twin is rebuilt at this anchor's step boundary
      model_ = std::move(*nextModel_);
      nextModel_.reset();
      in.recalibrated = true;
    }
  }
  std::lock_guard lock(timelineMutex_);
  if (run.epoch != epoch_) {  // the robot restarted: weld and build anew
    run.epoch = epoch_;
    run.world.reset();
    run.policy.reset();
    run.applied = commands_.sent();
  }
  for (SentCommand& c : commands_.from(run.applied))
    (c.time <= in.frame.time ? in.effective : in.pending).push_back(std::move(c));
  in.target = options_.runAhead ? clock_.ghostTime(now()) : in.frame.time;
  return true;
}

std::string Ghost::rebuildTwin(AnchorRun& run, const RobotFrame& frame, bool hold) {
  std::string error;
  std::shared_ptr<const Twin> next = makeTwin(frame.jointPositions, hold, error);
  std::unique_ptr<World> built = next ? buildWorld(*next, &error) : nullptr;
  if (!built) return error;
  // The set-points of the commands in effect carry over.
  if (run.world) carryControl(*run.world, *run.twin, *built, *next, frame.jointPositions);
  run.twin = std::move(next);
  run.world = std::move(built);
  run.anchored = run.world->snapshot();
  std::lock_guard lock(statsMutex_);
  ++stats_.twins;
  stats_.held = hold;
  return {};
}

std::string Ghost::setAnchorState(AnchorRun& run, AnchorInput& in, bool latched) {
  World& w = *run.world;
  const RobotFrame& frame = in.frame;
  if (!in.effective.empty()) run.applied = in.effective.back().seq + 1;
  if (latched) {
    // The robot holds still and refuses what it is sent meanwhile.
    if (!in.pending.empty()) run.applied = in.pending.back().seq + 1;
    in.effective.assign(1, SentCommand{0, frame.time, StopCmd{}});
    in.pending.clear();
  }
  if (!options_.inFlight) in.pending.clear();
  for (const SentCommand& c : in.effective) w.submit(c.command);
  if (!in.effective.empty() && !w.step()) {
    w.restore(run.anchored);
    return "the ghost diverged applying the commands in effect: " + w.health().message();
  }
  std::vector<std::pair<std::string, Pose>> objects;
  for (const ObjectReadout& o : frame.objects) objects.emplace_back(o.name, o.pose);
  const RigidRobot* rigid = run.twin->rigid ? &*run.twin->rigid : nullptr;
  const std::vector<double> positions = rigid ? rigidJoints(*rigid, frame.jointPositions) : frame.jointPositions;
  const std::vector<double> rates = rigid ? rigidJoints(*rigid, frame.jointRates) : frame.jointRates;
  const std::string error = w.setRobotMotion(
      0,
      linkMotions(w.robotModel(0), frame.base, frame.hasBaseVelocity ? frame.baseLinearVelocity : Vec3{},
                  frame.hasBaseVelocity ? frame.baseAngularVelocity : Vec3{}, positions, rates),
      objects);
  if (!error.empty()) {
    w.restore(run.anchored);
    return "telemetry at " + std::to_string(frame.time) + " s does not fit the robot: " + error;
  }
  run.anchored = w.snapshot();
  return {};
}

void Ghost::anchorLoop() {
  nameThread("ghost-anchor");
  yieldToOthers();
  AnchorRun run(held_, model_.robots[0].model);
  for (;;) {
    AnchorInput in;
    if (!takeAnchorInput(run, in)) return;
    const RobotFrame& frame = in.frame;
    if (!(in.target <= frame.time + options_.maxAhead)) {  // NaN too
      setProblem(aheadProblem(in.target - frame.time));
      in.target = frame.time + options_.maxAhead;
    }
    run.lastStart = now();
    const size_t joints = run.robot.joints.size();
    if (frame.jointPositions.size() != joints || frame.jointRates.size() != joints) {
      setProblem("telemetry at " + std::to_string(frame.time) + " s has " +
                 std::to_string(frame.jointPositions.size()) + " joint positions and " +
                 std::to_string(frame.jointRates.size()) + " rates; the robot has " + std::to_string(joints) +
                 " joints");
      continue;
    }
    const bool latched = frame.estop || frame.failsafe;
    const HoldDecision decision = run.policy.decide(frame, in.effective, in.pending,
                                                    run.world && run.twin->rigid ? &*run.twin->rigid : nullptr,
                                                    run.world != nullptr);
    if (decision.rebuild || (in.recalibrated && run.world))
      if (std::string problem = rebuildTwin(run, frame, decision.hold); !problem.empty()) {
        setProblem(problem);
        continue;
      }
    if (std::string problem = setAnchorState(run, in, latched); !problem.empty()) {
      setProblem(problem);
      continue;
    }
    World& w = *run.world;
    double t = frame.time;
    size_t next = 0;
    const bool ok = advance(w, t, in.target, in.pending, next, [this] { return stopping(); });
    if (stopping()) return;
    auto base = std::make_shared<Base>();
    base->twin = run.twin;
    base->time = t;
    base->nextSeq = next < in.pending.size() ? in.pending[next].seq
                                             : (in.pending.empty() ? run.applied : in.pending.back().seq + 1);
    base->made = frame.time;
    base->latched = latched;
    if (ok) base->snapshot = w.snapshot();
    std::string why;
    if (!ok) why = offTheMap(w);
    if (!ok && why.empty())
      why = "the ghost diverged predicting from " + std::to_string(frame.time) + " s: " + w.health().message();
    w.restore(run.anchored);
    if (!ok) {
      setProblem(why);
      continue;
    }
    {
      std::lock_guard lock(timelineMutex_);
      if (run.epoch != epoch_) continue;  // a reset came meanwhile
      bases_.publish(std::move(base));
    }
    {
      std::lock_guard lock(statsMutex_);
      ++stats_.anchors;
      stats_.anchorMs = (now() - run.lastStart) * 1000;
      stats_.anchorSpan = t - frame.time;
    }
    presentBell_.ring();
  }
}

void Ghost::presentLoop() {
  nameThread("ghost-present");
  std::shared_ptr<const Twin> twin;
  std::unique_ptr<World> world;
  std::shared_ptr<const Base> base;
  uint64_t seenBase = 0, seenCommands = 0, next = 0, rung = 0;
  double t = 0, lastTrail = -1e9;
  const auto period = steady(options_.frameInterval);
  for (;;) {
    std::vector<SentCommand> commands;
    std::vector<std::pair<double, Command>> timeline;  // for the region's scale
    double target = 0, ahead = 0, newest = 0, spread = 0;
    bool newBase = false, newCommands = false, capped = false;
    if (!presentBell_.waitUntil(rung, std::chrono::steady_clock::now() + period)) return;
    if (const auto [version, latest] = bases_.latest(); version != seenBase) {
      seenBase = version;
      base = latest;
      newBase = true;
      next = base->nextSeq;
    }
    {
      std::lock_guard lock(timelineMutex_);
      newCommands = commands_.sent() != seenCommands;
      seenCommands = commands_.sent();
      if (!base) continue;
      if (!base->latched && options_.inFlight) commands = commands_.from(next);
      target = options_.runAhead ? clock_.ghostTime(now()) : clock_.newest();
      newest = clock_.newest();
      // From the newest telemetry, or from the base it runs on when that
      // is older: a base the anchor thread has not yet replaced after a
      // leap in the robot's time is not run up to it.
      const double from = std::min(base->time, newest);
      capped = !(target <= from + options_.maxAhead);
      if (capped) {
        ahead = target - from;
        target = from + options_.maxAhead;
      }
      timeline = commands_.upTo(target);
      spread = clock_.spread();
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
    if (!advance(w, t, target, commands, applied, [this] { return stopping(); })) {
      if (stopping()) return;
      std::string why = offTheMap(w);
      if (why.empty()) why = "the ghost diverged: " + w.health().message();
      w.restore(base->snapshot);
      t = base->time;
      next = base->nextSeq;
      setProblem(why);
      continue;
    }
    if (applied > 0) next = commands[applied - 1].seq + 1;
    const RobotReadout r = readRobot(w);
    const double wall = now();
    std::shared_ptr<TrailRequest> trail;
    if (newCommands || wall - lastTrail >= kTrailPeriod) {
      trail = std::make_shared<TrailRequest>(
          TrailRequest{twin, w.snapshot(), t, next, base->latched, newCommands, base->made});
      lastTrail = wall;
    }
    double scale = 0, inner = 0, outer = 0;
    ErrorSources sources;
    std::string departure;
    {
      std::lock_guard lock(recordMutex_);
      sources = sourcesOf(t, base->made, std::hypot(r.baseLinearVelocity.x, r.baseLinearVelocity.y), timeline, spread);
      scale = errorScale(sources, errorModel_);
      inner = region_.multiplier(0) * scale;
      outer = region_.multiplier(1) * scale;
      if (watch_.departing()) departure = watch_.last()->describe();
    }
    const std::shared_ptr<const RobotFrame> reported = frames_.latest().second;
    std::vector<double> shownPositions;
    {
      std::lock_guard lock(viewMutex_);
      if (!halted_.empty()) continue;  // the robot's twin diverged: nothing to predict until it reports again
      GhostView& v = view_;
      ++v.version;
      v.time = t;
      v.span = t - newest;
      v.base = r.base;
      v.jointPositions = fullPositions(*twin, r.jointPositions, reported ? &reported->jointPositions : nullptr);
      shownPositions = v.jointPositions;
      v.objects = r.objects;
      if (capped) v.problem = aheadProblem(ahead);
      else v.problem.clear();
      v.commands = next;
      v.scale = scale;
      v.inner = inner;
      v.outer = outer;
      v.innerLevel = params_.ghostRegionInner;
      v.outerLevel = params_.ghostRegionOuter;
      v.departure = std::move(departure);
    }
    const WheelClearances clearance = wheelClearances(
        robot_, [&w](double x, double y) { return w.terrainHeight(x, y); }, r.base, shownPositions);
    {
      std::lock_guard lock(recordMutex_);
      record_.shown(t, base->made, r.base, scale, sources, clearance);
    }
    {
      std::lock_guard lock(statsMutex_);
      ++stats_.views;
    }
    if (trail) {
      trailRequests_.publish(std::move(trail));
      trailBell_.ring();
    }
  }
}

void Ghost::trailLoop() {
  nameThread("ghost-trail");
  yieldToOthers();
  std::shared_ptr<const Twin> twin;
  std::unique_ptr<World> world;
  uint64_t seen = 0, rung = 0;
  for (;;) {
    while (trailRequests_.version() == seen)
      if (!trailBell_.wait(rung)) return;
    std::shared_ptr<const TrailRequest> request;
    std::tie(seen, request) = trailRequests_.latest();
    std::vector<SentCommand> commands;
    std::vector<std::pair<double, Command>> timeline;
    double spread = 0;
    {
      std::lock_guard lock(timelineMutex_);
      if (!request->latched && options_.inFlight) commands = commands_.from(request->nextSeq);
      timeline = commands_.upTo(request->time + params_.ghostHorizon);
      spread = clock_.spread();
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
    std::vector<double> band;
    // The outer region's radius at a trail point of robot time `at`.
    const auto bandAt = [&](double at) {
      const Vec3 v = w.linkLinearVelocity(0, 0);
      std::lock_guard lock(recordMutex_);
      return region_.multiplier(1) * errorScale(sourcesOf(at, request->made, std::hypot(v.x, v.y), timeline, spread), errorModel_);
    };
    band.push_back(bandAt(t));
    // Given up when the commands changed meanwhile; a newer request that
    // only starts from a fresher state waits for this one to finish.
    const auto superseded = [&] {
      if (stopping()) return true;
      const auto [version, newer] = trailRequests_.latest();
      return version != seen && newer->urgent;
    };
    const int count = static_cast<int>(std::floor(params_.ghostHorizon / options_.trailSpacing + 1e-9));
    bool complete = true;
    for (int k = 1; k <= count && complete; ++k) {
      complete = advance(w, t, request->time + k * options_.trailSpacing, commands, next, superseded);
      if (complete) {
        points.push_back(groundPoint());
        band.push_back(bandAt(t));
      }
    }
    if (!complete && superseded()) continue;
    {
      std::lock_guard lock(viewMutex_);
      view_.trail = std::move(points);  // up to where it diverged, if it did
      view_.trailBand = std::move(band);
      view_.trailTime = request->time;
      ++view_.version;
    }
    std::lock_guard lock(statsMutex_);
    ++stats_.trails;
    stats_.trailMs = (now() - start) * 1000;
  }
}

}  // namespace sp
