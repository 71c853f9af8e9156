// The controller kind: which input u the loop applies to the error system dx = f(x) + g(x) u
// (eq. 9), with the torque tau = h_hat + mu - u (mu the RISE term when controller.rise is on):
//   adp      u = u_hat + probe(t)     (eq. 20 plus the probe; the critic and actor learn)
//   rise     u = 0                    (RISE and the feedforward alone)
//   pd       u = -(kp e1 + kd de1)    (PD on e1, de1 = e2 - alpha1 e1)
//   optimal  u = u* = -R^-1 e2        (the exact optimal policy of ERRATA, known model)
// Only adp learns and probes; for the others the weights and Gamma stay at their initial values.
// A new kind is a new enumerator and a new case here; the loop calls input() and learns() only.
#pragma once

#include "adparm/error_system.hpp"

namespace adparm {

enum class ControllerKind { adp, rise, pd, optimal };

struct ControllerSettings {
  ControllerKind kind = ControllerKind::adp;
  bool rise = true;  // add the RISE feedback mu of eq. (27) to the torque
  Eigen::MatrixXd kp = 50.0 * Mat2::Identity();  // pd only, N m / rad, n x n
  Eigen::MatrixXd kd = 10.0 * Mat2::Identity();  // pd only, N m s / rad, n x n
};

template <int N = 2>
class ControllerT {
 public:
  using Joint = JointVector<N>;
  using Matrix = JointMatrix<N>;
  ControllerT() = default;
  ControllerT(const ControllerSettings& settings, Eigen::Index n)
      : kind_(settings.kind), rise_(settings.rise) {
    check_size(settings.kp, n, n, "controller.kp");
    check_size(settings.kd, n, n, "controller.kd");
    check_finite(settings.kp, "controller.kp");
    check_finite(settings.kd, "controller.kd");
    kp_ = settings.kp;
    kd_ = settings.kd;
    if (settings.kind == ControllerKind::rise && !settings.rise)
      throw std::invalid_argument(
          "controller.rise: the rise controller is the RISE feedback alone, so rise must be true");
  }

  ControllerKind kind() const { return kind_; }
  bool learns() const { return kind_ == ControllerKind::adp; }
  bool uses_rise() const { return rise_; }

  // The input u for the current errors; u_hat is the actor's eq. (20), probe the probing signal.
  // With an input bound (input_bound.hpp) optimal is u* = -lambda tanh(R^-1 e2 / lambda).
  template <class Bound>
  Joint input(const TrackingErrorsT<N>& errors, const Matrix& alpha1, const Matrix& R_inverse,
              const Bound& bound, const Joint& u_hat, const Joint& probe) const {
    switch (kind_) {
      case ControllerKind::adp:
        return u_hat + probe;
      case ControllerKind::rise:
        return Joint::Zero(errors.e1.size());
      case ControllerKind::pd: {
        const Joint de1 = errors.e2 - alpha1 * errors.e1;
        return -(kp_ * errors.e1 + kd_ * de1);
      }
      case ControllerKind::optimal:
        if (bound.bounded()) return bound.saturate(-(R_inverse * errors.e2));
        return -(R_inverse * errors.e2);
    }
    return Joint::Zero(errors.e1.size());
  }

 private:
  ControllerKind kind_ = ControllerKind::adp;
  bool rise_ = true;
  Matrix kp_, kd_;
};
using Controller = ControllerT<2>;

}  // namespace adparm
