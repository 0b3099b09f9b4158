// simpartner-sim validate: the founding paper's experiments and their report.

#include "app/tools/sim_tool.h"

#include <fstream>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "app/data/data_files.h"

#include "app/state/run_params.h"

#include "app/validation/plot_svg.h"

#include "app/validation/validation.h"

namespace sp::simtool {

int validate(const std::vector<std::string>& args) {
  sp::ValidationOptions o;
  std::string out = "validation", paramsFile, convergence;
  std::vector<std::string> overrides;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--quick") {
      o.quick = true;
    } else if (a == "--convergence" && i + 1 < args.size()) {
      convergence = args[++i];
    } else if ((a == "--out" || a == "--params" || a == "--set") && i + 1 < args.size()) {
      (a == "--out" ? out : a == "--params" ? paramsFile : overrides.emplace_back()) = args[++i];
    } else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  sp::Diagnostics diag;
  auto params = sp::loadRunParams(paramsFile, overrides, diag);
  std::cerr << diag.format();
  if (!params) return 2;
  o.params = *params;
  // The shipped robots/ and terrains/: from the working directory or the
  // data folder (app/data/data_files.h).
  namespace fs = std::filesystem;
  std::string dataError;
  const std::string flat = sp::findDataFile("terrains/flat.world.xml", dataError);
  if (flat.empty()) {
    std::cerr << dataError << "\n";
    return 1;
  }
  o.sourceDir = fs::path(flat).parent_path().parent_path().string();
  if (o.sourceDir.empty()) o.sourceDir = ".";
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) {
    std::cerr << out << ": error: cannot create the output folder: " << ec.message() << "\n";
    return 1;
  }
  if (!convergence.empty()) {
    std::string error;
    const auto settings = sp::parsePhysicsSettings(convergence, error);
    if (!settings) {
      std::cerr << "<command line>: error: " << error << "\n";
      return 2;
    }
    std::string report;
    try {
      report = sp::convergenceReport(sp::convergenceStudy(o, *settings, std::cout), o);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 1;
    }
    std::ofstream(out + "/convergence.md") << report;
    std::cout << report << "written to " << out << "/convergence.md\n";
    return 0;
  }
  std::cout << "SimPartner validation" << (o.quick ? " (quick)" : "") << ": the founding paper's five experiments\n";
  std::vector<sp::ExperimentResult> results;
  try {
    results = sp::runValidation(o, std::cout);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  for (const sp::ExperimentResult& r : results)
    for (const sp::ExperimentPlot& p : r.plots) {
      std::ofstream(out + "/" + p.file + ".csv") << sp::toCsv(p.spec);
      std::string error;
      if (!sp::writePlotSvg(p.spec, out + "/" + p.file + ".svg", error)) {
        std::cerr << "error: " << error << "\n";
        return 1;
      }
    }
  std::ofstream(out + "/report.md") << sp::validationReport(results, o);
  int passed = 0;
  for (const sp::ExperimentResult& r : results) passed += r.pass();
  std::cout << passed << " of " << results.size() << " experiments pass; report: " << out << "/report.md\n";
  return passed == static_cast<int>(results.size()) ? 0 : 4;
}

}  // namespace sp::simtool
