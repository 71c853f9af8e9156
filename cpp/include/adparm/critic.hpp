// Critic: normalised least squares with covariance resetting (eqs. 23-24, ERRATA's normalisation).
//   rho   = 1 + nu omega^T Gamma omega
//   dWc   = -eta_c Gamma omega eps_hjb / rho                 (eq. 23)
//   dGamma = -eta_c Gamma omega omega^T Gamma / rho           (eq. 24)
// With Bellman-error extrapolation each law gains the average of the same term over the N
// extrapolation points (extrapolation.hpp).
// Gamma is reset to gamma0 I when its smallest eigenvalue falls below epsilon_T. The test needs no
// eigen-decomposition: lambda_min(Gamma) >= epsilon_T exactly when Gamma - epsilon_T I has a
// Cholesky factor.
#pragma once

#include <cmath>

#include "adparm/types.hpp"

namespace adparm {

struct CriticSettings {
  double eta_c = 800.0;
  double nu = 1.0;
  double gamma0 = 100.0;
  double epsilon_T = 0.001;
};

template <class Basis>
class Critic {
 public:
  static constexpr int kSize = Basis::kSize;
  using Vector = typename Basis::Vector;
  // Gamma lives in the loop's state vector (a Map of this type); plain, not bounded.
  using Covariance = Eigen::Matrix<double, kSize, kSize>;

  Critic() = default;
  // `size`: the basis size K (== kSize when it is fixed).
  Critic(const CriticSettings& settings, Eigen::Index size)
      : settings_(settings), factor_(size, size) {
    check_non_negative(settings.eta_c, "critic.eta_c");
    check_non_negative(settings.nu, "critic.nu");
    check_positive(settings.gamma0, "critic.gamma0");
    check_non_negative(settings.epsilon_T, "critic.epsilon_T");
    if (settings.epsilon_T >= settings.gamma0)
      throw std::invalid_argument("critic.epsilon_T: must be smaller than critic.gamma0");
  }

  const CriticSettings& settings() const { return settings_; }

  // Adds one sample's share of eqs. (23)-(24) to the rates:
  //   weight_rate -= w eta_c Gamma omega eps / rho
  //   gamma_rate  -= w eta_c Gamma omega omega^T Gamma / rho
  // with w = 1 for the trajectory and w = 1/N for each of N extrapolation points
  // (extrapolation.hpp). Gamma is symmetric: Gamma omega omega^T Gamma = (Gamma omega)(...)^T.
  template <class CovarianceIn, class CovarianceOut>
  void add_rates(const Vector& omega, double hjb_error, const CovarianceIn& gamma, double weight,
                 Vector& weight_rate, CovarianceOut&& gamma_rate) const {
    const Vector gamma_omega = gamma.lazyProduct(omega);  // unrolled; no GEMV call for 8 x 8
    const double gain = weight * settings_.eta_c / (1.0 + settings_.nu * omega.dot(gamma_omega));
    weight_rate.noalias() -= (gain * hjb_error) * gamma_omega;
    gamma_rate.noalias() -= (gain * gamma_omega).lazyProduct(gamma_omega.transpose());
  }

  // True when lambda_min(Gamma) < epsilon_T (also for a non-finite Gamma): an in-place Cholesky
  // factorisation of Gamma - epsilon_T I (lower triangle; Gamma is symmetric), fixed size, that
  // stops at the first pivot that is not positive: about N^3 / 6 multiply-adds, no
  // eigen-decomposition. A NaN or infinity reaches a pivot and fails the test.
  template <class CovarianceIn>
  bool needs_reset(const CovarianceIn& gamma) const {
    const Eigen::Index n = factor_.rows();
    Covariance& factor = factor_;  // its lower triangle becomes L, Gamma - epsilon_T I = L L^T
    factor = gamma;                // (a buffer sized once: no allocation)
    for (Eigen::Index j = 0; j < n; ++j) {
      double pivot = factor(j, j) - settings_.epsilon_T;
      for (Eigen::Index k = 0; k < j; ++k) pivot -= factor(j, k) * factor(j, k);
      if (!(pivot > 0.0)) return true;  // also catches NaN
      const double diagonal = std::sqrt(pivot);
      const double inverse = 1.0 / diagonal;  // one division per column
      factor(j, j) = diagonal;
      for (Eigen::Index i = j + 1; i < n; ++i) {
        double value = factor(i, j);
        for (Eigen::Index k = 0; k < j; ++k) value -= factor(i, k) * factor(j, k);
        factor(i, j) = value * inverse;
      }
    }
    return false;
  }

  // Gamma(0) = gamma0 I (also the reset value), written into `gamma` (a Map into the state).
  template <class CovarianceOut>
  void reset(CovarianceOut&& gamma) const {
    gamma.setIdentity();
    gamma *= settings_.gamma0;
  }

 private:
  CriticSettings settings_{};
  mutable Covariance factor_;  // needs_reset's work buffer
};

}  // namespace adparm
