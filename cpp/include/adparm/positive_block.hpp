// Keeps the e2 block of the learned value positive definite (a deviation from the paper, which
// projects only onto a ball, eq. 26).
// In the paper/augmented basis (basis.hpp) the part of V = W^T phi that is quadratic in e2 is
//   e2^T P(c) e2,   P(c) = [[W4 + c W5, (W7 + c W8) / 2], [(W7 + c W8) / 2, W6]],   c = cos q2,
// (1-based weight indices). P is affine in c, so P(c) > 0 for every c in [-1, 1] (every q) exactly
// when P(+1) > 0 and P(-1) > 0. The HJB equation of eq. (21) also has an anti-stabilising solution
// with this block negated; on-trajectory learning can end there. The projection below changes the
// weights' rate least so that lambda_min(P(c)), c = +-1, does not fall once at or below `margin`
// and is pulled back up to it (the ODE projection of eq. 26's proj{}, for two concave constraints):
//   n_c = d lambda_min(P(c)) / dW = [v1^2, c v1^2, v2^2, v1 v2, c v1 v2] on W4..W8,
// v the unit eigenvector of lambda_min; n_c . rate >= kE2Recovery (margin - lambda_min) for every
// active c. Weights that start inside {lambda_min >= margin} stay there (up to the RK4 step);
// weights that start below it are brought up to it.
#pragma once

#include <cmath>
#include <type_traits>

#include "adparm/basis.hpp"
#include "adparm/dynamic_size.hpp"

namespace adparm {

// Whether a basis has the paper's layout (W4..W8 on the e2 block): the paper and augmented bases,
// with fixed sizes or seen through dynamic sizes (dynamic_size.hpp).
template <class Basis>
struct HasPaperE2Block : std::is_base_of<QuadraticArmBasis, Basis> {};
template <class FixedBasis>
struct HasPaperE2Block<DynamicBasis<FixedBasis>> : HasPaperE2Block<FixedBasis> {};

// The Euclidean metric of the actor's gradient law: metric * v = v, with nothing to allocate.
struct IdentityMetric {
  template <class V>
  const V& operator*(const V& v) const {
    return v;
  }
};

// lambda_min of P(c) and its gradient with respect to the weights (zero outside W4..W8).
template <class Vector>
double e2_block_lambda_min(const Vector& W, double c, Vector& gradient) {
  const double a = W[3] + c * W[4], d = W[5], b = 0.5 * (W[6] + c * W[7]);
  const double mean = 0.5 * (a + d), half = 0.5 * (a - d);
  const double radius = std::sqrt(half * half + b * b);
  const double lambda = mean - radius;
  double v1 = 1.0, v2 = 0.0;  // eigenvector of lambda: (P - lambda I) v = 0
  if (radius > 0.0) {
    if (half <= 0.0) {  // a <= d: the eigenvector leans towards e2_1
      v1 = d - lambda;
      v2 = -b;
    } else {
      v1 = -b;
      v2 = a - lambda;
    }
    const double norm = std::hypot(v1, v2);
    v1 /= norm;
    v2 /= norm;
  }
  gradient.setZero(W.size());
  gradient[3] = v1 * v1;
  gradient[4] = c * v1 * v1;
  gradient[5] = v2 * v2;
  gradient[6] = v1 * v2;
  gradient[7] = c * v1 * v2;
  return lambda;
}

// lambda_min(P(c)) > margin, without a square root: P - margin I has positive pivots.
template <class Vector>
bool e2_block_above(const Vector& W, double c, double margin) {
  const double a = W[3] + c * W[4] - margin, d = W[5] - margin, b = 0.5 * (W[6] + c * W[7]);
  return a > 0.0 && a * d > b * b;
}

// The smallest eigenvalue of P(c) over c in [-1, 1] (at c = +-1).
template <class Vector>
double e2_block_lambda_min(const Vector& W) {
  Vector gradient(W.size());
  return std::min(e2_block_lambda_min(W, 1.0, gradient), e2_block_lambda_min(W, -1.0, gradient));
}

// Below the margin, lambda_min is also pulled back at this rate (1/s): the linearised constraint
// lets RK4 steps along the boundary drift below it (lambda_min is concave in W).
constexpr double kE2Recovery = 100.0;

// Projects `rate` (dW/dt) so that d lambda_min(P(c)) / dt >= kE2Recovery (margin - lambda) for
// c = +-1 whenever lambda_min(P(c)) <= margin, by the least change in the metric of `metric`
// (identity for the actor's gradient law; the critic's Gamma for its least-squares law):
// rate += metric N mu, mu >= 0. Bases other than the paper/augmented ones are left alone.
template <class Basis, class Vector, class Metric>
Vector keep_e2_block_positive(const Vector& W, const Vector& rate, double margin,
                              const Metric& metric) {
  if constexpr (!HasPaperE2Block<Basis>::value) {
    return rate;
  } else {
    // the common case, inside at both ends: a few multiplications, no square root
    if (e2_block_above(W, 1.0, margin) && e2_block_above(W, -1.0, margin)) return rate;
    Vector n[2], metric_n[2];
    bool active[2];
    double floor[2];  // the least d lambda / dt allowed
    for (int i = 0; i < 2; ++i) {
      const double lambda = e2_block_lambda_min(W, i == 0 ? 1.0 : -1.0, n[i]);
      active[i] = lambda <= margin;
      floor[i] = kE2Recovery * (margin - lambda);
      metric_n[i].noalias() = metric * n[i];
    }
    const auto violates = [&](int i, const Vector& r) {
      return active[i] && n[i].dot(r) < floor[i];
    };
    if (!violates(0, rate) && !violates(1, rate)) return rate;
    for (int i = 0; i < 2; ++i) {  // one constraint met with equality
      if (!violates(i, rate)) continue;
      const Vector projected =
          rate + ((floor[i] - n[i].dot(rate)) / n[i].dot(metric_n[i])) * metric_n[i];
      if (!violates(1 - i, projected)) return projected;
    }
    // both: N^T (rate + Metric N mu) = floor, N = [n0 n1]
    const double g00 = n[0].dot(metric_n[0]), g11 = n[1].dot(metric_n[1]);
    const double g01 = n[0].dot(metric_n[1]);
    const double det = g00 * g11 - g01 * g01;
    const double r0 = floor[0] - n[0].dot(rate), r1 = floor[1] - n[1].dot(rate);
    if (!(det > 1e-12 * g00 * g11)) return rate + (r0 / g00) * metric_n[0];  // parallel normals
    const double mu0 = (g11 * r0 - g01 * r1) / det, mu1 = (g00 * r1 - g01 * r0) / det;
    return rate + mu0 * metric_n[0] + mu1 * metric_n[1];
  }
}

template <class Basis, class Vector>
Vector keep_e2_block_positive(const Vector& W, const Vector& rate, double margin) {
  return keep_e2_block_positive<Basis>(W, rate, margin, IdentityMetric{});
}

// The same, given the basis object: a basis with data of its own (the structured basis of a URDF
// arm, pinocchio_structured_basis.hpp) overloads this; the others are projected as above.
template <class Basis, class Vector, class Metric>
Vector keep_e2_block_positive(const Basis&, const Vector& W, const Vector& rate, double margin,
                              const Metric& metric) {
  return keep_e2_block_positive<Basis>(W, rate, margin, metric);
}

}  // namespace adparm
