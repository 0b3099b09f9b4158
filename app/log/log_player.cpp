#include "app/log/log_player.h"

#include "app/state/robot_shapes.h"

#include <algorithm>
#include <cmath>

#include "sim/command_file.h"
#include "sim/math.h"
#include "sim/terrain_brush.h"
#include "sim/world.h"

namespace sp {

std::unique_ptr<LogPlayer> LogPlayer::open(const std::string& path, std::string& error) {
  std::unique_ptr<LogPlayer> p(new LogPlayer);
  p->path_ = path;
  p->reader_ = SessionLogReader::open(path, error);
  if (!p->reader_) return nullptr;
  std::optional<LoggedWorld> world = loggedWorld(*p->reader_, path, error);
  if (!world) return nullptr;
  p->logged_ = std::move(*world);
  const std::optional<std::pair<double, double>> range = p->reader_->sampleTimeRange();
  if (!range) {
    error = path + ": the log holds no samples to replay";
    return nullptr;
  }
  p->start_ = range->first;
  p->end_ = range->second;
  p->events_ = p->reader_->events();
  p->hasSnapshots_ = !p->reader_->snapshotSteps().empty();
  // Terrain edits: few, read once (a drag logs one per dab).
  for (const LogCommand& c : p->reader_->commands()) {
    if (c.text.rfind("terrain ", 0) != 0) continue;
    std::string why;
    std::optional<Command> command = parseCommand(c.text, why, &p->logged_.world.robots[0].model);
    if (const auto* patch = command ? std::get_if<TerrainPatchCmd>(&*command) : nullptr;
        patch && patchFits(&p->logged_.world.terrain.grid, *patch).empty())
      p->terrainEdits_.emplace_back(static_cast<double>(c.step) * p->logged_.params.step, *patch);
  }
  return p;
}

std::optional<RobotFrame> LogPlayer::frameAt(double time) const {
  std::optional<LogSample> s = reader_->sampleAt(std::max(time, start_));
  if (!s) return std::nullopt;
  return frameFromSample(*s, logged_.world.robots[0].model.joints.size());
}

std::optional<LaserFrame> LogPlayer::laserAt(double time) const {
  // One row, not the second's scans: the replay asks at every tick.
  std::optional<LogLaser> l = reader_->laserAt(time);
  if (!l || l->time < time - 1.0) return std::nullopt;
  return LaserFrame{l->time, l->angleMin, l->angleStep, std::move(l->ranges)};
}

size_t LogPlayer::terrainEditsAt(double time) const {
  // A command logged at step s applies in the step from s: drawn from s on.
  return static_cast<size_t>(std::upper_bound(terrainEdits_.begin(), terrainEdits_.end(), time,
                                              [](double t, const auto& e) { return t < e.first; }) -
                             terrainEdits_.begin());
}

HeightGrid LogPlayer::terrainAfter(size_t count) const {
  HeightGrid grid = logged_.world.terrain.grid;
  for (size_t i = 0; i < count && i < terrainEdits_.size(); ++i) applyPatch(grid, terrainEdits_[i].second);
  return grid;
}

std::optional<RehearsalStart> LogPlayer::startAt(double time) const {
  const std::optional<RobotFrame> f = frameAt(time);
  if (!f) return std::nullopt;
  RehearsalStart s;
  s.base = f->base;
  s.jointPositions = f->jointPositions;
  s.jointRates = f->jointRates;
  // The base's twist by differencing with the sample before: the angular
  // velocity (world frame) is 2 vec(q1 conj(q0)) / dt for a small turn.
  if (const std::optional<RobotFrame> before = frameAt(f->time - 1e-9);
      before && before->time < f->time && f->time - before->time <= 0.5) {
    const double dt = f->time - before->time;
    s.baseLinear = (1.0 / dt) * (f->base.p - before->base.p);
    Quat d = f->base.q * conjugate(before->base.q);
    if (d.w < 0) d = Quat{-d.w, -d.x, -d.y, -d.z};  // the shorter way
    s.baseAngular = (2.0 / dt) * Vec3{d.x, d.y, d.z};
  }
  return s;
}

std::optional<BranchPoint> LogPlayer::branchAt(double time, std::string& error,
                                               const std::function<bool(double)>& progress) const {
  if (hasSnapshots_) return sp::branchAt(path_, time, error, progress);
  const std::optional<RehearsalStart> start = startAt(time);
  if (!start) {
    error = path_ + ": no sample at t = " + std::to_string(time) + " s";
    return std::nullopt;
  }
  Diagnostics diag;
  std::unique_ptr<World> world = World::create(logged_.world, logged_.params, diag);
  if (!world) {
    error = path_ + ": cannot build the logged world:\n" + diag.format();
    return std::nullopt;
  }
  if (std::string why = placeRobot(*world, *start); !why.empty()) {
    error = path_ + ": the logged state at t = " + std::to_string(time) + " s does not fit the world: " + why;
    return std::nullopt;
  }
  // At the logged time: the branch's clock goes on from the log's.
  Snapshot at = world->snapshot();
  at.step = std::llround(std::max(time, start_) / logged_.params.step);
  if (std::string why = world->restore(at); !why.empty()) {
    error = path_ + ": cannot set the reconstructed state: " + why;
    return std::nullopt;
  }
  BranchPoint b;
  b.logged = logged_;
  b.state = world->snapshot();
  b.hash = world->stateHash();
  b.step = world->stepCount();
  b.meta = reader_->meta();
  b.reconstructed = true;
  return b;
}

namespace {
// The signals before the joints', in signalNames() order.
constexpr const char* kBaseSignals[] = {"base x [m]", "base y [m]", "base z [m]", "roll [deg]", "pitch [deg]",
                                        "yaw [deg]", "wheel FL normal [N]", "wheel FR normal [N]",
                                        "wheel RL normal [N]", "wheel RR normal [N]"};
constexpr int kBaseCount = 10;
constexpr const char* kGhostSignals[] = {"ghost predicted x [m]", "ghost predicted y [m]", "ghost position error [m]",
                                         "ghost heading error [deg]"};
}  // namespace

std::vector<std::string> LogPlayer::signalNames() const {
  std::vector<std::string> out(std::begin(kBaseSignals), std::end(kBaseSignals));
  for (const JointSpec& j : logged_.world.robots[0].model.joints) {
    const bool slider = j.type == JointType::Slider;
    out.push_back(j.name + (slider ? " position [m]" : " position [deg]"));
    out.push_back(j.name + (slider ? " rate [m/s]" : " rate [deg/s]"));
  }
  out.insert(out.end(), std::begin(kGhostSignals), std::end(kGhostSignals));
  return out;
}

std::vector<std::pair<double, double>> LogPlayer::signal(int index, double t0, double t1, int points) const {
  std::vector<std::pair<double, double>> out;
  const RobotModel& robot = logged_.world.robots[0].model;
  const int joints = static_cast<int>(robot.joints.size());
  const int ghost = kBaseCount + 2 * joints;
  if (index < 0 || index >= ghost + 4 || points < 2 || !(t1 > t0)) return out;
  if (index >= ghost) {
    // Predictions are sparse (one per telemetry frame): read the range, keep
    // about `points` of them.
    const std::vector<LogPrediction> p = reader_->predictionsBetween(t0, t1);
    const size_t every = std::max<size_t>(1, p.size() / static_cast<size_t>(points));
    for (size_t i = 0; i < p.size(); i += every) {
      const LogPrediction& q = p[i];
      const double v[] = {q.base[0], q.base[1], q.positionError, radToDeg(q.headingError)};
      out.emplace_back(q.time, v[index - ghost]);
    }
    return out;
  }
  for (int k = 0; k < points; ++k) {
    const double t = t0 + (t1 - t0) * k / (points - 1);
    const std::optional<RobotFrame> f = frameAt(t);
    if (!f || (!out.empty() && f->time <= out.back().first)) continue;
    double v = 0;
    if (index < kBaseCount) {
      const Vec3 tilted = tilt(f->base.q);
      switch (index) {
        case 0: v = f->base.p.x; break;
        case 1: v = f->base.p.y; break;
        case 2: v = f->base.p.z; break;
        case 3: v = radToDeg(tilted.x); break;
        case 4: v = radToDeg(tilted.y); break;
        case 5: v = radToDeg(heading(f->base.q)); break;
        default: v = f->wheelNormal[static_cast<size_t>(index - 6)];
      }
    } else {
      const int j = (index - kBaseCount) / 2;
      const bool rate = (index - kBaseCount) % 2 == 1;
      v = rate ? f->jointRates[static_cast<size_t>(j)] : f->jointPositions[static_cast<size_t>(j)];
      if (robot.joints[static_cast<size_t>(j)].type != JointType::Slider) v = radToDeg(v);
    }
    out.emplace_back(f->time, v);
  }
  return out;
}

}  // namespace sp
