// Any fixed-base serial arm from a URDF, with Pinocchio as the rigid-body engine (eq. 1):
//   M(q) ddq + C(q, dq) dq + G(q) + F(dq) + tau_d(t) = tau
//   C      Pinocchio's Coriolis matrix (pinocchio::computeCoriolisMatrix), so dM/dt - 2C is skew
//   M      CRBA's last step on that pass's composite inertias (= pinocchio::crba), symmetrised
//   G      J^T (composite inertias x -gravity) from the same pass (= computeGeneralizedGravity)
//   M^-1   from the Cholesky factor of M (plain loops, as LAPACK's potf2 and potri), symmetrised
//   F      coulomb_i sign(dq_i) + viscous_i dq_i, per joint
// The joints q are the URDF's revolute, continuous and prismatic joints in Pinocchio's model order
// (depth first from the root); fixed joints merge their links into the parent body. A continuous
// joint's q is its angle (Pinocchio stores it as cos, sin; the conversion is done here).
// Locked joints (a name and a position each) are held at that position through Pinocchio's
// reduced model (pinocchio::buildReducedModel): their links merge into the parent body as fixed
// joints' do, and q has the free joints only. A mimic joint must be locked, or follow a locked
// joint (it is then locked at multiplier * value + offset).
//
// Physical checks when the arm is read (each names the link): every link's <inertial> has a
// mass >= 0 and an inertia that is positive semi-definite and meets the triangle inequality of
// its principal moments; every body a joint moves (its link and those fixed or locked to it, as
// Pinocchio merges them) has a positive mass and a positive definite inertia; no revolute,
// continuous or prismatic joint has a zero axis.
//
// Same members as TwoLinkArm (kDof, Terms, compute, acceleration) with dynamic sizes. This header
// does not include Pinocchio (pimpl): everything that does is compiled once, in cpp/src/ (the
// static library adparm_pinocchio).
//
// The arm is immutable once read: compute() works in the caller's buffers (pinocchio::Data, in the
// Terms of make_terms(), allocated once), so that it never allocates; threads may share an arm,
// each with its own Terms. A copy shares the parsed model (const) with the original: a run's plant,
// model and structured basis read from one file hold one pinocchio::Model, each with its own Data.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "adparm/types.hpp"

namespace adparm {

// Joints held at a position (rad or m), by name.
using LockedJoints = std::vector<std::pair<std::string, double>>;

// A problem with the locked joints (an unknown name, a position outside the joint's limits, a
// mimic joint left free): the message starts with "locked_joints: " (the argument), which a
// configuration replaces by its field (plant.locked_joints; with_field below).
class LockedJointsError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
  // The message for the field of a configuration section ("plant" or "model"):
  // "plant.locked_joints: ...", and "[plant] locked_joints = {...}" where it says what to lock.
  std::string with_section(const std::string& section) const;
};

// How many URDF texts the core has parsed so far, in every thread (PinocchioArm's constructor and
// from_xml count one each; a copy or with_gravity_and_friction counts none): what tests check
// "parsed once" by.
long urdf_parse_count();

class PinocchioArm {
 public:
  static constexpr int kDof = Eigen::Dynamic;

  // Pinocchio's work space of one evaluation (pinocchio::Data, Pinocchio's q and v; opaque,
  // cpp/src/pinocchio_arm_impl.hpp), owned by the caller: the arm itself is never written.
  struct WorkspaceData;
  struct WorkspaceDeleter {
    void operator()(WorkspaceData* workspace) const;
  };
  using Workspace = std::unique_ptr<WorkspaceData, WorkspaceDeleter>;
  // A work space for this arm (allocates; once per run).
  Workspace workspace() const;

  // Model terms at one (q, dq), and compute()'s work space; made by make_terms() (move-only).
  struct Terms {
    Eigen::MatrixXd mass;          // M(q)
    Eigen::MatrixXd mass_inverse;  // M(q)^-1
    Eigen::MatrixXd coriolis;      // C(q, dq)
    Eigen::VectorXd gravity;       // G(q)
    Eigen::VectorXd friction;      // F(dq)
    Eigen::VectorXd residual;      // acceleration()'s work space
    Workspace workspace;           // compute()'s (this arm's)
  };

  // Joint position limits (+-inf for a continuous joint, and where the URDF's lower equals its
  // upper: left out, it reads 0 and 0), velocity and effort limits, as the URDF gives them (0
  // where it gives none).
  struct Limits {
    Eigen::VectorXd lower, upper, velocity, effort;
  };

  // Reads the URDF file at `urdf_path`. gravity: the acceleration of gravity in the URDF's root
  // frame (m/s^2). coulomb, viscous: one value per (free) joint, or one value for all, or empty
  // (0). locked: joints held at a position (see above). Throws std::invalid_argument, naming the
  // file and the problem, for a file that cannot be read or parsed, an arm without any free
  // revolute, continuous or prismatic joint, a joint that is not one of those (floating,
  // planar, ...) or a failed physical check (naming the link); LockedJointsError for a locked
  // joint that the URDF does not have (the message lists its joints), a position outside the
  // joint's limits, or a mimic joint left free (the message says what to lock).
  explicit PinocchioArm(const std::string& urdf_path,
                        const Eigen::Vector3d& gravity = Eigen::Vector3d(0.0, 0.0, -9.81),
                        const Eigen::VectorXd& coulomb = Eigen::VectorXd(),
                        const Eigen::VectorXd& viscous = Eigen::VectorXd(),
                        const LockedJoints& locked = LockedJoints());
  // The same from the URDF's XML text; `name` stands for the file in error messages.
  static PinocchioArm from_xml(const std::string& xml,
                               const Eigen::Vector3d& gravity = Eigen::Vector3d(0.0, 0.0, -9.81),
                               const Eigen::VectorXd& coulomb = Eigen::VectorXd(),
                               const Eigen::VectorXd& viscous = Eigen::VectorXd(),
                               const std::string& name = "<URDF string>",
                               const LockedJoints& locked = LockedJoints());

  // The arm the constructor would read with this gravity and friction (the same numbers), without
  // reading the URDF again: shared if they are this arm's, else a copy of the parsed model.
  PinocchioArm with_gravity_and_friction(const Eigen::Vector3d& gravity,
                                         const Eigen::VectorXd& coulomb,
                                         const Eigen::VectorXd& viscous) const;
  // This arm with every link's mass and inertia (its spatial inertia) times `scale` > 0: M, C and
  // G times scale, friction and kinematics unchanged (a model whose inertia is off). scale = 1:
  // this arm, shared.
  PinocchioArm with_inertia_scaled(double scale) const;

  // Copies share the parsed model.
  PinocchioArm(const PinocchioArm& other);
  PinocchioArm& operator=(const PinocchioArm& other);
  PinocchioArm(PinocchioArm&&) noexcept;
  PinocchioArm& operator=(PinocchioArm&&) noexcept;
  ~PinocchioArm();

  int dof() const { return dof_; }
  // Where the arm came from: the file path, or the name given to from_xml.
  const std::string& source() const;
  const std::vector<std::string>& joint_names() const;
  // URDF type of each joint: "revolute", "continuous" or "prismatic".
  const std::vector<std::string>& joint_types() const;
  const Limits& limits() const;
  const Eigen::Vector3d& gravity_vector() const;
  const Eigen::VectorXd& coulomb() const;
  const Eigen::VectorXd& viscous() const;
  // Every locked joint and its position: those given, then the mimic joints that follow one of
  // them (multiplier * position + offset), in that order.
  const LockedJoints& locked_joints() const;

  Terms make_terms() const;

  // Other inertial parameters and friction on this arm's kinematics (the online identifier's
  // estimate, urdf_regressor.hpp): a copy of the parsed model whose inertias set_estimate writes,
  // and per-joint friction. Opaque (cpp/src/pinocchio_arm_impl.hpp); make_estimate allocates
  // once, set_estimate and compute never.
  struct EstimateData;
  struct EstimateDeleter {
    void operator()(EstimateData* estimate) const;
  };
  using Estimate = std::unique_ptr<EstimateData, EstimateDeleter>;
  // An estimate equal to this arm (its inertias and friction).
  Estimate make_estimate() const;
  // Writes the inertial parameters pi (10 n, inertial_parameters()' order) and the friction (n
  // each) into `estimate`; returns false, leaving it unchanged, when a body's mass is not > 0
  // (Pinocchio's inertia holds the lever c = (m c) / m). Any other pi is taken: the algorithms
  // are linear in pi, physical or not.
  bool set_estimate(const Eigen::Ref<const Eigen::VectorXd>& pi,
                    const Eigen::Ref<const Eigen::VectorXd>& coulomb,
                    const Eigen::Ref<const Eigen::VectorXd>& viscous, EstimateData& estimate) const;

  // All terms at (q, dq), without heap allocation (terms from this arm's make_terms(), whose
  // work space it uses); with an estimate (make_estimate of this arm), the estimate's terms.
  // Throws std::invalid_argument for a q or dq that is not of size dof().
  void compute(const Eigen::Ref<const Eigen::VectorXd>& q,
               const Eigen::Ref<const Eigen::VectorXd>& dq, Terms& terms,
               const EstimateData* estimate = nullptr) const;

  // Joint acceleration of eq. (1) for a given torque and disturbance, written into ddq (size
  // dof()); no heap allocation (terms.residual is its work space).
  void acceleration(Terms& terms, const Eigen::Ref<const Eigen::VectorXd>& dq,
                    const Eigen::Ref<const Eigen::VectorXd>& tau,
                    const Eigen::Ref<const Eigen::VectorXd>& tau_d,
                    Eigen::Ref<Eigen::VectorXd> ddq) const {
    terms.residual = tau - terms.gravity - terms.friction - tau_d;
    terms.residual -= small_product(terms.coriolis, dq);
    ddq = small_product(terms.mass_inverse, terms.residual);
  }

  // The inertial parameters pi of the URDF (10 per joint, Pinocchio's order for the body that
  // joint moves: m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz, with the first moment
  // m c and the inertia I about the joint frame's origin, in that frame).
  int parameter_count() const { return 10 * dof_; }
  Eigen::VectorXd inertial_parameters() const;

  // M_k(q) = dM/dpi_k for every inertial parameter k (allocates a work space), so that M(q) = sum_k
  // pi_k M_k(q): out (dof, dof * parameter_count()) holds M_k in columns [k dof, (k + 1) dof).
  // Column j of M_k is column k of Pinocchio's joint torque regressor Y(q, dq = 0, ddq = e_j)
  // without gravity.
  void mass_regressor(const Eigen::Ref<const Eigen::VectorXd>& q,
                      Eigen::Ref<Eigen::MatrixXd> out) const;
  // The same in a work space of this arm (no work space to allocate: for many positions).
  void mass_regressor(const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Ref<Eigen::MatrixXd> out,
                      Workspace& workspace) const;

  struct Impl;  // opaque: Pinocchio's model (cpp/src/pinocchio_arm_impl.hpp)
  // For the other Pinocchio translation units of the core (pinocchio_structured_basis.cpp, which
  // shares the model).
  const Impl& impl() const { return *impl_; }
  const std::shared_ptr<const Impl>& shared_impl() const { return impl_; }

 private:
  explicit PinocchioArm(std::shared_ptr<const Impl> impl);

  std::shared_ptr<const Impl> impl_;  // never written once built: shared by copies
  int dof_ = 0;
};

}  // namespace adparm
