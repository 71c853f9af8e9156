// Probing (exploration) signal added to the applied input while t < until, for persistence of
// excitation (eq. 25). The paper does not print one; ours is a sum of sinusoids per joint:
//   probe_j(t) = amplitude_j * sum_k sin(frequencies_k t + phases_jk)   for t < until, else 0.
#pragma once

#include <cmath>

#include "adparm/types.hpp"

namespace adparm {

struct ProbeSettings {
  Vec2 amplitude = Vec2::Zero();
  double until = 0.0;
  Eigen::VectorXd frequencies;                      // rad/s, one entry per sinusoid
  Eigen::Matrix<double, 2, Eigen::Dynamic> phases;  // rad, 2 x frequencies.size()
};

class ProbingSignal {
 public:
  ProbingSignal() = default;
  explicit ProbingSignal(const ProbeSettings& settings) : settings_(settings) {
    check_finite(settings.amplitude, "probe.amplitude");
    check_finite(settings.until, "probe.until");
    check_finite(settings.frequencies, "probe.frequencies");
    check_size(settings.phases, 2, settings.frequencies.size(), "probe.phases");
    check_finite(settings.phases, "probe.phases");
  }

  Vec2 operator()(double t) const {
    Vec2 value = Vec2::Zero();
    if (t >= settings_.until) return value;
    for (Eigen::Index k = 0; k < settings_.frequencies.size(); ++k) {
      const double angle = settings_.frequencies[k] * t;
      value[0] += std::sin(angle + settings_.phases(0, k));
      value[1] += std::sin(angle + settings_.phases(1, k));
    }
    return settings_.amplitude.cwiseProduct(value);
  }

 private:
  ProbeSettings settings_{};
};

}  // namespace adparm
