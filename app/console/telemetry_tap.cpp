// Telemetry's one way in (app/console/telemetry_tap.h).
#include "app/console/telemetry_tap.h"

#include <cstdio>

#include "app/calibration/live_calibrator.h"
#include "app/ghost/ghost.h"
#include "app/log/telemetry_recorder.h"
#include "app/robot/stand_in.h"
#include "app/state/robot_shapes.h"

namespace sp {

void TelemetryTap::bind(const Parts& parts) {
  std::lock_guard lock(mutex_);
  parts_ = parts;
  positions_.reset();
  rates_.reset();
  rate_.reset();
  lastPrediction_.reset();
  frames_ = 0;
}

TelemetryTap::Tapped TelemetryTap::telemetry(const net::TelemetryMsg& t, double wall, double roundTrip) {
  std::lock_guard lock(mutex_);
  Tapped out;
  out.frame = frameFromTelemetry(t, parts_.robot, positions_, rates_);
  const RobotFrame& f = out.frame;
  ++frames_;
  rate_.add(wall, t.time);
  if (!parts_.robot) return out;
  if (parts_.recorder) parts_.recorder->telemetry(t, *parts_.robot);
  if (parts_.ghost && !f.health.empty()) {
    // A diverged robot twin reports no state to predict from.
    parts_.ghost->halt("the robot's twin diverged: " + f.health);
    lastPrediction_.reset();
  } else if (parts_.ghost) {
    lastPrediction_ = parts_.ghost->anchor(f, roundTrip > 0 ? roundTrip : t.rttMs / 1000);
    if (lastPrediction_) logPrediction(*lastPrediction_);
    if (lastPrediction_ && lastPrediction_->departure != 0) logDeparture();
  }
  if (parts_.calibrator) parts_.calibrator->frame(f, lastPrediction_ && lastPrediction_->suspect);
  out.prediction = lastPrediction_;
  return out;
}

void TelemetryTap::laser(const net::LaserMsg& m) {
  std::lock_guard lock(mutex_);
  if (parts_.recorder) parts_.recorder->laser(m);
}

void TelemetryTap::logPrediction(const GhostError& e) {
  LogPrediction p;
  p.time = e.time;
  p.made = e.made;
  p.base = {e.predicted.p.x, e.predicted.p.y, e.predicted.p.z};
  p.quat = {e.predicted.q.w, e.predicted.q.x, e.predicted.q.y, e.predicted.q.z};
  p.positionError = e.position;
  p.headingError = e.heading;
  if (parts_.recorder) parts_.recorder->prediction(p);
  else if (parts_.standIn) parts_.standIn->logPrediction(p);
}

void TelemetryTap::logDeparture() {
  const std::vector<Departure> all = parts_.ghost->departures();
  if (all.empty()) return;
  const Departure& d = all.back();
  std::string text = d.describe();
  if (d.ended >= 0) {
    char back[160];
    std::snprintf(back, sizeof back,
                  "the robot is back inside its twin's region (it departed by %.0f cm at (%.1f, %.1f) for %.1f s)",
                  d.error * 100, d.where.x, d.where.y, d.ended - d.time);
    text = back;
  }
  if (parts_.recorder) parts_.recorder->event("departure", text);
  else if (parts_.standIn) parts_.standIn->logEvent("departure", text);
}

std::optional<GhostError> TelemetryTap::lastPrediction() const {
  std::lock_guard lock(mutex_);
  return lastPrediction_;
}

double TelemetryTap::realTimeFactor() const {
  std::lock_guard lock(mutex_);
  return rate_.factor();
}

uint64_t TelemetryTap::frames() const {
  std::lock_guard lock(mutex_);
  return frames_;
}

}  // namespace sp
