// The one settings struct of a closed-loop run, passed whole from Python (or built in C++ by
// paper_settings()). Python's adparm.paper_config() holds the same values; a test keeps them equal.
// Every sized member follows the arm's joint count n (the defaults are for n = 2) and the basis
// size K; the loop checks each against n and K and names the member when a size is wrong. `arm`
// holds the arm of the run: the two-link arm's parameters (TwoLinkArms) or a URDF arm's settings
// (UrdfArms, urdf_loop_arm.hpp); make_loop (any_simulation.hpp) builds the loop's arms from it.
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "adparm/actor.hpp"
#include "adparm/arm_model.hpp"
#include "adparm/basis.hpp"
#include "adparm/controller.hpp"
#include "adparm/critic.hpp"
#include "adparm/expression_basis.hpp"
#include "adparm/extrapolation.hpp"
#include "adparm/identifier.hpp"
#include "adparm/input_bound.hpp"
#include "adparm/probing.hpp"
#include "adparm/rise.hpp"
#include "adparm/trajectory.hpp"

namespace adparm {

struct TaskSettings {
  Eigen::VectorXd q0 = Vec2(0.1598, 0.2257);  // n
  Eigen::VectorXd dq0 = Vec2::Zero();         // n
  TrajectorySettings qd{};                    // desired trajectory; default the set-point qd = 0
};

struct ControlSettings {
  Eigen::MatrixXd alpha1 = (Mat2() << 15.6, 10.6, 10.6, 10.4).finished();  // n x n
  RiseGains rise{};
  // While a joint's torque is clipped at its limit, RISE's integral nu stops integrating in the
  // direction that pushes the torque further into the limit (conditional integration,
  // closed_loop.hpp). false: nu integrates eq. (28) whatever the drive applies (it winds up).
  bool anti_windup = true;
};

struct SimSettings {
  double T = 150.0;
  double dt = 1e-3;
  long record_every = 10;
  double divergence_bound = 1e6;  // |q|, |dq|, |Wc|, |Wa| above this stop the run as diverged
};

// A URDF arm of the loop (urdf_loop_arm.hpp). coulomb, viscous: one value per joint, one value for
// all, or empty (0).
struct UrdfArmSettings {
  std::string urdf;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  Eigen::VectorXd coulomb;
  Eigen::VectorXd viscous;
  // Joints held at a position (rad or m), by name (PinocchioArm's locked joints).
  std::vector<std::pair<std::string, double>> locked_joints;
  // Every link's mass and inertia times this (> 0): M, C and G times it, friction unchanged (a
  // believed model whose inertia is off: model.scale; PinocchioArm::with_inertia_scaled).
  double inertia_scale = 1.0;

  friend bool operator==(const UrdfArmSettings& a, const UrdfArmSettings& b) {
    return a.urdf == b.urdf && a.gravity == b.gravity && a.coulomb.size() == b.coulomb.size() &&
           a.coulomb == b.coulomb && a.viscous.size() == b.viscous.size() &&
           a.viscous == b.viscous && a.locked_joints == b.locked_joints &&
           a.inertia_scale == b.inertia_scale;
  }
};

// The two-link arm of a run: the plant and the model the controller believes (feedforward h, f,
// g).
struct TwoLinkArms {
  TwoLinkArmParameters plant{};
  TwoLinkArmParameters model{};
};

// A URDF arm of a run: the plant and its believed model (an empty model.urdf: the plant, an exact
// model).
struct UrdfArms {
  UrdfArmSettings plant{};
  UrdfArmSettings model{};
};

using ArmSettings = std::variant<TwoLinkArms, UrdfArms>;

struct Settings {
  ArmSettings arm = TwoLinkArms{};               // the arm of the run
  Eigen::VectorXd disturbance = Vec2(0.1, 0.1);  // n amplitudes (arm_model.hpp)
  // The plant's actuator limits |tau_i| <= torque_limits_i, N m (n values; empty: no limit; an
  // infinite entry: no limit on that joint). The drive applies the commanded torque clipped to
  // them.
  Eigen::VectorXd torque_limits;
  TaskSettings task{};
  Eigen::MatrixXd Q = Mat4::Identity();  // 2n x 2n
  Eigen::MatrixXd R = Mat2::Identity();  // n x n
  Eigen::VectorXd input_bound;           // lambda, n entries > 0; empty: no bound (input_bound.hpp)
  E2Cost e2_cost = E2Cost::quadratic;    // logcosh: the e2 block of the state cost (needs a bound)
  ControlSettings control{};
  CriticSettings critic{};
  ActorSettings actor{};
  ControllerSettings controller{};
  BasisKind basis = BasisKind::augmented;  // equals the paper's basis while qd2 = 0
  ExpressionProgram basis_program{};       // basis = expression: the compiled terms (bases.py)
  bool dynamic_sizes = false;  // run the two-link arm through the dynamic-size loop (a check)
  ExtrapolationSettings extrapolation{};
  IdentifierSettings
      identifier{};                // the online identifier of beta (identifier.hpp); off: the model
  Eigen::VectorXd critic_weights;  // Wc(0), one entry per basis function
  Eigen::VectorXd actor_weights;   // Wa(0)
  ProbeSettings probe{};
  SimSettings sim{};
};

// The paper's instance (Section 4) with this project's documented choices for what it leaves open.
inline Settings paper_settings() {
  Settings s;
  s.Q.resize(4, 4);
  s.Q << 40, 2, -4, 4,  //
      2, 40, 4, -6,     //
      -4, 4, 4, 0,      //
      4, -6, 0, 4;
  s.R = 0.25 * Mat2::Identity();
  s.critic_weights = Eigen::VectorXd::Ones(8);
  s.actor_weights = Eigen::VectorXd::Ones(8);
  s.probe.until = 100.0;
  s.probe.frequencies.resize(4);
  s.probe.frequencies << 1.0, 2.7, 5.3, 9.1;
  s.probe.amplitude.resize(2, 4);
  s.probe.amplitude.row(0).setConstant(71.0);  // N m; direction M(qd) v_fast (README)
  s.probe.amplitude.row(1).setConstant(23.0);
  s.probe.phases.resize(2, 4);
  s.probe.phases.row(0) << 0.0, 1.0, 2.0, 3.0;
  s.probe.phases.row(1) = s.probe.phases.row(0);
  s.critic.epsilon_T = 1e-6;  // the paper's 1e-3 stalls; README, "Probing"
  return s;
}

}  // namespace adparm
