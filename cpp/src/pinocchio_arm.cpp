// adparm::PinocchioArm (pinocchio_arm.hpp). With pinocchio_structured_basis.cpp, the translation
// units that include Pinocchio (the library adparm_pinocchio); Impl is in pinocchio_arm_impl.hpp.
#include "adparm/pinocchio_arm.hpp"

#include <urdf_parser/urdf_parser.h>

#include <fstream>
#include <limits>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/regressor.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/parsers/urdf.hpp>
#include <sstream>
#include <stdexcept>

#include "adparm/types.hpp"
#include "pinocchio_arm_impl.hpp"

namespace adparm {

namespace {

[[noreturn]] void refuse(const std::string& source, const std::string& problem) {
  throw std::invalid_argument("URDF " + source + ": " + problem);
}

const char* urdf_type_name(int type) {
  switch (type) {
    case ::urdf::Joint::REVOLUTE:
      return "revolute";
    case ::urdf::Joint::CONTINUOUS:
      return "continuous";
    case ::urdf::Joint::PRISMATIC:
      return "prismatic";
    case ::urdf::Joint::FLOATING:
      return "floating";
    case ::urdf::Joint::PLANAR:
      return "planar";
    case ::urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

// One value per joint from n values, one value or none (zeros).
Eigen::VectorXd per_joint(const Eigen::VectorXd& values, int dof, const std::string& source,
                          const char* name) {
  if (values.size() == 0) return Eigen::VectorXd::Zero(dof);
  if (values.size() == 1) return Eigen::VectorXd::Constant(dof, values[0]);
  if (values.size() != dof) {
    std::ostringstream message;
    message << name << ": expected " << dof << " values (one per joint of " << source
            << ") or one, got " << values.size();
    throw std::invalid_argument(message.str());
  }
  return values;
}

}  // namespace

namespace {

std::unique_ptr<PinocchioArm::Impl> build(const std::string& xml, const std::string& source,
                                          const Eigen::Vector3d& gravity,
                                          const Eigen::VectorXd& coulomb,
                                          const Eigen::VectorXd& viscous) {
  check_finite(gravity, "gravity");
  check_finite(coulomb, "coulomb");
  check_finite(viscous, "viscous");
  const ::urdf::ModelInterfaceSharedPtr tree = ::urdf::parseURDF(xml);
  if (!tree)
    refuse(source,
           "not a valid URDF (urdfdom could not parse it: its reason is printed on "
           "stderr; a joint type other than revolute, continuous, prismatic, fixed, "
           "floating or planar is one cause)");
  // Refuse what the arm cannot be: a joint the loop cannot actuate as one coordinate.
  for (const auto& [name, joint] : tree->joints_) {
    if (joint->mimic)
      refuse(source, "joint '" + name + "' is a mimic joint (of '" + joint->mimic->joint_name +
                         "'); mimic joints are not supported: every joint must be actuated");
    switch (joint->type) {
      case ::urdf::Joint::REVOLUTE:
      case ::urdf::Joint::CONTINUOUS:
      case ::urdf::Joint::PRISMATIC:
      case ::urdf::Joint::FIXED:
        break;
      case ::urdf::Joint::FLOATING:
        refuse(source, "joint '" + name +
                           "' is floating (a floating base); only fixed-base serial arms are "
                           "supported (revolute, continuous, prismatic and fixed joints)");
      default:
        refuse(source, "joint '" + name + "' is " + urdf_type_name(joint->type) +
                           "; only revolute, continuous, prismatic and fixed joints are "
                           "supported");
    }
  }
  auto impl = std::make_unique<PinocchioArm::Impl>();
  impl->source = source;
  try {
    pinocchio::urdf::buildModel(tree, impl->model);
  } catch (const std::exception& error) {
    refuse(source, std::string("Pinocchio could not build a model: ") + error.what());
  }
  pinocchio::Model& model = impl->model;
  const int dof = model.njoints - 1;
  if (dof == 0)
    refuse(source,
           "no actuated joint (the arm needs at least one revolute, continuous or "
           "prismatic joint)");
  if (model.nv != dof)
    refuse(source, "Pinocchio's model has " + std::to_string(model.nv) + " velocities for " +
                       std::to_string(dof) + " joints; only one-coordinate joints are supported");
  model.gravity.linear(gravity);
  impl->model_without_gravity = model;
  impl->model_without_gravity.gravity.setZero();
  impl->data = std::make_unique<pinocchio::Data>(model);
  impl->gravity = gravity;

  impl->limits.lower.resize(dof);
  impl->limits.upper.resize(dof);
  impl->limits.velocity.resize(dof);
  impl->limits.effort.resize(dof);
  const double inf = std::numeric_limits<double>::infinity();
  for (int i = 0; i < dof; ++i) {
    const pinocchio::JointIndex joint = static_cast<pinocchio::JointIndex>(i + 1);
    const int nq = model.nqs[joint];
    const int iq = model.idx_qs[joint];
    const int iv = model.idx_vs[joint];
    if (iv != i)
      refuse(source, "unexpected velocity index in Pinocchio's model for joint '" +
                         model.names[joint] + "'");
    const ::urdf::JointConstSharedPtr urdf_joint = tree->getJoint(model.names[joint]);
    const bool continuous = nq == 2;
    if (nq != 1 && !continuous)
      refuse(source, "joint '" + model.names[joint] + "' has " + std::to_string(nq) +
                         " coordinates; only one-coordinate joints are supported");
    impl->q_index.push_back(iq);
    impl->continuous.push_back(continuous);
    impl->joint_names.push_back(model.names[joint]);
    impl->joint_types.push_back(urdf_joint ? urdf_type_name(urdf_joint->type)
                                           : (continuous ? "continuous" : "revolute"));
    impl->limits.lower[i] = continuous ? -inf : model.lowerPositionLimit[iq];
    impl->limits.upper[i] = continuous ? inf : model.upperPositionLimit[iq];
    impl->limits.velocity[i] = model.velocityLimit[iv];
    impl->limits.effort[i] = model.effortLimit[iv];
  }
  impl->configuration = pinocchio::neutral(model);
  impl->velocity = Eigen::VectorXd::Zero(dof);
  impl->zero_velocity = Eigen::VectorXd::Zero(dof);
  impl->unit_acceleration = Eigen::VectorXd::Zero(dof);
  impl->coulomb = per_joint(coulomb, dof, source, "coulomb");
  impl->viscous = per_joint(viscous, dof, source, "viscous");
  return impl;
}

std::string read_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) refuse(path, "cannot open the file");
  std::ostringstream text;
  text << file.rdbuf();
  if (!file && !file.eof()) refuse(path, "cannot read the file");
  return text.str();
}

}  // namespace

PinocchioArm::PinocchioArm(std::unique_ptr<Impl> impl)
    : impl_(std::move(impl)),
      dof_(impl_->model.nv),
      residual_(Eigen::VectorXd::Zero(impl_->model.nv)) {}

PinocchioArm::PinocchioArm(const std::string& urdf_path, const Eigen::Vector3d& gravity,
                           const Eigen::VectorXd& coulomb, const Eigen::VectorXd& viscous)
    : PinocchioArm(build(read_file(urdf_path), urdf_path, gravity, coulomb, viscous)) {}

PinocchioArm PinocchioArm::from_xml(const std::string& xml, const Eigen::Vector3d& gravity,
                                    const Eigen::VectorXd& coulomb, const Eigen::VectorXd& viscous,
                                    const std::string& name) {
  return PinocchioArm(build(xml, name, gravity, coulomb, viscous));
}

PinocchioArm::PinocchioArm(const PinocchioArm& other)
    : impl_(std::make_unique<Impl>(*other.impl_)), dof_(other.dof_), residual_(other.residual_) {}

PinocchioArm& PinocchioArm::operator=(const PinocchioArm& other) {
  if (this != &other) {
    impl_ = std::make_unique<Impl>(*other.impl_);
    dof_ = other.dof_;
    residual_ = other.residual_;
  }
  return *this;
}

PinocchioArm::PinocchioArm(PinocchioArm&&) noexcept = default;
PinocchioArm& PinocchioArm::operator=(PinocchioArm&&) noexcept = default;
PinocchioArm::~PinocchioArm() = default;

const std::string& PinocchioArm::source() const { return impl_->source; }
const std::vector<std::string>& PinocchioArm::joint_names() const { return impl_->joint_names; }
const std::vector<std::string>& PinocchioArm::joint_types() const { return impl_->joint_types; }
const PinocchioArm::Limits& PinocchioArm::limits() const { return impl_->limits; }
const Eigen::Vector3d& PinocchioArm::gravity_vector() const { return impl_->gravity; }
const Eigen::VectorXd& PinocchioArm::coulomb() const { return impl_->coulomb; }
const Eigen::VectorXd& PinocchioArm::viscous() const { return impl_->viscous; }

PinocchioArm::Terms PinocchioArm::make_terms() const {
  Terms terms;
  terms.mass = Eigen::MatrixXd::Zero(dof_, dof_);
  terms.mass_inverse = Eigen::MatrixXd::Zero(dof_, dof_);
  terms.coriolis = Eigen::MatrixXd::Zero(dof_, dof_);
  terms.gravity = Eigen::VectorXd::Zero(dof_);
  terms.friction = Eigen::VectorXd::Zero(dof_);
  return terms;
}

void PinocchioArm::compute(const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& dq, Terms& terms) const {
  check_size(q, dof_, 1, "q");
  check_size(dq, dof_, 1, "dq");
  const Impl& s = *impl_;
  const pinocchio::Model& model = s.model;
  pinocchio::Data& data = *s.data;
  s.set_configuration(q);
  s.velocity = dq;
  // CRBA and the articulated-body M^-1 fill the upper triangles only: mirror them.
  pinocchio::crba(model, data, s.configuration);
  terms.mass = data.M.selfadjointView<Eigen::Upper>();
  pinocchio::computeCoriolisMatrix(model, data, s.configuration, s.velocity);
  terms.coriolis = data.C;
  pinocchio::computeGeneralizedGravity(model, data, s.configuration);
  terms.gravity = data.g;
  pinocchio::computeMinverse(model, data, s.configuration);
  terms.mass_inverse = data.Minv.selfadjointView<Eigen::Upper>();
  for (Eigen::Index i = 0; i < dof_; ++i)
    terms.friction[i] =
        s.coulomb[i] * static_cast<double>((dq[i] > 0.0) - (dq[i] < 0.0)) + s.viscous[i] * dq[i];
}

Eigen::VectorXd PinocchioArm::inertial_parameters() const {
  Eigen::VectorXd pi(parameter_count());
  for (int i = 0; i < dof_; ++i)
    pi.segment<10>(10 * i) =
        impl_->model.inertias[static_cast<pinocchio::JointIndex>(i + 1)].toDynamicParameters();
  return pi;
}

void PinocchioArm::mass_regressor(const Eigen::Ref<const Eigen::VectorXd>& q,
                                  Eigen::Ref<Eigen::MatrixXd> out) const {
  check_size(q, dof_, 1, "q");
  check_size(out, dof_, static_cast<Eigen::Index>(dof_) * parameter_count(), "out");
  const Impl& s = *impl_;
  s.set_configuration(q);
  const Eigen::Index n = dof_;
  for (Eigen::Index j = 0; j < n; ++j) {
    s.unit_acceleration.setZero();
    s.unit_acceleration[j] = 1.0;
    // Y(q, 0, e_j) pi = M(q) e_j without gravity: its column k is column j of M_k.
    const auto& regressor = pinocchio::computeJointTorqueRegressor(
        s.model_without_gravity, *s.data, s.configuration, s.zero_velocity, s.unit_acceleration);
    for (Eigen::Index k = 0; k < parameter_count(); ++k) out.col(k * n + j) = regressor.col(k);
  }
}

}  // namespace adparm
