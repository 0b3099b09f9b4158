// Each wheel motor's torque limit from the wheels' forces (calibration.h,
// calibration_twin.h fitMotorTorques).
//
// Why the forces: four velocity-controlled wheels on one body share the
// work, so a motor at half its torque is carried along by the other three
// at the speed they hold. The motion hardly shows it (a half-torque
// rear-left motor moved the end of a 30 s drive on the bumpy field by 3 mm);
// a fit of the motion put it into the delay or the tyres. What it changes is
// what that wheel pushes: where the wheel asks more than the motor has, its
// tangential force stops at the limit and the others' grow. The twin, run
// with the fitted values from the same anchors, pushes with its own limits;
// the robot's frames say what its wheels pushed.
//
// A limit is a hinge: above what the wheel asks it changes nothing, so the
// probes go down (a limit a share lower), and a motor that never reaches
// its limit in the window is left unobserved, at its start value.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "app/calibration/calibration_solver.h"
#include "app/calibration/calibration_twin.h"

namespace sp::calibration_detail {

namespace {

constexpr size_t kFirstTorque = static_cast<size_t>(CalParam::TorqueFL);
constexpr int kTorqueSteps = 3;  // Levenberg-Marquardt steps: the hinge is steep once reached

bool reportsForces(const std::vector<RobotFrame>& frames) {
  for (const RobotFrame& f : frames)
    for (double t : f.wheelTangential)
      if (t != 0) return true;
  return false;
}

// The twin's wheels' forces less the robot's, every checkpoint.
std::optional<std::vector<double>> forceResiduals(const Problem& pb, const CalValues& v, std::string& why) {
  std::vector<double> f;
  if (!residuals(pb, v, why, nullptr, 0, &f)) return std::nullopt;
  return f;
}

}  // namespace

std::string fitMotorTorques(const Problem& pb, const CalibrationOptions& o, CalValues& v, CalibrationFit& fit,
                            const std::function<double()>& elapsedMs, const std::function<bool()>& abort) {
  if (!reportsForces(*pb.frames)) return {};  // a log from before the forces were kept: nothing to judge
  std::vector<int> free;
  for (size_t i = kFirstTorque; i < kFirstTorque + 4; ++i)
    if (!o.fixed[i]) free.push_back(static_cast<int>(i));
  if (free.empty()) return {};
  std::string why;
  std::optional<std::vector<double>> first = forceResiduals(pb, v, why);
  if (!first) return "the twin diverged comparing the wheels' forces: " + why;
  std::vector<double> r = std::move(*first);
  ++fit.twinRuns;
  const CalValues start = v;
  Columns jac(kCalParams);
  std::vector<int> on, everSmooth;
  double lambda = 1e-3;
  for (int it = 0; it < kTorqueSteps; ++it) {
    const double began = elapsedMs();
    if (abort && abort()) return "cancelled";
    std::vector<Candidate> probes;
    for (int p : free) {
      probes.push_back({v, 0, true});
      probes.back().values[static_cast<size_t>(p)] -= calParams()[static_cast<size_t>(p)].probe;
    }
    probes.push_back({v, 1e-6, true});  // the contacts' chaos alone
    const auto runs = runAll(pb, probes, o.threads, why, abort);
    fit.twinRuns += static_cast<int>(probes.size());
    for (const auto& run : runs)
      if (!run) return why == "cancelled" ? why : "the twin diverged probing the motors' torque: " + why;
    double noise = 0;
    for (size_t i = 0; i < r.size(); ++i) noise += ((*runs.back())[i] - r[i]) * ((*runs.back())[i] - r[i]);
    std::vector<int> smooth;
    for (size_t k = 0; k < free.size(); ++k) {
      const CalParamInfo& info = calParams()[static_cast<size_t>(free[k])];
      std::vector<double>& col = jac[static_cast<size_t>(free[k])];
      col.resize(r.size());
      double move = 0;
      for (size_t i = 0; i < r.size(); ++i) {
        const double apart = (*runs[k])[i] - r[i];
        col[i] = -apart / info.probe * info.scale;
        move += apart * apart;
      }
      // One probe against the chaos: a limit the wheel never reached moves
      // the forces no more than anchors a micrometre off do.
      if (move > 4 * noise) {
        smooth.push_back(free[k]);
        if (std::find(everSmooth.begin(), everSmooth.end(), free[k]) == everSmooth.end()) everSmooth.push_back(free[k]);
      }
    }
    CalValues sigma{};
    on = observable(jac, r, smooth, sigma, 1, 0.5);
    if (on.empty()) break;
    const Normal n = normalEquations(jac, r, on);
    bool stepped = false;
    for (int attempt = 0; attempt < 4 && !stepped; ++attempt) {
      const std::optional<Eigen::VectorXd> dx = levenbergMarquardtStep(n, lambda);
      if (!dx) break;
      CalValues c = v;
      for (size_t k = 0; k < on.size(); ++k) {
        const CalParamInfo& info = calParams()[static_cast<size_t>(on[k])];
        c[static_cast<size_t>(on[k])] = std::clamp(c[static_cast<size_t>(on[k])] + (*dx)(static_cast<Eigen::Index>(k)) * info.scale,
                                                   info.lower, info.upper);
      }
      std::string cwhy;
      ++fit.twinRuns;
      std::optional<std::vector<double>> cr = forceResiduals(pb, c, cwhy);
      if (cr && meanSquare(*cr) < meanSquare(r)) {
        v = c;
        r = std::move(*cr);
        lambda = std::max(1e-6, lambda / 3);
        stepped = true;
      } else {
        lambda *= 8;
      }
    }
    if (!stepped) break;
    const double now = elapsedMs();
    if (o.budgetMs > 0 && now + (now - began) > o.budgetMs) break;
  }
  // The deviations at the fit, each segment's checkpoints counted as one.
  CalValues sigma{};
  std::sort(everSmooth.begin(), everSmooth.end());
  on = everSmooth.empty() ? std::vector<int>{} : observable(jac, r, everSmooth, sigma, std::max(1.0, o.horizon / o.checkpoint), 0.5);
  for (int p : free) {
    const size_t i = static_cast<size_t>(p);
    const bool observed = std::find(on.begin(), on.end(), p) != on.end();
    fit.observed[i] = observed;
    fit.sigma[i] = observed ? sigma[i] : 0;
    if (!observed) v[i] = start[i];  // unobserved: left alone
    fit.value[i] = v[i];
  }
  return {};
}

}  // namespace sp::calibration_detail
