// The structured basis of any URDF arm (issue 14): the critic basis whose exact weights are the
// cost's K and the arm's base inertial parameters.
//   phi(x, qd) = [e1_i e1_j (i <= j, row by row: e1_1^2, e1_1 e1_2, ..., e1_n^2);
//                 e2^T M_b(q) e2 for each base inertial parameter b],   q = qd - e1,
// with M(q) = sum_b beta_b M_b(q) over a minimal (identifiable) set of inertial parameters. Under
// the exact-solution conditions (Q11 = K alpha1 + alpha1^T K, Q12 = -K, Q22 = R^-1) the optimal
// value V* = e1^T K e1 + e2^T M(q) e2 is W*^T phi with
//   W* = [K_ii on squares, K_ij + K_ji on cross terms; beta]            (optimal_weights(K)).
//
// Base parameters (base_parameters()): the upper-triangle entries of M_k(q) = dM/dpi_k
// (PinocchioArm::mass_regressor) for the 10 n standard parameters, stacked over `samples` poses
// drawn uniformly within the joint limits clipped to [-pi, pi] (a fixed, seeded generator: the
// same poses on every platform), reduced by a QR decomposition with column pivoting: the r
// columns whose |R_ii| > tolerance |R_00| are independent (kept in increasing order, so M_b is
// M_{column b}) and every other column is a fixed combination of them, folded into
// beta = combination pi.
//
// Exact Jacobians from the kinetic-energy regressor: e2^T M_k(q) e2 = 2 T_k(q, v = e2), where for
// the body of joint i with local spatial velocity (v, w) (pinocchio data.v) and parameters
// (m, m c, I) about the joint frame's origin
//   T = 1/2 m |v|^2 + m c . (v x w) + 1/2 w^T I w   (Pinocchio's computeKineticEnergyRegressor).
// Each T_k is a quadratic form in (v, w), so 2 T_k = g_k . (v, w) with g_k its gradient (1 x 6),
// and d(2 T_k)/d(q, e2) = 2 g_k [dv_i/dq, dv_i/dv], the body's LOCAL velocity derivatives, which
// for each supporting joint j are oMi^-1 dJ_j and oMi^-1 J_j (J and dJ = ov x J in the world
// frame from one pass, computeJointJacobiansTimeVariation): g_k times them is oMi.act(g_k) . dJ_j
// and oMi.act(g_k) . J_j, one transform per row (as getJointVelocityDerivatives, LOCAL, but
// without its two transforms per supporting joint). Then
//   d phi_b / d e1 = -2 g_b dv_i/dq,   d phi_b / d e2 = 2 g_b dv_i/dv,
//   desired rate (d phi_b / d qd) dqd = 2 g_b dv_i/dq dqd,
// O(n^2) per evaluation, no finite difference.
//
// The basis has the dynamic-size basis members the loop expects (basis.hpp, dynamic_size.hpp):
// kSize = kStateDim = Dynamic, Vector, Jacobian, size(), evaluate(x, desired, [terms,] phi,
// jacobian, desired_rate). Given the arm's terms (the loop's second form: the model's terms at
// the same q = qd - e1, to round-off), the basis reuses the kinematics the arm's Coriolis pass
// left, oMi and J at that q, when the arm is of the same parsed URDF as the basis' (its
// kinematics token: derived arms with other inertias, gravity or friction share it), and forms
// from them the world velocities of v = e2, ov_i = ov_parent(i) + J_i e2_i, the local ones
// v_i = oMi^-1 ov_i and dJ_j = ov_j x J_j (Pinocchio's own recursions, in the world frame): no
// forward pass of its own. Otherwise it runs computeJointJacobiansTimeVariation at qd - e1.
// It has no paper e2 block (positive_block.hpp's HasPaperE2Block is false): its e2 block,
// e2^T M_W(q) e2 with M_W(q) = sum_b W_b M_b(q), is not affine in one cos q2, so positivity at
// every q cannot be checked at two end points. Instead (not in the paper), with actor.positive_e2
// the projection keeps lambda_min(M_W(q_s)) >= e2_margin at the check positions q_s given before
// the run (set_check_positions; the run's: qd(0), q(0) and the joint positions of the
// extrapolation box), as positive_block.hpp does at c = +-1, one constraint after the other.
//
// This header does not include Pinocchio (pimpl, as pinocchio_arm.hpp); the implementation is in
// cpp/src/pinocchio_structured_basis.cpp. Not thread-safe: evaluate() works in buffers the basis
// owns (its own pinocchio::Data, allocated at construction) and allocates nothing; give each
// thread its own copy (a copy builds a fresh work space).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "adparm/pinocchio_arm.hpp"
#include "adparm/positive_block.hpp"
#include "adparm/types.hpp"

namespace adparm {

// A minimal set of inertial parameters of M(q): M(q) = sum_b values[b] M_{columns[b]}(q) for
// every q, values = combination pi (combination: r x 10 n, the identity on `columns`).
struct BaseParameters {
  Eigen::VectorXd values;
  std::vector<int> columns;  // increasing indices into PinocchioArm::inertial_parameters()
  Eigen::MatrixXd combination;
};

// The base parameters of `arm` from `samples` seeded poses (see above). Throws
// std::invalid_argument for samples < 1 or a tolerance outside (0, 1).
BaseParameters base_parameters(const PinocchioArm& arm, int samples = 100, std::uint64_t seed = 0,
                               double tolerance = 1e-9);

// "m", "mc_x", "mc_y", "mc_z", "I_xx", "I_xy", "I_yy", "I_xz", "I_yz", "I_zz" and the body's
// name, for each of the 10 n inertial parameters (e.g. "m link2").
std::vector<std::string> inertial_parameter_names(const PinocchioArm& arm);

class PinocchioStructuredBasis {
 public:
  static constexpr int kSize = Dynamic;
  static constexpr int kStateDim = Dynamic;
  using Vector = BasisVector<Dynamic>;
  using Jacobian = BasisMatrix<Dynamic, Dynamic>;

  // The basis of `arm`, whose inertial parameters give beta (the believed model's arm, in a
  // run); it shares the arm's parsed model (const), with a pinocchio::Data of its own. Throws
  // std::invalid_argument (naming controller.basis) when the arm has more than kMaxDof joints or
  // the basis more than kMaxBasisSize functions.
  explicit PinocchioStructuredBasis(const PinocchioArm& arm);

  PinocchioStructuredBasis(const PinocchioStructuredBasis& other);
  PinocchioStructuredBasis& operator=(const PinocchioStructuredBasis& other);
  PinocchioStructuredBasis(PinocchioStructuredBasis&&) noexcept;
  PinocchioStructuredBasis& operator=(PinocchioStructuredBasis&&) noexcept;
  ~PinocchioStructuredBasis();

  int size() const { return size_; }
  int joints() const { return joints_; }
  // n (n + 1) / 2, the e1 block's size; the e2 block follows, one function per base parameter.
  int e1_size() const { return joints_ * (joints_ + 1) / 2; }
  const BaseParameters& base_parameters() const;
  // "e1_1^2", "e1_1 e1_2", ..., then "e2'M_b e2 (m link2)", ... (size()).
  const std::vector<std::string>& names() const;
  // W* = [K_ii on squares, K_ij + K_ji on cross terms; beta] for a K (n x n). Throws
  // std::invalid_argument for a K of the wrong size or not finite.
  Eigen::VectorXd optimal_weights(const Eigen::Ref<const Eigen::MatrixXd>& K) const;
  // The same for another arm of the same kinematics (the plant, when this basis is the believed
  // model's): beta = combination pi for its inertial parameters pi (10 n). The combination
  // depends on the kinematics only, so this is exact when the two arms differ in their inertias
  // alone (not checked here). Throws std::invalid_argument for a pi of the wrong size.
  Eigen::VectorXd optimal_weights(
      const Eigen::Ref<const Eigen::MatrixXd>& K,
      const Eigen::Ref<const Eigen::VectorXd>& inertial_parameters) const;

  // The work space of an evaluation (Pinocchio's data and buffers; opaque, in the .cpp), owned by
  // the caller (the loop's Data): the basis itself is never written.
  struct WorkspaceData;
  struct WorkspaceDeleter {
    void operator()(WorkspaceData* workspace) const;
  };
  using Workspace = std::unique_ptr<WorkspaceData, WorkspaceDeleter>;
  // A work space for this basis (allocates; once per run).
  Workspace workspace() const;

  // phi (size()), d phi / dx (size() x 2n) and (d phi / d qd) dqd (size()) at x = [e1; e2] (2n)
  // and the desired qd, dqd (n), in a work space of this basis; no heap allocation. Sizes are
  // checked. arm_terms: the arm's terms computed at q = qd - e1 (to round-off), whose kinematics
  // are reused when shares_kinematics (above; the e2 block is then at their q); nullptr: none.
  void evaluate_at(const Eigen::Ref<const Eigen::VectorXd>& x,
                   const Eigen::Ref<const Eigen::VectorXd>& qd,
                   const Eigen::Ref<const Eigen::VectorXd>& dqd, Eigen::Ref<Eigen::VectorXd> phi,
                   Eigen::Ref<Eigen::MatrixXd> jacobian, Eigen::Ref<Eigen::VectorXd> desired_rate,
                   Workspace& workspace, const PinocchioArm::Terms* arm_terms = nullptr) const;

  // Whether evaluate_at reuses the kinematics of `arm`'s terms: the same parsed URDF (and only
  // revolute or prismatic joints of one coordinate each, which every URDF arm has).
  bool shares_kinematics(const PinocchioArm& arm) const;

  // Only the Pinocchio pass of evaluate_at (computeJointJacobiansTimeVariation at q = qd - e1,
  // v = e2), without the basis' own products: the bench times it for the share of a loop step
  // spent in Pinocchio. No heap allocation.
  void pinocchio_passes(const Eigen::Ref<const Eigen::VectorXd>& x,
                        const Eigen::Ref<const Eigen::VectorXd>& qd, Workspace& workspace) const;

  // The loop's seam (bounded storage: resizing allocates nothing).
  template <class Desired>
  void evaluate(const ErrorVector<Dynamic>& x, const Desired& desired, Vector& phi,
                Jacobian& jacobian, Vector& desired_rate, Workspace& workspace) const {
    evaluate_sized(x, desired, phi, jacobian, desired_rate, workspace, nullptr);
  }
  // With the model's terms at the same q (the loop's second form): a URDF arm's (a member
  // `pinocchio`, PinocchioArm::Terms) lend their kinematics; other terms are not used.
  template <class Desired, class Terms>
  void evaluate(const ErrorVector<Dynamic>& x, const Desired& desired, const Terms& terms,
                Vector& phi, Jacobian& jacobian, Vector& desired_rate, Workspace& workspace) const {
    const PinocchioArm::Terms* arm_terms = nullptr;
    if constexpr (HasPinocchioTerms<Terms>::value) arm_terms = &terms.pinocchio;
    evaluate_sized(x, desired, phi, jacobian, desired_rate, workspace, arm_terms);
  }

  // The check positions of the positive_e2 projection (n x S, S >= 0) with `arm` the arm whose
  // inertial parameters this basis was built from (its kinematics); allocates, once before a run.
  // Throws std::invalid_argument (naming actor.e2_check_positions) for a wrong row count or
  // values that are not finite.
  void set_check_positions(const PinocchioArm& arm,
                           const Eigen::Ref<const Eigen::MatrixXd>& positions);
  Eigen::Index check_count() const { return static_cast<Eigen::Index>(check_blocks_.size()); }
  // vec(M_b(q_s)) of every base parameter b in columns: (n^2, size() - e1_size()).
  const Eigen::MatrixXd& check_block(Eigen::Index s) const {
    return check_blocks_[static_cast<std::size_t>(s)];
  }

  struct Impl;  // opaque: Pinocchio's model and the basis' tables

 private:
  template <class Desired>
  void evaluate_sized(const ErrorVector<Dynamic>& x, const Desired& desired, Vector& phi,
                      Jacobian& jacobian, Vector& desired_rate, Workspace& workspace,
                      const PinocchioArm::Terms* arm_terms) const {
    phi.resize(size_);
    jacobian.resize(size_, 2 * joints_);
    desired_rate.resize(size_);
    evaluate_at(x, desired.q, desired.dq, phi, jacobian, desired_rate, workspace, arm_terms);
  }
  template <class Terms, class = void>
  struct HasPinocchioTerms : std::false_type {};
  template <class Terms>
  struct HasPinocchioTerms<Terms, std::void_t<decltype(std::declval<const Terms&>().pinocchio)>>
      : std::is_same<std::decay_t<decltype(std::declval<const Terms&>().pinocchio)>,
                     PinocchioArm::Terms> {};

  std::unique_ptr<Impl> impl_;
  int joints_ = 0;
  int size_ = 0;
  std::vector<Eigen::MatrixXd> check_blocks_;
};

// actor.positive_e2 on the structured basis (see above): `rate` (dW/dt) changed least, in the
// metric of `metric` (identity for the actor, Gamma for the critic), so that at every check
// position s with lambda_min(M_W(q_s)) <= margin, d lambda_min / dt >= kE2Recovery (margin -
// lambda_min); the gradient of lambda_min is n_b = v^T M_b(q_s) v (v its unit eigenvector).
// Positions inside the margin cost one n x n Cholesky each; no heap allocation.
template <class Vector, class Metric>
Vector keep_e2_block_positive(const PinocchioStructuredBasis& basis, const Vector& W,
                              const Vector& rate, double margin, const Metric& metric) {
  const Eigen::Index count = basis.check_count();
  if (count == 0) return rate;
  using Block = JointMatrix<Dynamic>;  // n x n, bounded: no heap
  const Eigen::Index n = basis.joints(), e1 = basis.e1_size(), r = basis.size() - e1;
  Vector projected = rate;
  Block M(n, n), outer(n, n);
  for (Eigen::Index s = 0; s < count; ++s) {
    const Eigen::MatrixXd& blocks = basis.check_block(s);
    Eigen::Map<Eigen::VectorXd>(M.data(), n * n).noalias() = blocks * W.tail(r);
    Block shifted = M;
    shifted.diagonal().array() -= margin;
    if (Eigen::LLT<Block>(shifted).info() == Eigen::Success) continue;  // inside: lambda > margin
    const Eigen::SelfAdjointEigenSolver<Block> eigen(M);
    const double lambda = eigen.eigenvalues()[0];
    outer.noalias() = eigen.eigenvectors().col(0) * eigen.eigenvectors().col(0).transpose();
    Vector normal = Vector::Zero(W.size());
    normal.tail(r).noalias() =
        blocks.transpose() * Eigen::Map<const Eigen::VectorXd>(outer.data(), n * n);
    const double floor = kE2Recovery * (margin - lambda);
    const double slope = normal.dot(projected);
    if (!(slope < floor)) continue;
    const Vector metric_normal = metric * normal;
    const double g = normal.dot(metric_normal);
    if (!(g > 0.0)) continue;
    projected += ((floor - slope) / g) * metric_normal;
  }
  return projected;
}

}  // namespace adparm
