// The HJB error of eqs. (21)-(22) with critic weights Wc and actor weights Wa at one state x:
//   eps_hjb = x^T Q x + u_hat^T R u_hat + Wc^T (dphi/dx) (f(x) + g(x) u_hat),   u_hat from eq. (20)
//   omega   = (dphi/dx) (f(x) + g(x) u_hat)   (the regressor of eqs. 23-26)
// With Wc = Wa = W* (basis.hpp) and the ERRATA conditions on Q and R, eps_hjb = 0 at every x.
#pragma once

#include "adparm/actor.hpp"
#include "adparm/cost.hpp"
#include "adparm/error_system.hpp"

namespace adparm {

template <class Basis, int Dof>
struct HjbEvaluation {
  using ActorType = Actor<Basis, Dof>;
  typename Basis::Vector phi;
  typename Basis::Jacobian jacobian;
  typename ActorType::InputGradient input_gradient;  // B = (dphi/dx) g(x)
  typename ActorType::Input u_hat;                   // eq. (20)
  typename Basis::Vector omega;
  double error = 0.0;  // eq. (21)
};

// Evaluates eq. (21) at x, given the drift f(x) and M^-1 of the model at the matching joint state
// (g(x) = [0; M^-1]).
template <class Basis, int Dof>
void evaluate_hjb(const Vec4& x, const Vec4& drift,
                  const Eigen::Matrix<double, Dof, Dof>& mass_inverse, const QuadraticCost& cost,
                  const typename Basis::Vector& critic_weights,
                  const typename Basis::Vector& actor_weights, HjbEvaluation<Basis, Dof>& out) {
  Basis::evaluate(x, out.phi, out.jacobian);
  out.input_gradient.noalias() = out.jacobian.template rightCols<Dof>() * mass_inverse;
  out.u_hat = Actor<Basis, Dof>::policy(out.input_gradient, cost.R_inverse(), actor_weights);
  out.omega.noalias() = out.jacobian * drift;
  out.omega.noalias() += out.input_gradient * out.u_hat;
  out.error = cost(x, out.u_hat) + critic_weights.dot(out.omega);
}

// eq. (21) at a state x of the error system for a set-point (q, dq recovered from x).
template <class Basis, class Arm>
double hjb_error(const ErrorSystem<Arm>& system, const QuadraticCost& cost, const Vec4& x,
                 const typename Basis::Vector& critic_weights,
                 const typename Basis::Vector& actor_weights) {
  Vec2 q, dq;
  system.joint_state(x, q, dq);
  typename Arm::Terms terms;
  system.model().compute(q, dq, terms);
  HjbEvaluation<Basis, Arm::kDof> evaluation;
  evaluate_hjb<Basis, Arm::kDof>(x, system.drift(x, terms), terms.mass_inverse, cost,
                                 critic_weights, actor_weights, evaluation);
  return evaluation.error;
}

}  // namespace adparm
