#pragma once
// The status bar's permanent fields: terrain, ghost, time, real-time factor,
// health and log. They describe what the views show: while a replay is
// shown, its time and terrain, and the ghost off.
//
// Thread: GUI thread only.

#include <QObject>
#include <QString>

class QLabel;
class QStatusBar;

namespace sp {

class ConsoleSession;
class ConsoleState;
class LiveLinkFeed;
struct TerrainSpec;

class StatusFields : public QObject {
  Q_OBJECT

 public:
  /// Adds the fields to `bar`.
  explicit StatusFields(QStatusBar* bar);
  /// Everything from the state, the session and the live link's newest telemetry.
  void refresh(const ConsoleState& state, const ConsoleSession& session, const LiveLinkFeed& live);
  /// The replayed frame's time.
  void showReplayTime(double time);
  /// The terrain drawn; `replay` when it is a replayed log's; `edgeWarning`
  /// [m]: the console warns that near a heightfield's edge.
  void showTerrain(const TerrainSpec& terrain, bool replay, double edgeWarning);
  /// The ghost field's text ("ghost +1.02 s, 1.3 cm / 0.2°").
  QString ghostText() const;

 private:
  QLabel* terrain_ = nullptr;
  QLabel* ghost_ = nullptr;
  QLabel* time_ = nullptr;
  QLabel* rtf_ = nullptr;
  QLabel* health_ = nullptr;
  QLabel* log_ = nullptr;
};

}  // namespace sp
