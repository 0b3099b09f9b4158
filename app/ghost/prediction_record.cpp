#include "app/ghost/prediction_record.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace sp {

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

void PredictionRecord::shown(double time, double made, const Pose& base, double scale, const ErrorSources& sources,
                             const WheelClearances& clearance) {
  while (!shown_.empty() && shown_.back().time >= time) shown_.pop_back();  // superseded
  shown_.push_back({time, made, base, scale, sources, clearance});
  while (shown_.front().time < time - kShownWindow) shown_.pop_front();
}

std::optional<GhostError> PredictionRecord::compare(const RobotFrame& frame) {
  const auto after = std::lower_bound(shown_.begin(), shown_.end(), frame.time,
                                      [](const Shown& s, double t) { return s.time < t; });
  if (after == shown_.end() || after == shown_.begin() || after->time - frame.time > kMatchWindow ||
      frame.time - std::prev(after)->time > kMatchWindow)
    return std::nullopt;
  const Shown& a = *std::prev(after);
  const Shown& b = *after;
  const double u = b.time > a.time ? (frame.time - a.time) / (b.time - a.time) : 1;
  GhostError e;
  e.time = frame.time;
  e.made = u < 0.5 ? a.made : b.made;
  e.predicted = u < 0.5 ? a.base : b.base;
  e.predicted.p = a.base.p + u * (b.base.p - a.base.p);
  e.scale = a.scale + u * (b.scale - a.scale);
  e.sources = u < 0.5 ? a.sources : b.sources;
  for (size_t w = 0; w < e.clearance.size(); ++w) e.clearance[w] = a.clearance[w] + u * (b.clearance[w] - a.clearance[w]);
  e.position = std::hypot(e.predicted.p.x - frame.base.p.x, e.predicted.p.y - frame.base.p.y);
  e.heading = std::abs(std::remainder(heading(e.predicted.q) - heading(frame.base.q), 2 * kPi));
  errors_.push_back(e);
  while (errors_.front().time < frame.time - kErrorWindow) errors_.pop_front();
  return e;
}

std::optional<std::pair<double, double>> PredictionRecord::median() const {
  if (errors_.empty()) return std::nullopt;
  std::vector<double> position, heading;
  for (const GhostError& e : errors_) {
    position.push_back(e.position);
    heading.push_back(e.heading);
  }
  return std::pair{sp::median(std::move(position)), sp::median(std::move(heading))};
}

std::optional<double> PredictionRecord::worstPosition() const {
  if (errors_.empty()) return std::nullopt;
  double worst = 0;
  for (const GhostError& e : errors_) worst = std::max(worst, e.position);
  return worst;
}

void PredictionRecord::clear() {
  shown_.clear();
  errors_.clear();
}

}  // namespace sp
