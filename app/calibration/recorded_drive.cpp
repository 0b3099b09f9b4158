#include "app/calibration/recorded_drive.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "app/state/robot_shapes.h"
#include "sim/readout.h"
#include "sim/runner.h"
#include "sim/world.h"

namespace sp {

RecordedDrive recordDrive(const WorldModel& world, const SimParams& params, const Perturbation& p,
                          const std::vector<TimedCommand>& commands, double duration) {
  RecordedDrive out;
  Diagnostics diag;
  std::unique_ptr<World> w = World::create(perturbWorld(world, p), params, diag);
  if (!w) {
    out.problem = "the robot's world: " + diag.format();
    return out;
  }
  out.commands = commands;
  Runner runner(*w);
  // The robot acts on a command its actuator delay after it arrived.
  std::vector<TimedCommand> acting = commands;
  for (TimedCommand& c : acting) c.time += p.delay;
  runner.schedule(acting);
  const auto every = std::max<int64_t>(1, std::llround(1 / (params.telemetryRate * params.step)));
  const auto record = [&](const World& x) {
    if (x.stepCount() % every == 0) {
      RobotFrame f = frameFromReadout(readRobot(x));
      f.roll += p.rollBias;
      f.pitch += p.pitchBias;
      out.frames.push_back(std::move(f));
    }
    return true;
  };
  record(*w);
  runner.setMonitor(record);
  if (runner.advanceToTime(duration).stop != RunOutcome::Stop::Reached)
    out.problem = "the robot diverged: " + w->health().message();
  return out;
}

}  // namespace sp
