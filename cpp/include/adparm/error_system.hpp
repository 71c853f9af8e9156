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
struct TrackingErrors {
  Vec2 e1;
  Vec2 e2;
  Vec4 x() const { return (Vec4() << e1, e2).finished(); }
};

inline TrackingErrors tracking_errors(const Vec2& q, const Vec2& dq, const Vec2& qd,
                                      const Vec2& dqd, const Mat2& alpha1) {
  TrackingErrors errors;
  errors.e1 = qd - q;
  errors.e2 = (dqd - dq) + alpha1 * errors.e1;
  return errors;
}

inline TrackingErrors tracking_errors(const Vec2& q, const Vec2& dq, const DesiredState& desired,
                                      const Mat2& alpha1) {
  return tracking_errors(q, dq, desired.q, desired.dq, alpha1);
}

// The error system on the arm model the controller believes.
template <class Arm>
class ErrorSystem {
 public:
  using Terms = typename Arm::Terms;

  ErrorSystem(const Arm& model, const Mat2& alpha1) : model_(model), alpha1_(alpha1) {}

  const Arm& model() const { return model_; }
  const Mat2& alpha1() const { return alpha1_; }

  // q = qd - e1, dq = dqd - e2 + alpha1 e1.
  void joint_state(const Vec4& x, const DesiredState& desired, Vec2& q, Vec2& dq) const {
    q = desired.q - x.head<2>();
    dq = desired.dq + alpha1_ * x.head<2>() - x.tail<2>();
  }

  // f(x) = [-alpha1 e1 + e2; -M^-1 C e2] (eq. 9) from model terms at the matching joint state.
  Vec4 drift(const Vec4& x, const Terms& terms) const {
    Vec4 f;
    f.head<2>() = -alpha1_ * x.head<2>() + x.tail<2>();
    f.tail<2>() = -terms.mass_inverse * (terms.coriolis * x.tail<2>());
    return f;
  }

  // Exact-linearization feedforward (eq. 5 in full, ERRATA):
  //   h = M (ddqd + alpha1 de1) + C (dqd + alpha1 e1) + G + F,  de1 = dqd - dq.
  Vec2 feedforward(const Terms& terms, const Vec2& dq, const TrackingErrors& errors,
                   const DesiredState& desired) const {
    const Vec2 de1 = desired.dq - dq;
    return terms.mass * (desired.ddq + alpha1_ * de1) +
           terms.coriolis * (desired.dq + alpha1_ * errors.e1) + terms.gravity + terms.friction;
  }

 private:
  Arm model_;
  Mat2 alpha1_;
};

}  // namespace adparm
