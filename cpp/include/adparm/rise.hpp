// RISE feedback (eqs. 27-28):
//   mu(t) = (ks + 1) e2(t) - (ks + 1) e2(0) + nu(t)
//   dnu   = (ks + 1) alpha2 e2 + beta1 sgn(e2)
// beta1 should exceed the bound of condition (29) on the disturbance and its derivative.
#pragma once

#include "adparm/types.hpp"

namespace adparm {

struct RiseGains {
  double ks = 10.0;
  double alpha2 = 1.0;
  double beta1 = 0.5;
};

template <int N = 2>
class RiseT {
 public:
  using Joint = JointVector<N>;
  RiseT() = default;
  RiseT(const RiseGains& gains, const Joint& e2_initial) : gains_(gains), e2_initial_(e2_initial) {
    check_non_negative(gains.ks, "control.ks");
    check_non_negative(gains.alpha2, "control.alpha2");
    check_non_negative(gains.beta1, "control.beta1");
  }

  const RiseGains& gains() const { return gains_; }

  // eq. (27)
  Joint feedback(const Joint& e2, const Joint& nu) const {
    return (gains_.ks + 1.0) * (e2 - e2_initial_) + nu;
  }

  // eq. (28)
  Joint integral_rate(const Joint& e2) const {
    return (gains_.ks + 1.0) * gains_.alpha2 * e2 + gains_.beta1 * sign(e2);
  }

 private:
  RiseGains gains_{};
  Joint e2_initial_ = Joint::Zero(size_of(N, 0));
};
using Rise = RiseT<2>;

}  // namespace adparm
