// The HJB error of eqs. (21)-(22) with critic weights Wc and actor weights Wa at one state x:
//   eps_hjb = x^T Q x + u_hat^T R u_hat + Wc^T omega,   u_hat from eq. (20)
//   omega   = (dphi/dx) (f(x) + g(x) u_hat) + (dphi/dqd) dqd   (the regressor of eqs. 23-26)
// The last term is d phi / dt from the desired position moving (zero for the paper's set-point).
// With Wc = Wa = W* (basis.hpp) and the ERRATA conditions on Q and R, eps_hjb = 0 at every x.
// With an input bound (input_bound.hpp): u_hat = -lambda tanh(D), D = (2 lambda)^-1 R^-1 B^T Wa,
// and u_hat^T R u_hat becomes U(u_hat) (Abu-Khalaf & Lewis 2005); with e2_cost = logcosh and the
// exact family's Q, eps_hjb = 0 at W* again.
//
// The evaluation is split in two: an HjbPoint holds what does not depend on the weights (the
// drift part of omega, B = (dphi/dx) g and x^T Q x), so that fixed extrapolation points compute it
// once; evaluate_hjb() then costs a few small matrix-vector products per point.
#pragma once

#include "adparm/actor.hpp"
#include "adparm/basis.hpp"
#include "adparm/cost.hpp"
#include "adparm/dense_kernels.hpp"
#include "adparm/error_system.hpp"

namespace adparm {

template <class Basis, int Dof>
struct HjbPoint {
  using ActorType = Actor<Basis, Dof>;
  typename Basis::Vector drift_rate;                 // (dphi/dx) f(x) + (dphi/dqd) dqd
  typename ActorType::InputGradient input_gradient;  // B = (dphi/dx) g(x)
  double state_cost = 0.0;                           // x^T Q x
};

template <class Basis, int Dof>
struct HjbEvaluation {
  using ActorType = Actor<Basis, Dof>;
  typename ActorType::Input u_hat;  // eq. (20)
  typename Basis::Vector omega;
  double error = 0.0;       // eq. (21)
  double input_cost = 0.0;  // u_hat^T R u_hat, or U(u_hat) with an input bound
};

// The weight-free part at x, given the desired state, the drift f(x) and the model terms at the
// matching joint state (their M^-1 gives g(x) = [0; M^-1]; the basis may use them too), with the
// basis' workspace (basis.hpp; the caller's). With `kernels` (dense_kernels.hpp; dynamic sizes)
// the two products with the basis' Jacobian J (K x 2n) run in them:
//   drift_rate += J f as drift_rate -= J (-f) (the same sum, negated),  B = J_e2 M^-1.
// Always inlined: the fixed-size loop's flattened evaluation had kept it a call (GCC's limits).
template <class Basis, int Dof, class Terms>
[[gnu::always_inline]] inline void prepare_hjb_point(
    const Basis& basis, const ErrorVector<Dof>& x, const DesiredStateT<Dof>& desired,
    const ErrorVector<Dof>& drift, const Terms& terms, const QuadraticCostT<Dof>& cost,
    HjbPoint<Basis, Dof>& point, BasisWorkspace<Basis>& workspace,
    const DenseKernels* kernels = nullptr) {
  const Eigen::Index n = desired.q.size();
  typename Basis::Vector phi;
  typename Basis::Jacobian jacobian;
  evaluate_basis(basis, x, desired, terms, phi, jacobian, point.drift_rate, workspace);
  point.state_cost = cost.state_cost(x);
  if constexpr (Dof == Dynamic) {
    if (kernels != nullptr) {
      const Eigen::Index k = jacobian.rows(), stride = jacobian.outerStride();
      const ErrorVector<Dof> negative_drift = -drift;
      kernels->product(k, 1, 2 * n, jacobian.data(), stride, negative_drift.data(), 1, 2 * n,
                       point.drift_rate.data(), k, true);
      point.input_gradient.resize(k, n);
      kernels->product(k, n, n, jacobian.data() + n * stride, stride, terms.mass_inverse.data(), 1,
                       terms.mass_inverse.outerStride(), point.input_gradient.data(),
                       point.input_gradient.outerStride(), false);
      return;
    }
  }
  point.drift_rate.noalias() += jacobian * drift;
  if constexpr (Dof == Dynamic)  // coefficient-based: no GEMM (its blocking may allocate)
    point.input_gradient.noalias() =
        jacobian.template rightCols<Dof>(n).lazyProduct(terms.mass_inverse);
  else
    point.input_gradient.noalias() = jacobian.template rightCols<Dof>() * terms.mass_inverse;
}

// eqs. (20)-(21) at a prepared point.
template <class Basis, int Dof>
void evaluate_hjb(const HjbPoint<Basis, Dof>& point, const QuadraticCostT<Dof>& cost,
                  const typename Basis::Vector& critic_weights,
                  const typename Basis::Vector& actor_weights, HjbEvaluation<Basis, Dof>& out) {
  out.u_hat = Actor<Basis, Dof>::policy(point.input_gradient, cost.R_inverse(), actor_weights);
  if (cost.bounded()) {  // u_hat = -lambda tanh(D) and U(u_hat) (input_bound.hpp)
    out.input_cost = cost.bound().bound_policy(out.u_hat);
  } else {
    out.input_cost = cost.input_cost(out.u_hat);
  }
  out.omega = point.drift_rate;
  out.omega.noalias() += point.input_gradient * out.u_hat;
  out.error = point.state_cost + out.input_cost + critic_weights.dot(out.omega);
}

// The same as evaluate_hjb, given the product B^T Wa of eq. (20) (ClosedLoop computes it for the
// prepared extrapolation points). With `kernels` (dense_kernels.hpp; dynamic sizes) omega's
// product B u_hat runs in them, B read from `input_gradient` (K x n, column-major, leading
// dimension K: the point's B, e.g. its block of the stacked [B_1 ... B_N]); without, Eigen's
// product of point.input_gradient.
template <class Basis, int Dof>
void evaluate_hjb_from_product(const HjbPoint<Basis, Dof>& point, const QuadraticCostT<Dof>& cost,
                               const typename Basis::Vector& critic_weights,
                               const JointVector<Dof>& input_gradient_times_actor_weights,
                               HjbEvaluation<Basis, Dof>& out,
                               const DenseKernels* kernels = nullptr,
                               const double* input_gradient = nullptr) {
  out.u_hat = -0.5 * cost.R_inverse().lazyProduct(input_gradient_times_actor_weights);  // eq. (20)
  out.input_cost =
      cost.bounded() ? cost.bound().bound_policy(out.u_hat) : cost.input_cost(out.u_hat);
  out.omega = point.drift_rate;
  if (kernels != nullptr) {  // omega += B u_hat as omega -= B (-u_hat): the same sum, negated
    const JointVector<Dof> negative_u_hat = -out.u_hat;
    const Eigen::Index k = out.omega.size(), n = negative_u_hat.size();
    kernels->product(k, 1, n, input_gradient, k, negative_u_hat.data(), 1, n, out.omega.data(), k,
                     true);
  } else {
    out.omega.noalias() += point.input_gradient * out.u_hat;
  }
  out.error = point.state_cost + out.input_cost + critic_weights.dot(out.omega);
}

// The weight-free part at an error state x with the desired state `desired` (q, dq recovered from
// x), on the model the controller believes; `terms` is a buffer (Arm::init_terms).
template <class Basis, class Arm>
void prepare_hjb_point(const Basis& basis, const ErrorSystem<Arm>& system,
                       const QuadraticCostT<Arm::kDof>& cost, const ErrorVector<Arm::kDof>& x,
                       const DesiredStateT<Arm::kDof>& desired, typename Arm::Terms& terms,
                       HjbPoint<Basis, Arm::kDof>& point, BasisWorkspace<Basis>& workspace) {
  JointVector<Arm::kDof> q, dq;
  system.joint_state(x, desired, q, dq);
  system.model().compute(q, dq, terms);
  prepare_hjb_point<Basis, Arm::kDof>(basis, x, desired, system.drift(x, terms), terms, cost, point,
                                      workspace);
}

// eqs. (20)-(21) at an error state x with the desired state `desired`: u_hat, omega and eps_hjb.
template <class Basis, class Arm>
HjbEvaluation<Basis, Arm::kDof> hjb_evaluation(const Basis& basis, const ErrorSystem<Arm>& system,
                                               const QuadraticCostT<Arm::kDof>& cost,
                                               const ErrorVector<Arm::kDof>& x,
                                               const DesiredStateT<Arm::kDof>& desired,
                                               const typename Basis::Vector& critic_weights,
                                               const typename Basis::Vector& actor_weights) {
  typename Arm::Terms terms;
  system.model().init_terms(terms);
  BasisWorkspace<Basis> workspace = basis_workspace(basis);
  HjbPoint<Basis, Arm::kDof> point;
  prepare_hjb_point(basis, system, cost, x, desired, terms, point, workspace);
  HjbEvaluation<Basis, Arm::kDof> evaluation;
  evaluate_hjb(point, cost, critic_weights, actor_weights, evaluation);
  return evaluation;
}

// eq. (21) at an error state x with the desired state `desired`.
template <class Basis, class Arm>
double hjb_error(const Basis& basis, const ErrorSystem<Arm>& system,
                 const QuadraticCostT<Arm::kDof>& cost, const ErrorVector<Arm::kDof>& x,
                 const DesiredStateT<Arm::kDof>& desired,
                 const typename Basis::Vector& critic_weights,
                 const typename Basis::Vector& actor_weights) {
  return hjb_evaluation(basis, system, cost, x, desired, critic_weights, actor_weights).error;
}

}  // namespace adparm
