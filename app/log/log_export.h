#pragma once
// `simpartner-sim export LOG --csv DIR`: one CSV file per stream of a session
// log (app/log/session_log.h), each with a header row naming every column and
// its unit (RFC 4180 quoting, '.' decimals, 17 significant digits so doubles
// read back exactly; readable by Python's csv, pandas and Matlab).
//
//   samples.csv   step, time_s, base_x_m, base_y_m, base_z_m, base_qw..qz,
//                 <joint>_pos_rad|_pos_m per joint, <joint>_vel_rad_s|_vel_m_s
//                 per joint, wheel_fl/fr/rl/rr_normal_N, roll_rad, pitch_rad
//   laser.csv     step, time_s, angle_min_rad, angle_step_rad, range_000_m...
//                 (as many range columns as the longest scan; shorter scans
//                 leave the rest empty)
//   commands.csv  step, time_s, source, text
//   events.csv    step, time_s, kind, text
//
// Joint names come from the robot file stored in the log; if it does not
// parse, columns are named joint_0, joint_1, ...

#include <string>
#include <vector>

namespace sp {

/// Writes the CSV files of the log at `logPath` into `dir` (created if
/// missing). Returns false and sets `error` when the log cannot be read or a
/// file cannot be written. `written` (if not null) receives the paths
/// written. Thread: any.
bool exportLogCsv(const std::string& logPath, const std::string& dir, std::string& error,
                  std::vector<std::string>* written = nullptr);

}  // namespace sp
