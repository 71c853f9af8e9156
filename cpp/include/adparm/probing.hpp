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
  Eigen::Matrix<double, 2, Eigen::Dynamic> amplitude;  // N m, 2 x frequencies.size()
  double until = 0.0;
  double ramp = 0.0;                                // s
  Eigen::VectorXd frequencies;                      // rad/s, one entry per sinusoid
  Eigen::Matrix<double, 2, Eigen::Dynamic> phases;  // rad, 2 x frequencies.size()
};

class ProbingSignal {
 public:
  ProbingSignal() = default;
  explicit ProbingSignal(const ProbeSettings& settings) : settings_(settings) {
    check_finite(settings.until, "probe.until");
    check_non_negative(settings.ramp, "probe.ramp");
    check_finite(settings.frequencies, "probe.frequencies");
    check_size(settings.amplitude, 2, settings.frequencies.size(), "probe.amplitude");
    check_finite(settings.amplitude, "probe.amplitude");
    check_size(settings.phases, 2, settings.frequencies.size(), "probe.phases");
    check_finite(settings.phases, "probe.phases");
  }

  Vec2 operator()(double t) const {
    Vec2 value = Vec2::Zero();
    if (t >= settings_.until) return value;
    for (Eigen::Index k = 0; k < settings_.frequencies.size(); ++k) {
      const double angle = settings_.frequencies[k] * t;
      value[0] += settings_.amplitude(0, k) * std::sin(angle + settings_.phases(0, k));
      value[1] += settings_.amplitude(1, k) * std::sin(angle + settings_.phases(1, k));
    }
    if (t < settings_.ramp) value *= t / settings_.ramp;
    return value;
  }

 private:
  ProbeSettings settings_{};
};

}  // namespace adparm
