#include "app/log/telemetry_recorder.h"

#include "app/state/robot_shapes.h"

#include <cmath>

#include "app/log/session_recorder.h"

namespace sp {

std::unique_ptr<TelemetryRecorder> TelemetryRecorder::open(const std::string& path, const WorldModel& world,
                                                           const std::string& endpoint, std::string& error) {
  SessionInfo info;
#ifdef SP_VERSION
  info.programVersion = SP_VERSION;
#endif
  info.files.push_back({"world", world.file, readWholeFile(world.file)});
  if (!world.robots.empty())
    info.files.push_back({"robot", world.robots[0].model.file, readWholeFile(world.robots[0].model.file)});
  if (!world.terrain.file.empty())
    info.files.push_back({"terrain", world.terrain.file, readWholeFile(world.terrain.file)});
  info.extraMeta["log_source"] = "telemetry";
  info.extraMeta["robot_endpoint"] = endpoint;
  std::unique_ptr<SessionLogWriter> writer = SessionLogWriter::open(path, info, error);
  if (!writer) return nullptr;
  return std::unique_ptr<TelemetryRecorder>(new TelemetryRecorder(std::move(writer)));
}

int64_t TelemetryRecorder::rowKey() const { return std::llround(time_ * 1000); }

void TelemetryRecorder::telemetry(const net::TelemetryMsg& t, const RobotModel& robot) {
  time_ = t.time;
  LogSample s = sampleFromTelemetry(t, rowKey(), robot, joints_, joints_);
  writer_->logSample(std::move(s));
}

void TelemetryRecorder::laser(const net::LaserMsg& m) {
  writer_->logLaser(LogLaser{std::llround(m.time * 1000), m.time, m.angleMin, m.angleStep, m.ranges});
}

void TelemetryRecorder::command(const Command& command, const RobotModel* robot, std::optional<double> arrival) {
  const double t = arrival ? *arrival : time_.load();
  writer_->logCommand(std::llround(t * 1000), t, "operator", command, robot);
}

void TelemetryRecorder::event(const std::string& kind, const std::string& text) {
  const double t = time_;
  writer_->logEvent(std::llround(t * 1000), t, kind, text);
}

}  // namespace sp
