#include "app/console/session_drive.h"

#include <chrono>
#include <deque>
#include <mutex>
#include <thread>

#include "app/console/console_session.h"
#include "net/robot_client.h"

namespace sp {

std::string driveSession(ConsoleSession& session, const std::string& token, const std::vector<DrivePhase>& phases,
                         double seconds,
                         const std::function<void(const net::TelemetryMsg&, const std::optional<GhostError>&)>& each) {
  std::mutex mutex;
  bool ready = false, lease = false;
  std::deque<net::TelemetryMsg> arrived;
  net::RobotClientCallbacks cb;
  cb.connection = [&](net::ConnectionState s, const std::string&) {
    std::lock_guard lock(mutex);
    ready = s == net::ConnectionState::Ready;
  };
  cb.lease = [&](const net::LeaseStateMsg& m) {
    std::lock_guard lock(mutex);
    lease = m.yours;
  };
  cb.telemetry = [&](const net::TelemetryMsg& t) {
    std::lock_guard lock(mutex);
    arrived.push_back(t);
  };
  net::RobotClientConfig config = session.clientConfig("session drive");
  config.host = session.endpoint().host;
  config.port = session.endpoint().port;
  config.token = token;
  net::RobotClient client(config, cb);
  client.start();
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const auto waitFor = [&](const bool& flag) {
    while (elapsed() < 30) {
      {
        std::lock_guard lock(mutex);
        if (flag) return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  };
  // Every frame that came, through the session; `each` after the drive began.
  const auto takeFrames = [&](bool driving) {
    std::deque<net::TelemetryMsg> batch;
    {
      std::lock_guard lock(mutex);
      batch.swap(arrived);
    }
    if (batch.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    for (const net::TelemetryMsg& t : batch) {
      session.telemetry(t, elapsed(), client.stats().rttMs / 1000);
      session.takeCalibration();
      if (driving && each) each(t, session.lastPrediction());
    }
  };
  std::string why;
  if (!waitFor(ready)) why = "no connection to the robot within 30 s";
  if (why.empty()) client.acquireLease();
  if (why.empty() && !waitFor(lease)) why = "the robot did not give the lease within 30 s";
  // The console has been reading telemetry before the operator drives.
  while (why.empty() && session.ghost() && session.ghost()->viewVersion() == 0 && elapsed() < 30) takeFrames(false);
  const double t0 = elapsed();
  size_t next = 0;
  while (why.empty() && elapsed() - t0 < seconds) {
    for (; next < phases.size() && elapsed() - t0 >= phases[next].at; ++next) {
      client.sendCommand(phases[next].command, 0, session.robot());
      session.commandSent(phases[next].command);
    }
    takeFrames(true);
  }
  client.stop();
  return why;
}

}  // namespace sp
