// Experiment 1: circular drive (validation.h).

#include "app/validation/experiment.h"

namespace sp {

using namespace experiment;

// The circular errors [%] are near zero: converged means within a tenth of
// a percentage point, a fifth of the 0.5 % the paper's error allows.
constexpr double kCircularConverged = 0.1;

// 1. Articulation hinge held at several angles, wheel speeds from the
// articulated-steering kinematics; the hinge's path against the model circle.
ExperimentResult circularDrive(const ValidationOptions& o) {
  ExperimentResult r;
  r.number = 1;
  r.title = "Circular drive";
  const WorldModel model = loadModel(o, "terrains/flat.world.xml");
  // The quick suite records as long as the full one: over 8 s the arc at
  // 10 deg is 36 degrees of the circle and the fitted radius moved the
  // commanded-angle verdict (-1.1 % against -0.31 % over 20 s), and the
  // quick suite must give the full one's verdicts (issue 29). 3 s of wall time.
  const double speed = 0.5, settle = 3, record = 20;
  r.conditions = "terrains/flat.world.xml (rubber on ground, mu 1.0); drive " + num(speed, 1) +
                 " m/s at the hinge; " + num(settle, 0) + " s to settle, then the hinge point's path over " +
                 num(record, 0) + " s is fitted with a circle";
  PlotSpec paths{"Circular drive: path of the articulation hinge", "x [m]", "y [m]", {}, 900, 900, {}, {}};
  // The quick suite checks every angle the full one does.
  const std::vector<double> angles = {10, 20, 30};
  double worst = 0;
  for (double gammaDeg : angles) {
    auto w = makeWorld(model, o.params);
    w->submit(DriveCmd{speed, degToRad(gammaDeg)});
    stepFor(*w, settle);
    std::vector<Vec3> points;
    DriveGeometry mean{};
    int n = 0;
    const auto samples = std::llround(record / 0.02);
    for (int64_t i = 0; i < samples; ++i) {
      stepFor(*w, 0.02);
      points.push_back(hingePoint(*w));
      const DriveGeometry g = *w->driveGeometry(0);
      mean.frontLength += g.frontLength, mean.rearLength += g.rearLength, mean.articulation += g.articulation;
      ++n;
    }
    requireHealthy(*w, r.title);
    mean.frontLength /= n, mean.rearLength /= n, mean.articulation /= n;
    const auto [centre, radius] = fitCircle(points);
    // The kinematic radius for a hinge angle (workpartner-facts.md §3).
    const auto kinematic = [&](double gamma) {
      const double rRear = (mean.frontLength + mean.rearLength * std::cos(gamma)) / std::sin(gamma);
      return std::hypot(mean.rearLength, rRear);
    };
    const double expected = kinematic(mean.articulation), nominal = kinematic(degToRad(gammaDeg));
    const double error = 100 * (radius - expected) / expected;
    const double nominalError = 100 * (radius - nominal) / nominal;
    worst = std::max(worst, std::abs(error));
    r.metrics.push_back({"hinge path radius at " + num(gammaDeg, 0) + " deg, measured hinge angle " +
                             num(radToDeg(mean.articulation), 3) + " deg: model " + num(expected, 3) +
                             " m, simulated " + num(radius, 3) + " m; error",
                         "about 0.5", error, "%", "|error| <= 0.5 %", std::abs(error) <= 0.5, true, Basis::Mathematics,
                         kCircularConverged});
    r.metrics.push_back({"the same against the commanded (nominal) hinge angle: model " + num(nominal, 3) + " m; error",
                         "about 0.5", nominalError, "%", "|error| <= 0.5 %", std::abs(nominalError) <= 0.5, true,
                         Basis::Paper, kCircularConverged});
    PlotSeries path{"simulated, " + num(gammaDeg, 0) + " deg", {}, {}, PlotSeries::Style::Line};
    for (const Vec3& p : points) {
      path.x.push_back(p.x);
      path.y.push_back(p.y);
    }
    PlotSeries circle{"kinematic circle, " + num(gammaDeg, 0) + " deg", {}, {}, PlotSeries::Style::Points};
    for (int k = 0; k < 72; ++k) {
      const double a = 2 * kPi * k / 72;
      circle.x.push_back(centre.x + expected * std::cos(a));
      circle.y.push_back(centre.y + expected * std::sin(a));
    }
    paths.series.push_back(std::move(path));
    paths.series.push_back(std::move(circle));
    r.simSeconds += settle + record;
  }
  r.plots.push_back({"circular_paths", paths});
  r.discussion =
      "With the hinge held at gamma, both axle lines meet in one instantaneous centre, and the hinge runs on "
      "a circle of radius R_H = sqrt(L_r^2 + R_r^2), R_r = (L_f + L_r cos gamma) / sin gamma "
      "(workpartner-facts.md §3), with L_f, L_r and gamma measured on the twin during the run (they move "
      "slightly with the legs). The wheel speeds come from the same kinematics, recomputed every step. The "
      "criterion uses the measured hinge angle, as an experimenter with an encoder on the hinge would; the "
      "largest deviation is " + num(worst, 2) + " %, the compliance of the contacts and joints under the "
      "tyres' side forces (at ERP 0.2 it was about 0.5 %, see config/defaults.params). The paper's 0.5 % is "
      "judged against the commanded geometry too, as an operator would see it: there the error also holds "
      "the hinge controller's error under the steering load and the legs' give.";
  return r;
}

// 2. The torso turns at a constant rate in front of a wall; the laser's
// range error against time and distance, with the wall at three distances.

}  // namespace sp
