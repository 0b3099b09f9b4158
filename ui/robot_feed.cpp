#include "ui/robot_feed.h"

#include <QFileInfo>

#include "app/console/console_session.h"
#include "app/state/robot_shapes.h"
#include "ui/robot_connection.h"

namespace sp {

namespace {

QString qs(const std::string& s) { return QString::fromStdString(s); }

}  // namespace

LiveLinkFeed::LiveLinkFeed(RobotConnection* connection, ConsoleSession* session, QObject* parent)
    : RobotFeed(parent), session_(session) {
  // The frames come handed on already (the session's tap, on the link's
  // worker): here they are only drawn.
  connection->setTap(session_->tap());
  connect(connection, &RobotConnection::telemetry, this, [this](const net::TelemetryMsg& t, const TelemetryTap::Tapped& f) {
    ++telemetryCount_;
    lastTelemetry_ = t;
    lastPrediction_ = f.prediction;
    session_->takeCalibration();
    emit frame(f.frame);
  });
  connect(connection, &RobotConnection::laser, this, [this](const net::LaserMsg& m) {
    ++laserCount_;
    emit laser(laserFromMessage(m));
  });
  connect(connection, &RobotConnection::reply, this, [this](const net::ReplyMsg& m) {
    if (m.status == net::ReplyStatus::Ok) return;
    linkEvent(QStringLiteral("refused"),
              tr("command %1 %2: %3").arg(m.seq).arg(QLatin1String(net::toString(m.status)), qs(m.reason)), "link");
  });
  connect(connection, &RobotConnection::event, this, [this](const net::EventMsg& m) {
    const QLatin1String kind(net::toString(m.kind));
    linkEvent(QStringLiteral("robot"), tr("robot %1: %2").arg(kind, qs(m.text)), net::toString(m.kind));
  });
  connect(connection, &RobotConnection::lease, this, [this](const net::LeaseStateMsg& lease) {
    linkEvent(QStringLiteral("link"), lease.yours            ? tr("control: yours")
                                      : lease.holder.empty() ? tr("control: free")
                                                             : tr("control: held by %1").arg(qs(lease.holder)),
              "link");
  });
  connect(connection, &RobotConnection::connectionChanged, this, [this](net::ConnectionState s, const QString& d) {
    const QLatin1String state(net::toString(s));
    linkEvent(QStringLiteral("link"), tr("link %1%2").arg(state, d.isEmpty() ? QString() : QStringLiteral(": ") + d),
              "link");
    emit stateChanged(state, d);
  });
  connect(connection, &RobotConnection::linkError, this,
          [this](const QString& reason) {
            // The robot's ERRORs and the client's own notices, logged whichever the robot is.
            session_->logEvent("error", reason.toStdString());
            linkEvent(QStringLiteral("error"), tr("error: %1").arg(reason));
          });
}

void LiveLinkFeed::linkEvent(const QString& kind, const QString& text, const char* logKind) {
  if (logKind) session_->event(logKind, text.toStdString());
  emit event(kind, text);
}

const WorldModel* LiveLinkFeed::shownWorld() const { return session_->world(); }

void LiveLinkFeed::announceWorld() {
  if (const WorldModel* w = session_->world()) emit worldChanged(*w);
}

GhostFeed::GhostFeed(ConsoleSession* session, QObject* parent) : RobotFeed(parent), session_(session) {}

const WorldModel* GhostFeed::shownWorld() const { return session_->world(); }

void GhostFeed::reset() {
  version_ = -1;
  trailTime_ = -1;
}

void GhostFeed::poll() {
  const Ghost* ghost = session_->ghost();
  if (!ghost || ghost->viewVersion() == version_) return;
  const GhostView v = ghost->view();
  version_ = v.version;
  if (v.version == 0) return;  // nothing predicted yet: the ghost stays where it is
  emit frame(frameFromGhost(v));
  emit region(v.inner, v.outer);
  if (v.trailTime != trailTime_) {
    trailTime_ = v.trailTime;
    emit trail(v.trail);
    emit trailBand(v.trailBand);
  }
}

FeedSwitch::FeedSwitch(RobotFeed* live, QObject* parent) : QObject(parent), live_(live), current_(nullptr) {
  show(live);
}

void FeedSwitch::show(RobotFeed* feed) {
  if (!feed) feed = live_;
  if (feed == current_) return;
  for (const QMetaObject::Connection& c : links_) disconnect(c);
  links_ = {connect(feed, &RobotFeed::frame, this, &FeedSwitch::frame),
            connect(feed, &RobotFeed::laser, this, &FeedSwitch::laser),
            connect(feed, &RobotFeed::terrain, this, &FeedSwitch::terrain),
            connect(feed, &RobotFeed::worldChanged, this, &FeedSwitch::worldChanged)};
  current_ = feed;
  emit switched(feed);
}

}  // namespace sp
