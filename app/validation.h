#pragma once
// The founding paper's validation experiments, run headless on the twin
// (`simpartner-sim validate`). Each experiment returns its figures beside the
// paper's, pass or fail against a stated target, the conditions, and the
// data behind its plots; nothing in a report is typed by hand.

#include <iosfwd>
#include <string>
#include <vector>

#include "app/plot.h"
#include "sim/params.h"

namespace sp {

/// One figure of an experiment: ours beside the paper's.
struct Metric {
  std::string quantity;
  std::string paper;   ///< the paper's figure as text ("" if it gives none)
  double ours = 0;
  std::string unit;
  std::string target;  ///< what counts as a pass, in words
  bool pass = true;
};

struct ExperimentPlot {
  std::string file;  ///< base name, no extension: file.png and file.csv
  PlotSpec spec;
};

struct ExperimentResult {
  int number = 0;
  std::string title;
  std::string conditions;  ///< world, friction, commands
  std::vector<Metric> metrics;
  std::vector<ExperimentPlot> plots;
  std::string discussion;  ///< what the figures mean, with the numbers filled in
  double simSeconds = 0, wallSeconds = 0;
  bool pass() const;
};

struct ValidationOptions {
  std::string sourceDir = ".";  ///< where robots/ and terrains/ are
  bool quick = false;           ///< shorter runs (for CI)
  SimParams params;             ///< physics parameters for every experiment
};

/// Runs the five experiments in order, logging progress to `log`. Throws
/// std::runtime_error (with the loader's diagnostics) if a shipped file is
/// broken. Thread: any; builds its own worlds.
std::vector<ExperimentResult> runValidation(const ValidationOptions& options, std::ostream& log);

ExperimentResult circularDrive(const ValidationOptions& options);
ExperimentResult laserSweep(const ValidationOptions& options);
ExperimentResult pickAndPlace(const ValidationOptions& options);
ExperimentResult slipperySurface(const ValidationOptions& options);
ExperimentResult testTrack(const ValidationOptions& options);

/// The report in Markdown: a summary table of every metric beside the
/// paper's with pass or fail, the conditions, then a section per experiment
/// with its plots (`file.png`) and discussion.
std::string validationReport(const std::vector<ExperimentResult>& results, const ValidationOptions& options);

}  // namespace sp
