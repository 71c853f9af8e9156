// The two-link arm and its bases seen through dynamic sizes: DynamicArm<TwoLinkArm> has
// kDof = Eigen::Dynamic and DynamicBasis<AugmentedBasis> kSize = Eigen::Dynamic, so that
// ClosedLoop<DynamicArm<TwoLinkArm>, DynamicBasis<...>> runs the n-joint loop of any arm (bounded
// types, buffers sized once) on the paper's instance. The two paths compute the same laws; a test
// compares their recordings (tests/test_dynamic_sizes.py, bench --checks). Settings::dynamic_sizes
// selects this path (simulation.hpp), and so does an expression basis on the two-link arm.
// DynamicRegressor<TwoLinkRegressor> is the online identifier's regressor (identifier.hpp) of
// DynamicArm<TwoLinkArm>: the fixed-size one's, its joint vectors seen through dynamic sizes.
#pragma once

#include <utility>

#include "adparm/arm_model.hpp"
#include "adparm/basis.hpp"
#include "adparm/identifier.hpp"

namespace adparm {

// A fixed-size arm behind the dynamic-size Arm concept (arm_model.hpp).
template <class FixedArm>
class DynamicArm {
 public:
  static constexpr int kDof = Dynamic;
  static constexpr int kFixedDof = FixedArm::kDof;
  using Parameters = typename FixedArm::Parameters;
  using Joint = JointVector<Dynamic>;

  struct Terms : DynamicTerms {
    typename FixedArm::Terms fixed;  // the wrapped arm's own terms (cos q2, sin q2 for its bases)
  };

  DynamicArm() = default;
  DynamicArm(const Parameters& parameters, const char* name) : arm_(parameters, name) {}
  explicit DynamicArm(const FixedArm& arm) : arm_(arm) {}

  const FixedArm& fixed() const { return arm_; }
  int dof() const { return kFixedDof; }

  void init_terms(Terms& terms) const { init_dynamic_terms(terms, kFixedDof); }

  void compute(const Joint& q, const Joint& dq, Terms& terms) const {
    using Fixed = JointVector<kFixedDof>;
    arm_.compute(Fixed(q), Fixed(dq), terms.fixed);
    terms.mass = terms.fixed.mass;
    terms.mass_inverse = terms.fixed.mass_inverse;
    terms.coriolis = terms.fixed.coriolis;
    terms.gravity = terms.fixed.gravity;
    terms.friction = terms.fixed.friction;
  }

  // eq. (1), with the dynamic terms
  Joint acceleration(const Terms& terms, const Joint& dq, const Joint& tau,
                     const Joint& tau_d) const {
    return dynamic_acceleration(terms, dq, tau, tau_d);
  }

 private:
  FixedArm arm_{};
};

// A fixed-size basis of the two-link arm behind dynamic sizes. The terms must be DynamicArm's
// (the wrapped basis reads the fixed terms, e.g. cos q2).
template <class FixedBasis>
struct DynamicBasis {
  static constexpr int kSize = Dynamic;
  static constexpr int kStateDim = Dynamic;
  using Vector = BasisVector<Dynamic>;
  using Jacobian = BasisMatrix<Dynamic, Dynamic>;
  static constexpr int kFixedDof = FixedBasis::kStateDim / 2;

  int size() const { return FixedBasis::kSize; }

  template <class Terms>
  void evaluate(const ErrorVector<Dynamic>& x, const DesiredStateT<Dynamic>& desired,
                const Terms& terms, Vector& phi, Jacobian& jacobian, Vector& desired_rate) const {
    typename FixedBasis::Vector fixed_phi, fixed_rate;
    typename FixedBasis::Jacobian fixed_jacobian;
    FixedBasis::evaluate(ErrorVector<kFixedDof>(x), fixed_desired(desired), terms.fixed, fixed_phi,
                         fixed_jacobian, fixed_rate);
    phi = fixed_phi;
    jacobian = fixed_jacobian;
    desired_rate = fixed_rate;
  }

  void evaluate(const ErrorVector<Dynamic>& x, const DesiredStateT<Dynamic>& desired, Vector& phi,
                Jacobian& jacobian, Vector& desired_rate) const {
    typename FixedBasis::Vector fixed_phi, fixed_rate;
    typename FixedBasis::Jacobian fixed_jacobian;
    FixedBasis::evaluate(ErrorVector<kFixedDof>(x), fixed_desired(desired), fixed_phi,
                         fixed_jacobian, fixed_rate);
    phi = fixed_phi;
    jacobian = fixed_jacobian;
    desired_rate = fixed_rate;
  }

 private:
  static DesiredStateT<kFixedDof> fixed_desired(const DesiredStateT<Dynamic>& desired) {
    DesiredStateT<kFixedDof> d;
    d.q = desired.q;
    d.dq = desired.dq;
    d.ddq = desired.ddq;
    return d;
  }
};

// A fixed-size Regressor (identifier.hpp) behind the dynamic-size joint vectors of DynamicArm: the
// same regressors, beta and checks, so the dynamic-size loop identifies as the fixed-size one.
template <class FixedRegressor>
class DynamicRegressor {
 public:
  static constexpr int kDof = Dynamic;
  static constexpr int kFixedDof = FixedRegressor::kDof;
  static constexpr int kParameters = FixedRegressor::kParameters;
  static constexpr int kMaxParameters = FixedRegressor::kMaxParameters;
  using Arm = DynamicArm<typename FixedRegressor::Arm>;
  using Joint = JointVector<Dynamic>;
  using Parameters = typename FixedRegressor::Parameters;
  using Matrix = Eigen::Matrix<double, Dynamic, kParameters, 0, kMaxDof, kParameters>;
  using Workspace = typename FixedRegressor::Workspace;

  static DynamicRegressor of(const Arm& model) {
    return DynamicRegressor(FixedRegressor::of(model.fixed()));
  }
  Parameters beta(const Arm& arm) const { return fixed_.beta(arm.fixed()); }
  int dof() const { return kFixedDof; }
  int parameters() const { return fixed_.parameters(); }
  ParameterGroup group(int i) const { return fixed_.group(i); }
  Workspace make_workspace(const Parameters& initial) const {
    return fixed_.make_workspace(initial);
  }
  void reference_regressor(const Joint& q, const Joint& dq, const Joint& v, const Joint& a,
                           Matrix& out, Workspace& workspace) const {
    typename FixedRegressor::Matrix fixed;
    fixed_.reference_regressor(Fixed(q), Fixed(dq), Fixed(v), Fixed(a), fixed, workspace);
    out = fixed;
  }
  void momentum_regressor(const Joint& q, const Joint& dq, Matrix& out,
                          Workspace& workspace) const {
    typename FixedRegressor::Matrix fixed;
    fixed_.momentum_regressor(Fixed(q), Fixed(dq), fixed, workspace);
    out = fixed;
  }
  void momentum_rate_regressor(const Joint& q, const Joint& dq, Matrix& out,
                               Workspace& workspace) const {
    typename FixedRegressor::Matrix fixed;
    fixed_.momentum_rate_regressor(Fixed(q), Fixed(dq), fixed, workspace);
    out = fixed;
  }
  bool accept(const Parameters& next, const Joint& q, Workspace& workspace) const {
    return fixed_.accept(next, Fixed(q), workspace);
  }
  Arm arm(const Parameters& estimate, const Workspace& workspace) const {
    return Arm(fixed_.arm(estimate, workspace));
  }

  DynamicRegressor() = default;

 private:
  using Fixed = JointVector<kFixedDof>;
  explicit DynamicRegressor(FixedRegressor fixed) : fixed_(std::move(fixed)) {}
  FixedRegressor fixed_{};
};

template <>
struct IdentifierOf<DynamicArm<TwoLinkArm>> {
  using type = Identifier<DynamicRegressor<TwoLinkRegressor>>;
};

}  // namespace adparm
