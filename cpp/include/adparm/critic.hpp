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

#include <Eigen/Cholesky>

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
  using Vector = typename Basis::Vector;
  using Covariance = Eigen::Matrix<double, Basis::kSize, Basis::kSize>;

  Critic() = default;
  explicit Critic(const CriticSettings& settings) : settings_(settings) {
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
    const Vector gamma_omega = gamma * omega;
    const double gain = weight * settings_.eta_c / (1.0 + settings_.nu * omega.dot(gamma_omega));
    weight_rate.noalias() -= (gain * hjb_error) * gamma_omega;
    gamma_rate.noalias() -= gain * gamma_omega * gamma_omega.transpose();
  }

  // True when lambda_min(Gamma) < epsilon_T (also for a non-finite Gamma).
  template <class CovarianceIn>
  bool needs_reset(const CovarianceIn& gamma) const {
    Covariance shifted = gamma;
    shifted.diagonal().array() -= settings_.epsilon_T;
    const Eigen::LLT<Covariance> cholesky(shifted);
    return cholesky.info() != Eigen::Success;
  }

  Covariance initial_covariance() const { return settings_.gamma0 * Covariance::Identity(); }

 private:
  CriticSettings settings_{};
};

}  // namespace adparm
