// The linear algebra of a calibration fit (calibration_solver.h).
#include "app/calibration/calibration_solver.h"

#include <algorithm>
#include <cmath>

#include "app/calibration/calibration_twin.h"

namespace sp::calibration_detail {

namespace {

constexpr double kSingular = 1e-12;

// The columns `on` of `jac` as a matrix (residuals x parameters).
Eigen::MatrixXd jacobian(const Columns& jac, size_t rows, const std::vector<int>& on) {
  Eigen::MatrixXd j(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(on.size()));
  for (size_t k = 0; k < on.size(); ++k)
    j.col(static_cast<Eigen::Index>(k)) =
        Eigen::Map<const Eigen::VectorXd>(jac[static_cast<size_t>(on[k])].data(), static_cast<Eigen::Index>(rows));
  return j;
}

std::optional<Eigen::LDLT<Eigen::MatrixXd>> factor(const Eigen::MatrixXd& a) {
  Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
  if (ldlt.info() != Eigen::Success || a.rows() == 0 || ldlt.vectorD().cwiseAbs().minCoeff() < kSingular)
    return std::nullopt;
  return ldlt;
}

}  // namespace

Normal normalEquations(const Columns& jac, const std::vector<double>& r, const std::vector<int>& on) {
  const Eigen::MatrixXd j = jacobian(jac, r.size(), on);
  const Eigen::Map<const Eigen::VectorXd> res(r.data(), static_cast<Eigen::Index>(r.size()));
  return Normal{j.transpose() * j, j.transpose() * res};
}

std::optional<Eigen::MatrixXd> inverseSymmetric(const Eigen::MatrixXd& a) {
  const auto ldlt = factor(a);
  if (!ldlt) return std::nullopt;
  return ldlt->solve(Eigen::MatrixXd::Identity(a.rows(), a.cols()));
}

std::optional<Eigen::VectorXd> solveSymmetric(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  const auto ldlt = factor(a);
  if (!ldlt) return std::nullopt;
  return ldlt->solve(b);
}

std::optional<Eigen::VectorXd> levenbergMarquardtStep(const Normal& n, double lambda) {
  Eigen::MatrixXd a = n.h;
  a.diagonal() *= 1 + lambda;
  return solveSymmetric(a, -n.g);
}

std::vector<int> observable(const Columns& jac, const std::vector<double>& r, std::vector<int> on, CalValues& sigma,
                            double correlated, double threshold) {
  const double dof = std::max<double>(1, static_cast<double>(r.size()) - static_cast<double>(on.size()));
  const double inflate = correlated * meanSquare(r) * static_cast<double>(r.size()) / dof;
  while (!on.empty()) {
    const Normal n = normalEquations(jac, r, on);
    const std::optional<Eigen::MatrixXd> covariance = inverseSymmetric(n.h);
    // Singular: the parameter the data moves least goes; else the least pinned.
    Eigen::Index worst = 0;
    if (covariance) covariance->diagonal().maxCoeff(&worst);
    else n.h.diagonal().minCoeff(&worst);
    if (covariance && std::sqrt((*covariance)(worst, worst)) <= threshold) {
      for (size_t k = 0; k < on.size(); ++k) {
        const auto e = static_cast<Eigen::Index>(k);
        sigma[static_cast<size_t>(on[k])] = std::sqrt((*covariance)(e, e) * inflate) * calParams()[static_cast<size_t>(on[k])].scale;
      }
      return on;
    }
    on.erase(on.begin() + worst);
  }
  return on;
}

}  // namespace sp::calibration_detail

// Consider covariance (calibration.h).
namespace sp {

std::vector<double> consideredVariance(const std::vector<std::vector<double>>& jac, const std::vector<int>& on,
                                       const std::vector<int>& held, const CalValues& heldVariance) {
  using namespace calibration_detail;
  std::vector<double> add(on.size(), 0);
  if (on.empty() || held.empty()) return add;
  const size_t rows = jac[static_cast<size_t>(on[0])].size();
  const Eigen::MatrixXd jo = jacobian(jac, rows, on);
  const Eigen::MatrixXd ju = jacobian(jac, rows, held);
  // Fitting `on` alone moves them by -H_oo^-1 H_ou per unit of a held one's error.
  const auto hoo = factor(jo.transpose() * jo);
  if (!hoo) return std::vector<double>(on.size(), INFINITY);
  const Eigen::MatrixXd moved = hoo->solve(jo.transpose() * ju);
  for (size_t u = 0; u < held.size(); ++u)
    for (size_t k = 0; k < on.size(); ++k) {
      const double x = moved(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(u));
      add[k] += x * x * heldVariance[static_cast<size_t>(held[u])];
    }
  return add;
}

}  // namespace sp
