#include "ui/jobs/replay/replay_feed.h"

#include <QFileInfo>

#include <algorithm>

namespace sp {

ReplayFeed::ReplayFeed(QObject* parent) : RobotFeed(parent) {}

const WorldModel* ReplayFeed::shownWorld() const { return player_ ? &player_->world() : nullptr; }

QString ReplayFeed::label() const {
  return player_ ? QFileInfo(QString::fromStdString(player_->path())).fileName() : sourceName();
}

QString ReplayFeed::logPath() const { return player_ ? QString::fromStdString(player_->path()) : QString(); }

void ReplayFeed::adopt(std::unique_ptr<LogPlayer> player) {
  player_ = std::move(player);
  if (!player_) return;
  cursor_ = player_->startTime();
  terrainShown_ = 0;  // worldChanged draws the terrain as loaded
  emit worldChanged(player_->world());
}

void ReplayFeed::seek(double time) {
  if (!player_) return;
  cursor_ = std::clamp(time, player_->startTime(), player_->endTime());
  if (std::optional<RobotFrame> f = player_->frameAt(cursor_)) emit frame(*f);
  if (std::optional<LaserFrame> l = player_->laserAt(cursor_)) emit laser(*l);
  if (const size_t edits = player_->terrainEditsAt(cursor_); edits != terrainShown_) {
    terrainShown_ = edits;
    emit terrain(player_->terrainAfter(edits));
  }
  emit moved(cursor_);
}

}  // namespace sp
