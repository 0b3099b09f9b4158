// The calibrated parameters (app/calibration/calibration.h): their table,
// the estimates and their fusing, and how a value or a fit is said.
#include "app/calibration/calibration.h"

#include <cmath>
#include <cstdio>

#include "sim/text.h"

namespace sp {

const std::array<CalParamInfo, kCalParams>& calParams() {
  // Bounds are calibration.*'s in sim/params.cpp; scales the ranges
  // of a real robot's deviations (sim/perturbation.h), so that "observed"
  // means "pinned well inside what a robot may differ by".
  static const std::array<CalParamInfo, kCalParams> table{{
      // Probes of half a scale: a smaller one drowns in the contacts' noise.
      {"calibration.wheel_radius", "wheel radius", "", 1, 0.8, 1.2, 0.03, 0.015, 0},
      {"calibration.wheel_radius_split", "radius front - rear", "", 0, -0.1, 0.1, 0.03, 0.015, 0},
      {"calibration.wheel_radius_side", "radius left - right", "", 0, -0.1, 0.1, 0.03, 0.015, 0},
      {"calibration.wheel_radius_diag", "radius FL+RR - FR+RL", "", 0, -0.1, 0.1, 0.03, 0.015, 0},
      {"calibration.friction", "tyre friction", "", 1, 0.3, 3, 0.3, 0.15, 0},
      {"calibration.motor_gain", "wheel motor gain", "", 1, 0.5, 1.5, 0.2, 0.1, 0},
      {"calibration.delay", "command delay", "s", 0, 0, 0.5, 0.06, 0.03, 0},
      {"calibration.mass", "total mass", "", 1, 0.5, 2, 0.15, 0, 0},
      // Each link's centre may be 2 cm off on each axis (sim/perturbation.h);
      // the robot's, their mass-weighted mean, rather less.
      {"calibration.com_x", "centre of mass forward", "m", 0, -0.1, 0.1, 0.02, 0, kComBias},
      {"calibration.com_y", "centre of mass left", "m", 0, -0.1, 0.1, 0.02, 0, kComBias},
  }};
  return table;
}

namespace {

// Where each parameter lives in SimParams, in CalParam order: the one
// table calValues and withCalValues read.
constexpr std::array<double SimParams::*, kCalParams> kCalFields{
    &SimParams::calWheelRadius, &SimParams::calWheelRadiusSplit, &SimParams::calWheelRadiusSide,
    &SimParams::calWheelRadiusDiag, &SimParams::calFriction, &SimParams::calMotorGain,
    &SimParams::calDelay, &SimParams::calMass, &SimParams::calComX, &SimParams::calComY};

}  // namespace

CalValues calValues(const SimParams& p) {
  CalValues v{};
  for (size_t i = 0; i < kCalParams; ++i) v[i] = p.*kCalFields[i];
  return v;
}

SimParams withCalValues(SimParams p, const CalValues& v) {
  for (size_t i = 0; i < kCalParams; ++i) p.*kCalFields[i] = v[i];
  return p;
}

CalValues filesCalValues() { return calValues(SimParams{}); }

CalEstimate filesEstimate() {
  CalEstimate e;
  e.value = filesCalValues();
  return e;
}

CalValues significantValues(const CalEstimate& e) {
  CalValues out = e.value;
  for (size_t i = 0; i < kCalParams; ++i)
    if (e.observed[i] && std::abs(e.value[i] - calParams()[i].files) <= kSignificance * e.sigma[i]) out[i] = calParams()[i].files;
  return out;
}

CalEstimate fuse(const CalEstimate& prior, const CalibrationFit& fit, double overlap) {
  CalEstimate out = prior;
  out.time = std::max(prior.time, fit.to);
  const double dt = std::max(0.0, fit.to - prior.time);
  for (size_t i = 0; i < kCalParams; ++i) {
    if (!fit.observed[i] || !(fit.sigma[i] > 0) || !std::isfinite(fit.sigma[i])) continue;  // no information
    const double sigma = fit.sigma[i] * std::sqrt(std::max(1.0, overlap));
    if (!prior.observed[i]) {
      out.value[i] = fit.value[i];
      out.sigma[i] = sigma;
      out.observed[i] = true;
      continue;
    }
    const double drift = kDrift * calParams()[i].scale;
    const double p = prior.sigma[i] * prior.sigma[i] + drift * drift * dt;
    const double q = sigma * sigma;
    out.value[i] = (prior.value[i] * q + fit.value[i] * p) / (p + q);
    out.sigma[i] = std::max(std::sqrt(p * q / (p + q)), calParams()[i].floor);
  }
  return out;
}

std::string boundsRefusal(const CalParamInfo& info, double value) {
  // In words and the parameter's unit, three digits: what the operator
  // reads in the Calibration panel (issue 59: a raw key with 16 digits).
  const std::string unit = *info.unit ? std::string(" ") + info.unit : std::string(" ×");
  char text[200];
  std::snprintf(text, sizeof text, "the %s came out at %.3g%s, outside what the robot can have (%.3g to %.3g%s; %s)",
                info.label, value, unit.c_str(), info.lower, info.upper, unit.c_str(), info.key);
  return text;
}

std::string calibrationParamsText(const CalibrationFit& fit) {
  std::string out = "# Calibration fitted from telemetry " + shortestText(fit.from) + " - " + shortestText(fit.to) +
                    " s (" + std::to_string(fit.segments) + " segments; app/calibration/calibration.h)\n";
  for (size_t i = 0; i < kCalParams; ++i) {
    const CalParamInfo& info = calParams()[i];
    out += "# " + std::string(info.label) + ": " +
           (fit.observed[i] ? "+- " + shortestText(fit.sigma[i]) : std::string("unobserved, the files' or the previous value")) + "\n";
    out += std::string(info.key) + " = " + shortestText(fit.value[i]) + "\n";
  }
  return out;
}

}  // namespace sp
