#pragma once
// A session log as a feed (ui/robot_feed.h): the feed owns the log's
// player and the replay's cursor; seeking moves the cursor and the frame,
// scan and ground there follow. The Replay dock (replay_panel.h) is its
// face: its timeline, steps, playback and events all seek through it.
//
// Thread: GUI thread.

#include <cstddef>
#include <memory>

#include "app/log/log_player.h"
#include "ui/robot_feed.h"

namespace sp {

class ReplayFeed : public RobotFeed {
  Q_OBJECT

 public:
  explicit ReplayFeed(QObject* parent = nullptr);
  QString sourceName() const override { return tr("replay"); }
  /// The log's file name ("replay" before one is open).
  QString label() const override;
  QString logPath() const override;
  const WorldModel* shownWorld() const override;

  /// Shows `player`'s log from its start (its world announced:
  /// worldChanged); null closes it.
  void adopt(std::unique_ptr<LogPlayer> player);
  const LogPlayer* player() const { return player_.get(); }
  /// The cursor [s, log time].
  double cursor() const { return cursor_; }
  /// Moves the cursor to `time` (clamped to the log): the frame, scan and
  /// ground there follow, then `moved`.
  void seek(double time);

 signals:
  void moved(double cursor);

 private:
  std::unique_ptr<LogPlayer> player_;
  double cursor_ = 0;
  size_t terrainShown_ = 0;  // terrain edits drawn (those up to the cursor)
};

}  // namespace sp
