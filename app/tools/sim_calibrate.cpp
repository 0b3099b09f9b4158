// simpartner-sim calibrate: the twin fitted to a session log.

#include "app/tools/sim_tool.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <cstdio>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "app/calibration/calibration.h"

#include "app/ghost/ghost.h"

#include "app/log/resimulation.h"

namespace sp::simtool {

int calibrate(const std::vector<std::string>& args) {
  std::string log, out, robotOut, profileName = "ghost";
  double window = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if ((a == "--out" || a == "--robot-out" || a == "--window" || a == "--profile") && i + 1 < args.size()) {
      const std::string& v = args[++i];
      if (a == "--out") out = v;
      else if (a == "--robot-out") robotOut = v;
      else if (a == "--profile") profileName = v;
      else {
        char* end = nullptr;
        window = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || *end != '\0' || !(window > 0)) {
          std::cerr << "<command line>: error: --window: expected seconds > 0, got '" << v << "'\n";
          return 2;
        }
      }
    } else if (log.empty() && !a.empty() && a[0] != '-') {
      log = a;
    } else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (log.empty() || (profileName != "ghost" && profileName != "robot")) {
    std::cerr << "<command line>: error: calibrate needs a LOG file (and --profile ghost or robot)\n";
    return 2;
  }
  std::string error;
  std::optional<sp::CalibrationInput> in = sp::calibrationInput(log, error);
  if (!in) {
    std::cerr << error << "\n";
    return 1;
  }
  const sp::SimParams profile = profileName == "ghost" ? sp::Ghost::profile(in->params) : in->params;
  sp::CalibrationOptions options;
  options.window = window;
  options.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  options.iterations = 5;
  const sp::CalibrationFit fit =
      sp::fitCalibration(in->world, profile, in->frames, in->commands, sp::calValues(in->params), options);
  if (!fit.refused.empty()) {
    std::cerr << log << ": calibration refused: " << fit.refused << "\n";
    return 7;
  }
  std::printf("%s: %d segments over %.1f - %.1f s, %d twin runs, %.0f ms; cost %.3g -> %.3g\n", log.c_str(),
              fit.segments, fit.from, fit.to, fit.twinRuns, fit.wallMs, fit.costBefore, fit.costAfter);
  // Fitted in the ghost's profile: the radius splits and the motors' limits
  // are checked in the log's own physics before a file gets them, as the console does for its
  // rehearsals (calibration.h, fullPhysicsValues), over the newest 16 s.
  sp::CalibrationFit written = fit;
  if (profileName == "ghost") {
    const sp::FullPhysicsCheck check =
        sp::fullPhysicsValues(in->world, in->params, in->frames, in->commands, fit.value, 16, options.threads);
    if (!check.problem.empty()) {
      std::printf("full physics: not checked (%s): the splits are written as fitted\n", check.problem.c_str());
    } else {
      for (sp::CalParam q : sp::kFullPhysicsChecked) {
        const size_t i = static_cast<size_t>(q);
        if (check.values[i] == fit.value[i]) continue;
        const bool limit = sp::isTorqueLimit(q);
        std::printf("full physics: %s %.5f put back to the files' %.5f (it predicts the robot%s better without it: cost %.4g "
                    "against %.4g)\n",
                    sp::calParams()[i].key, fit.value[i], check.values[i], limit ? "'s wheel forces" : "", check.costWithout[i],
                    limit ? check.forceCost : check.cost);
        written.value[i] = check.values[i];
        written.observed[i] = false;
      }
    }
  }
  for (size_t i = 0; i < sp::kCalParams; ++i) {
    const sp::CalParamInfo& p = sp::calParams()[i];
    if (fit.observed[i])
      std::printf("%-32s %.5f +- %.5f%s\n", p.key, fit.value[i], fit.sigma[i], *p.unit ? (std::string(" ") + p.unit).c_str() : "");
    else
      std::printf("%-32s %.5f unobserved\n", p.key, fit.value[i]);
  }
  if (!out.empty()) {
    std::ofstream f(out);
    f << sp::calibrationParamsText(written);
    if (!f.flush()) {
      std::cerr << out << ": error: cannot write the parameters file\n";
      return 1;
    }
    std::printf("wrote %s\n", out.c_str());
  }
  if (!robotOut.empty()) {
    const std::optional<std::string> text = sp::calibratedRobotText(
        in->robotText, in->world.robots[0].model, sp::withCalValues(in->params, written.value), error);
    std::ofstream f;
    if (text) f.open(robotOut);
    if (!text || !(f << *text).flush()) {
      std::cerr << (text ? robotOut + ": error: cannot write the robot file" : error) << "\n";
      return 1;
    }
    std::printf("wrote %s\n", robotOut.c_str());
  }
  return 0;
}

}  // namespace sp::simtool
