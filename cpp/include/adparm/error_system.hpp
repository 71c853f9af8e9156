// Error system and exact-linearization feedforward (eqs. 4-9), in the ERRATA's sign convention:
//
//   e1 = qd - q,  e2 = de1 + alpha1 e1,  x = [e1; e2],  u = h + tau_d - tau      (eqs. 4, 6, 7)
//   M de2 = -C e2 + u,   so   dx = f(x) + g(x) u,                                 (eq. 9)
//   f(x) = [-alpha1 e1 + e2; -M^-1 C e2],   g(x) = [0; M^-1]
//
// (the paper prints g = [0; -M^-1], the same system with the opposite sign of u). The torque that
// realises an input u is tau = h_hat + mu - u, with h_hat the feedforward of the model the
// controller believes and mu the RISE term (rise.hpp). The joint state follows from x and the
// desired state: q = qd - e1, dq = dqd - e2 + alpha1 e1; f is a function of x alone only for a
// constant qd, and of [x; qd; dqd] for a trajectory (ERRATA).
#pragma once

#include "adparm/types.hpp"

namespace adparm {

// Tracking errors (eqs. 6-7) for a desired position qd with velocity dqd.
template <int N = 2>
struct TrackingErrorsT {
  JointVector<N> e1;
  JointVector<N> e2;
  ErrorVector<N> x() const { return (ErrorVector<N>(2 * e1.size()) << e1, e2).finished(); }
};
using TrackingErrors = TrackingErrorsT<2>;

template <int N>
TrackingErrorsT<N> tracking_errors(const JointVector<N>& q, const JointVector<N>& dq,
                                   const JointVector<N>& qd, const JointVector<N>& dqd,
                                   const JointMatrix<N>& alpha1) {
  TrackingErrorsT<N> errors;
  errors.e1 = qd - q;
  errors.e2 = (dqd - dq) + small_product(alpha1, errors.e1);
  return errors;
}

template <int N>
TrackingErrorsT<N> tracking_errors(const JointVector<N>& q, const JointVector<N>& dq,
                                   const DesiredStateT<N>& desired, const JointMatrix<N>& alpha1) {
  return tracking_errors<N>(q, dq, desired.q, desired.dq, alpha1);
}

// The error system on the arm model the controller believes.
template <class Arm>
class ErrorSystem {
 public:
  static constexpr int kDof = Arm::kDof;
  using Terms = typename Arm::Terms;
  using Joint = JointVector<kDof>;
  using Error = ErrorVector<kDof>;
  using Desired = DesiredStateT<kDof>;

  ErrorSystem() = default;
  ErrorSystem(const Arm& model, const JointMatrix<kDof>& alpha1) : model_(model), alpha1_(alpha1) {}

  const Arm& model() const { return model_; }
  const JointMatrix<kDof>& alpha1() const { return alpha1_; }
  Eigen::Index dof() const { return alpha1_.rows(); }

  // q = qd - e1, dq = dqd - e2 + alpha1 e1.
  void joint_state(const Error& x, const Desired& desired, Joint& q, Joint& dq) const {
    const Eigen::Index n = dof();
    q = desired.q - x.template head<kDof>(n);
    dq = desired.dq + small_product(alpha1_, x.template head<kDof>(n)) -
         x.template segment<kDof>(n, n);
  }

  // f(x) = [-alpha1 e1 + e2; -M^-1 C e2] (eq. 9) from model terms at the matching joint state.
  Error drift(const Error& x, const Terms& terms) const {
    const Eigen::Index n = dof();
    Error f(2 * n);
    f.template head<kDof>(n) =
        -small_product(alpha1_, x.template head<kDof>(n)) + x.template segment<kDof>(n, n);
    const Joint coriolis_e2 = small_product(terms.coriolis, x.template segment<kDof>(n, n));
    f.template segment<kDof>(n, n) = -small_product(terms.mass_inverse, coriolis_e2);
    return f;
  }

  // Exact-linearization feedforward (eq. 5 in full, ERRATA):
  //   h = M (ddqd + alpha1 de1) + C (dqd + alpha1 e1) + G + F,  de1 = dqd - dq.
  Joint feedforward(const Terms& terms, const Joint& dq, const TrackingErrorsT<kDof>& errors,
                    const Desired& desired) const {
    const Joint de1 = desired.dq - dq;
    const Joint acceleration = desired.ddq + small_product(alpha1_, de1);
    const Joint velocity = desired.dq + small_product(alpha1_, errors.e1);
    return small_product(terms.mass, acceleration) + small_product(terms.coriolis, velocity) +
           terms.gravity + terms.friction;
  }

 private:
  Arm model_;
  JointMatrix<kDof> alpha1_;
};

}  // namespace adparm
