// Actor: the policy of eq. (20) and its gradient update law with projection (eq. 26); with an input
// bound the tanh policy and its law (input_bound.hpp, hjb.hpp; Modares, Lewis & Naghibi-Sistani,
// IEEE TNNLS 2013; Vamvoudakis, Miranda & Hespanha, IEEE TNNLS 2016).
//   u_hat = -1/2 R^-1 g^T (dphi/dx)^T Wa = -1/2 R^-1 B^T Wa,   B = (dphi/dx) g   (N x m)
//   dWa = proj{ -eta_a1 / sqrt(1 + omega^T omega) B R^-1 B^T (Wa - Wc) eps_hjb - eta_a2 (Wa - Wc) }
// B R^-1 B^T is the ERRATA's grad(phi) G grad(phi)^T with G = g R^-1 g^T. The law is the gradient
// of eps_hjb^2 up to a factor 1/2 that eta_a1 absorbs. With Bellman-error extrapolation the
// gradient term gains its average over the N extrapolation points (extrapolation.hpp). proj keeps
// ||Wa|| <= weight_bound: at the boundary the outward radial component of the rate is removed.
// Not in the paper: with positive_e2 on, proj also keeps the e2 block of Wa positive definite
// (lambda_min >= e2_margin, positive_block.hpp), away from the anti-stabilising HJB solution.
#pragma once

#include "adparm/positive_block.hpp"
#include "adparm/types.hpp"

namespace adparm {

struct ActorSettings {
  double eta_a1 = 0.01;
  double eta_a2 = 1.0;
  double weight_bound = 100.0;
  bool positive_e2 = true;  // keep the e2 block of Wa positive definite (positive_block.hpp)
  double e2_margin = 0.01;  // ... with lambda_min >= e2_margin
  // The joint positions (n x S) where the structured basis of a URDF arm checks its e2 block
  // sum_b W_b M_b(q) (pinocchio_structured_basis.hpp); empty: that basis is not projected.
  Eigen::MatrixXd e2_check_positions;
};

template <class Basis, int Inputs>
class Actor {
 public:
  using Vector = typename Basis::Vector;
  using InputGradient = BasisMatrix<Basis::kSize, Inputs>;  // K x n
  using Input = JointVector<Inputs>;
  using InputWeight = JointMatrix<Inputs>;

  Actor() = default;
  explicit Actor(const ActorSettings& settings) : settings_(settings) {
    check_non_negative(settings.eta_a1, "actor.eta_a1");
    check_non_negative(settings.eta_a2, "actor.eta_a2");
    check_positive(settings.weight_bound, "actor.weight_bound");
    check_non_negative(settings.e2_margin, "actor.e2_margin");
  }

  const ActorSettings& settings() const { return settings_; }

  // eq. (20)
  static Input policy(const InputGradient& B, const InputWeight& R_inverse, const Vector& Wa) {
    return -0.5 * (R_inverse * (B.transpose() * Wa));
  }

  // Adds one sample's share of the gradient term of eq. (26) to `gradient`:
  //   gradient -= w eta_a1 / sqrt(1 + omega^T omega) B R^-1 B^T (Wa - Wc) eps_hjb
  // (w = 1 for the trajectory, 1/N for each of N extrapolation points).
  // With an input bound (input_bound.hpp; u_hat the bounded policy) the term is
  //   B R^-1 diag(sech^2 D) B^T (Wa - Wc) eps_hjb,
  // the gradient of eps_hjb for u_hat = -lambda tanh(D): d eps/du_hat = -B^T (Wa - Wc) (since
  // dU/du = -B^T Wa at u_hat) and du_hat/dWa = -1/2 diag(sech^2 D) R^-1 B^T (R diagonal).
  template <class Bound>
  void add_gradient(const InputGradient& B, const InputWeight& R_inverse, const Bound& bound,
                    const Input& u_hat, const Vector& omega, double hjb_error,
                    const Vector& difference, double weight, Vector& gradient) const {
    Input projected = R_inverse * (B.transpose() * difference);
    if (bound.bounded()) bound.scale_by_slope(u_hat, projected);
    gradient.noalias() -= gradient_scale(hjb_error, omega.squaredNorm(), weight) * (B * projected);
  }

  // add_gradient's share as the coefficients c of B, gradient -= B c, given the product
  // B^T (Wa - Wc) (ClosedLoop stacks the B of the prepared extrapolation points: one product
  // [B_1 ... B_N] [c_1; ...; c_N] for all of them).
  template <class Bound>
  Input gradient_coefficients(const Input& input_gradient_times_difference,
                              const InputWeight& R_inverse, const Bound& bound, const Input& u_hat,
                              const Vector& omega, double hjb_error, double weight) const {
    Input projected = R_inverse.lazyProduct(input_gradient_times_difference);  // no kernel call
    if (bound.bounded()) bound.scale_by_slope(u_hat, projected);
    return gradient_scale(hjb_error, omega.squaredNorm(), weight) * projected;
  }

  // The scalar of eq. (26)'s share: w eta_a1 eps / sqrt(1 + omega^T omega).
  double gradient_scale(double hjb_error, double omega_squared_norm, double weight) const {
    return weight * settings_.eta_a1 * hjb_error / std::sqrt(1.0 + omega_squared_norm);
  }

  // eq. (26): dWa = proj{gradient - eta_a2 (Wa - Wc)}, difference = Wa - Wc.
  Vector weight_rate(const Basis& basis, const Vector& gradient, const Vector& difference,
                     const Vector& Wa) const {
    return project(basis, Wa, gradient - settings_.eta_a2 * difference);
  }

  // proj{}: on or outside the ball ||Wa|| <= weight_bound, drop the outward radial component;
  // with positive_e2, first keep lambda_min of the e2 block >= e2_margin (positive_block.hpp;
  // the structured basis of a URDF arm at its check positions, pinocchio_structured_basis.hpp).
  Vector project(const Basis& basis, const Vector& Wa, const Vector& unprojected) const {
    const Vector rate =
        settings_.positive_e2
            ? keep_e2_block_positive(basis, Wa, unprojected, settings_.e2_margin, IdentityMetric{})
            : unprojected;
    const double norm_squared = Wa.squaredNorm();
    const double outward = Wa.dot(rate);
    if (norm_squared >= settings_.weight_bound * settings_.weight_bound && outward > 0.0)
      return rate - (outward / norm_squared) * Wa;
    return rate;
  }

 private:
  ActorSettings settings_{};
};

}  // namespace adparm
