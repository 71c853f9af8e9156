// A URDF arm in the closed loop: PinocchioArm (pinocchio_arm.hpp) behind the Arm concept of
// arm_model.hpp, with bounded dynamic sizes (types.hpp), so that ClosedLoop<UrdfLoopArm, Basis>
// runs the paper's laws (eqs. 1-28) on any fixed-base serial arm of up to kMaxDof joints.
//   M, M^-1, C, G, F   PinocchioArm::compute, copied into the loop's bounded Terms
//   ddq                eq. (1): M^-1 (tau - C dq - G - F - tau_d)
// make_loop (any_simulation.hpp) builds the plant and the model of a run from its UrdfArmSettings.
//
// Not thread-safe, like PinocchioArm: compute() works in buffers the arm owns; every run has its
// own arms.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

#include "adparm/pinocchio_arm.hpp"
#include "adparm/settings.hpp"
#include "adparm/types.hpp"

namespace adparm {

class UrdfLoopArm {
 public:
  static constexpr int kDof = Dynamic;
  using Joint = JointVector<Dynamic>;

  // The loop's bounded terms, and Pinocchio's (dynamic) terms that compute() copies into them.
  struct Terms : DynamicTerms {
    PinocchioArm::Terms pinocchio;
  };

  // Reads the URDF of `arm`; errors name `field` (plant.urdf or model.urdf).
  UrdfLoopArm(const UrdfArmSettings& arm, const std::string& field) : arm_(read(arm, field)) {
    if (arm_.dof() > kMaxDof)
      throw std::invalid_argument(field + ": the arm has " + std::to_string(arm_.dof()) +
                                  " joints; the core supports 1 to " + std::to_string(kMaxDof));
  }

  // An arm already read (the bench builds its arms so).
  explicit UrdfLoopArm(const PinocchioArm& arm) : arm_(arm) {
    if (arm_.dof() > kMaxDof)
      throw std::invalid_argument("the arm has " + std::to_string(arm_.dof()) +
                                  " joints; the core supports 1 to " + std::to_string(kMaxDof));
  }

  int dof() const { return arm_.dof(); }
  const PinocchioArm& arm() const { return arm_; }

  void init_terms(Terms& terms) const {
    init_dynamic_terms(terms, dof());
    terms.pinocchio = arm_.make_terms();
  }

  // No heap allocation: Pinocchio fills the terms' own buffers, copied into the bounded terms.
  void compute(const Joint& q, const Joint& dq, Terms& terms) const {
    arm_.compute(q, dq, terms.pinocchio);
    terms.mass = terms.pinocchio.mass;
    terms.mass_inverse = terms.pinocchio.mass_inverse;
    terms.coriolis = terms.pinocchio.coriolis;
    terms.gravity = terms.pinocchio.gravity;
    terms.friction = terms.pinocchio.friction;
  }

  // eq. (1)
  Joint acceleration(const Terms& terms, const Joint& dq, const Joint& tau,
                     const Joint& tau_d) const {
    return dynamic_acceleration(terms, dq, tau, tau_d);
  }

 private:
  static PinocchioArm read(const UrdfArmSettings& arm, const std::string& field) {
    if (arm.urdf.empty()) throw std::invalid_argument(field + ": no URDF file given");
    try {
      return PinocchioArm(arm.urdf, arm.gravity, arm.coulomb, arm.viscous, arm.locked_joints);
    } catch (const LockedJointsError& error) {  // names field's section: plant.locked_joints
      throw std::invalid_argument(error.with_section(field.substr(0, field.find('.'))));
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(field + ": " + error.what());
    }
  }

  PinocchioArm arm_;
};

}  // namespace adparm
