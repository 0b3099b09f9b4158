#include "app/console/console_state.h"

#include <cmath>
#include <cstdio>

namespace sp {

namespace {

// Fixed decimals in the C locale's form ("4.8"), as the operator reads it.
std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

}  // namespace

bool ConsoleState::connection(net::ConnectionState state, std::string detail) {
  connection_ = state;
  connectionDetail_ = std::move(detail);
  bool lost = false;
  if (state != net::ConnectionState::Ready) {
    lost = lease_;
    lease_ = false;
    // Staleness is a connected robot that went quiet; a dropped link says so itself.
    stale_ = false;
    // What was in flight may never land: the banner says the link is down.
    estopInFlight_ = rearmInFlight_ = false;
  }
  ++revision_;
  return lost;
}

bool ConsoleState::lease(bool yours) {
  const bool lost = lease_ && !yours;
  if (lease_ != yours) ++revision_;
  lease_ = yours;
  return lost;
}

void ConsoleState::failsafeReason(std::string text) {
  failsafeReason_ = std::move(text);
  ++revision_;
}

void ConsoleState::filesMismatch(std::string text) {
  if (text == filesMismatch_) return;
  filesMismatch_ = std::move(text);
  ++revision_;
}

void ConsoleState::departure(std::string text) {
  if (text == departure_) return;
  departure_ = std::move(text);
  ++revision_;
}

void ConsoleState::terrain(bool heightfield, double width, double depth) {
  heightfield_ = heightfield;
  terrainWidth_ = width;
  terrainDepth_ = depth;
  ++revision_;
}

FrameChanges ConsoleState::frame(const RobotFrame& f, double wall, std::optional<double> edge) {
  FrameChanges changes;
  // Odometry before haveFrame_ changes: the first frame only sets the start.
  const double dx = f.base.p.x - odometry_.x, dy = f.base.p.y - odometry_.y;
  const double step = std::hypot(dx, dy), dt = f.time - odometryTime_;
  if (haveFrame_ && step < 1.0) odometry_.distance += step;
  if (f.hasBaseVelocity) odometry_.speed = std::hypot(f.baseLinearVelocity.x, f.baseLinearVelocity.y);
  else if (haveFrame_ && dt > 0 && step < 1.0) odometry_.speed = step / dt;
  odometry_.x = f.base.p.x;
  odometry_.y = f.base.p.y;
  odometry_.heading = heading(f.base.q);
  odometryTime_ = f.time;
  lastFrameWall_ = now_ = wall;
  haveFrame_ = true;
  if (stale_) {
    stale_ = false;
    changes.staleEnded = true;
    ++revision_;
  }
  // Near a heightfield's edge the operator is warned before the robot
  // drives off into a fall (and a divergence); the distance shown moves in
  // 0.1 m steps so the banner is not rewritten at every frame.
  const bool wasNear = nearEdge();
  edge_ = edge;
  if (wasNear != nearEdge() || (nearEdge() && std::abs(*edge_ - shownEdge_) > 0.1)) {
    shownEdge_ = edge_.value_or(0);
    changes.banner = true;
  }
  // What was in flight has landed once the robot reports it.
  if ((estopInFlight_ && f.estop) || (rearmInFlight_ && !f.estop && !f.failsafe)) {
    estopInFlight_ = estopInFlight_ && !f.estop;
    rearmInFlight_ = rearmInFlight_ && (f.estop || f.failsafe);
    changes.banner = true;
  }
  if (f.failsafe != failsafe_ || f.estop != estop_ || f.health != health_) {
    changes.latchedNow = (f.failsafe && !failsafe_) || (f.estop && !estop_);
    if (!f.failsafe) failsafeReason_.clear();  // the next failsafe has its own
    failsafe_ = f.failsafe;
    estop_ = f.estop;
    health_ = f.health;
    changes.latches = true;
    changes.banner = true;
  }
  if (changes.banner) ++revision_;
  return changes;
}

void ConsoleState::estopSent(double landsIn, double wall) {
  estopInFlight_ = true;
  rearmInFlight_ = false;
  estopLandsIn_ = landsIn;
  estopSentAt_ = now_ = wall;
  ++revision_;
}

void ConsoleState::rearmSent(double landsIn, double wall) {
  if (!latched()) return;
  rearmInFlight_ = true;
  rearmLandsIn_ = landsIn;
  rearmSentAt_ = now_ = wall;
  ++revision_;
}

std::string ConsoleState::estopPressedText(bool queued) const {
  const std::string live = replaying() ? " to the live robot" : "";
  if (connected()) return "E-STOP sent" + live;
  if (queued)
    return "E-STOP NOT sent" + live + ": the link is down; it goes out when the robot answers again. The robot's "
           "own deadman stops it meanwhile.";
  return "E-STOP NOT sent" + live + ": not connected to the robot";
}

std::string ConsoleState::inFlightText(const char* what, double landsIn, double sentAt) const {
  if (landsIn < 0) return std::string(what) + " in flight: the round trip is not measured yet";
  const double left = landsIn - (now_ - sentAt);
  if (left > 0) return std::string(what) + " in flight: lands in ~" + fixed(left, 1) + " s";
  return std::string(what) + " should have landed (sent " + fixed(now_ - sentAt, 1) +
         " s ago); waiting for the robot's report";
}

bool ConsoleState::tick(double wall) {
  now_ = wall;
  // The countdown of what is in flight moves in tenths of a second.
  if (estopInFlight_ || rearmInFlight_) {
    const double sentAt = estopInFlight_ ? estopSentAt_ : rearmSentAt_;
    const double landsIn = estopInFlight_ ? estopLandsIn_ : rearmLandsIn_;
    const auto shown = static_cast<int64_t>(std::floor(std::max(0.0, landsIn - (wall - sentAt)) * 10));
    if (shown != shownCountdown_) {
      shownCountdown_ = shown;
      ++revision_;
    }
  }
  const bool stale = connected() && haveFrame_ && wall - lastFrameWall_ > config_.staleAfter;
  if (stale == stale_) return false;
  stale_ = stale;
  ++revision_;
  return true;
}

void ConsoleState::clearFrames() {
  haveFrame_ = false;
  odometry_ = {};
  stale_ = false;
  edge_.reset();
  shownEdge_ = 0;
  ++revision_;
}

void ConsoleState::replay(std::string label) {
  replay_ = std::move(label);
  ++revision_;
}

void ConsoleState::realTime(double factor, double target, double wall) {
  if (!(factor > 0) || !(target > 0) || !connected()) {
    slowSince_ = -1;
    if (slowTwin_) {
      slowTwin_ = false;
      ++revision_;
    }
    return;
  }
  targetFactor_ = target;
  if (factor < 0.8 * target) {
    if (slowSince_ < 0) slowSince_ = wall;
  } else {
    slowSince_ = -1;
  }
  const bool slow = slowTwin_ ? factor < 0.9 * target : slowSince_ >= 0 && wall - slowSince_ >= 3;
  // The figure shown moves in steps of 0.05: the banner is not rewritten every tick.
  const double shown = std::round(factor * 20) / 20;
  if (slow != slowTwin_ || (slow && shown != shownFactor_)) {
    slowTwin_ = slow;
    shownFactor_ = shown;
    ++revision_;
  }
}

std::string ConsoleState::poseText() const {
  if (!haveFrame_) return {};
  constexpr double kDegrees = 180 / 3.14159265358979323846;
  // Rounded first, so that a hair below zero reads 0.00, not -0.00.
  const auto shown = [](double v, int decimals) {
    const double scale = std::pow(10.0, decimals);
    return fixed(std::round(v * scale) / scale + 0.0, decimals);
  };
  return "x " + shown(odometry_.x, 2) + " m  y " + shown(odometry_.y, 2) + " m  heading " +
         shown(odometry_.heading * kDegrees, 1) + "°";
}

std::string ConsoleState::motionText() const {
  if (!haveFrame_) return {};
  return fixed(odometry_.speed, 2) + " m/s, " + fixed(odometry_.distance, 1) + " m driven";
}

std::string ConsoleState::staleText(double wall) const {
  if (replaying() || !haveFrame_) return {};
  const std::string age = fixed(dataAge(wall), 1);
  // A robot last seen before the link went down is as old as a quiet one
  // (issue 59: it stayed drawn in full colour, as if live).
  if (!connected()) return "not connected: the robot drawn is where it was " + age + " s ago";
  if (!stale_) return {};
  return "no data " + age + " s: the robot drawn is where it was " + age + " s ago";
}

std::vector<std::string> ConsoleState::bannerLines() const {
  std::vector<std::string> lines;
  // While a replay is shown, the live robot's alarms still reach the
  // operator, saying which robot they are about.
  const std::string live = replaying() ? "Live robot: " : "";
  if (replaying())
    lines.push_back("Replay of " + replay_ + ": the live robot is not shown and the drive keys act on nothing. "
                    "Close the replay to drive.");
  if (!health_.empty()) lines.push_back(live + "The twin diverged and stopped: " + health_);
  // In flight first: the operator must see at once that the stop is on
  // its way, not two seconds later when the robot reports it.
  if (estopInFlight_)
    lines.push_back(live + inFlightText("E-STOP", estopLandsIn_, estopSentAt_) +
                    "; the robot drives on until then (the ghost shows where it stops).");
  // One line for the latches, whichever are on: what latched, why, and
  // what to do, each said once.
  if (latched()) {
    const std::string what = estop_ && failsafe_ ? "E-STOP and FAILSAFE latched" : estop_ ? "E-STOP latched" : "FAILSAFE latched";
    const std::string why = !failsafe_               ? "the robot is stopped"
                            : failsafeReason_.empty() ? "the robot stopped itself (its reason did not reach this console: see the robot's log)"
                                                      : failsafeReason_ + "; the robot stopped";
    const std::string next = rearmInFlight_ ? inFlightText("Re-arm", rearmLandsIn_, rearmSentAt_) + "."
                                            : std::string("Re-arm to continue.");
    lines.push_back(live + what + ": " + why + ". " + next);
  }
  if (nearEdge() && !replaying()) {
    lines.push_back(*edge_ < 0 ? "The robot is off the terrain (" + fixed(-*edge_, 1) +
                                     " m beyond its edge): Robot ▸ Reset puts it back."
                               : "Near the terrain's edge: " + fixed(*edge_, 1) + " m to the edge of the " +
                                     fixed(terrainWidth_, 1) + " × " + fixed(terrainDepth_, 1) +
                                     " m heightfield; beyond it the robot falls.");
  }
  if (!filesMismatch_.empty()) lines.push_back(live + filesMismatch_);
  if (!departure_.empty())
    lines.push_back(live + "The ghost cannot be trusted here: " + departure_ +
                    ". The calibration leaves this stretch out.");
  if (slowTwin_ && !replaying())
    lines.push_back("The stand-in's twin runs at " + fixed(shownFactor_, 2) + " × real time (asked " +
                    fixed(targetFactor_, 2) + "): this machine cannot keep up, and the robot, its deadman and the "
                    "ghost run slow with it.");
  if (connection_ == net::ConnectionState::Waiting || connection_ == net::ConnectionState::Refused)
    lines.push_back(live + "Robot link down (" + connectionDetail_ + "): the robot's own deadman stops it; reconnecting.");
  return lines;
}

bool ConsoleState::bannerAlarm() const {
  return latched() || estopInFlight_ || !health_.empty() || (nearEdge() && *edge_ < 0) ||
         connection_ == net::ConnectionState::Waiting || connection_ == net::ConnectionState::Refused;
}

std::string ConsoleState::controlsRefusal() const {
  if (replaying()) return "A replay is shown: close it (File ▸ Close replay) to drive the live robot";
  if (!connected()) return "Not connected to the robot";
  if (!lease_) return "Take control first (Robot ▸ Take control)";
  if (estopInFlight_) return inFlightText("E-STOP", estopLandsIn_, estopSentAt_);
  if (latched() && rearmInFlight_) return inFlightText("Re-arm", rearmLandsIn_, rearmSentAt_);
  if (latched()) return "The robot is stopped and latched: re-arm first";
  return {};
}

HealthStatus ConsoleState::health() const {
  if (replaying()) return {"replay", HealthLevel::Neutral, "The views show a logged session, not the live robot"};
  if (!health_.empty()) return {"diverged", HealthLevel::Alarm, health_};
  if (stale_) return {"no data", HealthLevel::Warning, {}};
  if (!connected()) return {"not connected", HealthLevel::Neutral, {}};
  if (haveFrame_) return {"healthy", HealthLevel::Good, {}};
  return {"no telemetry", HealthLevel::Neutral, {}};
}

}  // namespace sp
