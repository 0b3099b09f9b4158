#include "app/validation/validation.h"

#include "app/validation/experiment.h"

namespace sp {

using namespace experiment;

LinearFit linearFit(const std::vector<double>& x, const std::vector<double>& y) {
  LinearFit f;
  if (x.size() < 2 || x.size() != y.size()) return f;
  f.slope = slope(x, y);
  f.intercept = mean(y) - f.slope * mean(x);
  const double my = mean(y);
  double residual = 0, total = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double e = y[i] - (f.intercept + f.slope * x[i]);
    residual += e * e;
    total += (y[i] - my) * (y[i] - my);
  }
  f.r2 = total > 0 ? 1 - residual / total : 0;
  return f;
}

double proportionalityMismatch(const ErrorSeries& a, const ErrorSeries& b, double floor) {
  std::vector<double> mismatch;
  // The instants both have (a beam out of range gives no sample).
  for (size_t i = 0, j = 0; i < a.times.size() && j < b.times.size();) {
    if (a.times[i] < b.times[j] - 1e-9) {
      ++i;
    } else if (b.times[j] < a.times[i] - 1e-9) {
      ++j;
    } else {
      if (std::abs(b.errors[j]) >= floor && a.ranges[i] > 0 && b.ranges[j] > 0) {
        const double perMetreA = a.errors[i] / a.ranges[i], perMetreB = b.errors[j] / b.ranges[j];
        mismatch.push_back(std::abs(perMetreB - perMetreA) / std::abs(perMetreB));
      }
      ++i, ++j;
    }
  }
  if (mismatch.empty()) return std::numeric_limits<double>::infinity();
  std::sort(mismatch.begin(), mismatch.end());
  return mismatch[mismatch.size() / 2];
}

namespace {

std::string solverText(const SimParams& p) {
  return "step " + num(p.step * 1000, 1) + " ms, " +
         (p.solver == Solver::Quick ? "quick solver " + std::to_string(p.iterations) + " iterations"
                                    : std::string("exact solver")) +
         ", ERP " + num(p.erp, 2) + ", CFM " + num(p.cfm * 1e6, 1) + "e-6";
}

}  // namespace

namespace {

// "Validation: 2 criteria against the paper (1 failed); verification: ..."
std::string checkedAgainst(const ExperimentResult& r) {
  std::string out;
  for (Basis b : {Basis::Paper, Basis::Mathematics, Basis::Solver, Basis::Control}) {
    int judged = 0, failed = 0;
    for (const Metric& m : r.metrics)
      if (m.judged && m.basis == b) ++judged, failed += !m.pass;
    if (judged == 0) continue;
    std::string text = basisText(b);
    text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
    out += (out.empty() ? "" : "; ") + text + ", " + std::to_string(judged) + (judged == 1 ? " criterion" : " criteria") +
           (failed ? " (" + std::to_string(failed) + " failed)" : "");
  }
  return (out.empty() ? "Nothing judged" : out) + ".";
}

}  // namespace

const char* basisText(Basis b) {
  switch (b) {
    case Basis::Paper: return "validation: the paper";
    case Basis::Mathematics: return "verification: mathematics";
    case Basis::Solver: return "numerics: the solver";
    case Basis::Control: return "control";
  }
  return "";
}

bool ExperimentResult::pass() const {
  return std::all_of(metrics.begin(), metrics.end(), [](const Metric& m) { return !m.judged || m.pass; });
}

std::vector<ExperimentResult> runValidation(const ValidationOptions& o, std::ostream& log) {
  std::vector<ExperimentResult> results;
  for (auto experiment : {circularDrive, laserSweep, pickAndPlace, slipperySurface, testTrack}) {
    const auto t0 = Clock::now();
    ExperimentResult r = experiment(o);
    r.wallSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    log << "  " << r.number << ". " << r.title << ": " << (r.pass() ? "pass" : "FAIL") << " (" << num(r.simSeconds, 0)
        << " s simulated in " << num(r.wallSeconds, 1) << " s)\n";
    results.push_back(std::move(r));
  }
  return results;
}

std::string validationReport(const std::vector<ExperimentResult>& results, const ValidationOptions& o) {
  // Table cells: a '|' would end the cell.
  auto cell = [](const std::string& text) {
    std::string out;
    for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
  };
  std::ostringstream md;
  int passed = 0;
  for (const ExperimentResult& r : results) passed += r.pass();
  // Model version: a hash of the robot file's bytes, so a report names the
  // exact model it was made with.
  std::ifstream robotFile(o.sourceDir + "/robots/workpartner.xml", std::ios::binary);
  std::ostringstream robotText;
  robotText << robotFile.rdbuf();
  const uint64_t hash = fnv1a64(robotText.str());
  char version[24];
  std::snprintf(version, sizeof version, "%016llx", static_cast<unsigned long long>(hash));
  md << "# SimPartner validation report\n\n"
     << "The founding paper's five validation experiments, run on the twin by `simpartner-sim validate"
     << (o.quick ? " --quick" : "") << "`. Every number below was computed by that run; the paper's figures are "
     << "quoted from ../shared/MISSION.md.\n\n"
     << "**" << passed << " of " << results.size() << " experiments pass.** Conditions common to all: WorkPartner "
     << "model robots/workpartner.xml (FNV-1a 64 of its contents: " << version << "), " << solverText(o.params)
     << ".\n\n"
     << "Each criterion says what it is checked against: **validation** compares with the paper's figures or "
     << "observations (from outside the twin); **verification** with the mathematics the twin must obey "
     << "(kinematics, statics); **numerics** that a figure does not hang on the solver's settings; a **control** is "
     << "a case that must fail the test beside it. Rows marked info are for the record and judge nothing.\n\n"
     << "| # | experiment | quantity | paper | ours | unit | target | checked against | result |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const ExperimentResult& r : results)
    for (const Metric& m : r.metrics)
      md << "| " << r.number << " | " << r.title << " | " << cell(m.quantity) << " | " << cell(m.paper) << " | "
         << num(m.ours, std::abs(m.ours) < 0.1 ? 4 : 2) << " | " << cell(m.unit) << " | " << cell(m.target) << " | "
         << (m.judged ? basisText(m.basis) : "") << " | " << (!m.judged ? "info" : m.pass ? "pass" : "**fail**") << " |\n";
  for (const ExperimentResult& r : results) {
    md << "\n## " << r.number << ". " << r.title << " — " << (r.pass() ? "pass" : "fail") << "\n\n"
       << checkedAgainst(r) << "\n\nConditions: " << r.conditions << ". Simulated " << num(r.simSeconds, 0)
       << " s in " << num(r.wallSeconds, 1) << " s.\n\n"
       << r.discussion << "\n\n";
    for (const ExperimentPlot& p : r.plots)
      md << "![" << p.spec.title << "](" << p.file << ".svg) (data: [" << p.file << ".csv](" << p.file
         << ".csv))\n\n";
  }
  return md.str();
}

std::string PhysicsSetting::label() const {
  return num(step * 1000, step < 0.001 ? 2 : 1) + " ms, " + (exact ? std::string("exact") : std::to_string(iterations) + " it.");
}

std::optional<std::vector<PhysicsSetting>> parsePhysicsSettings(const std::string& text, std::string& error) {
  std::vector<PhysicsSetting> out;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    at = comma + 1;
    const size_t slash = item.find('/');
    PhysicsSetting s;
    char* end = nullptr;
    const std::string step = item.substr(0, slash);
    s.step = std::strtod(step.c_str(), &end);
    const bool stepOk = slash != std::string::npos && !step.empty() && *end == '\0' && std::isfinite(s.step) &&
                        s.step >= 1e-5 && s.step <= 0.01;
    const std::string rest = slash == std::string::npos ? "" : item.substr(slash + 1);
    bool restOk = rest == "exact";
    if (restOk) {
      s.exact = true;
    } else {
      const long n = std::strtol(rest.c_str(), &end, 10);
      restOk = !rest.empty() && *end == '\0' && n >= 1 && n <= 10000;
      s.iterations = static_cast<int>(n);
    }
    if (!stepOk || !restOk) {
      error = "--convergence: '" + item + "': expected STEP/ITERATIONS or STEP/exact, the step in seconds (1e-5 to 0.01), " +
              "iterations 1 to 10000";
      return std::nullopt;
    }
    out.push_back(s);
    if (comma == text.size()) break;
  }
  if (out.size() < 2) {
    error = "--convergence: give at least two settings, the reference (the finest) last";
    return std::nullopt;
  }
  return out;
}

bool ConvergenceStudy::figureWithin(size_t s, size_t f) const {
  const double ref = values.back()[f];
  const double allowed = f < absolute.size() && absolute[f] > 0 ? absolute[f] : tolerance * std::abs(ref);
  return std::abs(values[s][f] - ref) <= allowed;
}

bool ConvergenceStudy::withinTolerance(size_t s) const {
  for (size_t f = 0; f < figures.size(); ++f)
    if (!figureWithin(s, f)) return false;
  return true;
}

ConvergenceStudy convergenceStudy(const ValidationOptions& base, const std::vector<PhysicsSetting>& settings,
                                  std::ostream& log) {
  ConvergenceStudy study;
  study.settings = settings;
  for (const PhysicsSetting& s : settings) {
    ValidationOptions o = base;
    o.params.step = s.step;
    o.params.iterations = s.iterations;
    o.params.solver = s.exact ? Solver::Exact : Solver::Quick;
    log << s.label() << ":\n";
    const auto t0 = Clock::now();
    const std::vector<ExperimentResult> results = runValidation(o, log);
    study.wallSeconds.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    std::vector<std::string> figures;
    std::vector<double>& values = study.values.emplace_back();
    std::vector<bool>& passes = study.passes.emplace_back();
    std::vector<double> absolute;
    for (const ExperimentResult& r : results)
      for (const Metric& m : r.metrics)
        // A numerics criterion measures the solver by design: not a figure to converge.
        if (m.judged && m.basis != Basis::Solver) {
          figures.push_back(std::to_string(r.number) + ". " + r.title + ": " + m.quantity);
          values.push_back(m.ours);
          passes.push_back(m.pass);
          absolute.push_back(m.converged);
        }
    if (study.absolute.empty()) study.absolute = absolute;
    // The quantity texts carry figures measured in the run (a hinge angle,
    // a radius): the first setting's name the rows.
    if (study.figures.empty()) study.figures = figures;
    if (values.size() != study.figures.size())
      throw std::runtime_error("convergence study: " + s.label() + " judged " + std::to_string(values.size()) +
                               " figures, the first setting " + std::to_string(study.figures.size()));
  }
  return study;
}

std::string convergenceReport(const ConvergenceStudy& study, const ValidationOptions& base) {
  std::string out = "# Convergence of the validation figures\n\n";
  out += std::string("Each judged figure of the ") + (base.quick ? "quick" : "full") +
         " suite at each physics setting (the rest as the parameters give: ERP " + num(base.params.erp, 2) +
         ", CFM " + num(base.params.cfm * 1e6, 1) + "e-6), against the last setting, the reference. A setting is "
         "within tolerance when every figure is within " + num(study.tolerance * 100, 0) +
         " % of the reference's, or within the tolerance its criterion states (in brackets after the figure's name, "
         "where a relative one means nothing: a figure near zero). Numerics criteria (they measure the solver) are "
         "not figures here. A value marked * is outside its tolerance. Written by `simpartner-sim validate "
         "--convergence`.\n\n";
  out += "| figure |";
  for (const PhysicsSetting& s : study.settings) out += " " + s.label() + " |";
  out += "\n|---|";
  for (size_t s = 0; s < study.settings.size(); ++s) out += "---|";
  out += "\n";
  const std::vector<double>& ref = study.values.back();
  for (size_t f = 0; f < study.figures.size(); ++f) {
    const bool stated = f < study.absolute.size() && study.absolute[f] > 0;
    out += "| " + study.figures[f] + (stated ? " (within " + shortestText(study.absolute[f]) + ")" : "") + " |";
    for (size_t s = 0; s < study.settings.size(); ++s) {
      const double v = study.values[s][f];
      out += " " + num(v, std::abs(v) < 0.1 ? 4 : 3) + (study.passes[s][f] ? "" : " (fail)") +
             (s + 1 < study.settings.size() && !study.figureWithin(s, f) ? " *" : "");
      if (s + 1 < study.settings.size())
        out += ref[f] != 0 ? " (" + std::string(v - ref[f] >= 0 ? "+" : "") + num(100 * (v - ref[f]) / std::abs(ref[f]), 0) + " %)"
                           : "";
      out += " |";
    }
    out += "\n";
  }
  out += "| within tolerance of the reference |";
  for (size_t s = 0; s + 1 < study.settings.size(); ++s) out += study.withinTolerance(s) ? " yes |" : " no |";
  out += " (reference) |\n| suite wall time |";
  for (double w : study.wallSeconds) out += " " + num(w, 0) + " s |";
  out += "\n\n";
  size_t cheapest = study.settings.size();
  for (size_t s = 0; s + 1 < study.settings.size(); ++s)
    if (study.withinTolerance(s) && (cheapest == study.settings.size() || study.wallSeconds[s] < study.wallSeconds[cheapest]))
      cheapest = s;
  out += cheapest < study.settings.size()
             ? "The cheapest setting within tolerance: **" + study.settings[cheapest].label() + "** (" +
                   num(study.wallSeconds[cheapest], 0) + " s).\n"
             : "No setting but the reference is within tolerance on every figure.\n";
  // A condition outside the suite, stated where the rule's result is.
  out += "\nThe default physics (config/defaults.params) is the cheapest setting within tolerance that also keeps "
         "what the stand-in robot reports consistent with its bodies' motion, which this suite does not judge: "
         "`build/bench/bench_rolling` (docs/performance.md, \"Default physics\").\n";
  return out;
}

}  // namespace sp
