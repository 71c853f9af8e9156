// Critic: normalised least squares with covariance resetting (eqs. 23-24, ERRATA's normalisation).
//   rho   = 1 + nu omega^T Gamma omega
//   dWc   = -eta_c Gamma omega eps_hjb / rho                 (eq. 23)
//   dGamma = -eta_c Gamma omega omega^T Gamma / rho           (eq. 24)
// With Bellman-error extrapolation each law gains the average of the same term over the N
// extrapolation points (extrapolation.hpp).
// Gamma is reset to gamma0 I when its smallest eigenvalue falls below epsilon_T. The test needs no
// eigen-decomposition: lambda_min(Gamma) >= epsilon_T exactly when the pivots of a factorisation
// of Gamma - epsilon_T I (Cholesky's, L D L^T's) are all positive.
// Dynamic sizes (K = Eigen::Dynamic, the URDF arms) gather the samples (trajectory and points) in
// blocks (gather/flush): Gamma [omega_1 ... omega_s] is then one matrix product and the s rank-one
// terms of dGamma one rank-s product, instead of s matrix-vector and s outer products (the same
// sums up to round-off; the fixed-size path keeps add_rates). Those products run in the dense
// kernels chosen at run time for the CPU (dense_kernels.hpp: AVX2 or AVX-512), or, with
// ADPARM_KERNELS=portable or on a CPU without them, in Eigen's portable products.
// Without extrapolation points (one sample per evaluation) the dynamic-size loop's RK4 step keeps
// each stage's rank-one dGamma as (Gamma omega, gain) instead of a K x K rate (stage_rates,
// low_rank_update; ClosedLoop::step).
#pragma once

#include <algorithm>
#include <cmath>

#include "adparm/dense_kernels.hpp"
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
    bool lower_only = false;      // gamma_rate holds blocks in its lower triangle only (flush)
    bool rate_unwritten = false;  // gamma_rate not zeroed yet (leave_rate_to_flush)
    // flush() mirrors a rank-s rate's lower triangle; false: the caller reads the lower triangle
    // alone and the entries above it are left as they are (ClosedLoop::lower_step).
    bool mirror_rate = true;
    // low_rank_update's column of Gamma_next - Gamma, and its ||.||_F for the next
    // needs_reset(previous, gamma, w) (negative: none; that call sums it from the matrices).
    Vector change_column;
    double step_change = -1.0;
    // needs_reset(previous, gamma, w)'s evolving state: lambda_min(Gamma) >= epsilon_T + bound -
    // bound_used; the margin of its next test above epsilon_T (0: none).
    double bound = 0.0, bound_used = 0.0, margin = 0.0;
  };

  Critic() = default;
  // `size`: the basis size K (== kSize when it is fixed); `blocks`: whether an evaluation gathers
  // more than one sample (extrapolation points).
  // The dense kernels are chosen here, once (ADPARM_KERNELS, dense_kernels.hpp; checked for
  // every loop, used by the dynamic sizes' gather/flush).
  Critic(const CriticSettings& settings, Eigen::Index size, bool blocks = true)
      : settings_(settings), size_(size), kernels_(select_dense_kernels(blocks)) {
    if constexpr (kSize != Dynamic) kernels_ = nullptr;  // add_rates: no kernels
    check_non_negative(settings.eta_c, "critic.eta_c");
    check_non_negative(settings.nu, "critic.nu");
    check_positive(settings.gamma0, "critic.gamma0");
    check_non_negative(settings.epsilon_T, "critic.epsilon_T");
    if (settings.epsilon_T >= settings.gamma0)
      throw std::invalid_argument("critic.epsilon_T: must be smaller than critic.gamma0");
  }

  const CriticSettings& settings() const { return settings_; }
  // The dense kernels of gather/flush (nullptr: Eigen's portable products).
  const DenseKernels* kernels() const { return kernels_; }

  Workspace workspace() const {
    Workspace w;
    w.factor.resize(size_, size_);
    if constexpr (kSize == Dynamic) {
      w.omegas.setZero(size_, kBlock);
      w.gamma_omegas.setZero(size_, kBlock);
      w.scaled.setZero(size_, kBlock);
      w.coefficients.setZero(kBlock);
      w.weights.setZero(kBlock);
      w.change_column.setZero(size_);
    }
    w.margin = 0.5 * (settings_.gamma0 - settings_.epsilon_T);  // needs_reset(previous, ...)'s
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

  // Dynamic sizes: gather() of a sample whose omega, eps and w the caller wrote straight into the
  // block's next column (w.omegas, w.coefficients and w.weights at w.gathered).
  template <class CovarianceIn, class CovarianceOut>
  void gathered(const CovarianceIn& gamma, Vector& weight_rate, CovarianceOut&& gamma_rate,
                Workspace& w) const {
    static_assert(kSize == Dynamic, "gather/flush are for dynamic sizes; use add_rates");
    if (++w.gathered == kBlock) add_block(gamma, weight_rate, gamma_rate, w);
  }

  // Adds the gathered samples' shares (eqs. 23-24) to the rates, then empties the block:
  //   G = Gamma [omega_1 ... omega_s]                            (one product)
  //   g_i = w_i eta_c / (1 + nu omega_i^T G_i)
  //   weight_rate -= G [g_i eps_i],  gamma_rate -= [g_i G_i] G^T   (rank s)
  // The rank-s term is symmetric: for s > 1 only its lower triangle is computed (half the
  // products), and the upper triangle is its mirror image, written once per evaluation (one
  // sample, s = 1, is a whole outer product). The covariance test reads the lower triangle.
  template <class CovarianceIn, class CovarianceOut>
  void flush(const CovarianceIn& gamma, Vector& weight_rate, CovarianceOut&& gamma_rate,
             Workspace& w) const {
    static_assert(kSize == Dynamic, "gather/flush are for dynamic sizes; use add_rates");
    add_block(gamma, weight_rate, gamma_rate, w);
    if (w.rate_unwritten) {  // nothing gathered (leave_rate_to_flush)
      gamma_rate.setZero();
      w.rate_unwritten = false;
    }
    if (w.lower_only) {  // mirror the lower triangle (the blocks of this evaluation)
      w.lower_only = false;
      if (!w.mirror_rate) return;
      const Eigen::Index n = gamma_rate.rows();
      if (kernels_ != nullptr) {  // in tiles transposed in registers (the same copies)
        kernels_->mirror_lower(n, gamma_rate.data(), gamma_rate.outerStride());
      } else {
        for (Eigen::Index j = 1; j < n; ++j)
          gamma_rate.col(j).head(j) = gamma_rate.row(j).head(j).transpose();
      }
    }
  }

  // Dynamic sizes with the dispatched kernels (kernels() not nullptr): instead of zeroing
  // gamma_rate before an evaluation's gather/flush, the first gathered block's rank-s term is
  // written into it (C = -(A B^T), the same bits as C -= A B^T on a zeroed C, without the pass
  // that zeroes K^2 entries); flush() zeroes it if nothing was gathered. The caller then leaves
  // gamma_rate as it was until flush().
  void leave_rate_to_flush(Workspace& w) const { w.rate_unwritten = kernels_ != nullptr; }

  // True when lambda_min(Gamma) < epsilon_T (also for a non-finite Gamma): below(gamma,
  // epsilon_T, w), a factorisation's pivots.
  template <class CovarianceIn>
  bool needs_reset(const CovarianceIn& gamma, Workspace& w) const {
    return below(gamma, settings_.epsilon_T, w);
  }

  // The same answer as needs_reset(gamma), after a step from previous_gamma, mostly without the
  // Cholesky factorisation (dynamic sizes; Gamma is the symmetric matrix of its lower triangle,
  // the one the factorisation reads). Weyl's inequality:
  //   lambda_min(Gamma_k+1) >= lambda_min(Gamma_k) - ||Gamma_k+1 - Gamma_k||_2,
  //   ||.||_2 <= ||.||_F,
  // so once lambda_min >= epsilon_T + m is known (gamma0 after a reset, or a factorisation of
  // Gamma - (epsilon_T + m) I that succeeded), no reset is due while the steps' summed changes
  // ||dGamma||_F stay below m (less a tolerance above the factorisation's round-off, so that the
  // answer is needs_reset's at every step). When that bound is used up: the test at epsilon_T + m
  // (success: a new bound m), else needs_reset's test; m is quartered after each failed try (down
  // to 0: needs_reset's test alone at every step until the next reset).
  template <class PreviousIn, class CovarianceIn>
  bool needs_reset(const PreviousIn& previous_gamma, const CovarianceIn& gamma,
                   Workspace& w) const {
    const Eigen::Index n = gamma.rows();
    if (w.step_change >= 0.0) {  // summed by low_rank_update
      w.bound_used += w.step_change;
      w.step_change = -1.0;
    } else {
      double change = 0.0;  // ||Gamma - previous||_F of the symmetric matrices (lower triangles)
      for (Eigen::Index j = 0; j < n; ++j) {
        const double diagonal = gamma(j, j) - previous_gamma(j, j);
        change += diagonal * diagonal +
                  2.0 * (gamma.col(j).tail(n - j - 1) - previous_gamma.col(j).tail(n - j - 1))
                            .squaredNorm();
      }
      w.bound_used += std::sqrt(change);
    }
    if (w.bound_used < w.bound) return false;  // lambda_min > epsilon_T (also false for NaN)
    w.bound = 0.0;
    w.bound_used = 0.0;
    const double tolerance = round_off_tolerance(n);
    if (w.margin > 0.0) {
      if (!below(gamma, settings_.epsilon_T + w.margin, w)) {
        w.bound = w.margin - tolerance;
        return false;
      }
      w.margin = w.margin > 64.0 * tolerance ? 0.25 * w.margin : 0.0;
    }
    return needs_reset(gamma, w);
  }

  // After a reset (Gamma = gamma0 I, lambda_min = gamma0): the bound for needs_reset(previous,
  // gamma, w) is gamma0 - epsilon_T.
  void after_reset(Workspace& w) const {
    const double tolerance = round_off_tolerance(size_);
    w.bound = settings_.gamma0 - settings_.epsilon_T - tolerance;
    w.bound_used = 0.0;
    w.margin = 0.5 * (settings_.gamma0 - settings_.epsilon_T);
  }

  // True when lambda_min(Gamma) < threshold (also for a non-finite Gamma): an in-place
  // factorisation of Gamma - threshold I (lower triangle; Gamma is symmetric) that stops at the
  // first pivot that is not positive (Sylvester: all pivots are positive exactly when the matrix is
  // positive definite): about N^3 / 6 multiply-adds, no eigen-decomposition. A NaN or infinity
  // reaches a pivot and fails the test. Dynamic sizes above 24 functions take Cholesky's factor
  // column by column (left-looking: column j is updated by one matrix-vector product with the
  // columns before it, contiguous in the column-major buffer); up to 24 functions (the paper's 8
  // among them) the loop below, L D L^T's pivots, whose short columns stay in cache.
  template <class CovarianceIn>
  bool below(const CovarianceIn& gamma, double threshold, Workspace& w) const {
    const Eigen::Index n = w.factor.rows();
    Covariance& factor = w.factor;  // its lower triangle: the factorisation's work
    factor = gamma;                 // (a buffer sized once: no allocation)
    if constexpr (kSize == Dynamic) {
      if (n > 24) {
        for (Eigen::Index j = 0; j < n; ++j) {
          if (j > 0)
            factor.col(j).tail(n - j).noalias() -=
                factor.block(j, 0, n - j, j) * factor.row(j).head(j).transpose();
          const double pivot = factor(j, j) - threshold;
          if (!(pivot > 0.0)) return true;  // also catches NaN
          factor.col(j).tail(n - j - 1) *= 1.0 / std::sqrt(pivot);
        }
        return false;
      }
    }
    // Right-looking, without square roots (the pivots of L D L^T, Gaussian elimination of the
    // symmetric matrix): column j's pivot d, then the trailing lower triangle less the outer
    // product of its column scaled by 1/d. The pivots are those of the Cholesky factorisation
    // (d_j = L_jj^2) up to round-off; the chain from one pivot to the next is a division and a
    // multiply-add instead of a square root, a division and a dot product.
    for (Eigen::Index j = 0; j < n; ++j) factor(j, j) -= threshold;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double pivot = factor(j, j);
      if (!(pivot > 0.0)) return true;  // also catches NaN
      const double inverse = 1.0 / pivot;
      for (Eigen::Index i = j + 1; i < n; ++i) {
        const double scaled = factor(i, j) * inverse;
        if constexpr (kSize != Dynamic)  // whole fixed-size columns (above the diagonal: unread)
          factor.col(i) -= scaled * factor.col(j);
        else
          factor.col(i).tail(n - i) -= scaled * factor.col(j).tail(n - i);
      }
    }
    return false;
  }

  // The low-rank RK4 step (dynamic sizes, one sample per evaluation: no extrapolation points;
  // ClosedLoop::step). Each stage's dGamma = -g u u^T is rank one (eq. 24, u = Gamma_s omega), so
  // a stage's covariance Gamma_s = Gamma - c g_p u_p u_p^T (Gamma the step's, (u_p, g_p) the
  // previous stage's, c = h/2 or h) is never formed:
  //   u = Gamma omega - c g_p (u_p^T omega) u_p,   g = w eta_c / (1 + nu omega^T u),
  //   weight_rate -= g eps u                                       (eqs. 23-24)
  // Writes u, returns g; previous_scale = c g_p (0 at the first stage: Gamma_s = Gamma).
  template <class CovarianceIn, class Previous, class Column>
  double stage_rates(const Vector& omega, double hjb_error, const CovarianceIn& gamma,
                     const Previous& previous, double previous_scale, double weight,
                     Vector& weight_rate, Column&& u) const {
    const Eigen::Index k = gamma.rows();
    if (kernels_ != nullptr)
      kernels_->product(k, 1, k, gamma.data(), gamma.outerStride(), omega.data(), 1, k, u.data(), k,
                        false);
    else
      u.noalias() = gamma * omega;
    if (previous_scale != 0.0) u -= (previous_scale * previous.dot(omega)) * previous;
    const double gain = weight * settings_.eta_c / (1.0 + settings_.nu * omega.dot(u));
    weight_rate.noalias() -= (gain * hjb_error) * u;
    return gain;
  }

  // A low-rank stage's Gamma_s as a metric (positive_block.hpp's projection): Gamma_s v.
  template <class CovarianceIn, class Previous>
  struct StageCovariance {
    const CovarianceIn& gamma;
    const Previous& previous;
    double scale;  // c g_p
    Vector operator*(const Vector& v) const {
      Vector product = gamma * v;
      if (scale != 0.0) product -= (scale * previous.dot(v)) * previous;
      return product;
    }
  };

  // The step's end: Gamma_next = Gamma - sum_s c_s u_s u_s^T over the four stages' u_s (columns
  // of `u`; c_s = h/6 {1, 2, 2, 1} g_s, RK4's weights), in one pass over the columns that also
  // sums ||Gamma_next - Gamma||_F (the symmetric matrix of its lower triangle, as
  // needs_reset(previous, gamma, w)) for the covariance test's next call. (The stored
  // Gamma_next differs from Gamma - D by the subtraction's round-off, about 1e-16 gamma0 per
  // entry and step: far inside the bound's tolerance, 1e-12 K^2 gamma0.)
  // With the dispatched kernels (dense_kernels.hpp) the same pass runs in them, and the norm is
  // that of every entry of D (the symmetric D's, up to round-off).
  template <class CovarianceIn, class Vectors, class CovarianceOut>
  void low_rank_update(const CovarianceIn& gamma, const Vectors& u, const Eigen::Vector4d& c,
                       CovarianceOut&& gamma_next, Workspace& w) const {
    const Eigen::Index n = gamma.rows();
    if (kernels_ != nullptr) {
      w.step_change = std::sqrt(kernels_->low_rank_update(
          n, u.data(), u.outerStride(), c.data(), gamma.data(), gamma.outerStride(),
          gamma_next.data(), gamma_next.outerStride()));
      return;
    }
    Vector& d = w.change_column;
    double change = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) {
      d.noalias() = (c[0] * u(j, 0)) * u.col(0) + (c[1] * u(j, 1)) * u.col(1) +
                    (c[2] * u(j, 2)) * u.col(2) + (c[3] * u(j, 3)) * u.col(3);
      gamma_next.col(j) = gamma.col(j) - d;
      change += d[j] * d[j] + 2.0 * d.tail(n - j - 1).squaredNorm();
    }
    w.step_change = std::sqrt(change);
  }

  // Gamma(0) = gamma0 I (also the reset value), written into `gamma` (a Map into the state).
  template <class CovarianceOut>
  void reset(CovarianceOut&& gamma) const {
    gamma.setIdentity();
    gamma *= settings_.gamma0;
  }

 private:
  // Above the round-off of a Cholesky (or L D L^T) factorisation of an n x n matrix of norm <=
  // gamma0 (Gamma only decreases between resets: each RK4 stage's dGamma is negative
  // semi-definite).
  double round_off_tolerance(Eigen::Index n) const {
    return 1e-12 * static_cast<double>(n * n) * settings_.gamma0;
  }

  // flush() without the mirror: the gathered block's shares, the rank-s term (s > 1) in the lower
  // triangle of gamma_rate only (w.lower_only remembers that the upper one is still to be written).
  template <class CovarianceIn, class CovarianceOut>
  void add_block(const CovarianceIn& gamma, Vector& weight_rate, CovarianceOut& gamma_rate,
                 Workspace& w) const {
    const Eigen::Index s = w.gathered;
    if (s == 0) return;
    w.gathered = 0;
    const auto omegas = w.omegas.leftCols(s);
    auto gamma_omegas = w.gamma_omegas.leftCols(s);
    auto scaled = w.scaled.leftCols(s);
    const Eigen::Index k = gamma.rows();
    if (kernels_ != nullptr)
      kernels_->product(k, s, k, gamma.data(), gamma.outerStride(), omegas.data(),
                        omegas.innerStride(), omegas.outerStride(), gamma_omegas.data(),
                        gamma_omegas.outerStride(), false);
    else
      gamma_omegas.noalias() = gamma * omegas;
    if (kernels_ != nullptr) {  // the same products in the dispatched kernels
      kernels_->gains(k, s, omegas.data(), omegas.outerStride(), gamma_omegas.data(),
                      gamma_omegas.outerStride(), w.weights.data(), settings_.eta_c, settings_.nu,
                      w.coefficients.data(), scaled.data(), scaled.outerStride());
      kernels_->product(k, 1, s, gamma_omegas.data(), gamma_omegas.outerStride(),
                        w.coefficients.data(), 1, s, weight_rate.data(), k, true);
      kernels_->rank_update(k, s, scaled.data(), scaled.outerStride(), gamma_omegas.data(),
                            gamma_omegas.outerStride(), gamma_rate.data(), gamma_rate.outerStride(),
                            s > 1, w.rate_unwritten);
      w.rate_unwritten = false;
      w.lower_only = w.lower_only || s > 1;
      return;
    }
    for (Eigen::Index i = 0; i < s; ++i) {
      const double gain = w.weights[i] * settings_.eta_c /
                          (1.0 + settings_.nu * omegas.col(i).dot(gamma_omegas.col(i)));
      w.coefficients[i] *= gain;
      scaled.col(i) = gain * gamma_omegas.col(i);
    }
    weight_rate.noalias() -= gamma_omegas * w.coefficients.head(s);
    if (s == 1) {  // an outer product, whole (no GEMM for one column; cheaper than a mirror)
      gamma_rate.noalias() -= scaled.col(0).lazyProduct(gamma_omegas.col(0).transpose());
    } else {  // the lower triangle of the rank-s product (Eigen's triangular GEMM kernel)
      gamma_rate.template triangularView<Eigen::Lower>() -= scaled * gamma_omegas.transpose();
      w.lower_only = true;
    }
  }

  CriticSettings settings_{};
  Eigen::Index size_ = kSize == Dynamic ? 0 : kSize;
  const DenseKernels* kernels_ = nullptr;  // fixed sizes: none (add_rates)
};

}  // namespace adparm
