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

// Below a = 1, tanh(a) / a and ln cosh(a) / a^2 as rational functions of y = a^2: their [7/7] Pade
// approximants (from the Taylor series, whose coefficients are the Bernoulli numbers'
// 2^2n (2^2n - 1) B_2n / (2n)! and those over 2n), normalised to a denominator 1 + ..., the
// coefficients rounded from 80-digit values. All are positive (no cancellation); with the
// rounding of the sums and of the quotient, tanh a is within 4.0e-16 and ln cosh a within 5.7e-16
// relative on [0, 1) (2e6 arguments against long double; tests/test_input_bound.py: 3.6e-16 and
// 5.2e-16 on a grid against 40-digit values). Both side by side, {tanh, ln cosh} (SSE2 / NEON
// lanes): the numerators and the denominators in two independent sums, then one packed division,
// a short dependency chain: 14.5 ns per call chained on the development machine, against 18 and
// 27 ns for the 10- and 16-term Taylor series used before below 1/4 and 1/2 (a multiply then an
// add per term without FMA) and 27 ns for exp then log. The policy's D is on the right-hand
// side's critical path (u_hat, omega, eps_hjb, the rates).
struct PadePairs {
  alignas(16) double numerator[8][2];
  alignas(16) double denominator[8][2];
};
inline constexpr PadePairs kTanhLogCoshPade = {{{1.0, 0.5},
                                                {0.14942528735632185, 0.6601802513611896},
                                                {0.00561941251596424, 0.3402736240665753},
                                                {8.0277321656632e-05, 0.08633999569391451},
                                                {4.935803703086729e-07, 0.011157225914998535},
                                                {1.2820269358666827e-09, 0.0006815323597634236},
                                                {1.1534205450892331e-12, 1.5578976334345767e-05},
                                                {1.6154349370997664e-16, 5.773771893359739e-08}},
                                               {{1.0, 1.0},
                                                {0.4827586206896552, 1.487027169389046},
                                                {0.033205619412515965, 0.8839406652535472},
                                                {0.0007492550021285653, 0.2674054026715261},
                                                {6.9806366657940875e-06, 0.043284934429460964},
                                                {2.8204592589067017e-08, 0.0035918206682784577},
                                                {4.4983401258480094e-11, 0.00013108868126246426},
                                                {1.9385219245197195e-14, 1.3834347708450946e-06}}};

// {tanh(a) / a, ln cosh(a) / a^2} at a2 = a^2 < 1 (kTanhLogCoshPade). Each degree-7 polynomial
// as p = c0 + y q(y), q in Estrin's scheme, q = (c1 + c2 y) + y^2 (c3 + c4 y) +
// y^4 [(c5 + c6 y) + y^2 c7]: as many operations as Horner's and half its dependency chain; the
// leading c0 added last keeps q's rounding a fraction of p's (y q / p < 0.35).
inline Eigen::Array2d tanh_log_cosh_ratios(double a2) {
  using Pair = Eigen::Map<const Eigen::Array2d, Eigen::Aligned16>;
  const double a4 = a2 * a2;
  const auto polynomial = [&](const double (&c)[8][2]) {
    const Eigen::Array2d c12 = Pair(c[1]) + a2 * Pair(c[2]);
    const Eigen::Array2d c34 = Pair(c[3]) + a2 * Pair(c[4]);
    const Eigen::Array2d c567 = (Pair(c[5]) + a2 * Pair(c[6])) + a4 * Pair(c[7]);
    const Eigen::Array2d q = (c12 + a4 * c34) + (a4 * a4) * c567;
    return Eigen::Array2d(Pair(c[0]) + a2 * q);
  };
  return polynomial(kTanhLogCoshPade.numerator) / polynomial(kTanhLogCoshPade.denominator);
}

struct TanhLogCosh {
  double tanh = 0.0;      // tanh a
  double log_cosh = 0.0;  // ln cosh a
};

// ln 2 in two parts: the first has 20 significant bits, so a - kLn2High is exact for
// 1/2 <= a < 2^33 (above, its rounding is half an ulp of the result).
constexpr double kLn2High = 6.93145751953125e-1;
constexpr double kLn2Low = 1.42860682030941723212e-6;

// log1p(x) for x > -1 from one log: with w = 1 + x rounded, ln(1 + x) = ln w - ((w - 1) - x) / w
// (the rounding of w, computed exactly, corrected to first order; x itself where w = 1). glibc's
// log is several times cheaper than its log1p (and its exp than its expm1).
inline double log1p_from_log(double x) {
  const double w = 1.0 + x;
  return std::log(w) - ((w - 1.0) - x) / w;
}

// tanh a and ln cosh a for a = |x| >= 0, accurate to round-off: below a = 1 their Pade
// approximants (no transcendental call: the policy's D and the ln cosh cost's argument are mostly
// there), else from one exp and one log: e = e^-2a <= e^-2, w = 1 + e rounded,
// tanh a = (1 - e) / w and ln cosh a = a - ln 2 + log1p(e) (log1p_from_log); no overflow, and
// log1p(e) <= 0.13 against a - ln 2 >= 0.30: no cancellation.
inline TanhLogCosh tanh_log_cosh(double a) {
  if (a < 1.0) {
    const double a2 = a * a;
    const Eigen::Array2d ratios = tanh_log_cosh_ratios(a2);
    return {a * ratios[0], a2 * ratios[1]};
  }
  const double e = std::exp(-2.0 * a);
  const double w = 1.0 + e;
  const double log1p_e = std::log(w) - ((w - 1.0) - e) / w;  // log1p_from_log(e), w shared
  return {(1.0 - e) / w, ((a - kLn2High) - kLn2Low) + log1p_e};
}

// ln cosh z (tanh_log_cosh).
inline double log_cosh(double z) { return tanh_log_cosh(std::abs(z)).log_cosh; }

// (1 + s) ln(1 + s) + (1 - s) ln(1 - s) for |s| <= 1 (0 ln 0 = 0; 2 ln 2 at |s| >= 1, no call);
// below |s| = 1e-3 its series sum_k s^2k / (k (2k - 1)) to s^6 (no cancellation).
inline double bounded_input_shape(double s) {
  const double a = std::abs(s);
  if (a >= 1.0) return 2.0 * kLn2;
  if (a < 1e-3) {
    const double a2 = a * a;
    return a2 * (1.0 + a2 * (1.0 / 6.0 + a2 / 15.0));
  }
  return (1.0 + a) * log1p_from_log(a) + (1.0 - a) * log1p_from_log(-a);
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
    inverse_bound_ = bound.cwiseInverse();
    input_weight_ = R.diagonal();
    shape_weight_ = input_weight_.cwiseProduct(bound_).cwiseProduct(bound_);
    if (e2_cost == E2Cost::logcosh) {
      const Eigen::MatrixXd Q22 = Q.bottomRightCorner(n, n);
      const Eigen::MatrixXd off = Q22 - Eigen::MatrixXd(Q22.diagonal().asDiagonal());
      if (!(off.cwiseAbs().maxCoeff() == 0.0))
        throw std::invalid_argument(
            "cost.Q: its e2 block Q22 must be diagonal with cost.e2_cost = logcosh");
      logcosh_ = true;
      const Joint e2_scale = (Q22.diagonal().array() * R.diagonal().array()).sqrt().matrix();
      e2_factor_ = e2_scale.cwiseQuotient(input_weight_.cwiseProduct(bound_));
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
  // U(u) = sum_i R_i lambda_i^2 [2 D_i tanh D_i - 2 ln cosh D_i] (tanh D and ln cosh D from
  // tanh_log_cosh: no atanh of u / lambda, since atanh(tanh D) = D).
  double bound_policy(Joint& u) const {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      const double D = -u[i] * inverse_bound_[i];
      const double a = std::abs(D);
      const TanhLogCosh f = tanh_log_cosh(a);
      sum += shape_weight_[i] * 2.0 * (a * f.tanh - f.log_cosh);
      u[i] = -bound_[i] * std::copysign(f.tanh, D);
    }
    return sum;
  }

  // U(u) at an applied input; beyond the bound, U at the bound plus R_i (|u_i| - lambda_i)^2.
  double input_cost(const Joint& u) const {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      sum += shape_weight_[i] * bounded_input_shape(u[i] * inverse_bound_[i]);
      const double excess = std::abs(u[i]) - bound_[i];
      if (excess > 0.0) sum += input_weight_[i] * excess * excess;
    }
    return sum;
  }

  // The actor law's factor sech^2 D_i = 1 - tanh^2 D_i = 1 - (u_i / lambda_i)^2 at the policy u,
  // applied to `projected` = R^-1 B^T (Wa - Wc) (actor.hpp).
  void scale_by_slope(const Joint& u_hat, Joint& projected) const {
    for (Eigen::Index i = 0; i < projected.size(); ++i) {
      const double s = u_hat[i] * inverse_bound_[i];
      projected[i] *= (1.0 - s) * (1.0 + s);
    }
  }

  // sum_i 2 lambda_i^2 R_i ln cosh(s_i e2_i / (R_i lambda_i)) (logcosh only).
  template <class Derived>
  double e2_cost(const Eigen::MatrixBase<Derived>& e2) const {
    double sum = 0.0;
    for (Eigen::Index i = 0; i < e2.size(); ++i)
      sum += shape_weight_[i] * 2.0 * log_cosh(e2_factor_[i] * e2[i]);
    return sum;
  }

 private:
  bool bounded_ = false;
  bool logcosh_ = false;
  Joint bound_ = Joint::Zero(size_of(N, 0));          // lambda
  Joint inverse_bound_ = Joint::Zero(size_of(N, 0));  // 1 / lambda
  Joint input_weight_ = Joint::Zero(size_of(N, 0));   // the diagonal of R
  Joint shape_weight_ = Joint::Zero(size_of(N, 0));   // R_i lambda_i^2
  Joint e2_factor_ = Joint::Zero(size_of(N, 0));  // s_i / (R_i lambda_i), s_i = sqrt(Q22_ii R_i)
};

}  // namespace adparm
