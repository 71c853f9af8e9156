// PinocchioArm::Impl and WorkspaceData (pinocchio_arm.hpp's opaque parts): Pinocchio's model, and
// the work space of one evaluation. Private to cpp/src (the translation units that include
// Pinocchio); users of the core never see them.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <memory>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <string>
#include <vector>

#include "adparm/pinocchio_arm.hpp"

namespace adparm {

// The arm, copied as is.
struct PinocchioArm::Impl {
  std::string source;
  pinocchio::Model model;
  pinocchio::Model model_without_gravity;  // for mass_regressor
  std::vector<int> q_index;                // Pinocchio's idx_q of joint i
  std::vector<bool> continuous;
  std::vector<std::string> joint_names, joint_types;
  PinocchioArm::Limits limits;
  Eigen::Vector3d gravity;
  Eigen::VectorXd coulomb, viscous;
  LockedJoints locked;  // given and implied (mimic joints of locked joints)
  // One token per parsed URDF, shared by the arms derived from it (with_gravity_and_friction,
  // with_inertia_scaled, estimates: other gravity, friction or inertias, the same joints and
  // placements), so that equal tokens mean equal kinematics (PinocchioStructuredBasis reuses
  // the arm's oMi and J).
  std::shared_ptr<const char> kinematics;

  // Pinocchio's configuration for joint angles/positions q.
  void set_configuration(const Eigen::Ref<const Eigen::VectorXd>& q,
                         Eigen::VectorXd& configuration) const {
    for (std::size_t i = 0; i < q_index.size(); ++i) {
      const Eigen::Index j = static_cast<Eigen::Index>(i);
      if (continuous[i]) {
        configuration[q_index[i]] = std::cos(q[j]);
        configuration[q_index[i] + 1] = std::sin(q[j]);
      } else {
        configuration[q_index[i]] = q[j];
      }
    }
  }
};

// Pinocchio's work space of one evaluation, built from the model (a copy of a pinocchio::Data
// would read its never-set members: UBSan finds Eigen's LLT::m_info).
struct PinocchioArm::WorkspaceData {
  pinocchio::Data data;
  Eigen::VectorXd configuration;  // Pinocchio's q (nq: cos, sin for a continuous joint)
  Eigen::VectorXd velocity;
  Eigen::VectorXd zero_velocity;
  Eigen::VectorXd unit_acceleration;
  Eigen::MatrixXd mass_factor;     // the Cholesky factor L of M, for M^-1 (lower triangle)
  Eigen::MatrixXd inverse_factor;  // L^-1 (lower triangle)
  // Set by PinocchioArm::compute to its arm's kinematics token: data.oMi and data.J hold the
  // joints' placements and world motion subspaces at compute()'s q; nullptr otherwise (cleared
  // by mass_regressor, the one other call that runs Pinocchio in an arm's work space; the
  // regressors of urdf_regressor.cpp run in work spaces of their own, never marked).
  const char* kinematics = nullptr;

  explicit WorkspaceData(const pinocchio::Model& model)
      : data(model),
        configuration(pinocchio::neutral(model)),
        velocity(Eigen::VectorXd::Zero(model.nv)),
        zero_velocity(Eigen::VectorXd::Zero(model.nv)),
        unit_acceleration(Eigen::VectorXd::Zero(model.nv)),
        mass_factor(Eigen::MatrixXd::Zero(model.nv, model.nv)),
        inverse_factor(Eigen::MatrixXd::Zero(model.nv, model.nv)) {}
};

// SplitMix64: a fixed generator, so that the sampled poses (and the base parameters) are the same
// with every standard library.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

// An estimate of the arm (PinocchioArm::Estimate): the model with other inertias, and friction.
struct PinocchioArm::EstimateData {
  pinocchio::Model model;
  Eigen::VectorXd coulomb, viscous;
};

// The gradient g of 2 T_k with respect to a body's local spatial velocity (v, w), for its
// parameter k (0..9, Pinocchio's order: m, m c, I about the joint frame's origin); since T_k is a
// quadratic form, 2 T_k = g . (v, w) / 2 (Pinocchio's computeKineticEnergyRegressor).
//   m:     T = 1/2 |v|^2
//   mc_a:  T = (v x w)_a, with d/dv = w x e_a and d/dw = e_a x v
//   I_ab:  T = 1/2 w_a^2 (a = b) or w_a w_b (a != b)
inline Eigen::Matrix<double, 1, 6> energy_gradient(int k, const Eigen::Vector3d& v,
                                                   const Eigen::Vector3d& w) {
  Eigen::Matrix<double, 1, 6> g = Eigen::Matrix<double, 1, 6>::Zero();
  switch (k) {
    case 0:  // 2 T = |v|^2
      g.head<3>() = 2.0 * v.transpose();
      break;
    case 1:
    case 2:
    case 3: {  // 2 T = 2 (v x w)_a
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(k - 1);
      g.head<3>() = 2.0 * w.cross(e).transpose();
      g.tail<3>() = 2.0 * e.cross(v).transpose();
      break;
    }
    case 4:  // 2 T = w_x^2
      g[3] = 2.0 * w[0];
      break;
    case 5:  // 2 T = 2 w_x w_y
      g[3] = 2.0 * w[1];
      g[4] = 2.0 * w[0];
      break;
    case 6:  // 2 T = w_y^2
      g[4] = 2.0 * w[1];
      break;
    case 7:  // 2 T = 2 w_x w_z
      g[3] = 2.0 * w[2];
      g[5] = 2.0 * w[0];
      break;
    case 8:  // 2 T = 2 w_y w_z
      g[4] = 2.0 * w[2];
      g[5] = 2.0 * w[1];
      break;
    default:  // 2 T = w_z^2
      g[5] = 2.0 * w[2];
      break;
  }
  return g;
}

// A covector g of a body's local spatial velocity ([linear, angular], a force in the body frame)
// in the world frame, oMi.act(g): g . oMi^-1 m = oMi.act(g) . m for any motion m in the world
// frame. Its use: the LOCAL velocity derivatives of a body are oMi^-1 J_j (d/dv_j) and
// oMi^-1 (ov_parent(j) x J_j) = oMi^-1 dJ_j (d/dq_j; a one-coordinate joint's J_j x J_j = 0) for
// each supporting joint j (Pinocchio's getJointVelocityDerivatives), so g times them is
// world_covector(oMi, g) . J_j and . dJ_j with J, dJ of computeJointJacobiansTimeVariation: one
// transform per covector instead of two per supporting joint.
inline Eigen::Matrix<double, 1, 6> world_covector(const pinocchio::SE3& placement,
                                                  const Eigen::Matrix<double, 1, 6>& g) {
  const Eigen::Vector3d linear = placement.rotation() * g.head<3>().transpose();
  Eigen::Matrix<double, 1, 6> world;
  world.head<3>() = linear.transpose();
  world.tail<3>() =
      (placement.rotation() * g.tail<3>().transpose() + placement.translation().cross(linear))
          .transpose();
  return world;
}

// f(column) for the velocity column of each joint that carries body `joint` (Pinocchio's
// model.supports, the universe left out), in the order from the root: the columns a body's
// velocity derivatives can be nonzero in (world_covector), also in a branched tree.
template <class F>
void for_each_supporting_column(const pinocchio::Model& model, pinocchio::JointIndex joint, F&& f) {
  for (const pinocchio::JointIndex support : model.supports[joint])
    if (support != 0) f(static_cast<Eigen::Index>(model.idx_vs[support]));
}

}  // namespace adparm
