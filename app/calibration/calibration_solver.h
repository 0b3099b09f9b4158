#pragma once
// The linear algebra of a calibration fit (calibration.cpp): the normal
// equations of the scaled residuals, the Levenberg-Marquardt step, the
// parameters' covariance and which of them the data pins. On Eigen: its
// LDLT factors the small symmetric systems (at most 7 unknowns), and the
// covariance's off-diagonal terms are there for what needs them.
//
// Thread: pure functions.

#include <Eigen/Dense>
#include <optional>
#include <vector>

#include "app/calibration/calibration.h"

namespace sp::calibration_detail {

/// The scaled residuals' derivatives: one column per parameter (by its
/// CalParam index; empty for a parameter not probed), d r / d (value / scale).
using Columns = std::vector<std::vector<double>>;

/// J'J and J'r over the parameters `on` (indices into the columns), in that order.
struct Normal {
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
};
Normal normalEquations(const Columns& jac, const std::vector<double>& r, const std::vector<int>& on);

/// The inverse of the symmetric positive (semi)definite `a`, or nullopt
/// when `a` is singular (a pivot of its LDLT below 1e-12: the threshold the
/// hand-written elimination had).
std::optional<Eigen::MatrixXd> inverseSymmetric(const Eigen::MatrixXd& a);
/// a x = b for the symmetric positive definite `a`; nullopt when singular.
std::optional<Eigen::VectorXd> solveSymmetric(const Eigen::MatrixXd& a, const Eigen::VectorXd& b);

/// The Levenberg-Marquardt step of `n`: (H + lambda diag H) dx = -g.
std::optional<Eigen::VectorXd> levenbergMarquardtStep(const Normal& n, double lambda);

/// Each parameter's standard deviation (in its own units) given the scaled
/// Jacobian columns `jac`; parameters the data cannot pin are dropped from
/// `on` one at a time, worst first; returns those kept, their deviations
/// in `sigma`.
/// Observability is judged on the residuals' scales as given (far from the
/// fit they are large for want of fitting, not noise): a parameter is
/// observed when its deviation is at most `threshold` of its scale. The
/// deviations reported are the residuals' own scatter's, grown by
/// `correlated`, the residuals that move together (a segment's checkpoints
/// share its anchor's error: they count as one), so that fusing fits
/// (fuse()) weighs each window for what it is worth: a window the twin
/// follows closely counts more than one it follows loosely (a fit that has
/// not yet converged). They were floored at the residuals' scales, which
/// made every window's about 1.5-2 % on the radius where the fits' errors
/// were 0.2-0.3 %, and the fusion weighed the first windows (fitted before
/// the splits were pinned) as much as the rest (docs/performance.md).
std::vector<int> observable(const Columns& jac, const std::vector<double>& r, std::vector<int> on, CalValues& sigma,
                            double correlated, double threshold);

}  // namespace sp::calibration_detail
