// The calibrated parameters (app/calibration/calibration.h; their table is
// sim/calibration_table.h): their values in SimParams, the estimates and
// their fusing, and how a value or a fit is said.
#include "app/calibration/calibration.h"

#include <cmath>
#include <cstdio>

#include "sim/text.h"

namespace sp {

CalValues calValues(const SimParams& p) {
  CalValues v{};
  for (size_t i = 0; i < kCalParams; ++i) v[i] = p.*calParams()[i].field;
  return v;
}

SimParams withCalValues(SimParams p, const CalValues& v) {
  for (size_t i = 0; i < kCalParams; ++i) p.*calParams()[i].field = v[i];
  return p;
}

CalValues filesCalValues() {
  CalValues v{};
  for (size_t i = 0; i < kCalParams; ++i) v[i] = calParams()[i].files;
  return v;
}

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
