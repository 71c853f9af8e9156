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

// Taylor coefficients in a^2 of tanh(a) / a and ln cosh(a) / a^2 (the Bernoulli numbers'
// series, rounded from the exact rationals); 16 terms reach round-off for a < 1/2, 10 for a < 1/4
// (largest relative error 2.2e-16 against 40-digit values, checked by tests/test_input_bound.py).
inline constexpr double kTanhSeries[16] = {1.0,
                                           -0.3333333333333333,
                                           0.13333333333333333,
                                           -0.05396825396825397,
                                           0.021869488536155203,
                                           -0.008863235529902197,
                                           0.003592128036572481,
                                           -0.0014558343870513183,
                                           0.000590027440945586,
                                           -0.00023912911424355248,
                                           9.691537956929451e-05,
                                           -3.927832388331683e-05,
                                           1.5918905069328964e-05,
                                           -6.451689215655431e-06,
                                           2.6147711512907546e-06,
                                           -1.0597268320104654e-06};
inline constexpr double kLogCoshSeries[16] = {0.5,
                                              -0.08333333333333333,
                                              0.022222222222222223,
                                              -0.006746031746031746,
                                              0.0021869488536155205,
                                              -0.0007386029608251831,
                                              0.0002565805740408915,
                                              -9.09896491907074e-05,
                                              3.277930227475478e-05,
                                              -1.1956455712177625e-05,
                                              4.405244525877023e-06,
                                              -1.6365968284715348e-06,
                                              6.122655795895756e-07,
                                              -2.3041747198769394e-07,
                                              8.715903837635848e-08,
                                              -3.3116463500327045e-08};

// The two series side by side, {kTanhSeries[k], kLogCoshSeries[k]}: one Horner pass of pairs
// (SSE2 / NEON lanes) sums both, lane by lane the same operations as one series alone.
struct SeriesPairs {
  alignas(16) double c[16][2];
};
constexpr SeriesPairs series_pairs() {
  SeriesPairs pairs{};
  for (int k = 0; k < 16; ++k) {
    pairs.c[k][0] = kTanhSeries[k];
    pairs.c[k][1] = kLogCoshSeries[k];
  }
  return pairs;
}
inline constexpr SeriesPairs kSeriesPairs = series_pairs();

// {sum_k kTanhSeries[k] a2^k, sum_k kLogCoshSeries[k] a2^k} over the first K terms (Horner).
template <int K>
inline Eigen::Array2d even_series_pair(double a2) {
  using Pair = Eigen::Map<const Eigen::Array2d, Eigen::Aligned16>;
  Eigen::Array2d sum = Pair(kSeriesPairs.c[K - 1]);
  for (int k = K - 2; k >= 0; --k) sum = sum * a2 + Pair(kSeriesPairs.c[k]);
  return sum;
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

// tanh a and ln cosh a for a = |x| >= 0, accurate to round-off: below a = 1/2 their Taylor
// series (no transcendental call: the policy's D and the ln cosh cost's argument are mostly
// there), else from one exp and one log: e = e^-2a <= e^-1, w = 1 + e rounded,
// tanh a = (1 - e) / w and ln cosh a = a - ln 2 + log1p(e) (log1p_from_log); no overflow, and
// log1p(e) <= 0.32 against a - ln 2 >= -0.19: little cancellation.
inline TanhLogCosh tanh_log_cosh(double a) {
  if (a < 0.5) {
    const double a2 = a * a;
    const Eigen::Array2d sums = a < 0.25 ? even_series_pair<10>(a2) : even_series_pair<16>(a2);
    return {a * sums[0], a2 * sums[1]};
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
