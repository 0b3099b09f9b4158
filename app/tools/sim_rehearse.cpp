// simpartner-sim rehearse: a command sequence rehearsed against the flight rules.

#include "app/tools/sim_tool.h"

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "app/sweep/sweep.h"

#include "sim/command_file.h"
#include "sim/model_loader.h"

#include "sim/text.h"

namespace sp::simtool {

int rehearseCommand(const std::vector<std::string>& args) {
  std::string worldFile, commandsFile, rulesFile, paramsFile;
  std::vector<std::string> overrides;
  int robust = 0;
  bool fast = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--fast") {
      fast = true;
      continue;
    }
    if (!knownWithValue(args, i, {"--world", "--commands", "--rules", "--params", "--set", "--robust"})) return 2;
    const std::string& v = args[++i];
    if (a == "--world") worldFile = v;
    else if (a == "--commands") commandsFile = v;
    else if (a == "--rules") rulesFile = v;
    else if (a == "--params") paramsFile = v;
    else if (a == "--set") overrides.push_back(v);
    else {
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || n < 1 || n > 100000) {
        std::cerr << "<command line>: error: --robust: expected a count 1..100000, got '" << v << "'\n";
        return 2;
      }
      robust = static_cast<int>(n);
    }
  }
  if (worldFile.empty() || commandsFile.empty()) {
    std::cerr << "<command line>: error: rehearse needs --world FILE and --commands FILE\n";
    return 2;
  }
  sp::Diagnostics diag;
  std::optional<sp::WorldModel> world = sp::loadWorld(worldFile, diag);
  sp::SimParams params;
  if (world && world->robots.empty()) diag.error(worldFile, 0, "the world has no robot to rehearse");
  if (!paramsFile.empty()) sp::loadParams(paramsFile, params, diag);
  for (const std::string& o : overrides) sp::applyOverride(params, o, diag);
  sp::FlightRules rules;
  if (!rulesFile.empty()) sp::loadFlightRules(rulesFile, rules, diag);
  std::optional<std::vector<sp::TimedCommand>> commands;
  if (world && !world->robots.empty()) {
    commands = sp::loadCommandSequence(commandsFile, diag, &world->robots[0].model);
    if (commands) sp::checkCommands(*commands, *world, commandsFile, diag);
  }
  if (diag.hasErrors() || !commands) {
    std::cerr << diag.format();
    return 1;
  }
  if (robust > 0) rules.robustSamples = robust;
  sp::RehearsalPlan plan{*world, params, rules, *commands, std::nullopt};
  plan.fast = fast;
  const sp::RehearsalResult r = sp::rehearse(plan);
  if (!r.error.empty()) {
    std::cerr << "error: " << r.error << "\n";
    return 1;
  }
  std::cout << "rehearsal of " << commandsFile << " (hash " << sp::sequenceHash(sp::sequenceText(*commands, &world->robots[0].model))
            << ") on " << worldFile << ": " << r.duration << " s simulated in " << r.wallSeconds << " s, after "
            << r.settled << " s for the robot to settle from the world's start"
            << (!r.refined.empty() ? " (fast profile, run again at full fidelity: " + r.refined + "; not sendable)"
                : fast ? " (fast profile: step " + sp::shortestText(params.rehearsalFastStep * 1000) + " ms, " +
                             std::to_string(params.rehearsalFastIterations) + " iterations; a preview, not sendable)"
                       : std::string())
            << "\n";
  for (const sp::RuleVerdict& v : r.verdicts) std::cout << "  " << (v.passed ? "pass  " : "FAIL  ") << v.message() << "\n";
  for (const std::string& why : r.refused) std::cerr << commandsFile << ": error: refused: " << why << "\n";
  std::cout << (r.passed ? "passed" : "failed: " + r.summary()) << "\n";
  if (robust > 0) {
    sp::RehearsalPlan samples = plan;
    samples.fast = samples.stopAtFirstFailure = true;
    const sp::RobustnessResult rob = sp::robustness(samples, 1, 2);
    std::cout << "robustness: " << rob.passed << " of " << rob.samples << " passed (" << 100 * rob.probability()
              << " %), end positions within " << rob.spread << " m of their mean, " << rob.wallSeconds << " s; "
              << rob.refined << " run again at full fidelity (failed or near a limit)\n";
    for (int i = 0; i < rob.samples; ++i)
      if (!rob.samplePassed[i]) std::cout << "  sample " << i << ": " << rob.failures[i] << "\n";
  }
  return r.passed ? 0 : 6;
}

}  // namespace sp::simtool
