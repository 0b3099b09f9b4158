#pragma once
// The ghost's private parts shared by its two files: what the anchor thread
// publishes for the present thread (Base) and what the present thread asks
// of the trail thread (TrailRequest). app/ghost/ghost.cpp holds the Ghost's
// interface and its twins; app/ghost/ghost_threads.cpp its three threads.

#include <cstdint>
#include <memory>

#include "app/ghost/ghost.h"

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
};

}  // namespace sp
