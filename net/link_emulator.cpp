#include "net/link_emulator.h"

#include <algorithm>

namespace sp::net {

LinkEmulator::LinkEmulator(LinkEmulatorConfig config) : config_(config), engine_(config.seed) {}

void LinkEmulator::setConfig(const LinkEmulatorConfig& config) {
  config_ = config;
  engine_.seed(config.seed);
}

double LinkEmulator::uniform01() {
  // The top 53 bits make a double in [0, 1) exactly.
  return static_cast<double>(engine_() >> 11) * 0x1.0p-53;
}

std::optional<double> LinkEmulator::schedule(size_t bytes, double now) {
  ++sent_;
  bytes_ += bytes;
  // Draw both numbers for every frame, so that changing the loss does not
  // shift the jitter of the frames that get through.
  const double lossDraw = uniform01();
  const double jitterDraw = uniform01();
  if (config_.loss > 0 && lossDraw < config_.loss) {
    ++dropped_;  // a lost frame takes no bandwidth and does not hold others up
    return std::nullopt;
  }
  double leaves = std::max(now, fadeUntil_);
  if (config_.bandwidth > 0) {
    // Frames queue behind each other on the link at `bandwidth` bytes/s.
    linkFreeAt_ = std::max(linkFreeAt_, leaves) + static_cast<double>(bytes) / config_.bandwidth;
    leaves = linkFreeAt_;
  }
  const double delay = std::max(0.0, config_.delay + config_.jitter * (2 * jitterDraw - 1));
  double due = leaves + delay;
  if (config_.keepOrder) due = std::max(due, lastDue_);
  lastDue_ = std::max(lastDue_, due);
  return due;
}

}  // namespace sp::net
