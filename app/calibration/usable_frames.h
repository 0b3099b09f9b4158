#pragma once
// The robot's frames a calibration can use (calibration.cpp's fits and the
// load fits of calibration_loads.cpp).

#include <vector>

#include "app/state/robot_frame.h"

namespace sp::calibration_detail {

/// The robot's frames for calibration: the healthy, unlatched ones, in
/// time order, with a base twist from their neighbours where the source
/// reported none (a session log's samples carry none). `window` [s]: only
/// the newest that long; <= 0: all.
std::vector<RobotFrame> usableFrames(const std::vector<RobotFrame>& in, double window);

}  // namespace sp::calibration_detail
