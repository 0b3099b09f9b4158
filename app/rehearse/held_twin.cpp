#include "app/rehearse/held_twin.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "sim/diagnostics.h"
#include "sim/kinematics.h"
#include "sim/readout.h"

namespace sp {
namespace {

// The joint a command moves by name (targets, velocities, torques, modes),
// `legs` for a gait (it walks the legs), `none` for the rest: the drive
// turns only drive joints, which are never welded, and stop holds every
// joint where it is.
int jointMoved(const RobotModel& robot, const Command& command, int none, int legs) {
  return std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (requires { c.joint; })
          return robot.findJoint(c.joint);
        else if constexpr (std::is_same_v<T, GaitCmd>)
          return c.gait == Gait::Off ? none : legs;
        else
          return none;
      },
      command);
}

// The first step boundary at or after `time`, as Runner::due has it.
int64_t boundaryOf(double time, double step) {
  auto n = static_cast<int64_t>(std::ceil(time / step));
  while (n > 0 && static_cast<double>(n - 1) * step + 1e-9 >= time) --n;
  while (static_cast<double>(n) * step + 1e-9 < time) ++n;
  return std::max<int64_t>(0, n);
}

}  // namespace

HeldTwin::HeldTwin(WorldModel model, SimParams params, std::vector<TimedCommand> acting, bool hold,
                   std::vector<int> alsoHeld)
    : model_(std::move(model)), params_(std::move(params)), acting_(std::move(acting)), hold_(hold),
      alsoHeld_(std::move(alsoHeld)) {
  const RobotModel& full = model_.robots[0].model;
  drive_.assign(full.joints.size(), false);
  if (full.drive) {
    if (full.drive->articulation >= 0) drive_[static_cast<size_t>(full.drive->articulation)] = true;
    for (int w : full.drive->wheels)
      if (w >= 0) drive_[static_cast<size_t>(w)] = true;
  }
  freed_.assign(full.joints.size(), false);
  touched_.assign(full.links.size(), std::numeric_limits<int64_t>::min() / 2);
  for (const TimedCommand& c : acting_) {
    dueAt_.push_back(boundaryOf(c.time, params_.step));
    moves_.push_back(jointMoved(full, c.command, kNone, kLegs));
  }
  std::sort(alsoHeld_.begin(), alsoHeld_.end());
  for (int j : alsoHeld_) {
    const std::vector<int> below = subtreeJoints(full, full.joints[static_cast<size_t>(j)].name);
    if (std::any_of(below.begin(), below.end(), [&](int k) { return drive_[static_cast<size_t>(k)]; }))
      legs_.push_back(j);
  }
}

// Marks in `freed` what the acting command `c` frees: its joint, or the
// legs for a gait.
void HeldTwin::markFreed(size_t c, std::vector<bool>& freed) const {
  if (!hold_) return;  // nothing is welded: nothing to watch for rest
  if (moves_[c] >= 0) freed[static_cast<size_t>(moves_[c])] = true;
  if (moves_[c] == kLegs)
    for (int j : legs_) freed[static_cast<size_t>(j)] = true;
}

// Whether the acting command `c` moves a joint welded now.
bool HeldTwin::movesWelded(size_t c) const {
  const auto welded = [&](int j) { return std::binary_search(held_.begin(), held_.end(), j); };
  return moves_[c] >= 0 ? welded(moves_[c]) : moves_[c] == kLegs && std::any_of(legs_.begin(), legs_.end(), welded);
}

std::vector<int> HeldTwin::heldFor(const std::vector<bool>& freed) const {
  if (!hold_) return {};
  std::vector<bool> moved = drive_;
  for (size_t j = 0; j < moved.size(); ++j) moved[j] = moved[j] || freed[j];
  std::vector<int> held = unmovedSubtrees(model_.robots[0].model, moved);
  for (int j : alsoHeld_)
    if (!freed[static_cast<size_t>(j)] && !std::binary_search(held.begin(), held.end(), j)) held.push_back(j);
  std::sort(held.begin(), held.end());
  return held;
}

std::string HeldTwin::start(const RehearsalStart& state) {
  const RobotModel& full = model_.robots[0].model;
  // What the commands due at the start move is free from the start.
  for (size_t c = 0; c < acting_.size() && dueAt_[c] == 0; ++c) markFreed(c, freed_);
  held_ = heldFor(freed_);
  WorldModel model = model_;
  std::string why;
  if (!held_.empty() && (rigid_ = holdRigid(full, state.jointPositions, held_, why)))
    model.robots[0].model = rigid_->model;
  else
    held_.clear();  // the full robot, slower but the same
  always_.assign(full.joints.size(), false);
  for (int j : held_) always_[static_cast<size_t>(j)] = true;
  Diagnostics diag;
  world_ = World::create(model, params_, diag);
  if (!world_) return "cannot build the twin: " + diag.format();
  if (why = placeRobot(*world_, state, rigid()); !why.empty()) return "the start state does not fit: " + why;
  runner_ = std::make_unique<Runner>(*world_);
  runner_->schedule(acting_);
  return "";
}

Runner::Monitor HeldTwin::watch(bool anyFreed) {
  return [this, anyFreed](const World& w) {
    // Which links touch anything, while some joints are freed: a hand on
    // an object is not at rest however still it holds.
    if (anyFreed)
      for (const LinkContact& c : w.linkContacts())
        if (c.robot == 0 && c.link >= 0) {
          const int full = rigid_ ? rigid_->linkOf[static_cast<size_t>(c.link)] : c.link;
          touched_[static_cast<size_t>(full)] = w.stepCount();
          if (c.otherRobot == 0 && c.otherLink >= 0)
            touched_[static_cast<size_t>(rigid_ ? rigid_->linkOf[static_cast<size_t>(c.otherLink)] : c.otherLink)] =
                w.stepCount();
        }
    return !monitor_ || monitor_(w);
  };
}

RunOutcome HeldTwin::advanceTo(int64_t step) {
  RunOutcome out;
  const int64_t checkEvery = std::max<int64_t>(1, std::llround(kCheck / params_.step));
  size_t next = 0;  // the first acting command not yet due
  while (world_->stepCount() < step) {
    const int64_t now = world_->stepCount();
    while (next < acting_.size() && dueAt_[next] < now) ++next;
    // A command due now to a welded joint frees it before it is submitted.
    std::vector<bool> freed = freed_;
    for (size_t c = next; c < acting_.size() && dueAt_[c] == now; ++c)
      if (movesWelded(c)) markFreed(c, freed);
    if (freed != freed_) {
      freed_ = freed;
      switchTo(heldFor(freed_));
    }
    int64_t until = step;
    for (size_t c = next; c < acting_.size(); ++c)
      if (dueAt_[c] > now && movesWelded(c)) {
        until = std::min(until, dueAt_[c]);
        break;
      }
    const bool resting = std::find(freed_.begin(), freed_.end(), true) != freed_.end();
    if (resting) until = std::min(until, (now / checkEvery + 1) * checkEvery);
    runner_->setMonitor(watch(resting));
    runner_->setSubmitHook(submitHook_);
    const RunOutcome part = runner_->advanceTo(until);
    out.steps += part.steps;
    if (part.stop != RunOutcome::Stop::Reached) {
      out.stop = part.stop;
      return out;
    }
    if (resting && world_->stepCount() % checkEvery == 0) lookForRest();
  }
  return out;
}

std::vector<double> HeldTwin::fullPositions() const {
  const RobotReadout r = readRobot(*world_);
  return rigid_ ? fullJoints(*rigid_, r.jointPositions) : r.jointPositions;
}

void HeldTwin::lookForRest() {
  const int64_t now = world_->stepCount();
  const int64_t window = std::llround(kStill / params_.step);
  recent_.emplace_back(now, fullPositions());
  while (recent_.size() > 1 && recent_[1].first <= now - window) recent_.erase(recent_.begin());
  if (recent_.front().first > now - window) return;  // not watched for kStill yet
  const RobotModel& full = model_.robots[0].model;
  const RobotModel& form = world_->robotModel(0);
  const Snapshot control = world_->snapshot();
  const std::vector<double>& q = recent_.back().second;
  std::vector<bool> freed = freed_;
  for (size_t j = 0; j < freed.size(); ++j) {
    if (!freed[j]) continue;
    std::vector<bool> trial = freed;
    trial[j] = false;
    const std::vector<int> welded = heldFor(trial);
    bool rest = true;
    for (int k : welded) {
      if (std::binary_search(held_.begin(), held_.end(), k)) continue;
      const size_t i = static_cast<size_t>(k);
      for (const auto& [_, p] : recent_) rest = rest && std::abs(p[i] - q[i]) <= kBand;
      rest = rest && touched_[static_cast<size_t>(full.joints[i].child)] < now - window;
      // Its servo holds a position (a joint driven at a speed or a torque
      // may be still against a stop, but it pushes).
      for (size_t a = 0; a < form.actuators.size(); ++a) {
        const int modelJoint = form.actuators[a].joint;
        const int fullJoint = rigid_ ? rigid_->jointOf[static_cast<size_t>(modelJoint)] : modelJoint;
        if (fullJoint == k) rest = rest && control.robots[0].actuators[a].mode == JointMode::Position;
      }
    }
    if (rest) freed = trial;
  }
  if (freed == freed_) return;
  freed_ = freed;
  switchTo(heldFor(freed_));
}

bool HeldTwin::switchTo(const std::vector<int>& held) {
  if (held == held_) return true;
  const RobotModel& full = model_.robots[0].model;
  std::optional<RigidRobot> rigid;
  WorldModel model = model_;
  if (!held.empty()) {
    std::string why;
    rigid = holdRigid(full, fullPositions(), held, why);
    if (!rigid) return false;
    model.robots[0].model = rigid->model;
  }
  Diagnostics diag;
  std::unique_ptr<World> world = World::create(model, params_, diag);
  if (!world || !carryInto(*world, rigid ? &*rigid : nullptr).empty()) return false;
  auto runner = std::make_unique<Runner>(*world);
  runner->schedule(acting_);
  runner->skipBefore(world->stepCount());
  // The old form lives until the hook has seen the new one (a monitor
  // reads its names when it rebinds).
  const std::unique_ptr<World> old = std::move(world_);
  runner_ = std::move(runner);
  world_ = std::move(world);
  rigid_ = std::move(rigid);
  held_ = held;
  for (size_t j = 0; j < always_.size(); ++j)
    always_[j] = always_[j] && std::binary_search(held_.begin(), held_.end(), static_cast<int>(j));
  recent_.clear();
  ++switches_;
  if (switchHook_) switchHook_(*world_);
  return true;
}

std::string HeldTwin::carryInto(World& to, const RigidRobot* toRigid) {
  const World& from = *world_;
  const RobotModel& a = from.robotModel(0);
  const RobotModel& b = to.robotModel(0);
  const RobotReadout r = readRobot(from);
  const std::vector<double> q = rigid_ ? fullJoints(*rigid_, r.jointPositions) : r.jointPositions;
  const std::vector<double> dq = rigid_ ? fullJoints(*rigid_, r.jointRates, true) : r.jointRates;
  const std::vector<double> toQ = toRigid ? rigidJoints(*toRigid, q) : q;
  const std::vector<double> toDq = toRigid ? rigidJoints(*toRigid, dq) : dq;
  if (std::string why = to.setRobotMotion(
          0, linkMotions(b, r.base, r.baseLinearVelocity, r.baseAngularVelocity, toQ, toDq));
      !why.empty())
    return why;
  const Snapshot was = from.snapshot();
  Snapshot s = to.snapshot();
  // The objects' bodies follow the robot's links in both.
  const size_t objects = was.bodies.size() - a.links.size();
  if (s.bodies.size() - b.links.size() != objects) return "the two forms hold different objects";
  std::copy(was.bodies.end() - static_cast<std::ptrdiff_t>(objects), was.bodies.end(),
            s.bodies.end() - static_cast<std::ptrdiff_t>(objects));
  s.step = was.step;
  s.odeRandom = was.odeRandom;
  s.random = was.random;
  s.terrain = was.terrain;
  s.pending = was.pending;
  for (size_t k = 1; k < s.robots.size(); ++k) {
    s.robots[k] = was.robots[k];
    s.sensors[k] = was.sensors[k];
  }
  // Controllers: the drive and gait as they were; each actuator as it was
  // in the form it leaves, or when it was welded, or (welded since the
  // start) holding where it is, as placeRobot has it.
  const RobotControlState& old = was.robots[0];
  RobotControlState& now = s.robots[0];
  const RobotControlState fresh = now;
  now = old;
  now.actuators = fresh.actuators;
  for (size_t i = 0; i < a.actuators.size(); ++i) welded_[a.actuators[i].name] = old.actuators[i];
  for (size_t i = 0; i < b.actuators.size(); ++i) {
    const ActuatorSpec& spec = b.actuators[i];
    if (const auto it = welded_.find(spec.name); it != welded_.end()) {
      now.actuators[i] = it->second;
    } else if (spec.hasPid && spec.kp > 0 && !spec.continuous) {
      now.actuators[i].mode = JointMode::Position;
      now.actuators[i].target = toQ[static_cast<size_t>(spec.joint)];
      now.actuators[i].integral = 0;
    } else if (spec.mode == JointMode::Velocity) {
      now.actuators[i].velocity = 0;
    }
  }
  // Per link (the motion resistance) and per sensor, by name.
  for (std::vector<double> RobotControlState::*field :
       {&RobotControlState::resistance, &RobotControlState::resistanceShare, &RobotControlState::resistanceHold}) {
    std::vector<double>& into = now.*field;
    into = fresh.*field;
    const std::vector<double>& before = old.*field;
    for (size_t l = 0; l < b.links.size() && l < into.size(); ++l)
      if (const int k = a.findLink(b.links[l].name); k >= 0 && static_cast<size_t>(k) < before.size())
        into[l] = before[static_cast<size_t>(k)];
  }
  for (size_t i = 0; i < b.sensors.size(); ++i)
    for (size_t k = 0; k < a.sensors.size(); ++k)
      if (a.sensors[k].name == b.sensors[i].name) s.sensors[0][i] = was.sensors[0][k];
  return to.restore(s);
}

}  // namespace sp
