// simpartner-sim check FILE... and params: files validated, the parameters listed.

#include "app/tools/sim_tool.h"

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/params.h"

namespace sp::simtool {

int check(const std::vector<std::string>& files) {
  sp::Diagnostics diag;
  std::optional<sp::RobotModel> robot;
  std::optional<sp::WorldModel> world;  // when the robot came from a world: its terrain checks terrain edits
  std::vector<std::string> sequences;
  for (const std::string& f : files) {
    if (endsWith(f, ".params")) {
      sp::SimParams p;
      sp::loadParams(f, p, diag);
    } else if (endsWith(f, ".seq")) {
      sequences.push_back(f);
    } else if (endsWith(f, ".xml")) {
      const std::string root = sp::xmlRootName(f);
      if (root == "world") {
        auto w = sp::loadWorld(f, diag);
        if (w && !w->robots.empty() && !robot) {
          robot = w->robots[0].model;
          world = std::move(w);
        }
      } else if (root == "robot" || root.empty()) {
        // Not well-formed XML (root "") is reported by the robot loader.
        auto r = sp::loadRobot(f, diag);
        if (r && !robot) robot = std::move(r);
      } else {
        diag.error(f, 0, "root element <" + root + "> is neither <robot> nor <world>");
      }
    } else if (!std::filesystem::exists(f)) {
      diag.error(f, 0, "no such file");
    } else {
      diag.error(f, 0, "unknown kind of file (expected .xml, .params or .seq)");
    }
  }
  for (const std::string& f : sequences) {
    auto seq = sp::loadCommandSequence(f, diag, robot ? &*robot : nullptr);
    if (seq && world)
      sp::checkCommands(*seq, *world, f, diag);
    else if (seq && robot)
      sp::checkCommands(*seq, *robot, f, diag);
  }
  std::cerr << diag.format();
  const int errors = diag.errorCount();
  const int warnings = static_cast<int>(diag.items().size()) - errors;
  std::cout << files.size() << " file(s) checked: " << errors << " error(s), " << warnings << " warning(s)\n";
  return errors == 0 ? 0 : 1;
}

int printParams() {
  for (const sp::ParamInfo& p : sp::paramTable())
    std::cout << p.key << " = " << p.defaultValue << "\n    " << p.description << "\n";
  return 0;
}

}  // namespace sp::simtool
