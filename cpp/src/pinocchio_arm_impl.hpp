// PinocchioArm::Impl (pinocchio_arm.hpp's opaque part): Pinocchio's model and work space. Private
// to cpp/src (the translation units that include Pinocchio); users of the core never see it.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <string>
#include <vector>

#include "adparm/pinocchio_arm.hpp"

namespace adparm {

// Everything but the work space, copied as is.
struct PinocchioArmFields {
  std::string source;
  pinocchio::Model model;
  pinocchio::Model model_without_gravity;  // for mass_regressor
  mutable Eigen::VectorXd configuration;   // Pinocchio's q (nq: cos, sin for a continuous joint)
  mutable Eigen::VectorXd velocity;
  mutable Eigen::VectorXd zero_velocity;
  mutable Eigen::VectorXd unit_acceleration;
  std::vector<int> q_index;  // Pinocchio's idx_q of joint i
  std::vector<bool> continuous;
  std::vector<std::string> joint_names, joint_types;
  PinocchioArm::Limits limits;
  Eigen::Vector3d gravity;
  Eigen::VectorXd coulomb, viscous;
  LockedJoints locked;  // given and implied (mimic joints of locked joints)
};

// The fields and Pinocchio's work space (pinocchio::Data), which a copy builds afresh from the
// model: copying a Data would read its never-set members (UBSan finds Eigen's LLT::m_info).
struct PinocchioArm::Impl : PinocchioArmFields {
  std::unique_ptr<pinocchio::Data> data;

  Impl() = default;
  Impl(const Impl& other)
      : PinocchioArmFields(other), data(std::make_unique<pinocchio::Data>(other.model)) {}

  // Pinocchio's configuration for joint angles/positions q.
  void set_configuration(const Eigen::Ref<const Eigen::VectorXd>& q) const {
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

}  // namespace adparm
