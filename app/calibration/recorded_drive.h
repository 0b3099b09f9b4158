#pragma once
// A robot driven without the link, recorded as telemetry: what the
// calibration's tests and benchmark fit (a perturbed robot's physics, its
// delay and IMU bias, frames at the telemetry rate). The commands are
// returned at the robot times they arrived, as the console estimates them.
//
//   sp::Perturbation p;  p.wheelRadius = {0.98, 0.98, 0.98, 0.98};
//   sp::RecordedDrive d = sp::recordDrive(world, params, p, sequence, 10.0);
//   sp::CalibrationFit fit = sp::fitCalibration(world, profile, d.frames, d.commands, start);
//
// Thread: the calling thread owns the world it builds.

#include <string>
#include <vector>

#include "app/state/robot_frame.h"
#include "sim/command.h"
#include "sim/params.h"
#include "sim/perturbation.h"
#include "sim/robot_model.h"

namespace sp {

struct RecordedDrive {
  std::vector<RobotFrame> frames;      ///< at params.telemetryRate
  std::vector<TimedCommand> commands;  ///< at their arrival times
  std::string problem;                 ///< "" or why the drive stopped (a diverged twin)
};

/// Drives the robot of `world` perturbed by `p` (its physics, its actuator
/// delay, its IMU bias in the frames' roll and pitch) under `commands`
/// (arrival times) for `duration` seconds of robot time.
RecordedDrive recordDrive(const WorldModel& world, const SimParams& params, const Perturbation& p,
                          const std::vector<TimedCommand>& commands, double duration);

}  // namespace sp
