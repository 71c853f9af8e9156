// The arm alone, under tau = G(q) (gravity exactly compensated) or tau = 0, integrated with the
// same RK4. With no friction and no disturbance, gravity compensation leaves M ddq + C dq = 0 and
// so keeps the kinetic energy dq^T M dq / 2 constant (dM/dt - 2C skew): a property test of the
// model and RK4.
#pragma once

#include <vector>

#include "adparm/arm_model.hpp"
#include "adparm/rk4.hpp"

namespace adparm {

template <class Arm>
class OpenLoopArm {
 public:
  using State = Vec4;        // [q; dq]
  using TimeSignals = Vec2;  // tau_d(t)
  struct Outputs {};

  OpenLoopArm(const Arm& arm, const SinusoidalDisturbance& disturbance, bool compensate_gravity)
      : arm_(arm), disturbance_(disturbance), compensate_gravity_(compensate_gravity) {}

  void time_signals(double t, TimeSignals& signals) const { signals = disturbance_(t); }

  void derivative(const TimeSignals& tau_d, const State& x, State& rate, Outputs*) const {
    typename Arm::Terms terms;
    const Vec2 q = x.head<2>(), dq = x.tail<2>();
    arm_.compute(q, dq, terms);
    const Vec2 tau = compensate_gravity_ ? terms.gravity : Vec2::Zero();
    rate << dq, Arm::acceleration(terms, dq, tau, tau_d);
  }

 private:
  Arm arm_;
  SinusoidalDisturbance disturbance_;
  bool compensate_gravity_;
};

// Rows [q1, q2, dq1, dq2] at t = 0, dt, ..., steps * dt.
template <class Arm>
Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> simulate_open_loop(
    const OpenLoopArm<Arm>& system, const Vec4& initial_state, double dt, long steps) {
  check_positive(dt, "dt");
  if (steps < 0) throw std::invalid_argument("steps: must be >= 0");
  check_finite(initial_state, "initial_state");
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> states(steps + 1, 4);
  Vec4 x = initial_state;
  Rk4Workspace<OpenLoopArm<Arm>> workspace;
  states.row(0) = x.transpose();
  for (long k = 0; k < steps; ++k) {
    rk4_step(system, k * dt, (k + 1) * dt, x, workspace);
    states.row(k + 1) = x.transpose();
  }
  return states;
}

}  // namespace adparm
