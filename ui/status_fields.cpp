#include "ui/status_fields.h"

#include <cmath>

#include <QFileInfo>
#include <QLabel>
#include <QStatusBar>

#include "app/console/console_session.h"
#include "app/console/console_state.h"
#include "ui/limit_spin_box.h"
#include "ui/robot_feed.h"

namespace sp {

namespace {

QString qs(const std::string& s) { return QString::fromStdString(s); }

QString alarm(const QString& text) { return QStringLiteral("<b style='color:#c62828'>%1</b>").arg(text.toHtmlEscaped()); }

}  // namespace

StatusFields::StatusFields(QStatusBar* bar) : QObject(bar) {
  terrain_ = new QLabel;
  terrain_->setObjectName(QStringLiteral("terrainLabel"));
  ghost_ = new QLabel;
  ghost_->setObjectName(QStringLiteral("ghostLabel"));
  time_ = new QLabel;
  rtf_ = new QLabel;
  health_ = new QLabel;
  log_ = new QLabel;
  log_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  for (QLabel* l : {time_, rtf_, health_}) l->setMinimumWidth(l->fontMetrics().horizontalAdvance(QStringLiteral("t = 00000.00 s")));
  for (QLabel* l : {terrain_, ghost_, time_, rtf_, health_, log_}) {
    l->setProperty("permanentField", true);  // MainWindow::showStatus leaves them their room
    bar->addPermanentWidget(l);
  }
}

void StatusFields::refresh(const ConsoleState& state, const ConsoleSession& session, const LiveLinkFeed& live) {
  const std::optional<net::TelemetryMsg>& last = live.lastTelemetry();
  if (state.replaying()) {
    rtf_->setText(tr("RTF –"));  // the replay's frames set the time shown
  } else if (last) {
    time_->setText(tr("t = %1 s").arg(last->time, 0, 'f', 2));
    rtf_->setText(tr("RTF %1").arg(session.realTimeFactor(), 0, 'f', 2));
  } else {
    time_->setText(tr("t = –"));
    rtf_->setText(tr("RTF –"));
  }
  const HealthStatus h = state.health();
  const QString text = qs(h.text).toHtmlEscaped();
  switch (h.level) {
    case HealthLevel::Alarm: health_->setText(alarm(qs(h.text))); break;
    case HealthLevel::Warning: health_->setText(QStringLiteral("<b style='color:#616161'>%1</b>").arg(text)); break;
    case HealthLevel::Good: health_->setText(QStringLiteral("<span style='color:#2e7d32'>%1</span>").arg(text)); break;
    case HealthLevel::Neutral: health_->setText(text); break;
  }
  health_->setToolTip(qs(h.detail));

  ghost_->setToolTip(tr("The ghost: how far ahead of the newest telemetry it shows the robot (the link's round "
                        "trip and the telemetry's age), its error against the telemetry (median over 10 s), and the "
                        "radius of its outer region (the band along its trail): the share of predictions it holds "
                        "is stated and checked against telemetry (held)"));
  if (state.replaying()) {
    ghost_->setText(tr("ghost off (replay)"));
  } else if (const Ghost* ghost = session.ghost(); !ghost) {
    ghost_->setText(session.ghostError().empty() ? tr("ghost off") : tr("ghost failed"));
    if (!session.ghostError().empty()) ghost_->setToolTip(qs(session.ghostError()));
  } else if (const GhostView v = ghost->view(); !v.problem.empty()) {
    ghost_->setText(alarm(tr("ghost stopped")));
    ghost_->setToolTip(qs(v.problem));
  } else if (v.version == 0) {
    ghost_->setText(tr("ghost –"));
  } else {
    QString g = tr("ghost +%1 s").arg(v.span, 0, 'f', 2);
    QString tip = ghost_->toolTip();
    if (const auto median = ghost->errorMedian()) {
      g += tr(", %1 cm / %2°").arg(median->first * 100, 0, 'f', 1).arg(radToDeg(median->second), 0, 'f', 2);
      // The median over 10 s hid jumps of a metre: the worst is said too.
      if (const auto worst = ghost->errorWorst()) {
        const QString max = *worst < 1 ? tr("max %1 cm").arg(*worst * 100, 0, 'f', 1) : tr("max %1 m").arg(*worst, 0, 'f', 2);
        if (v.outer > 0) tip += tr("\nLargest error over 10 s: %1.").arg(max);
        else g += QStringLiteral(" (%1)").arg(max);
      }
    }
    // How far to trust it, in the place of the worst error: the outer
    // region's radius; how often the region held the robot so far (the
    // share the layer makes true) in the tooltip.
    if (v.outer > 0) {
      g += tr(", %1 % ≤ %2 cm").arg(std::lround(v.outerLevel * 100)).arg(v.outer * 100, 0, 'f', 1);
      const Ghost::Coverage c = ghost->coverage();
      if (c.judged > 0)
        tip += tr("\nThe %1 % region held the robot in %2 % of %3 frames so far.")
                   .arg(std::lround(v.outerLevel * 100))
                   .arg(c.share[1] * 100, 0, 'f', 1)
                   .arg(c.judged);
    }
    if (!v.departure.empty()) {
      g = alarm(g);
      tip += QStringLiteral("\n") + qs(v.departure);
    }
    ghost_->setText(g);
    ghost_->setToolTip(tip);
  }

  const QString log = qs(session.logPath());
  log_->setText(log.isEmpty() ? tr("log: off") : tr("log: %1").arg(QFileInfo(log).fileName()));
  log_->setToolTip(log);
  if (const QString error = qs(session.logError()); !error.isEmpty()) log_->setText(alarm(tr("log failed: %1").arg(error)));
}

void StatusFields::showReplayTime(double time) { time_->setText(tr("replay t = %1 s").arg(formatFixed(time, 2))); }

void StatusFields::showTerrain(const TerrainSpec& t, bool replay, double edgeWarning) {
  const bool field = t.kind == TerrainSpec::Kind::Heightfield;
  const QString text = field ? tr("terrain %1 × %2 m").arg(formatFixed(t.grid.width, 1), formatFixed(t.grid.depth, 1))
                             : tr("terrain: endless plane");
  terrain_->setText(replay ? tr("replay %1").arg(text) : text);
  terrain_->setToolTip(
      field && !replay
          ? tr("The heightfield spans x %1..%2 m, y %3..%4 m around its centre; the console warns within %5 m of its edge")
                .arg(formatFixed(t.pose.p.x - t.grid.width / 2, 1), formatFixed(t.pose.p.x + t.grid.width / 2, 1),
                     formatFixed(t.pose.p.y - t.grid.depth / 2, 1), formatFixed(t.pose.p.y + t.grid.depth / 2, 1),
                     formatFixed(edgeWarning, 1))
          : QString());
}

QString StatusFields::ghostText() const { return ghost_->text(); }

}  // namespace sp

