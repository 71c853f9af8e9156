// Probing (exploration) signal added to the applied input while t < until, for persistence of
// excitation (eq. 25). The paper does not print one; ours is a sum of sinusoids per joint:
//   probe_j(t) = ramp(t) sum_k amplitude_jk sin(frequencies_k t + phases_jk)   for t < until, else
//   0, ramp(t) = min(1, t / ramp) (a linear fade-in over the first `ramp` seconds; ramp = 0: none).
// A column of amplitude is the torque direction of one sinusoid (see README, "Probing").
#pragma once

#include <cmath>

#include "adparm/types.hpp"

namespace adparm {

struct ProbeSettings {
  Eigen::MatrixXd amplitude;  // N m, n x frequencies.size()
  double until = 0.0;
  double ramp = 0.0;            // s
  Eigen::VectorXd frequencies;  // rad/s, one entry per sinusoid
  Eigen::MatrixXd phases;       // rad, n x frequencies.size()
};

template <int N = 2>
class ProbingSignalT {
 public:
  using Joint = JointVector<N>;
  ProbingSignalT() = default;
  ProbingSignalT(const ProbeSettings& settings, Eigen::Index n) : settings_(settings), dof_(n) {
    check_finite(settings.until, "probe.until");
    check_non_negative(settings.ramp, "probe.ramp");
    check_finite(settings.frequencies, "probe.frequencies");
    check_size(settings.amplitude, n, settings.frequencies.size(), "probe.amplitude");
    check_finite(settings.amplitude, "probe.amplitude");
    check_size(settings.phases, n, settings.frequencies.size(), "probe.phases");
    check_finite(settings.phases, "probe.phases");
    // sin(w t + p) = sin(w t) cos p + cos(w t) sin p: one sin/cos pair per frequency and time.
    sin_weight_ = settings.amplitude.cwiseProduct(settings.phases.array().cos().matrix());
    cos_weight_ = settings.amplitude.cwiseProduct(settings.phases.array().sin().matrix());
  }

  // The sinusoids' count and frequencies (rad/s), and the signal at t given sin and cos of
  // frequency k times t (sine[k], cosine[k]; the vector loop's, vector_loop.hpp): operator()'s
  // sums.
  const Eigen::VectorXd& frequencies() const { return settings_.frequencies; }
  Joint from_sines(double t, const double* sine, const double* cosine) const {
    Joint value = Joint::Zero(dof_);
    if (t >= settings_.until) return value;
    for (Eigen::Index k = 0; k < settings_.frequencies.size(); ++k)
      value += sine[k] * sin_weight_.col(k) + cosine[k] * cos_weight_.col(k);
    if (t < settings_.ramp) value *= t / settings_.ramp;
    return value;
  }

  Joint operator()(double t) const {
    Joint value = Joint::Zero(dof_);
    if (t >= settings_.until) return value;
    for (Eigen::Index k = 0; k < settings_.frequencies.size(); ++k) {
      const double angle = settings_.frequencies[k] * t;
      const double s = std::sin(angle), c = std::cos(angle);
      value += s * sin_weight_.col(k) + c * cos_weight_.col(k);
    }
    if (t < settings_.ramp) value *= t / settings_.ramp;
    return value;
  }

 private:
  ProbeSettings settings_{};
  Eigen::Index dof_ = 2;
  Eigen::Matrix<double, N, Eigen::Dynamic> sin_weight_, cos_weight_;  // n x frequencies.size()
};
using ProbingSignal = ProbingSignalT<2>;

}  // namespace adparm
