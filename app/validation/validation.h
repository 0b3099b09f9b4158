#pragma once
// The founding paper's validation experiments, run headless on the twin
// (`simpartner-sim validate`). Each experiment returns its figures beside the
// paper's, pass or fail against a stated target, the conditions, and the
// data behind its plots; nothing in a report is typed by hand.

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "app/validation/plot.h"
#include "sim/params.h"

namespace sp {

/// What a figure is checked against: the report says so per criterion.
enum class Basis {
  Paper,        ///< validation: the paper's figure or observation (from outside the twin)
  Mathematics,  ///< verification: kinematics or statics the twin must obey
  Solver,       ///< numerics: the figure does not hang on the solver's settings
  Control,      ///< a case that must fail the test beside it (the test can fail)
};
const char* basisText(Basis basis);

/// One figure of an experiment: ours beside the paper's. A judged metric
/// has a target stated before the run that the figure can miss; an
/// unjudged one (judged = false) is reported for context and counts for
/// neither pass nor fail.
struct Metric {
  std::string quantity;
  std::string paper;   ///< the paper's figure as text ("" if it gives none)
  double ours = 0;
  std::string unit;
  std::string target;  ///< what counts as a pass, in words ("" when not judged)
  bool pass = false;
  bool judged = true;
  Basis basis = Basis::Paper;
  /// How close to the converged figure (the convergence study's reference)
  /// the figure must be for its verdict not to rest on solver error, in
  /// its unit; 0: within 10 % of the reference's. Stated where a relative
  /// one means nothing (a figure near zero).
  double converged = 0;
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

/// One physics setting of a convergence study.
struct PhysicsSetting {
  double step = 0.001;  ///< [s]
  int iterations = 40;  ///< the quick solver's; ignored when exact
  bool exact = false;   ///< ODE's exact (dense) solver
  std::string label() const;
};
/// Parses "STEP/ITERATIONS" or "STEP/exact" (step in seconds), comma-separated:
/// "0.001/40,0.0005/200,0.00025/exact". nullopt and `error` naming the item.
std::optional<std::vector<PhysicsSetting>> parsePhysicsSettings(const std::string& text, std::string& error);

/// Every judged figure of the suite at each setting, against the last
/// setting (the reference, the finest): so that no verdict rests on solver
/// error (issue 29). values[s][f]: setting s, figure f.
struct ConvergenceStudy {
  std::vector<PhysicsSetting> settings;
  std::vector<std::string> figures;  ///< "N. experiment: quantity", the judged metrics in suite order
  std::vector<std::vector<double>> values;
  std::vector<std::vector<bool>> passes;
  std::vector<double> wallSeconds;
  std::vector<double> absolute;  ///< each figure's Metric::converged (0: relative)
  double tolerance = 0.1;  ///< relative to the reference's figure
  /// |value - reference| <= absolute, or tolerance x |reference| where no
  /// absolute is stated, for every figure.
  bool withinTolerance(size_t setting) const;
  bool figureWithin(size_t setting, size_t figure) const;
};
/// Runs the suite (quick or full, as `base` says) at each setting, the
/// rest of the physics as `base.params`. Progress to `log`.
ConvergenceStudy convergenceStudy(const ValidationOptions& base, const std::vector<PhysicsSetting>& settings,
                                  std::ostream& log);
/// The study in Markdown: a table of each figure per setting, its relative
/// difference from the reference, and the cheapest setting within tolerance.
std::string convergenceReport(const ConvergenceStudy& study, const ValidationOptions& base);

/// A least-squares line y = intercept + slope x and its coefficient of
/// determination (1 = every point on the line; 0 = no better than the mean).
struct LinearFit {
  double slope = 0, intercept = 0, r2 = 0;
};
LinearFit linearFit(const std::vector<double>& x, const std::vector<double>& y);

/// Range errors sampled over time: errors[i] at range ranges[i] at times[i] (ascending).
struct ErrorSeries {
  std::vector<double> times, ranges, errors;
};
/// How far two series of range errors are from proportional to the range:
/// over the instants both have where |error of b| >= floor, the median of
/// |eb/db - ea/da| / |eb/db|. 0 when the error per metre of range is the
/// same in both; infinity without such instants.
double proportionalityMismatch(const ErrorSeries& a, const ErrorSeries& b, double floor);

/// The report in Markdown: a summary table of every metric beside the
/// paper's with pass or fail, the conditions, then a section per experiment
/// with its plots (`file.png`) and discussion.
std::string validationReport(const std::vector<ExperimentResult>& results, const ValidationOptions& options);

}  // namespace sp
