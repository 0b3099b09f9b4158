#include "app/log/log_export.h"

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>

#include "app/log/session_log.h"
#include "sim/model_loader.h"
#include "sim/robot_model.h"

namespace sp {
namespace fs = std::filesystem;
namespace {

// A field quoted as RFC 4180 asks when it holds a comma, quote or newline.
std::string quoted(const std::string& field) {
  if (field.find_first_of(",\"\r\n") == std::string::npos) return field;
  std::string q = "\"";
  for (char c : field) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + '"';
}

// Opens a CSV file with full double precision.
bool openCsv(std::ofstream& out, const fs::path& path, std::string& error, std::vector<std::string>* written) {
  out.open(path, std::ios::binary);
  if (!out) {
    error = path.string() + ": error: cannot write CSV file";
    return false;
  }
  out.imbue(std::locale::classic());
  out << std::setprecision(17);
  if (written) written->push_back(path.string());
  return true;
}

bool finish(std::ofstream& out, const fs::path& path, std::string& error) {
  out.close();
  if (!out) {
    error = path.string() + ": error: writing the CSV file failed";
    return false;
  }
  return true;
}

}  // namespace

bool exportLogCsv(const std::string& logPath, const std::string& dir, std::string& error,
                  std::vector<std::string>* written) {
  std::unique_ptr<SessionLogReader> reader = SessionLogReader::open(logPath, error);
  if (!reader) return false;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) {
    error = dir + ": error: cannot create the output folder";
    return false;
  }
  const std::map<std::string, std::string> meta = reader->meta();
  std::optional<RobotModel> robot;
  if (auto it = meta.find("robot_contents"); it != meta.end()) {
    Diagnostics diag;
    auto name = meta.find("robot_file");
    robot = parseRobot(it->second, name == meta.end() ? "robot" : name->second, diag);
  }
  const double all = 1e300;  // every time

  // Samples: joint columns follow the robot's joints (positions, then rates).
  {
    const std::vector<LogSample> samples = reader->samplesBetween(-all, all);
    size_t joints = 0;
    for (const LogSample& s : samples) joints = std::max(joints, s.joints.size() / 2);
    if (samples.empty() && robot) joints = robot->joints.size();
    const fs::path path = fs::path(dir) / "samples.csv";
    std::ofstream out;
    if (!openCsv(out, path, error, written)) return false;
    out << "step,time_s,base_x_m,base_y_m,base_z_m,base_qw,base_qx,base_qy,base_qz";
    auto jointName = [&](size_t j) {
      return robot && j < robot->joints.size() ? robot->joints[j].name : "joint_" + std::to_string(j);
    };
    auto slider = [&](size_t j) { return robot && j < robot->joints.size() && robot->joints[j].type == JointType::Slider; };
    for (size_t j = 0; j < joints; ++j) out << ',' << quoted(jointName(j) + (slider(j) ? "_pos_m" : "_pos_rad"));
    for (size_t j = 0; j < joints; ++j) out << ',' << quoted(jointName(j) + (slider(j) ? "_vel_m_s" : "_vel_rad_s"));
    out << ",wheel_fl_normal_N,wheel_fr_normal_N,wheel_rl_normal_N,wheel_rr_normal_N,roll_rad,pitch_rad\n";
    for (const LogSample& s : samples) {
      out << s.step << ',' << s.time;
      for (double v : s.base) out << ',' << v;
      for (double v : s.quat) out << ',' << v;
      for (size_t i = 0; i < 2 * joints; ++i) {
        out << ',';
        if (i < s.joints.size()) out << s.joints[i];
      }
      for (double v : s.wheelNormal) out << ',' << v;
      out << ',' << s.roll << ',' << s.pitch << '\n';
    }
    if (!finish(out, path, error)) return false;
  }

  // Laser scans: as many range columns as the longest scan.
  {
    const std::vector<LogLaser> scans = reader->laserBetween(-all, all);
    size_t n = 0;
    for (const LogLaser& s : scans) n = std::max(n, s.ranges.size());
    const fs::path path = fs::path(dir) / "laser.csv";
    std::ofstream out;
    if (!openCsv(out, path, error, written)) return false;
    out << "step,time_s,angle_min_rad,angle_step_rad";
    char name[32];
    for (size_t i = 0; i < n; ++i) {
      std::snprintf(name, sizeof name, ",range_%03zu_m", i);
      out << name;
    }
    out << '\n';
    for (const LogLaser& s : scans) {
      out << s.step << ',' << s.time << ',' << s.angleMin << ',' << s.angleStep;
      for (size_t i = 0; i < n; ++i) {
        out << ',';
        if (i < s.ranges.size()) out << s.ranges[i];
      }
      out << '\n';
    }
    if (!finish(out, path, error)) return false;
  }

  {
    const fs::path path = fs::path(dir) / "commands.csv";
    std::ofstream out;
    if (!openCsv(out, path, error, written)) return false;
    out << "step,time_s,source,text\n";
    for (const LogCommand& c : reader->commands())
      out << c.step << ',' << c.time << ',' << quoted(c.source) << ',' << quoted(c.text) << '\n';
    if (!finish(out, path, error)) return false;
  }
  {
    const fs::path path = fs::path(dir) / "events.csv";
    std::ofstream out;
    if (!openCsv(out, path, error, written)) return false;
    out << "step,time_s,kind,text\n";
    for (const LogEvent& e : reader->events())
      out << e.step << ',' << e.time << ',' << quoted(e.kind) << ',' << quoted(e.text) << '\n';
    if (!finish(out, path, error)) return false;
  }
  return true;
}

}  // namespace sp
