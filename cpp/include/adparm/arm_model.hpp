// Two-link arm in the general form of Section 4 (eq. 1):
//   M(q) ddq + C(q, dq) dq + G(q) + F(dq) + tau_d(t) = tau
//   M = [[p1 + 2 p3 cos q2, p2 + p3 cos q2], [p2 + p3 cos q2, p2]]
//   C = p3 sin q2 [[-dq2, -(dq1 + dq2)], [dq1, 0]]
//   G = [g1 cos q1 + g2 cos(q1 + q2), g2 cos(q1 + q2)]
//   F = coulomb sign(dq) + viscous dq
// The paper's instance is p = (5, 1, 1), g1 = 9.8 * 1.2, g2 = 9.8, coulomb = -0.1, viscous = 0.
//
// THE ARM CONCEPT. The loop (closed_loop.hpp) takes any arm type that offers exactly these members:
//
//   static constexpr int kDof;       // the joint count n, or Eigen::Dynamic (adparm::Dynamic)
//   int dof() const;                 // n at run time (== kDof when it is fixed)
//   struct/using Terms {             // the model terms at one (q, dq):
//     JointMatrix<kDof> mass;          //   M(q)            n x n, symmetric positive definite
//     JointMatrix<kDof> mass_inverse;  //   M(q)^-1         n x n
//     JointMatrix<kDof> coriolis;      //   C(q, dq)        n x n, with dM/dt - 2C skew-symmetric
//     JointVector<kDof> gravity;       //   G(q)            n
//     JointVector<kDof> friction;      //   F(dq)           n
//   };
//   void init_terms(Terms&) const;   // sizes every member to n (called once per run, may allocate)
//   void compute(const JointVector<kDof>& q, const JointVector<kDof>& dq, Terms&) const;
//                                    // fills the terms; called 4 times per RK4 step and per
//                                    // extrapolation point: it must not allocate
//   JointVector<kDof> acceleration(const Terms&, const JointVector<kDof>& dq,
//                                  const JointVector<kDof>& tau,
//                                  const JointVector<kDof>& tau_d) const;
//                                    // ddq of eq. (1): M^-1 (tau - C dq - G - F - tau_d)
//
// JointVector / JointMatrix come from types.hpp: for kDof = Dynamic they are bounded dynamic types
// (inline storage for up to kMaxDof joints), so that Terms, and every expression the loop builds
// from them, never touch the heap. An arm with buffers of its own (e.g. UrdfLoopArm: a
// PinocchioArm, a pinocchio::Model behind a pimpl, whose pinocchio::Data rides in the Terms,
// compute() in a .cpp) copies its results into the Terms members. Two arms of one type are the
// plant and the model the controller believes; each Arm is constructed once per run, outside the
// step. Extra members of Terms (like the two-link arm's cos q2) are for bases written for that arm.
#pragma once

#include <cmath>

#include "adparm/types.hpp"

namespace adparm {

struct TwoLinkArmParameters {
  double p1 = 5.0;
  double p2 = 1.0;
  double p3 = 1.0;
  double g1 = 9.8 * 1.2;
  double g2 = 9.8;
  double coulomb = -0.1;
  double viscous = 0.0;

  friend bool operator==(const TwoLinkArmParameters& a, const TwoLinkArmParameters& b) {
    return a.p1 == b.p1 && a.p2 == b.p2 && a.p3 == b.p3 && a.g1 == b.g1 && a.g2 == b.g2 &&
           a.coulomb == b.coulomb && a.viscous == b.viscous;
  }
};

// Model terms at one (q, dq), computed together so that cos q2 and sin q2 are evaluated once.
struct TwoLinkArmTerms {
  Mat2 mass;            // M(q)
  Mat2 mass_inverse;    // M(q)^-1 in closed form
  Mat2 coriolis;        // C(q, dq)
  Vec2 gravity;         // G(q)
  Vec2 friction;        // F(dq)
  double cos_q2 = 1.0;  // cos q2 and sin q2, for a basis that uses them (basis.hpp)
  double sin_q2 = 0.0;
};

class TwoLinkArm {
 public:
  static constexpr int kDof = 2;
  using Parameters = TwoLinkArmParameters;
  using Terms = TwoLinkArmTerms;

  TwoLinkArm() = default;

  // Refuses parameters for which M(q) is not positive definite for every q2:
  // p2 > 0 and det M = p1 p2 - p2^2 - p3^2 cos^2 q2 > 0, i.e. p1 p2 - p2^2 - p3^2 > 0.
  explicit TwoLinkArm(const Parameters& parameters, const char* name = "plant")
      : parameters_(parameters) {
    const std::string prefix(name);
    const Parameters& p = parameters;
    for (double v : {p.p1, p.p2, p.p3, p.g1, p.g2, p.coulomb, p.viscous})
      check_finite(v, (prefix + ": parameters").c_str());
    if (!(p.p2 > 0.0)) throw std::invalid_argument(prefix + ".p2: must be > 0");
    const double det = p.p1 * p.p2 - p.p2 * p.p2 - p.p3 * p.p3;  // inf - inf = nan: refused
    if (!(det > 0.0) || !std::isfinite(det))
      throw std::invalid_argument(prefix +
                                  ".p1, p2, p3: M(q) must be positive definite for all q "
                                  "(need p1 p2 - p2^2 - p3^2 > 0 and finite)");
  }

  // Without the checks: for parameters known to give a positive definite M(q) (the identifier's
  // estimate, identifier.hpp, which keeps it so), built at every step without allocating.
  static TwoLinkArm unchecked(const Parameters& parameters) {
    TwoLinkArm arm;
    arm.parameters_ = parameters;
    return arm;
  }

  const Parameters& parameters() const { return parameters_; }
  static constexpr int dof() { return kDof; }
  static void init_terms(Terms&) {}

  void compute(const Vec2& q, const Vec2& dq, Terms& terms) const {
    compute(dq, std::cos(q[0]), std::sin(q[0]), std::cos(q[1]), std::sin(q[1]), terms);
  }
  // The same from cos and sin of q1 and q2 (the vector loop's, vector_loop.hpp).
  void compute(const Vec2& dq, double c1, double s1, double c2, double s2, Terms& terms) const {
    const Parameters& p = parameters_;
    terms.cos_q2 = c2;
    terms.sin_q2 = s2;
    const double m11 = p.p1 + 2.0 * p.p3 * c2;
    const double m12 = p.p2 + p.p3 * c2;
    const double m22 = p.p2;
    terms.mass << m11, m12, m12, m22;
    const double inverse_det = 1.0 / (m11 * m22 - m12 * m12);
    terms.mass_inverse << m22 * inverse_det, -m12 * inverse_det, -m12 * inverse_det,
        m11 * inverse_det;
    const double h = p.p3 * s2;
    terms.coriolis << -h * dq[1], -h * (dq[0] + dq[1]), h * dq[0], 0.0;
    const double c12 = c1 * c2 - s1 * s2;  // cos(q1 + q2): two sincos calls in all, not three
    terms.gravity << p.g1 * c1 + p.g2 * c12, p.g2 * c12;
    terms.friction = p.coulomb * sign(dq) + p.viscous * dq;
  }

  // Joint acceleration of eq. (1) for a given torque and disturbance.
  static Vec2 acceleration(const Terms& terms, const Vec2& dq, const Vec2& tau, const Vec2& tau_d) {
    return terms.mass_inverse *
           (tau - terms.coriolis * dq - terms.gravity - terms.friction - tau_d);
  }

 private:
  Parameters parameters_{};
};

// The terms of a dynamic-size arm (bounded types: no heap) and what every such arm does with them
// the same way: size them once, and eq. (1).
struct DynamicTerms {
  JointMatrix<Dynamic> mass, mass_inverse, coriolis;
  JointVector<Dynamic> gravity, friction;
};

inline void init_dynamic_terms(DynamicTerms& terms, Eigen::Index n) {
  terms.mass.setZero(n, n);
  terms.mass_inverse.setZero(n, n);
  terms.coriolis.setZero(n, n);
  terms.gravity.setZero(n);
  terms.friction.setZero(n);
}

// ddq of eq. (1): M^-1 (tau - C dq - G - F - tau_d)
inline JointVector<Dynamic> dynamic_acceleration(const DynamicTerms& terms,
                                                 const JointVector<Dynamic>& dq,
                                                 const JointVector<Dynamic>& tau,
                                                 const JointVector<Dynamic>& tau_d) {
  const JointVector<Dynamic> residual =
      tau - small_product(terms.coriolis, dq) - terms.gravity - terms.friction - tau_d;
  return small_product(terms.mass_inverse, residual);
}

// tau_d(t) = [a1 sin t, a2 cos t] (Section 4, with a = (0.1, 0.1)); for n joints, joint j
// (from 1) has a_j sin t for odd j and a_j cos t for even j.
template <int N = 2>
struct SinusoidalDisturbanceT {
  JointVector<N> amplitude;
  JointVector<N> operator()(double t) const {
    const double s = std::sin(t), c = std::cos(t);
    JointVector<N> value(amplitude.size());
    for (Eigen::Index j = 0; j < amplitude.size(); ++j)
      value[j] = amplitude[j] * (j % 2 == 0 ? s : c);
    return value;
  }
};
using SinusoidalDisturbance = SinusoidalDisturbanceT<2>;

}  // namespace adparm
