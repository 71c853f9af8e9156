// Critic: normalised least squares with covariance resetting (eqs. 23-24, ERRATA's normalisation).
//   rho   = 1 + nu omega^T Gamma omega
//   dWc   = -eta_c Gamma omega eps_hjb / rho                 (eq. 23)
//   dGamma = -eta_c Gamma omega omega^T Gamma / rho           (eq. 24)
// With Bellman-error extrapolation each law gains the average of the same term over the N
// extrapolation points (extrapolation.hpp).
// Gamma is reset to gamma0 I when its smallest eigenvalue falls below epsilon_T. The test needs no
// eigen-decomposition: lambda_min(Gamma) >= epsilon_T exactly when Gamma - epsilon_T I has a
// Cholesky factor.
// Dynamic sizes (K = Eigen::Dynamic, the URDF arms) gather the samples (trajectory and points) in
// blocks (gather/flush): Gamma [omega_1 ... omega_s] is then one matrix product and the s rank-one
// terms of dGamma one rank-s product, instead of s matrix-vector and s outer products (the same
// sums up to round-off; the fixed-size path keeps add_rates).
#pragma once

#include <algorithm>
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

  // Samples per gathered block (dynamic sizes): Gamma times a block is a K x K x kBlock product,
  // whose packing buffers stay on the stack (Eigen's GEMM) for every K <= kMaxBasisSize.
  static constexpr Eigen::Index kBlock = 64;
  using Block = Eigen::Matrix<double, kSize, Eigen::Dynamic>;  // K x kBlock, sized once

  // The critic's work buffers, sized once (workspace()), passed to the calls that use them; each
  // run has its own.
  struct Workspace {
    Covariance factor;  // needs_reset's
    // gather/flush (dynamic sizes): omega_i, Gamma omega_i, g_i Gamma omega_i, eps_i (then
    // g_i eps_i), w_i; `gathered` samples so far. Buffers of one evaluation.
    Block omegas, gamma_omegas, scaled;
    Eigen::VectorXd coefficients, weights;
    Eigen::Index gathered = 0;
    bool lower_only = false;  // gamma_rate holds blocks in its lower triangle only (flush)
  };

  Critic() = default;
  // `size`: the basis size K (== kSize when it is fixed).
  Critic(const CriticSettings& settings, Eigen::Index size) : settings_(settings), size_(size) {
    check_non_negative(settings.eta_c, "critic.eta_c");
    check_non_negative(settings.nu, "critic.nu");
    check_positive(settings.gamma0, "critic.gamma0");
    check_non_negative(settings.epsilon_T, "critic.epsilon_T");
    if (settings.epsilon_T >= settings.gamma0)
      throw std::invalid_argument("critic.epsilon_T: must be smaller than critic.gamma0");
  }

  const CriticSettings& settings() const { return settings_; }

  Workspace workspace() const {
    Workspace w;
    w.factor.resize(size_, size_);
    if constexpr (kSize == Dynamic) {
      w.omegas.setZero(size_, kBlock);
      w.gamma_omegas.setZero(size_, kBlock);
      w.scaled.setZero(size_, kBlock);
      w.coefficients.setZero(kBlock);
      w.weights.setZero(kBlock);
    }
    return w;
  }

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

  // Dynamic sizes: the same shares as add_rates, gathered (omega, eps and w of one sample) and
  // added to the rates by flush(), which gather calls when a block is full. Call flush() after
  // the last sample of an evaluation, with the same gamma and rates.
  template <class CovarianceIn, class CovarianceOut>
  void gather(const Vector& omega, double hjb_error, const CovarianceIn& gamma, double weight,
              Vector& weight_rate, CovarianceOut&& gamma_rate, Workspace& w) const {
    static_assert(kSize == Dynamic, "gather/flush are for dynamic sizes; use add_rates");
    w.omegas.col(w.gathered) = omega;
    w.coefficients[w.gathered] = hjb_error;
    w.weights[w.gathered] = weight;
    if (++w.gathered == kBlock) add_block(gamma, weight_rate, gamma_rate, w);
  }

  // Adds the gathered samples' shares (eqs. 23-24) to the rates, then empties the block:
  //   G = Gamma [omega_1 ... omega_s]                            (one product)
  //   g_i = w_i eta_c / (1 + nu omega_i^T G_i)
  //   weight_rate -= G [g_i eps_i],  gamma_rate -= [g_i G_i] G^T   (rank s)
  // The rank-s term is symmetric: only its lower triangle is computed (half the products), and
  // the upper triangle is its mirror image, written once per evaluation (the rate is then exactly
  // symmetric, so Gamma stays so).
  template <class CovarianceIn, class CovarianceOut>
  void flush(const CovarianceIn& gamma, Vector& weight_rate, CovarianceOut&& gamma_rate,
             Workspace& w) const {
    static_assert(kSize == Dynamic, "gather/flush are for dynamic sizes; use add_rates");
    add_block(gamma, weight_rate, gamma_rate, w);
    if (w.lower_only) {  // mirror the lower triangle (the blocks of this evaluation)
      w.lower_only = false;
      const Eigen::Index n = gamma_rate.rows();
      for (Eigen::Index j = 1; j < n; ++j)
        gamma_rate.col(j).head(j) = gamma_rate.row(j).head(j).transpose();
    }
  }

  // True when lambda_min(Gamma) < epsilon_T (also for a non-finite Gamma): an in-place Cholesky
  // factorisation of Gamma - epsilon_T I (lower triangle; Gamma is symmetric), fixed size, that
  // stops at the first pivot that is not positive: about N^3 / 6 multiply-adds, no
  // eigen-decomposition. A NaN or infinity reaches a pivot and fails the test.
  // Dynamic sizes above 24 functions factor column by column (left-looking: column j is updated
  // by one matrix-vector product with the columns before it, contiguous in the column-major
  // buffer); smaller ones use the loop below, whose short rows stay in cache.
  template <class CovarianceIn>
  bool needs_reset(const CovarianceIn& gamma, Workspace& w) const {
    const Eigen::Index n = w.factor.rows();
    Covariance& factor = w.factor;  // its lower triangle becomes L, Gamma - epsilon_T I = L L^T
    factor = gamma;                 // (a buffer sized once: no allocation)
    if constexpr (kSize == Dynamic) {
      if (n > 24) {
        for (Eigen::Index j = 0; j < n; ++j) {
          if (j > 0)
            factor.col(j).tail(n - j).noalias() -=
                factor.block(j, 0, n - j, j) * factor.row(j).head(j).transpose();
          const double pivot = factor(j, j) - settings_.epsilon_T;
          if (!(pivot > 0.0)) return true;  // also catches NaN
          factor.col(j).tail(n - j - 1) *= 1.0 / std::sqrt(pivot);
        }
        return false;
      }
    }
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
  // flush() without the mirror: the gathered block's shares, the rank-s term in the lower triangle
  // of gamma_rate only (w.lower_only remembers that the upper one is still to be written).
  template <class CovarianceIn, class CovarianceOut>
  void add_block(const CovarianceIn& gamma, Vector& weight_rate, CovarianceOut& gamma_rate,
                 Workspace& w) const {
    const Eigen::Index s = w.gathered;
    if (s == 0) return;
    w.gathered = 0;
    w.lower_only = true;
    const auto omegas = w.omegas.leftCols(s);
    auto gamma_omegas = w.gamma_omegas.leftCols(s);
    auto scaled = w.scaled.leftCols(s);
    gamma_omegas.noalias() = gamma * omegas;
    for (Eigen::Index i = 0; i < s; ++i) {
      const double gain = w.weights[i] * settings_.eta_c /
                          (1.0 + settings_.nu * omegas.col(i).dot(gamma_omegas.col(i)));
      w.coefficients[i] *= gain;
      scaled.col(i) = gain * gamma_omegas.col(i);
    }
    weight_rate.noalias() -= gamma_omegas * w.coefficients.head(s);
    auto lower = gamma_rate.template triangularView<Eigen::Lower>();
    if (s == 1)  // an outer product (no GEMM for one column)
      lower -= scaled.col(0).lazyProduct(gamma_omegas.col(0).transpose());
    else  // the lower triangle of the rank-s product (Eigen's triangular GEMM kernel)
      lower -= scaled * gamma_omegas.transpose();
  }

  CriticSettings settings_{};
  Eigen::Index size_ = kSize == Dynamic ? 0 : kSize;
};

}  // namespace adparm
