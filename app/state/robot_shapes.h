#pragma once
// The robot's state comes in six shapes, each for its own reader, and every
// conversion between them is here, so a field added to one shape is carried
// to the others in one place:
//
//   sim::RobotReadout   what the twin reads of itself (sim/readout.h)
//   net::RobotState     what the robot side sends (net/robot_server.h)
//   net::TelemetryMsg   what arrives over the link (net/message.h)
//   LogSample           a row of a session log (app/log/session_log.h)
//   RobotFrame          what the console's views draw (app/state/robot_frame.h)
//   GhostView           what the ghost predicts (app/ghost/ghost.h)
//
//   RobotReadout ──stateFromReadout──► RobotState ──(link)──► TelemetryMsg
//   RobotReadout ──sampleFromReadout─► LogSample ◄──sampleFromTelemetry── TelemetryMsg
//   TelemetryMsg ──frameFromTelemetry─► RobotFrame ◄──frameFromSample── LogSample
//   GhostView ──frameFromGhost──► RobotFrame ◄──frameFromReadout── RobotReadout
//
// Joints travel by name over the link and in the model's order everywhere
// else; JointNameMap (robot_frame.h) maps them.
//
// Thread: pure functions of their arguments (the maps are their caller's).

#include <string>
#include <vector>

#include "app/state/robot_frame.h"
#include "app/state/ghost_view.h"
#include "app/state/log_sample.h"
#include "net/message.h"
#include "net/robot_server.h"
#include "sim/readout.h"

namespace sp {

/// What the robot side sends of `r`; `jointNames` in the model's order.
net::RobotState stateFromReadout(const RobotReadout& r, const std::vector<std::string>& jointNames);
/// A session log's row of `r`.
LogSample sampleFromReadout(const RobotReadout& r);
/// A session log's row of telemetry `t` (joints mapped into `robot`'s
/// order by `positions` and `rates`), at `step`.
LogSample sampleFromTelemetry(const net::TelemetryMsg& t, int64_t step, const RobotModel& robot, JointNameMap& positions,
                              JointNameMap& rates);
/// The frame to draw of telemetry `t`; joints mapped into `robot`'s order
/// (none without a robot).
RobotFrame frameFromTelemetry(const net::TelemetryMsg& t, const RobotModel* robot, JointNameMap& positions,
                              JointNameMap& rates);
/// The frame to draw of log row `s` of a robot with `joints` joints (a row
/// of another robot, with fewer values, reads 0 beyond them).
RobotFrame frameFromSample(const LogSample& s, size_t joints);
/// What telemetry reports of a robot read out of a twin (tests, benchmarks:
/// a robot without the link).
RobotFrame frameFromReadout(const RobotReadout& r);
/// The frame to draw of the ghost's view.
RobotFrame frameFromGhost(const GhostView& v);
/// The scan to draw of laser message `m`.
LaserFrame laserFromMessage(const net::LaserMsg& m);

}  // namespace sp
