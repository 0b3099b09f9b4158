#pragma once
// The commands the operator sent, each with the robot time it takes effect
// (ghost(sent): app/ghost/ghost_clock.h) and a sequence number, so that each
// of the ghost's threads can ask for the ones it has not applied yet.
//
// Thread: a plain value; its owner guards it (the Ghost's mutex).

#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "sim/command.h"

namespace sp {

/// A command on its way to the robot.
struct SentCommand {
  uint64_t seq = 0;   ///< counts commands sent
  double time = 0;    ///< [s] robot time it takes effect
  Command command;
};

class InFlightCommands {
 public:
  /// `command` takes effect at robot time `time`; returns its seq.
  uint64_t add(const Command& command, double time);
  /// The commands with seq >= `from`, oldest first.
  std::vector<SentCommand> from(uint64_t seq) const;
  /// The commands that take effect at robot times up to `upTo`, with
  /// those times, oldest first (as far back as they are remembered; the
  /// newest drive or stop forgotten first), terrain patches left out.
  std::vector<std::pair<double, Command>> upTo(double upTo) const;
  /// Forgets commands that took effect before robot time `time` (they are
  /// in the anchored state's set-points by then).
  void forgetBefore(double time);
  /// Forgets every command (the robot was reset); seqs go on counting.
  void clear() {
    commands_.clear();
    lastDrive_.reset();
  }
  /// Commands sent so far: the next seq.
  uint64_t sent() const { return next_; }

 private:
  std::deque<SentCommand> commands_;  // oldest first
  std::optional<SentCommand> lastDrive_;  // the newest drive or stop forgotten: the set-point before commands_
  uint64_t next_ = 0;
};

}  // namespace sp
