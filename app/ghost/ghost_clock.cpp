#include "app/ghost/ghost_clock.h"

#include <algorithm>
#include <cmath>

namespace sp {

bool GhostClock::frame(double robotTime, double wall, double roundTrip) {
  const bool reset = haveClock_ && robotTime < newest_;
  if (reset) offsets_.clear();
  offsets_.emplace_back(wall, robotTime - wall);
  while (offsets_.front().first < wall - kOffsetWindow) offsets_.pop_front();
  offset_ = offsets_.front().second;
  for (const auto& [arrival, offset] : offsets_) offset_ = std::max(offset_, offset);
  roundTrip_ = std::isfinite(roundTrip) && roundTrip > 0 ? roundTrip : 0;
  haveClock_ = true;
  newest_ = robotTime;
  return reset;
}

double GhostClock::spread() const {
  if (offsets_.size() < 2) return 0;
  double mean = 0;
  for (const auto& o : offsets_) mean += o.second;
  mean /= static_cast<double>(offsets_.size());
  double sum = 0;
  for (const auto& o : offsets_) sum += (o.second - mean) * (o.second - mean);
  return std::sqrt(sum / static_cast<double>(offsets_.size() - 1));
}

}  // namespace sp
