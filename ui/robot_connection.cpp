#include "ui/robot_connection.h"

#include <QMetaObject>

#include <chrono>
#include <utility>

namespace sp {

namespace {

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

RobotConnection::RobotConnection(QObject* parent) : QObject(parent) {}

RobotConnection::~RobotConnection() {
  // Joins the worker while client_ is still there (its callbacks use it):
  // no callback runs after this, and queued calls to a destroyed context
  // object are dropped by Qt.
  if (client_) client_->stop();
  client_.reset();
}

template <typename F>
void RobotConnection::post(F&& emitIt) {
  // Tagged with the connection it came from: what a closed connection
  // queued before it stopped is dropped, never shown as the new robot's.
  QMetaObject::invokeMethod(
      this,
      [this, generation = generation_.load(), emitIt = std::forward<F>(emitIt)]() mutable {
        if (generation == generation_.load()) emitIt();
      },
      Qt::QueuedConnection);
}

void RobotConnection::open(const net::RobotClientConfig& config) {
  close();
  guard_->reset();  // before the new client's worker can feed it
  config_ = config;
  net::RobotClientCallbacks callbacks;
  // Each callback copies its message into a queued call: the worker thread
  // never waits on the GUI thread.
  callbacks.telemetry = [this](const net::TelemetryMsg& m) {
    // The guard first, here on the worker: its ABORT must not wait for the window.
    if (std::optional<GuardDeparture> d = guard_->telemetry(m)) guardAbort(*d);
    // Then the log, the ghost and the calibration, here too: they never
    // wait for the window either.
    TelemetryTap::Tapped tapped;
    if (tap_) tapped = tap_->telemetry(m, wallSeconds(), client_->stats().rttMs / 1000);
    // At most kTelemetryQueued frames wait for the window: a window that
    // falls behind (a modal dialog, a loaded machine) gets the newest frame
    // when it is back, not a backlog it would show seconds late.
    if (telemetryQueued_.load() >= kTelemetryQueued) {
      ++telemetryShed_;
      return;
    }
    ++telemetryQueued_;
    post([this, m, tapped = std::move(tapped)] {
      --telemetryQueued_;
      emit telemetry(m, tapped);
    });
  };
  callbacks.refusedTelemetry = [this](const net::Refusal& r) {
    if (std::optional<GuardDeparture> d = guard_->cannotJudge(r.kind + ": " + r.detail)) guardAbort(*d);
  };
  callbacks.laser = [this](const net::LaserMsg& m) {
    if (tap_) tap_->laser(m);
    post([this, m] { emit laser(m); });
  };
  callbacks.reply = [this](const net::ReplyMsg& m) { post([this, m] { emit reply(m); }); };
  callbacks.event = [this](const net::EventMsg& m) { post([this, m] { emit event(m); }); };
  callbacks.lease = [this](const net::LeaseStateMsg& m) { post([this, m] { emit lease(m); }); };
  callbacks.sequence = [this](const net::SequenceStateMsg& m) {
    guard_->state(m);
    post([this, m] { emit sequenceState(m); });
  };
  callbacks.connection = [this](net::ConnectionState s, const std::string& detail) {
    post([this, s, d = QString::fromStdString(detail)] { emit connectionChanged(s, d); });
  };
  callbacks.error = [this](const net::ErrorMsg& m) {
    post([this, r = QString::fromStdString(m.reason)] { emit linkError(r); });
  };
  telemetryQueued_ = 0;
  client_ = std::make_unique<net::RobotClient>(config_, std::move(callbacks));
  client_->start();
}

void RobotConnection::guardAbort(const GuardDeparture& d) {
  const std::string hash = guard_->status().hash();
  client_->abortSequence(hash, "guard: " + d.message());
  post([this, h = QString::fromStdString(hash), d] { emit guardTripped(h, d); });
}

void RobotConnection::close() {
  if (!client_) return;
  client_->releaseLease();
  client_->stop();  // writes what is queued (the release) first
  client_.reset();
  ++generation_;  // drops what the old client queued and the window has not taken yet
  emit connectionChanged(net::ConnectionState::Stopped, tr("disconnected"));
}

void RobotConnection::acquireLease() {
  if (client_) client_->acquireLease();
}

void RobotConnection::releaseLease() {
  if (client_) client_->releaseLease();
}

uint64_t RobotConnection::send(const Command& command, const RobotModel* robot) {
  if (client_) return client_->sendCommand(command, 0, robot);
  net::ReplyMsg local{0, net::ReplyStatus::Failed, "console: not connected, not sent"};
  post([this, local] { emit reply(local); });
  return 0;
}

void RobotConnection::sendSequence(const net::SequenceMsg& message) {
  if (client_) client_->sendSequence(message);
  else emit linkError(tr("SEQUENCE not sent: not connected"));
}

void RobotConnection::abortSequence(const QString& hash, const QString& reason) {
  if (client_) client_->abortSequence(hash.toStdString(), reason.toStdString());
  else emit linkError(tr("ABORT not sent: not connected"));
}

void RobotConnection::estop(const QString& reason) {
  if (!client_) {
    emit linkError(tr("console: not connected: the e-stop could not be sent"));
    return;
  }
  client_->estop(reason.toStdString());
  emit estopSent();
}

void RobotConnection::rearm() {
  if (!client_) return;
  client_->rearm();
  emit rearmSent();
}

void RobotConnection::dropConnection() {
  if (client_) client_->dropConnection();
}

net::RobotClientStats RobotConnection::stats() const {
  return client_ ? client_->stats() : net::RobotClientStats{};
}

}  // namespace sp
