// simpartner-sim urdf: a robot written as URDF.

#include "app/tools/sim_tool.h"

#include <iostream>
#include <string>
#include <vector>

#include "sim/model_loader.h"

#include "sim/terrain_file.h"

#include "sim/urdf.h"

namespace sp::simtool {

int urdfCommand(const std::vector<std::string>& args) {
  std::string file, out;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--out" && i + 1 < args.size()) out = args[++i];
    else if (file.empty() && !args[i].empty() && args[i][0] != '-') file = args[i];
    else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << args[i] << "'\n" << kUsage;
      return 2;
    }
  }
  if (file.empty()) {
    std::cerr << "<command line>: error: urdf needs a robot or world file\n";
    return 2;
  }
  // A robot file, or a world's first robot.
  sp::Diagnostics diag;
  std::optional<sp::RobotModel> robot;
  if (endsWith(file, ".world.xml")) {
    if (std::optional<sp::WorldModel> world = sp::loadWorld(file, diag); world && !world->robots.empty())
      robot = world->robots.front().model;
    else if (world) diag.error(file, 0, "the world has no robot");
  } else {
    robot = sp::loadRobot(file, diag);
  }
  std::cerr << diag.format();
  if (!robot) return 1;
  std::string error;
  const std::optional<std::string> urdf = sp::robotUrdf(*robot, error);
  if (!urdf) {
    std::cerr << file << ": error: " << error << "\n";
    return 1;
  }
  if (out.empty()) {
    std::cout << *urdf;
    return 0;
  }
  if (!sp::writeFileAtomically(out, *urdf, error)) {  // nothing half-written
    std::cerr << error << "\n";
    return 1;
  }
  std::cout << "wrote " << out << " (" << robot->links.size() << " links, " << robot->joints.size() << " joints)\n";
  return 0;
}

}  // namespace sp::simtool
