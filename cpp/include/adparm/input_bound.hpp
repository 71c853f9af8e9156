// The constrained-input cost (Abu-Khalaf & Lewis, Automatica 41(5), 2005; Modares, Lewis &
// Naghibi-Sistani, IEEE TNNLS 24(10), 2013): with a bound |u_i| <= lambda_i and R diagonal,
//   U(u) = sum_i R_i [2 lambda_i u_i atanh(u_i / lambda_i) + lambda_i^2 ln(1 - u_i^2 / lambda_i^2)]
//        = sum_i R_i lambda_i^2 [(1 + s_i) ln(1 + s_i) + (1 - s_i) ln(1 - s_i)],  s = u / lambda,
// dU/du_i = 2 lambda_i R_i atanh(u_i / lambda_i). It replaces u^T R u in r(x, u), and the policy
// that minimises U(u) + dV/dx g u is
//   u = -lambda tanh(D),   D = (2 lambda)^-1 R^-1 g^T dV/dx,
// the unbounded policy v = -1/2 R^-1 g^T dV/dx = -lambda D squashed: u = lambda tanh(v / lambda).
// At that policy U(u) = sum_i R_i lambda_i^2 [2 D_i tanh D_i - 2 ln cosh D_i].
// An applied input beyond the bound (the actor's input stays inside it, the probe can push the sum
// outside) is charged U at the bound, R_i lambda_i^2 2 ln 2, plus R_i (|u_i| - lambda_i)^2 for the
// excess (the accumulated cost J only; the HJB error only sees the actor's input).
//
// e2_cost = logcosh: the e2 block of the state cost becomes
//   sum_i 2 lambda_i^2 R_i ln cosh(s_i e2_i / (R_i lambda_i)),   s_i = sqrt(Q22_ii R_i)
// (Q22 diagonal), whose small-e2 limit is e2^T Q22 e2; with Q22 = s^2 R^-1 (the exact family),
// V* = e1^T K e1 + s e2^T M(q) e2 solves the constrained HJB exactly (docs: constrained-input).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "adparm/types.hpp"

namespace adparm {

enum class E2Cost { quadratic, logcosh };

constexpr double kLn2 = 0.69314718055994530942;

// ln cosh z without overflow or cancellation: |z| + log1p(exp(-2 |z|)) - ln 2 for |z| >= 1,
// below log1p(m^2 / (2 (1 + m))), m = expm1(|z|), as cosh z - 1 = (e^|z| - 1)^2 / (2 e^|z|)
// (accurate to round-off near z = 0, where ln cosh z ~ z^2 / 2; one expm1, not sinh's call).
inline double log_cosh(double z) {
  const double a = std::abs(z);
  if (a < 1.0) {
    const double m = std::expm1(a);
    return std::log1p(m * m / (2.0 * (1.0 + m)));
  }
  return a + std::log1p(std::exp(-2.0 * a)) - kLn2;
}

// (1 + s) ln(1 + s) + (1 - s) ln(1 - s) for |s| <= 1 (0 ln 0 = 0); below |s| = 1e-3 its series
// sum_k s^2k / (k (2k - 1)) to s^6 (no cancellation).
inline double bounded_input_shape(double s) {
  const double a = std::min(std::abs(s), 1.0);
  if (a < 1e-3) {
    const double a2 = a * a;
    return a2 * (1.0 + a2 * (1.0 / 6.0 + a2 / 15.0));
  }
  return (1.0 + a) * std::log1p(a) + (a < 1.0 ? (1.0 - a) * std::log1p(-a) : 0.0);
}

template <int N = 2>
class InputBoundT {
 public:
  using Joint = JointVector<N>;

  InputBoundT() = default;  // no bound: the quadratic input cost
  // `bound`: lambda, n entries > 0 (empty: no bound); R must be diagonal then; `Q`: 2n x 2n, its
  // e2 block diagonal when e2_cost is logcosh (which needs a bound).
  InputBoundT(const Eigen::VectorXd& bound, E2Cost e2_cost, const Eigen::MatrixXd& Q,
              const Eigen::MatrixXd& R, Eigen::Index n) {
    if (bound.size() == 0) {
      if (e2_cost == E2Cost::logcosh)
        throw std::invalid_argument("cost.e2_cost: logcosh needs cost.input_bound");
      return;
    }
    check_size(bound, n, 1, "cost.input_bound");
    if (!(bound.array() > 0.0).all() || !bound.allFinite())
      throw std::invalid_argument("cost.input_bound: every entry must be a finite number > 0");
    const Eigen::MatrixXd off_diagonal = R - Eigen::MatrixXd(R.diagonal().asDiagonal());
    if (!(off_diagonal.cwiseAbs().maxCoeff() == 0.0))
      throw std::invalid_argument("cost.R: must be diagonal with cost.input_bound");
    bounded_ = true;
    bound_ = bound;
    input_weight_ = R.diagonal();
    if (e2_cost == E2Cost::logcosh) {
      const Eigen::MatrixXd Q22 = Q.bottomRightCorner(n, n);
      const Eigen::MatrixXd off = Q22 - Eigen::MatrixXd(Q22.diagonal().asDiagonal());
      if (!(off.cwiseAbs().maxCoeff() == 0.0))
        throw std::invalid_argument(
            "cost.Q: its e2 block Q22 must be diagonal with cost.e2_cost = logcosh");
      logcosh_ = true;
      e2_scale_ = (Q22.diagonal().array() * R.diagonal().array()).sqrt().matrix();
    }
  }

  bool bounded() const { return bounded_; }
  bool logcosh() const { return logcosh_; }
  const Joint& bound() const { return bound_; }

  // u = lambda tanh(v / lambda), v the unbounded policy -1/2 R^-1 B^T Wa (eq. 20).
  Joint saturate(const Joint& unbounded) const {
    Joint u = unbounded;
    for (Eigen::Index i = 0; i < u.size(); ++i)
      u[i] = bound_[i] * std::tanh(unbounded[i] / bound_[i]);
    return u;
  }

  // The policy and its cost in one pass: `u` holds the unbounded policy v on entry and
  // u = lambda tanh(v / lambda) = -lambda tanh(D) on return (D = -v / lambda); returns
  // U(u) = sum_i R_i lambda_i^2 [2 D_i tanh D_i - 2 ln cosh D_i]. One expm1 per joint gives both:
  // m = expm1(-2|D|) = e^-2|D| - 1, tanh|D| = -m / (2 + m), and ln cosh D = -1/2 ln(1 - t^2) for
  // |D| < 1, else |D| + ln(1 + e^-2|D|) - ln 2 (accurate to round-off, also when t rounds to +-1).
  double bound_policy(Joint& u) const {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      const double D = -u[i] / bound_[i];
      const double a = std::abs(D);
      const double m = std::expm1(-2.0 * a);
      const double b = -m / (2.0 + m);  // tanh |D|
      const double t = std::copysign(b, D);
      const double log_cosh_D =
          a < 1.0 ? -0.5 * std::log1p(-b * b) : a + std::log1p(1.0 + m) - kLn2;
      sum += input_weight_[i] * bound_[i] * bound_[i] * 2.0 * (a * b - log_cosh_D);
      u[i] = -bound_[i] * t;
    }
    return sum;
  }

  // U(u) at an applied input; beyond the bound, U at the bound plus R_i (|u_i| - lambda_i)^2.
  double input_cost(const Joint& u) const {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      const double s = u[i] / bound_[i];
      sum += input_weight_[i] * bound_[i] * bound_[i] * bounded_input_shape(s);
      const double excess = std::abs(u[i]) - bound_[i];
      if (excess > 0.0) sum += input_weight_[i] * excess * excess;
    }
    return sum;
  }

  // The actor law's factor sech^2 D_i = 1 - (u_i / lambda_i)^2 at the policy u, applied to
  // `projected` = R^-1 B^T (Wa - Wc) (actor.hpp).
  void scale_by_slope(const Joint& u_hat, Joint& projected) const {
    for (Eigen::Index i = 0; i < projected.size(); ++i) {
      const double s = u_hat[i] / bound_[i];
      projected[i] *= (1.0 - s) * (1.0 + s);
    }
  }

  // sum_i 2 lambda_i^2 R_i ln cosh(s_i e2_i / (R_i lambda_i)) (logcosh only).
  template <class Derived>
  double e2_cost(const Eigen::MatrixBase<Derived>& e2) const {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < e2.size(); ++i) {
      const double r = input_weight_[i], l = bound_[i];
      sum += 2.0 * l * l * r * log_cosh(e2_scale_[i] * e2[i] / (r * l));
    }
    return sum;
  }

 private:
  bool bounded_ = false;
  bool logcosh_ = false;
  Joint bound_ = Joint::Zero(size_of(N, 0));
  Joint input_weight_ = Joint::Zero(size_of(N, 0));  // the diagonal of R
  Joint e2_scale_ = Joint::Zero(size_of(N, 0));      // s_i = sqrt(Q22_ii R_i)
};

}  // namespace adparm
