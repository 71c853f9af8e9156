// The online identifier's regressor of a URDF arm (identifier.hpp's Regressor concept; issue 25,
// stage 2; guide "Unknown dynamics"). Pinocchio's joint torque regressor Y_pi (n x 10 n) is linear
// in the 10 n standard inertial parameters pi (computeJointTorqueRegressor):
//   M(q) ddq + C(q, dq) dq + G(q) = Y_pi(q, dq, ddq) pi.
// The base parameters (one table, computed when the regressor is built):
//   beta = [beta_M (r); beta_G (g); coulomb (n); viscous (n)]
//   beta_M = B_M pi   the kinetic energy's base parameters, those of the structured basis
//                     (pinocchio_structured_basis.hpp, base_parameters: columns S_M, identity on
//                     them), group "inertia";
//   beta_G = B_G pi   the parameters gravity sees beyond them (group "gravity"): the gravity
//                     regressor's columns G_k(q) = Y_pi(q, 0, 0) e_k less their M-expression,
//                     R_k = G_k - sum_s B_M(s, k) G_s (0 on S_M), sampled at seeded poses and
//                     reduced by a pivoted QR (columns S_G, identity on them); B_G solves
//                     R = R_{S_G} B_G;
//   F(dq) = diag(sign dq) coulomb + diag(dq) viscous (group "friction").
// In beta, Y = Y_pi P + [diag(sign dq), diag(dq)] with P = [E_{S_M}, D] (10 n x (r + g)): E_{S_M}
// selects the columns S_M, and D's column e is e_e - E_{S_M} B_M(:, e), a direction in which M(q)
// does not change, so that its column of Y_pi P is R_e, gravity alone. B P = I and Y_pi's null
// space contains B's (sampled), so Y_pi pi = Y_pi P B pi = Y beta.
//
// The four regressors (n x (r + g + 2 n)):
//   Y(q, dq, ddq)       eq. (1): Y_pi(q, dq, ddq) P and the friction columns;
//   Y_r(q, dq, v, a)    eq. (5)'s h: C(q, a) b is symmetric bilinear (Christoffel symbols), so
//                       C(q, dq) v = [C(q, s) s - C(q, d) d] / 4, s = dq + v, d = dq - v, and
//                       Y_r = [Y_pi(q, 0, a) + (Y_pi(q, s, 0) - Y_pi(q, d, 0)) / 4] P + F(dq)'s
//                       (gravity cancels in the difference): three regressor passes;
//   Y_M(q, dq)          M dq = Y_pi(q, 0, dq) P without gravity;
//   Y_N(q, dq)          G + F - C^T dq, with C^T dq = dT/dq (dM/dt = C + C^T and Lagrange's
//                       equations: M ddq + C dq = d/dt (M dq) - dT/dq); dT_k/dq of each
//                       parameter from the body's local spatial velocity (v, w) and
//                       Pinocchio's velocity derivatives: dT_k/dq = 1/2 g_k dv/dq, g_k the
//                       gradient of 2 T_k in (v, w) (energy_gradient, as the structured basis).
//
// The believed model of an estimate beta_hat: Pinocchio's algorithms are linear in pi, so any
// pi_hat with B pi_hat = beta_hat has beta_hat's dynamics exactly (Y_pi pi_hat = Y beta_hat);
// accept() takes pi_hat = pi_model + P (beta_hat - beta_model), writes it into a copy of the
// model (PinocchioArm::Estimate, in the workspace) with beta_hat's friction, and the loop's
// believed arm computes M, M^-1, C, G, F there (CRBA, the Coriolis matrix, gravity: what the
// model's terms cost) instead of n + 1 + 2 n regressor passes per evaluation. pi_hat need not be
// physical; an update is refused (beta_hat kept) when a body's mass in pi_hat is not > 0
// (Pinocchio's inertia stores the lever c = m c / m) or M_hat(q) is not positive definite at the
// step's q (a crude projection, as the two-link arm's; that check is at every q).
//
// Pinocchio is in cpp/src/urdf_regressor.cpp (pimpl); the regressor shares the model arm's
// parsed model (const); the workspace is the caller's (the identifier's Data). No heap allocation
// after make_workspace.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "adparm/identifier.hpp"
#include "adparm/pinocchio_arm.hpp"
#include "adparm/types.hpp"
#include "adparm/urdf_loop_arm.hpp"

namespace adparm {

class PinocchioRegressor {
 public:
  static constexpr int kDof = Dynamic;
  static constexpr int kParameters = Dynamic;
  static constexpr int kMaxParameters = 96;  // r + g + 2 n of the arms the identifier takes
  using Arm = UrdfLoopArm;
  using Joint = JointVector<Dynamic>;
  using Parameters = Eigen::Matrix<double, Dynamic, 1, 0, kMaxParameters, 1>;
  using Matrix = Eigen::Matrix<double, Dynamic, Dynamic, 0, kMaxDof, kMaxParameters>;

  struct WorkspaceData;  // Pinocchio's data, Y_pi, pi_hat and the estimated model (.cpp)
  struct WorkspaceDeleter {
    void operator()(WorkspaceData* workspace) const;
  };
  using Workspace = std::unique_ptr<WorkspaceData, WorkspaceDeleter>;

  PinocchioRegressor() = default;
  // The regressor of the believed model `arm` (its kinematics; its pi and friction are
  // beta_model). Throws std::invalid_argument naming identifier.enabled when r + g + 2 n exceeds
  // kMaxParameters.
  explicit PinocchioRegressor(const PinocchioArm& arm);
  static PinocchioRegressor of(const UrdfLoopArm& model) { return PinocchioRegressor(model.arm()); }

  int dof() const;
  int parameters() const;  // r + g + 2 n
  int inertia_count() const;
  int gravity_count() const;
  ParameterGroup group(int i) const;
  // "m link2", ... (r), then the gravity parameters' (g), "coulomb <joint>", "viscous <joint>".
  const std::vector<std::string>& names() const;
  // beta of an arm of the same kinematics: [B_M pi; B_G pi; coulomb; viscous].
  Eigen::VectorXd beta_of(const PinocchioArm& arm) const;
  Parameters beta(const UrdfLoopArm& arm) const { return Parameters(beta_of(arm.arm())); }

  // A work space whose estimated model holds beta_hat = `initial` (beta_model: the model).
  Workspace make_workspace(const Parameters& initial) const;

  void regressor(const Joint& q, const Joint& dq, const Joint& ddq, Matrix& out,
                 Workspace& workspace) const;
  void reference_regressor(const Joint& q, const Joint& dq, const Joint& v, const Joint& a,
                           Matrix& out, Workspace& workspace) const;
  void momentum_regressor(const Joint& q, const Joint& dq, Matrix& out, Workspace& workspace) const;
  void momentum_rate_regressor(const Joint& q, const Joint& dq, Matrix& out,
                               Workspace& workspace) const;
  // Writes beta_hat = next into the estimated model and returns true, or returns false (the
  // model unchanged) when it would not be physical enough (header comment).
  bool accept(const Parameters& next, const Joint& q, Workspace& workspace) const;
  // The believed arm of the estimate (the model arm computing in the workspace's estimated
  // model; `estimate` was accepted into it).
  UrdfLoopArm arm(const Parameters& estimate, const Workspace& workspace) const;

  struct Impl;

 private:
  std::shared_ptr<const Impl> impl_;
};

template <>
struct IdentifierOf<UrdfLoopArm> {
  using type = Identifier<PinocchioRegressor>;
};

}  // namespace adparm
