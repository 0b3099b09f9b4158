#include "app/ghost/ghost_region.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "sim/kinematics.h"

namespace sp {

double errorScale(const ErrorSources& s, const ErrorModel& m) {
  const double along = s.speed * s.horizon * m.speed;
  const double path = s.speed * s.horizon;
  const double across = m.curvature * path * path / 2;
  const double timing = s.timing * std::hypot(m.arrival, s.spread);
  const double tilt = m.terrain * m.height / m.wheelbase;
  return std::sqrt(m.floor * m.floor + along * along + across * across + timing * timing + tilt * tilt);
}

double commandTiming(const std::vector<std::pair<double, Command>>& commands, double made, double shown, double speed,
                     double wheelbase) {
  double v = 0, phi = 0, timing = 0;
  for (const auto& [time, command] : commands) {
    if (time > shown) break;
    double nv = v, nphi = phi;
    if (const auto* d = std::get_if<DriveCmd>(&command)) {
      nv = d->speed;
      nphi = d->articulation;
    } else if (std::holds_alternative<StopCmd>(command)) {
      nv = 0;
    } else if (std::holds_alternative<TerrainPatchCmd>(command)) {
      continue;
    } else if (time > made) {
      timing += speed;  // a gait or a joint moved: its effect on the base is the layer's to cover
      continue;
    }
    if (time > made) timing += std::abs(nv - v) + std::abs(speed * (nphi - phi)) * (shown - time) / wheelbase;
    v = nv;
    phi = nphi;
  }
  return timing;
}

ErrorModel errorModelFor(const WorldModel& world) {
  ErrorModel m;
  m.terrain = terrainUncertainty(world.terrain);
  if (world.robots.empty()) return m;
  const RobotModel& robot = world.robots[0].model;
  if (!robot.drive) return m;
  const std::array<int, 4>& w = robot.drive->wheels;
  const auto anchor = [&](int k) { return robot.joints[static_cast<size_t>(w[static_cast<size_t>(k)])].anchor; };
  if (std::all_of(w.begin(), w.end(), [&](int j) { return j >= 0 && j < static_cast<int>(robot.joints.size()); })) {
    m.track = std::abs(anchor(0).y - anchor(1).y);
    m.wheelbase = std::abs(anchor(0).x - anchor(2).x);
    if (!robot.links.empty()) m.height = std::max(0.0, robot.links[0].pose.p.z - anchor(0).z + robot.drive->wheelRadius);
  }
  return m;
}

double verticalScale(double horizontal, const ErrorModel& m) {
  const double floor = m.floor * 0.75, across = 0.02 * horizontal;
  return std::sqrt(floor * floor + m.terrain * m.terrain + across * across);
}

WheelClearances wheelClearances(const RobotModel& robot, const std::function<double(double, double)>& ground,
                                const Pose& base, std::span<const double> jointPositions, std::array<Vec3, 4>* hubs) {
  WheelClearances out{kNoClearance, kNoClearance, kNoClearance, kNoClearance};
  if (!robot.drive) return out;
  const std::vector<Pose> links = linkPoses(robot, base, jointPositions);
  constexpr double e = 0.05;  // [m] the slope's finite difference: under a tyre's contact patch
  for (size_t k = 0; k < 4; ++k) {
    const int j = robot.drive->wheels[k];
    if (j < 0 || j >= static_cast<int>(robot.joints.size())) continue;
    const int child = robot.joints[static_cast<size_t>(j)].child;
    if (child < 0 || child >= static_cast<int>(links.size())) continue;
    const Vec3 hub = links[static_cast<size_t>(child)].p;
    if (hubs) (*hubs)[k] = hub;
    const double gx = (ground(hub.x + e, hub.y) - ground(hub.x - e, hub.y)) / (2 * e);
    const double gy = (ground(hub.x, hub.y + e) - ground(hub.x, hub.y - e)) / (2 * e);
    // The hub's height above the ground's tangent plane, along its normal.
    out[k] = (hub.z - ground(hub.x, hub.y)) / std::sqrt(1 + gx * gx + gy * gy) - robot.drive->wheelRadius;
  }
  return out;
}

double groundDiscrepancy(const WheelClearances& predicted, const WheelClearances& actual, int* worst) {
  double most = 0;
  if (worst) *worst = -1;
  for (size_t k = 0; k < predicted.size(); ++k)
    if (predicted[k] < kLiftedClearance && std::isfinite(actual[k]) && std::abs(actual[k] - predicted[k]) > most) {
      most = std::abs(actual[k] - predicted[k]);
      if (worst) *worst = static_cast<int>(k);
    }
  return most;
}

double gaussianMultiplier(double level) { return std::sqrt(-2 * std::log(1 - level)); }

std::string ConformalLayer::checkLevels(const std::vector<double>& levels) {
  if (levels.empty()) return "no level given";
  for (size_t i = 0; i < levels.size(); ++i) {
    const double p = levels[i];
    if (!(p > 0 && p < 1)) {
      char text[96];
      std::snprintf(text, sizeof text, "level %g is not inside (0, 1)", p);
      return text;
    }
    if (i > 0 && !(p > levels[i - 1])) return "levels must ascend";
  }
  return "";
}

ConformalLayer::ConformalLayer(Options options) : options_(std::move(options)) {
  if (const std::string why = checkLevels(options_.levels); !why.empty()) throw std::invalid_argument(why);
  clear();
}

void ConformalLayer::clear() {
  window_.clear();
  alpha_ = options_.levels;
  multipliers_.clear();
  for (double p : options_.levels) multipliers_.push_back(gaussianMultiplier(p));
  hits_.assign(options_.levels.size(), 0);
  judged_ = 0;
}

void ConformalLayer::judge(double score) {
  if (!std::isfinite(score) || score < 0) return;
  ++judged_;
  for (size_t i = 0; i < multipliers_.size(); ++i) hits_[i] += score <= multipliers_[i];
}

void ConformalLayer::learn(double time, double score) {
  if (!std::isfinite(score) || score < 0) return;
  // Adaptive conformal inference: a miss raises the level the quantile is
  // taken at, a hit lowers it, so that misses come at 1 - level.
  // A high level's step is smaller in proportion (at 99 %, a tenth): with
  // one step for all, two misses in a row would take 0.99 to 1 and the
  // region to the largest score seen.
  if (options_.gamma > 0)
    for (size_t i = 0; i < alpha_.size(); ++i) {
      const bool hit = score <= multipliers_[i];
      const double gamma = options_.gamma * std::min(1.0, 10 * (1 - options_.levels[i]));
      alpha_[i] = std::clamp(alpha_[i] + gamma * ((hit ? 0.0 : 1.0) - (1 - options_.levels[i])), 0.0, 1.0);
    }
  window_.push_back({time, score});
  while (!window_.empty() && window_.front().time < time - options_.window) window_.pop_front();
  update();
}

void ConformalLayer::update() {
  const size_t n = window_.size();
  if (n < static_cast<size_t>(options_.minScores)) {
    for (size_t i = 0; i < multipliers_.size(); ++i) multipliers_[i] = gaussianMultiplier(options_.levels[i]);
    return;
  }
  std::vector<double> scores;
  scores.reserve(n);
  for (const Score& s : window_) scores.push_back(s.score);
  std::sort(scores.begin(), scores.end());
  for (size_t i = 0; i < multipliers_.size(); ++i) {
    // The split-conformal quantile: the ceil((n + 1) level)-th smallest;
    // a level past what n scores can hold takes the largest, widened by
    // how far past (a level of 1 after a run of misses: the region grows
    // until it holds again).
    const double level = alpha_[i];
    const double rank = std::ceil((static_cast<double>(n) + 1) * level);
    if (rank < 1) multipliers_[i] = scores.front();
    else if (rank <= static_cast<double>(n)) multipliers_[i] = scores[static_cast<size_t>(rank) - 1];
    else multipliers_[i] = scores.back() * (1 + (level - static_cast<double>(n) / static_cast<double>(n + 1)) * 4);
  }
}

double ConformalLayer::multiplierAt(double level) const {
  size_t best = 0;
  for (size_t i = 1; i < options_.levels.size(); ++i)
    if (std::abs(options_.levels[i] - level) < std::abs(options_.levels[best] - level)) best = i;
  return multipliers_[best];
}

std::optional<double> ConformalLayer::coverage(size_t i) const {
  if (judged_ == 0) return std::nullopt;
  return static_cast<double>(hits_.at(i)) / static_cast<double>(judged_);
}

std::string Departure::describe() const {
  char text[240];
  if (vertical > error)
    std::snprintf(text, sizeof text,
                  "the robot departs from its twin at (%.1f, %.1f): a wheel stands %.0f cm off the ground the map has "
                  "there (%.0f cm from where it was predicted): the ground or the robot differ from the files there",
                  where.x, where.y, vertical * 100, error * 100);
  else
    std::snprintf(text, sizeof text,
                  "the robot departs from its twin by %.0f cm at (%.1f, %.1f): the ground or the robot differ from the "
                  "files there",
                  error * 100, where.x, where.y);
  return text;
}

DepartureWatch::Change DepartureWatch::judge(double time, const Vec3& where, double error, double radius,
                                             double vertical, double verticalLimit, const std::optional<Vec3>& wheel) {
  const bool away = error > radius && error > options_.minimum;
  const bool off = vertical > verticalLimit && vertical > options_.minimumVertical;
  const bool outside = away || off;
  if (departing()) {
    last_->error = std::max(last_->error, error);
    last_->vertical = std::max(last_->vertical, vertical);
    last_->ground |= off;
    if (outside) {
      insideSince_ = -1;
      return Change::None;
    }
    if (insideSince_ < 0) insideSince_ = time;
    if (time - insideSince_ < options_.clear) return Change::None;
    last_->ended = time;
    insideSince_ = -1;
    outsideSince_ = -1;
    return Change::Ended;
  }
  if (!outside) {
    if (outsideSince_ >= 0 && time - outsideLast_ > options_.gap) outsideSince_ = -1;
    return Change::None;
  }
  outsideLast_ = time;
  if (outsideSince_ < 0) {
    outsideSince_ = time;
    outsideWhere_ = !away && wheel ? *wheel : where;
    outsideWorst_ = outsideVertical_ = 0;
    outsideGround_ = false;
  }
  outsideWorst_ = std::max(outsideWorst_, error);
  outsideVertical_ = std::max(outsideVertical_, vertical);
  outsideGround_ |= off;
  if (time - outsideSince_ < options_.hold) return Change::None;
  last_ = Departure{outsideSince_, outsideWhere_, outsideWorst_, outsideVertical_, -1, outsideGround_};
  ++count_;
  insideSince_ = -1;
  return Change::Began;
}

void DepartureWatch::clear() {
  outsideSince_ = insideSince_ = -1;
  last_.reset();
  count_ = 0;
}

}  // namespace sp
