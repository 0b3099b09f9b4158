#pragma once
// The link dock: connection state, round-trip time, telemetry rate and
// loss, the lease and the failsafe and e-stop latches, with the buttons to
// connect, take or release control, e-stop and re-arm.
//
// Thread: GUI thread only.

#include <QWidget>

#include "net/message.h"
#include "net/robot_client.h"

class QLabel;
class QPlainTextEdit;
class QPushButton;

namespace sp {

class ElidedLabel;

class LinkPanel : public QWidget {
  Q_OBJECT

 public:
  explicit LinkPanel(QWidget* parent = nullptr);

  /// Refreshes the figures from the client's statistics (called a few
  /// times a second) and the latches from the latest telemetry.
  void showStats(const net::RobotClientStats& stats);
  void showConnection(net::ConnectionState state, const QString& detail);
  void showLease(const net::LeaseStateMsg& lease);
  void showLatches(bool failsafe, bool estop);
  /// The robot's pose and motion read-outs (ConsoleState::poseText(),
  /// motionText(); "" shows a dash).
  void showOdometry(const QString& pose, const QString& motion);
  QString poseText() const;
  /// Where the console connects, e.g. "127.0.0.1:47800 (stand-in)".
  void setEndpoint(const QString& endpoint);
  /// Adds a line to the link's event list (replies refused, robot events,
  /// connection changes), stamped with the wall-clock time.
  void appendEvent(const QString& text);
  QStringList events() const;  ///< the list's lines, oldest first
  /// The whole texts of the link and latch fields (they show elided).
  QString stateText() const;
  QString latchesText() const;

  bool leaseHeld() const { return leaseHeld_; }

 signals:
  void connectRequested();
  void disconnectRequested();
  void takeControlRequested();
  void releaseControlRequested();
  void estopRequested();
  void rearmRequested();

 private:
  ElidedLabel* endpoint_ = nullptr;
  ElidedLabel* state_ = nullptr;
  ElidedLabel* rtt_ = nullptr;
  ElidedLabel* rate_ = nullptr;
  ElidedLabel* loss_ = nullptr;
  ElidedLabel* lease_ = nullptr;
  ElidedLabel* latches_ = nullptr;
  ElidedLabel* deadman_ = nullptr;  // the robot's, from WELCOME
  ElidedLabel* pose_ = nullptr;
  ElidedLabel* motion_ = nullptr;
  QPushButton* connect_ = nullptr;
  QPushButton* control_ = nullptr;
  QPushButton* estop_ = nullptr;
  QPushButton* rearm_ = nullptr;
  QPlainTextEdit* events_ = nullptr;
  bool open_ = false;
  bool leaseHeld_ = false;
  bool ready_ = false, latched_ = false;  // Re-arm is offered only when both
};

}  // namespace sp
