// PinocchioArm::Impl and WorkspaceData (pinocchio_arm.hpp's opaque parts): Pinocchio's model, and
// the work space of one evaluation. Private to cpp/src (the translation units that include
// Pinocchio); users of the core never see them.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
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
  Eigen::LLT<Eigen::MatrixXd> mass_factor;  // of M, for M^-1 (sized once)

  explicit WorkspaceData(const pinocchio::Model& model)
      : data(model),
        configuration(pinocchio::neutral(model)),
        velocity(Eigen::VectorXd::Zero(model.nv)),
        zero_velocity(Eigen::VectorXd::Zero(model.nv)),
        unit_acceleration(Eigen::VectorXd::Zero(model.nv)),
        mass_factor(model.nv) {}
};

}  // namespace adparm
