#include "ui/link_panel.h"

#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QPlainTextEdit>
#include <QTime>
#include <QPushButton>
#include <QVBoxLayout>

#include <algorithm>

#include "ui/icons.h"

namespace sp {

namespace {

}  // namespace

/// A one-line label that elides its text to the width it is given, with the
/// whole text as its tooltip: a long error or robot name never widens the
/// dock.
class ElidedLabel : public QLabel {
 public:
  ElidedLabel() {
    setSizePolicy(QSizePolicy::Ignored, QSizePolicy::Preferred);
    setMinimumWidth(40);
    setTextInteractionFlags(Qt::TextSelectableByMouse);
  }
  void setFullText(const QString& text, const char* colour = nullptr) {
    full_ = text;
    setStyleSheet(colour ? QStringLiteral("QLabel { color: %1; font-weight: bold; }").arg(QLatin1String(colour)) : QString());
    setToolTip(text);
    elide();
  }
  QString fullText() const { return full_; }

 protected:
  void resizeEvent(QResizeEvent* event) override {
    QLabel::resizeEvent(event);
    elide();
  }

 private:
  void elide() { setText(fontMetrics().elidedText(full_, Qt::ElideRight, std::max(width(), 40))); }
  QString full_;
};

LinkPanel::LinkPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  auto* form = new QFormLayout;
  endpoint_ = new ElidedLabel;
  state_ = new ElidedLabel;
  rtt_ = new ElidedLabel;
  rate_ = new ElidedLabel;
  loss_ = new ElidedLabel;
  lease_ = new ElidedLabel;
  latches_ = new ElidedLabel;
  deadman_ = new ElidedLabel;
  pose_ = new ElidedLabel;
  pose_->setObjectName(QStringLiteral("poseLabel"));
  pose_->setToolTip(tr("The robot's base by its newest telemetry: position on the ground and heading"));
  motion_ = new ElidedLabel;
  motion_->setObjectName(QStringLiteral("motionLabel"));
  motion_->setToolTip(tr("Ground speed as the robot reports it, and the distance driven since the session began"));
  deadman_->setToolTip(tr("The robot's deadman: it stops (failsafe) when the controller's keep-alives stop arriving for this long"));
  form->addRow(tr("robot"), endpoint_);
  form->addRow(tr("link"), state_);
  form->addRow(tr("round trip"), rtt_);
  form->addRow(tr("telemetry"), rate_);
  form->addRow(tr("lost"), loss_);
  form->addRow(tr("control"), lease_);
  form->addRow(tr("latches"), latches_);
  form->addRow(tr("deadman"), deadman_);
  form->addRow(tr("pose"), pose_);
  form->addRow(tr("moving"), motion_);
  layout->addLayout(form);

  auto* row = new QHBoxLayout;
  connect_ = new QPushButton(actionIcon(QStringLiteral("disconnect")), tr("Disconnect"));
  control_ = new QPushButton(actionIcon(QStringLiteral("take-control")), tr("Take control"));
  control_->setToolTip(tr("Ask the robot for the control lease: only its holder may command it"));
  row->addWidget(connect_);
  row->addWidget(control_);
  layout->addLayout(row);
  auto* row2 = new QHBoxLayout;
  estop_ = new QPushButton(actionIcon(QStringLiteral("estop")), tr("E-STOP (Esc)"));
  estop_->setIconSize(QSize(24, 24));
  estop_->setObjectName(QStringLiteral("estopButton"));
  estop_->setMinimumHeight(40);
  estop_->setStyleSheet(QStringLiteral("QPushButton { background: #c62828; color: white; font-weight: bold; }"));
  estop_->setToolTip(tr("Emergency stop: the robot stops and stays stopped until re-armed. Key Esc works anywhere in the console."));
  rearm_ = new QPushButton(actionIcon(QStringLiteral("rearm")), tr("Re-arm"));
  rearm_->setObjectName(QStringLiteral("rearmButton"));
  rearm_->setToolTip(tr("Clear a latched failsafe or e-stop (the lease holder only)"));
  row2->addWidget(estop_, 2);
  row2->addWidget(rearm_, 1);
  layout->addLayout(row2);
  // Buttons never take the keyboard: Space and arrows are drive keys, and
  // Space must never re-arm or release through a focused button.
  for (QPushButton* b : {connect_, control_, estop_, rearm_}) b->setFocusPolicy(Qt::NoFocus);
  events_ = new QPlainTextEdit;
  events_->setReadOnly(true);
  events_->setMaximumBlockCount(1000);  // a long session keeps its latest events
  events_->setPlaceholderText(tr("link events"));
  events_->setMinimumHeight(48);  // the rest of the height goes to the dock above when it needs it
  layout->addWidget(events_, 1);

  connect(connect_, &QPushButton::clicked, this, [this] { emit open_ ? disconnectRequested() : connectRequested(); });
  connect(control_, &QPushButton::clicked, this,
          [this] { emit leaseHeld_ ? releaseControlRequested() : takeControlRequested(); });
  connect(estop_, &QPushButton::clicked, this, &LinkPanel::estopRequested);
  connect(rearm_, &QPushButton::clicked, this, &LinkPanel::rearmRequested);
  showConnection(net::ConnectionState::Stopped, {});
  showLease({});
  showLatches(false, false);
}

void LinkPanel::setEndpoint(const QString& endpoint) { endpoint_->setFullText(endpoint); }

void LinkPanel::appendEvent(const QString& text) {
  events_->appendPlainText(QTime::currentTime().toString(QStringLiteral("HH:mm:ss.zzz  ")) + text);
}

QString LinkPanel::stateText() const { return state_->fullText(); }
QString LinkPanel::latchesText() const { return latches_->fullText(); }

QStringList LinkPanel::events() const { return events_->toPlainText().split(QLatin1Char('\n'), Qt::SkipEmptyParts); }

void LinkPanel::showStats(const net::RobotClientStats& s) {
  if (!s.connected) {
    rtt_->setFullText(QStringLiteral("–"));
    rate_->setFullText(QStringLiteral("–"));
  } else if (s.rttSamples == 0) {
    rtt_->setFullText(tr("measuring…"));
    rate_->setFullText(tr("%1 Hz of %2").arg(s.telemetryRateHz, 0, 'f', 1).arg(s.telemetryRateAnnounced, 0, 'f', 0));
  } else {
    rtt_->setFullText(tr("%1 ms (mean %2, max %3)")
                      .arg(s.rttMs, 0, 'f', 1)
                      .arg(s.rttMeanMs, 0, 'f', 1)
                      .arg(s.rttMaxMs, 0, 'f', 1));
    rate_->setFullText(tr("%1 Hz of %2").arg(s.telemetryRateHz, 0, 'f', 1).arg(s.telemetryRateAnnounced, 0, 'f', 0));
  }
  deadman_->setFullText(s.robotDeadman > 0 ? tr("%1 ms (the robot's)").arg(s.robotDeadman * 1000, 0, 'f', 0)
                                       : tr("not announced"));
  const uint64_t total = s.telemetryFrames + s.telemetryLost;
  const double percent = total ? 100.0 * static_cast<double>(s.telemetryLost) / static_cast<double>(total) : 0.0;
  // What the checks refused or shed is the robot's doing, not the link's:
  // said beside the loss when there is any (protocol.md, "What a client refuses").
  // Short enough for the dock's width at 1280x800 (issue 59).
  QString text = tr("%1 (%2 %), robot dropped %3, %4 reconnects")
                     .arg(s.telemetryLost)
                     .arg(percent, 0, 'f', 2)
                     .arg(s.robotDropped)
                     .arg(s.reconnects);
  if (s.refused + s.shed > 0) text += tr("; refused %1, shed %2").arg(s.refused).arg(s.shed);
  loss_->setFullText(text);
}

void LinkPanel::showOdometry(const QString& pose, const QString& motion) {
  pose_->setFullText(pose.isEmpty() ? QStringLiteral("–") : pose);
  motion_->setFullText(motion.isEmpty() ? QStringLiteral("–") : motion);
}

QString LinkPanel::poseText() const { return pose_->fullText(); }

void LinkPanel::showConnection(net::ConnectionState state, const QString& detail) {
  open_ = state != net::ConnectionState::Stopped;
  const QString name = QString::fromLatin1(net::toString(state));
  const QString text = detail.isEmpty() ? name : name + QStringLiteral(": ") + detail;
  const char* colour = state == net::ConnectionState::Ready      ? "#2e7d32"
                       : state == net::ConnectionState::Refused ? "#c62828"
                       : state == net::ConnectionState::Stopped ? "#555555"
                                                                 : "#ef6c00";
  state_->setFullText(text, colour);
  connect_->setText(open_ ? tr("Disconnect") : tr("Connect"));
  connect_->setIcon(actionIcon(open_ ? QStringLiteral("disconnect") : QStringLiteral("connect")));
  control_->setEnabled(state == net::ConnectionState::Ready);
  ready_ = state == net::ConnectionState::Ready;
  rearm_->setEnabled(ready_ && latched_);
  if (state != net::ConnectionState::Ready) showLease({});
}

void LinkPanel::showLease(const net::LeaseStateMsg& lease) {
  leaseHeld_ = lease.yours;
  if (lease.yours) lease_->setFullText(tr("yours"), "#2e7d32");
  else if (!lease.holder.empty()) lease_->setFullText(tr("held by %1").arg(QString::fromStdString(lease.holder)), "#ef6c00");
  else lease_->setFullText(tr("free (monitoring)"));
  control_->setText(lease.yours ? tr("Release control") : tr("Take control"));
}

void LinkPanel::showLatches(bool failsafe, bool estop) {
  latched_ = failsafe || estop;
  rearm_->setEnabled(ready_ && latched_);
  if (!failsafe && !estop) {
    latches_->setFullText(tr("clear"), "#2e7d32");
    return;
  }
  QStringList on;
  if (estop) on << tr("E-STOP");
  if (failsafe) on << tr("FAILSAFE");
  latches_->setFullText(on.join(QStringLiteral(" + ")) + tr(" latched: re-arm"), "#c62828");
}

}  // namespace sp
