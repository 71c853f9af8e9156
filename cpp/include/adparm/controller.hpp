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
  bool rise = true;                   // add the RISE feedback mu of eq. (27) to the torque
  Mat2 kp = 50.0 * Mat2::Identity();  // pd only, N m / rad
  Mat2 kd = 10.0 * Mat2::Identity();  // pd only, N m s / rad
};

class Controller {
 public:
  Controller() = default;
  explicit Controller(const ControllerSettings& settings) : settings_(settings) {
    check_finite(settings.kp, "controller.kp");
    check_finite(settings.kd, "controller.kd");
    if (settings.kind == ControllerKind::rise && !settings.rise)
      throw std::invalid_argument(
          "controller.rise: the rise controller is the RISE feedback alone, so rise must be true");
  }

  const ControllerSettings& settings() const { return settings_; }
  bool learns() const { return settings_.kind == ControllerKind::adp; }
  bool uses_rise() const { return settings_.rise; }

  // The input u for the current errors; u_hat is the actor's eq. (20), probe the probing signal.
  Vec2 input(const TrackingErrors& errors, const Mat2& alpha1, const Mat2& R_inverse,
             const Vec2& u_hat, const Vec2& probe) const {
    switch (settings_.kind) {
      case ControllerKind::adp:
        return u_hat + probe;
      case ControllerKind::rise:
        return Vec2::Zero();
      case ControllerKind::pd: {
        const Vec2 de1 = errors.e2 - alpha1 * errors.e1;
        return -(settings_.kp * errors.e1 + settings_.kd * de1);
      }
      case ControllerKind::optimal:
        return -(R_inverse * errors.e2);
    }
    return Vec2::Zero();
  }

 private:
  ControllerSettings settings_{};
};

}  // namespace adparm
