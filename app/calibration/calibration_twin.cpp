// The candidate twins of a calibration (calibration_twin.h).
#include "app/calibration/calibration_twin.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>

#include "app/ghost/hold_policy.h"
#include "app/state/parallel_for.h"
#include "app/state/robot_shapes.h"
#include "sim/kinematics.h"
#include "sim/perturbation.h"
#include "sim/readout.h"
#include "sim/rigid.h"
#include "sim/runner.h"
#include "sim/text.h"
#include "sim/world.h"

namespace sp::calibration_detail {

namespace {

double wrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

// The frame nearest robot time `t`, if one lies within `tolerance`.
std::optional<size_t> frameAt(const std::vector<RobotFrame>& f, double t, double tolerance) {
  const auto it = std::lower_bound(f.begin(), f.end(), t, [](const RobotFrame& r, double x) { return r.time < x; });
  std::optional<size_t> best;
  for (auto c : {it, it == f.begin() ? it : it - 1})
    if (c != f.end() && std::abs(c->time - t) <= tolerance &&
        (!best || std::abs(c->time - t) < std::abs(f[*best].time - t)))
      best = static_cast<size_t>(c - f.begin());
  return best;
}

// Cuts the frames into driving segments whose held joints stay at the weld.
std::vector<Segment> cutSegments(const Problem& pb, const CalibrationOptions& o) {
  const std::vector<RobotFrame>& f = *pb.frames;
  std::vector<Segment> out;
  if (f.size() < 2) return out;
  const double tolerance = 0.6 * std::min(o.checkpoint, 0.05);
  for (double a = f.front().time; a + o.horizon <= f.back().time + 1e-9; a += o.spacing) {
    const std::optional<size_t> anchor = frameAt(f, a, o.spacing / 2);
    if (!anchor) continue;
    Segment s;
    s.anchor = *anchor;
    const double t0 = f[*anchor].time;
    bool ok = true;
    double turning = 0;
    for (double t = t0 + o.checkpoint; t <= t0 + o.horizon + 1e-9; t += o.checkpoint) {
      const std::optional<size_t> c = frameAt(f, t, tolerance);
      if (c) s.checkpoints.push_back(*c);
    }
    for (size_t i = s.anchor; i < f.size() && f[i].time <= t0 + o.horizon + 1e-9 && ok; ++i) {
      for (int j : pb.held)
        if (std::abs(f[i].jointPositions[static_cast<size_t>(j)] - pb.weld[static_cast<size_t>(j)]) > 0.03) ok = false;
      for (int w : pb.wheels)
        if (w >= 0) turning = std::max(turning, std::abs(f[i].jointRates[static_cast<size_t>(w)]));
    }
    // A segment where the wheels stand still teaches nothing of wheels.
    if (ok && turning > 0.2 && s.checkpoints.size() >= 2) out.push_back(std::move(s));
  }
  return out;
}

// The model joint index (in `rigid`'s robot, or the full one) of the full robot's joint `full`.
int modelJoint(const std::optional<RigidRobot>& rigid, int full) {
  if (!rigid || full < 0) return full;
  const auto it = std::find(rigid->jointOf.begin(), rigid->jointOf.end(), full);
  return it == rigid->jointOf.end() ? -1 : static_cast<int>(it - rigid->jointOf.begin());
}

}  // namespace

std::optional<std::vector<double>> residuals(const Problem& pb, const CalValues& v, std::string& why,
                                             std::vector<std::pair<double, double>>* turns, double jitter,
                                             std::vector<double>* forces) {
  WorldModel model = calibratedWorld(*pb.files, withCalValues(pb.profile, v));
  std::optional<RigidRobot> rigid;
  if (!pb.held.empty()) {
    rigid = holdRigid(model.robots[0].model, pb.weld, pb.held, why);
    if (!rigid) return std::nullopt;
    model.robots[0].model = rigid->model;
  }
  WorldOptions options;
  options.sensors = false;
  options.wheelForces = forces != nullptr;
  Diagnostics diag;
  std::unique_ptr<World> world = World::create(model, pb.profile, diag, options);
  if (!world) {
    why = "the twin cannot be built: " + diag.format();
    return std::nullopt;
  }
  const Snapshot pristine = world->snapshot();
  const RobotModel& robot = world->robotModel(0);
  std::array<int, 4> wheels{};
  for (size_t w = 0; w < 4; ++w) wheels[w] = modelJoint(rigid, pb.wheels[w]);
  const int articulation = modelJoint(rigid, pb.articulation);
  const double delay = v[static_cast<size_t>(CalParam::Delay)];
  const double h = pb.profile.step;
  const std::vector<RobotFrame>& f = *pb.frames;
  std::vector<double> r;
  for (const Segment& s : pb.segments) {
    world->restore(pristine);
    const RobotFrame& a = f[s.anchor];
    // The commands in effect by the anchor set the controllers; the rest
    // fall due during the segment.
    size_t next = 0;
    bool submitted = false;
    for (; next < pb.commands.size() && pb.commands[next].time + delay <= a.time; ++next)
      submitted |= world->submit(pb.commands[next].command).empty();
    if (submitted && !world->step()) {
      why = "the twin diverged applying the commands in effect at " + shortestText(a.time) + " s";
      return std::nullopt;
    }
    const std::vector<double> positions = rigid ? rigidJoints(*rigid, a.jointPositions) : a.jointPositions;
    const std::vector<double> rates = rigid ? rigidJoints(*rigid, a.jointRates) : a.jointRates;
    Pose lifted = a.base;
    lifted.p.z += jitter;
    why = world->setRobotMotion(0, linkMotions(robot, lifted, a.baseLinearVelocity, a.baseAngularVelocity, positions, rates));
    if (!why.empty()) return std::nullopt;
    Runner runner(*world);
    const int64_t start = world->stepCount();
    for (size_t i = next; i < pb.commands.size(); ++i) {
      const double due = pb.commands[i].time + delay - a.time;
      if (due > f[s.checkpoints.back()].time - a.time) break;  // after the segment
      runner.schedule(ScheduledCommand{pb.commands[i].command, 0, start + static_cast<int64_t>(std::ceil(due / h - 1e-9))});
    }
    // How far each wheel turned since the anchor, by the twin and by the
    // robot: rates chatter with the contacts, turns are their integral.
    // Hinge angles wrap: increments between checkpoints (< pi) are summed.
    std::array<double, 4> twinTurn{}, robotTurn{}, twinLast{}, robotLast{};
    for (size_t w = 0; w < 4; ++w)
      if (wheels[w] >= 0) twinLast[w] = robotLast[w] = a.jointPositions[static_cast<size_t>(pb.wheels[w])];
    for (size_t c : s.checkpoints) {
      const int64_t target = start + static_cast<int64_t>(std::floor((f[c].time - a.time) / h + 0.5));
      if (target > world->stepCount() && runner.advanceBy(target - world->stepCount()).stop != RunOutcome::Stop::Reached) {
        why = "the twin diverged at " + shortestText(f[c].time) + " s: " + world->health().message();
        return std::nullopt;
      }
      const Pose base = world->linkPose(0, 0);
      r.push_back((base.p.x - f[c].base.p.x) / kResidualScale.position);
      r.push_back((base.p.y - f[c].base.p.y) / kResidualScale.position);
      r.push_back(wrapAngle(heading(base.q) - heading(f[c].base.q)) / kResidualScale.heading);
      for (size_t w = 0; w < 4; ++w) {
        if (wheels[w] < 0) {
          r.push_back(0);
          continue;
        }
        const double twinNow = world->jointPosition(0, wheels[w]);
        const double robotNow = f[c].jointPositions[static_cast<size_t>(pb.wheels[w])];
        twinTurn[w] += wrapAngle(twinNow - twinLast[w]);
        robotTurn[w] += wrapAngle(robotNow - robotLast[w]);
        twinLast[w] = twinNow;
        robotLast[w] = robotNow;
        r.push_back((twinTurn[w] - robotTurn[w]) / kResidualScale.wheelTurn);
        if (turns) turns->emplace_back(twinTurn[w], robotTurn[w]);
      }
      if (forces) {
        const std::array<double, 4> twin = readRobot(*world).wheelTangential;
        for (size_t w = 0; w < 4; ++w) forces->push_back((twin[w] - f[c].wheelTangential[w]) / kResidualScale.force);
      }
      r.push_back(articulation < 0 ? 0
                                   : (world->jointPosition(0, articulation) -
                                      f[c].jointPositions[static_cast<size_t>(pb.articulation)]) /
                                         kResidualScale.articulation);
    }
  }
  for (double x : r)
    if (!std::isfinite(x)) {
      why = "the twin's prediction is not finite";
      return std::nullopt;
    }
  return r;
}

double meanSquare(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return r.empty() ? 0 : s / static_cast<double>(r.size());
}

std::vector<std::optional<std::vector<double>>> runAll(const Problem& pb, const std::vector<Candidate>& candidates,
                                                       int threads, std::string& why,
                                                       const std::function<bool()>& abort) {
  std::vector<std::optional<std::vector<double>>> out(candidates.size());
  std::vector<std::string> whys(candidates.size());
  std::mutex asking;  // `abort` is asked from one thread at a time
  parallelFor(candidates.size(), threads, [&](size_t i) {
    if (abort) {
      std::lock_guard lock(asking);
      if (abort()) {
        whys[i] = "cancelled";
        return true;  // every candidate gets its why
      }
    }
    // The candidate fails, not the fit: a twin that throws is a bad candidate.
    try {
      if (candidates[i].forces) {
        std::vector<double> f;
        if (residuals(pb, candidates[i].values, whys[i], nullptr, candidates[i].jitter, &f)) out[i] = std::move(f);
      } else {
        out[i] = residuals(pb, candidates[i].values, whys[i], nullptr, candidates[i].jitter);
      }
    } catch (const std::exception& e) {
      out[i].reset();
      whys[i] = std::string("its twin failed: ") + e.what();
    }
    return true;
  });
  for (size_t i = 0; i < out.size(); ++i)
    if (!out[i]) {
      why = whys[i];
      break;
    }
  return out;
}

std::string makeProblem(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                        const std::vector<TimedCommand>& commands, const CalibrationOptions& o, Problem& pb) {
  const RobotModel& robot = files.robots[0].model;
  pb.files = &files;
  pb.profile = profile;
  pb.frames = &frames;
  std::string why;
  const std::optional<std::vector<int>> held = holdableJoints(robot, profile.ghostHold, "ghost.hold", why);
  if (!held) return why;
  pb.held = *held;
  pb.weld = frames.back().jointPositions;
  pb.wheels = robot.drive->wheels;
  pb.articulation = robot.drive->articulation;
  pb.commands = commands;
  std::stable_sort(pb.commands.begin(), pb.commands.end(), [](const TimedCommand& a, const TimedCommand& b) { return a.time < b.time; });
  pb.segments = cutSegments(pb, o);
  return {};
}

}  // namespace sp::calibration_detail
