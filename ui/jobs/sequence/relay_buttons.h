#pragma once
// The Sequence dock's relay (ui/jobs/sequence/sequence_panel.h): Send to
// robot, enabled only for a sequence the workflow's gate lets through, and
// Abort, enabled while a sent sequence runs on the robot.
//
// Thread: GUI thread.

#include <QWidget>

class QPushButton;

namespace sp {

class RelayButtons : public QWidget {
  Q_OBJECT

 public:
  explicit RelayButtons(QWidget* parent = nullptr);
  /// `canSend`: the gate lets the rehearsed sequence through; `running`:
  /// a sent one runs (or waits for the robot's answer).
  void setStates(bool canSend, bool running);
  QPushButton* sendButton() const { return send_; }
  QPushButton* abortButton() const { return abort_; }

 signals:
  void sendClicked();
  void abortClicked();

 private:
  QPushButton* send_ = nullptr;
  QPushButton* abort_ = nullptr;
};

}  // namespace sp
