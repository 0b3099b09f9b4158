#include "ui/console_monitor.h"

#include "app/console/console_session.h"
#include "app/ghost/ghost.h"
#include "ui/robot_connection.h"
#include "ui/robot_feed.h"

namespace sp {

ConsoleMonitor::ConsoleMonitor(RobotConnection* connection, LiveLinkFeed* live, ConsoleSession* session, QObject* parent)
    : QObject(parent), session_(session), connection_(connection) {
  clock_.start();
  state_.setConfig({session->params().consoleStaleAfter, ConsoleState::Config{}.edgeWarning});
  connect(connection, &RobotConnection::lease, this, [this](const net::LeaseStateMsg& lease) {
    // Losing or giving up control stops the robot.
    if (state_.lease(lease.yours)) emit robotStopped();
    notify();
  });
  connect(connection, &RobotConnection::connectionChanged, this, [this](net::ConnectionState s, const QString& d) {
    if (state_.connection(s, d.toStdString())) emit robotStopped();
    if (s == net::ConnectionState::Waiting || s == net::ConnectionState::Stopped || s == net::ConnectionState::Refused)
      session_->linkDown(d.toStdString());
    if (s == net::ConnectionState::Ready) {
      // The ghost is only as good as the files it is built from.
      const net::RobotClientStats stats = connection_->stats();
      const std::string differ = session_->filesMismatch(stats.robotWorldHash, stats.robotRobotHash);
      state_.filesMismatch(differ);
      if (!differ.empty()) emit filesDiffer(QString::fromStdString(differ));
    }
    notify();
  });
  connect(connection, &RobotConnection::event, this, [this](const net::EventMsg& m) {
    // The robot says why it stopped; the banner repeats it.
    if (m.kind == net::EventKind::Failsafe) state_.failsafeReason(m.text);
    if (m.kind == net::EventKind::Failsafe || m.kind == net::EventKind::Estop || m.kind == net::EventKind::Rearmed)
      emit robotStopped();
    notify();
  });
  // An e-stop or re-arm in flight: shown at once, the ghost stops where the
  // robot will, the controls go back to a stopped robot (they wait for it).
  // Half the round trip; -1 before one was measured (the banner says so
  // rather than "lands in ~0.0 s").
  const auto landsIn = [this] {
    const net::RobotClientStats s = connection_->stats();
    if (s.rttSamples == 0) return -1.0;
    return (s.rttMeanMs > 0 ? s.rttMeanMs : s.rttMs) / 2000;
  };
  connect(connection, &RobotConnection::estopSent, this, [this, landsIn] {
    if (!state_.connected()) return;
    state_.estopSent(landsIn(), wallSeconds());
    session_->estopSent();
    emit robotStopped();
    notify();
  });
  connect(connection, &RobotConnection::rearmSent, this, [this, landsIn] {
    if (!state_.connected()) return;
    state_.rearmSent(landsIn(), wallSeconds());
    notify();
  });
  connect(live, &RobotFeed::frame, this, [this](const RobotFrame& f) {
    if (!session_->robot()) return;
    const FrameChanges changes = state_.frame(f, wallSeconds(), session_->edgeDistance(f.base));
    watchDepartures();
    if (changes.latchedNow) emit robotStopped();  // a latch that comes on stopped the robot
    if (changes.latches) emit latchesChanged(state_.failsafe(), state_.estop());
    notify();
  });
}

void ConsoleMonitor::watchDepartures() {
  const Ghost* ghost = session_->ghost();
  if (!ghost) return;
  const size_t count = ghost->departureCount();
  const std::optional<Departure> on = ghost->departing();
  state_.departure(on ? on->describe() : std::string());
  if (count < departuresSeen_) departuresSeen_ = 0;  // a reset or a new ghost
  if (count == departuresSeen_) return;
  departuresSeen_ = count;
  const std::vector<Departure> all = ghost->departures();
  if (all.empty()) return;
  emit departure(all.back().where, QString::fromStdString(all.back().describe()));
}

void ConsoleMonitor::tick() {
  state_.tick(wallSeconds());
  notify();
}

void ConsoleMonitor::notify() {
  if (state_.revision() == notified_) return;
  notified_ = state_.revision();
  emit changed();
}

}  // namespace sp
