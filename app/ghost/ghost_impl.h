#pragma once
// The ghost's private parts shared by its two files: what the anchor thread
// publishes for the present thread (Base), what the present thread asks
// of the trail thread (TrailRequest), and the anchor thread's own state. app/ghost/ghost.cpp holds the Ghost's
// interface and its twins; app/ghost/ghost_threads.cpp its three threads.

#include <cstdint>
#include <memory>

#include "app/ghost/ghost.h"
#include "app/ghost/hold_policy.h"

namespace sp {

struct Ghost::Base {
  std::shared_ptr<const Twin> twin;  // what the snapshot is of
  Snapshot snapshot;
  double time = 0;       // robot time of the snapshot
  uint64_t nextSeq = 0;  // the first command not in it
  double made = 0;       // robot time of the telemetry it was anchored on
  bool latched = false;  // that telemetry reported an e-stop or failsafe
};

struct Ghost::TrailRequest {
  std::shared_ptr<const Twin> twin;
  Snapshot snapshot;
  double time = 0;
  uint64_t nextSeq = 0;
  bool latched = false;
  bool urgent = false;  // commands changed: the trail running now is wrong
  double made = 0;      // robot time of the telemetry its base was anchored on (the band's horizon)
};

// What the anchor thread keeps from one re-anchoring to the next.
struct Ghost::AnchorRun {
  AnchorRun(const std::vector<int>& held, const RobotModel& model) : robot(model), policy(held, robot) {}
  const RobotModel robot;  // its joints (model_ may be recalibrated)
  HoldPolicy policy;
  std::shared_ptr<const Twin> twin;
  std::unique_ptr<World> world;
  Snapshot anchored;  // the last anchored state, commands in effect included
  uint64_t seen = 0, applied = 0, epoch = 0, rung = 0;
  double lastStart = -1e9;
};

// One re-anchoring's input: the newest frame and the commands around it.
struct Ghost::AnchorInput {
  RobotFrame frame;
  std::vector<SentCommand> effective, pending;  // in effect by the frame's time; still in flight
  double target = 0;  // robot time to run to
  bool recalibrated = false;
};

}  // namespace sp
