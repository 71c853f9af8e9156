// adparm::PinocchioArm (pinocchio_arm.hpp). With pinocchio_structured_basis.cpp, the translation
// units that include Pinocchio (the library adparm_pinocchio); Impl is in pinocchio_arm_impl.hpp.
#include "adparm/pinocchio_arm.hpp"

#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/model.hpp>
#include <pinocchio/algorithm/regressor.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/parsers/urdf.hpp>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

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

// A number as TOML reads it back (0.0, not 0).
std::string number_text(double value) {
  std::ostringstream text;
  text << std::setprecision(12) << value;
  std::string out = text.str();
  if (out.find_first_of(".eEn") == std::string::npos) out += ".0";
  return out;
}

bool movable(int type) {
  return type == ::urdf::Joint::REVOLUTE || type == ::urdf::Joint::CONTINUOUS ||
         type == ::urdf::Joint::PRISMATIC;
}

// The principal moments of a symmetric 3 x 3 inertia, increasing.
Eigen::Vector3d principal_moments(const Eigen::Matrix3d& inertia) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia, Eigen::EigenvaluesOnly)
      .eigenvalues();
}

// Tolerance of the inertia checks: a millionth of the largest principal moment (URDFs print
// their inertias to a few digits), and 1e-12 kg m^2 absolute.
double inertia_tolerance(const Eigen::Vector3d& moments) {
  return 1e-6 * moments.cwiseAbs().maxCoeff() + 1e-12;
}

std::string moments_text(const Eigen::Vector3d& moments) {
  std::ostringstream text;
  text << std::setprecision(6) << moments[0] << ", " << moments[1] << ", " << moments[2];
  return text.str();
}

// Whether a joint of the path from `link` to the root moves it: a revolute, continuous or
// prismatic joint not locked. A link fixed (or locked) to the root never moves, and its inertia
// never enters the dynamics (TIAGo's antennas, fixed to its base).
bool moves(const ::urdf::ModelInterface& tree, const ::urdf::Link& link,
           const LockedJoints& locked) {
  const ::urdf::Link* current = &link;
  while (current != nullptr && current->parent_joint) {
    const ::urdf::Joint& joint = *current->parent_joint;
    const bool is_locked = std::any_of(
        locked.begin(), locked.end(), [&](const auto& entry) { return entry.first == joint.name; });
    if (movable(joint.type) && !is_locked) return true;
    const auto parent = tree.links_.find(joint.parent_link_name);
    current = parent == tree.links_.end() ? nullptr : parent->second.get();
  }
  return false;
}

// Each moving link's <inertial> as the URDF declares it (`locked`: the joints locked): mass >= 0,
// an inertia (about the centre of mass) positive semi-definite and meeting the triangle
// inequality of its principal moments. A link without mass and inertia (a frame) passes, and so
// does a link that never moves (moves()).
void check_links(const ::urdf::ModelInterface& tree, const LockedJoints& locked,
                 const std::string& source) {
  for (const auto& [name, link] : tree.links_) {
    if (!link || !link->inertial || !moves(tree, *link, locked)) continue;
    const ::urdf::Inertial& inertial = *link->inertial;
    const double mass = inertial.mass;
    if (!std::isfinite(mass) || mass < 0.0)
      refuse(source, "link '" + name + "' has mass " + number_text(mass) +
                         " in its <inertial>; a mass must be >= 0 (kg)");
    Eigen::Matrix3d inertia;
    inertia << inertial.ixx, inertial.ixy, inertial.ixz, inertial.ixy, inertial.iyy, inertial.iyz,
        inertial.ixz, inertial.iyz, inertial.izz;
    if (!inertia.allFinite())
      refuse(source, "link '" + name + "' has an inertia that is not finite");
    const Eigen::Vector3d moments = principal_moments(inertia);
    const double tolerance = inertia_tolerance(moments);
    if (moments[0] < -tolerance)
      refuse(source, "link '" + name +
                         "' has an inertia that is not positive semi-definite (principal "
                         "moments " +
                         moments_text(moments) + " kg m^2)");
    if (moments[0] + moments[1] < moments[2] - tolerance)
      refuse(source, "link '" + name +
                         "' has an inertia that breaks the triangle inequality (principal "
                         "moments " +
                         moments_text(moments) +
                         " kg m^2: the two smaller must add up to at least the largest)");
  }
}

// Every body a joint moves (its link and the links fixed or locked to it, as Pinocchio merged
// them): a positive mass and a positive definite inertia about its centre of mass.
void check_bodies(const pinocchio::Model& model, const std::string& source) {
  for (pinocchio::JointIndex joint = 1; joint < static_cast<pinocchio::JointIndex>(model.njoints);
       ++joint) {
    std::string link = model.names[joint];
    for (const auto& frame : model.frames)
      if (frame.type == pinocchio::BODY && frame.parentJoint == joint) {
        link = frame.name;
        break;
      }
    const std::string body = "link '" + link + "' (the body joint '" + model.names[joint] +
                             "' moves, with the links fixed or locked to it)";
    const pinocchio::Inertia& inertia = model.inertias[joint];
    if (!(inertia.mass() > 0.0))
      refuse(source, body + " has mass " + number_text(inertia.mass()) +
                         "; a body that a joint moves needs a positive mass");
    const Eigen::Vector3d moments = principal_moments(inertia.inertia().matrix());
    if (!(moments[0] > inertia_tolerance(moments)))
      refuse(source, body + " has an inertia that is not positive definite (principal moments " +
                         moments_text(moments) + " kg m^2)");
  }
}

// A joint's position limits: +-inf for a continuous joint, and for one whose lower equals its
// upper (a URDF that leaves <limit lower upper> out reads 0 and 0, which no moving joint means).
std::pair<double, double> position_limits(const pinocchio::Model& model,
                                          pinocchio::JointIndex joint) {
  const double inf = std::numeric_limits<double>::infinity();
  const int iq = model.idx_qs[joint];
  if (model.nqs[joint] == 2 || model.lowerPositionLimit[iq] == model.upperPositionLimit[iq])
    return {-inf, inf};
  return {model.lowerPositionLimit[iq], model.upperPositionLimit[iq]};
}

// Where joint `name` stands in Pinocchio's configuration, and its limits (position_limits).
struct JointSlot {
  pinocchio::JointIndex index;
  int iq;
  bool continuous;
  double lower, upper;
};

JointSlot joint_slot(const pinocchio::Model& model, const std::string& name) {
  const pinocchio::JointIndex index = model.getJointId(name);
  const int iq = model.idx_qs[index];
  const auto [lower, upper] = position_limits(model, index);
  return {index, iq, model.nqs[index] == 2, lower, upper};
}

[[noreturn]] void refuse_locked(const std::string& problem) {
  throw LockedJointsError("locked_joints: " + problem);
}

// The locked joints checked against the URDF (names, limits) and completed with the mimic joints
// that follow a locked joint; a mimic joint left free is refused, saying what to lock.
LockedJoints resolve_locked(const ::urdf::ModelInterface& tree, const pinocchio::Model& full,
                            const LockedJoints& given, const std::string& source) {
  std::vector<std::string> names;  // the URDF's movable joints, in Pinocchio's order
  for (pinocchio::JointIndex joint = 1; joint < static_cast<pinocchio::JointIndex>(full.njoints);
       ++joint)
    names.push_back(full.names[joint]);
  auto joined = [](const std::vector<std::string>& items) {
    std::string out;
    for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
    return out;
  };
  auto check_value = [&](const std::string& name, double value, const std::string& why) {
    const JointSlot slot = joint_slot(full, name);
    if (!std::isfinite(value))
      refuse_locked("joint '" + name + "'" + why + ": the position must be finite, got " +
                    number_text(value));
    if (value < slot.lower || value > slot.upper)
      refuse_locked("joint '" + name + "'" + why + " at " + number_text(value) +
                    ", outside its limits [" + number_text(slot.lower) + ", " +
                    number_text(slot.upper) + "] in " + source);
  };
  LockedJoints locked;
  std::map<std::string, double> value_of;
  for (const auto& [name, value] : given) {
    if (!full.existJointName(name) || name == "universe") {
      const ::urdf::JointConstSharedPtr joint = tree.getJoint(name);
      const std::string what =
          joint ? "joint '" + name + "' of " + source + " is fixed (it does not move)"
                : "no joint '" + name + "' in " + source;
      refuse_locked(what + "; its joints: " + joined(names));
    }
    if (value_of.count(name)) refuse_locked("joint '" + name + "' is given twice");
    check_value(name, value, " locked");
    value_of[name] = value;
    locked.emplace_back(name, value);
  }
  // Mimic joints (movable ones): locked with their leader, or given; a free one is refused.
  bool changed = true;
  while (changed) {
    changed = false;
    for (const auto& [name, joint] : tree.joints_) {
      if (!joint->mimic || !movable(joint->type)) continue;
      const std::string& leader = joint->mimic->joint_name;
      const auto found = value_of.find(leader);
      if (found == value_of.end()) continue;
      const double follows = joint->mimic->multiplier * found->second + joint->mimic->offset;
      const auto own = value_of.find(name);
      if (own == value_of.end()) {
        check_value(name, follows,
                    " (a mimic joint of '" + leader + "', locked with it: " +
                        number_text(joint->mimic->multiplier) + " * " + number_text(found->second) +
                        " + " + number_text(joint->mimic->offset) + ")");
        value_of[name] = follows;
        locked.emplace_back(name, follows);
        changed = true;
      } else if (std::abs(own->second - follows) > 1e-9 * (1.0 + std::abs(follows))) {
        refuse_locked("joint '" + name + "' is a mimic joint of '" + leader + "' (" +
                      number_text(joint->mimic->multiplier) + " * " + leader + " + " +
                      number_text(joint->mimic->offset) + "), locked at " +
                      number_text(own->second) + " where '" + leader + "' at " +
                      number_text(found->second) + " puts it at " + number_text(follows) +
                      "; lock it there or leave it out (it follows its leader)");
      }
    }
  }
  for (const auto& [name, joint] : tree.joints_) {
    if (!joint->mimic || !movable(joint->type) || value_of.count(name)) continue;
    // A free mimic joint: suggest locking it with its leader, at 0 or the nearest limit.
    const std::string& leader = joint->mimic->joint_name;
    std::string suggestion;
    if (full.existJointName(leader)) {
      const JointSlot slot = joint_slot(full, leader);
      const double at = std::min(std::max(0.0, slot.lower), slot.upper);
      const double follows = joint->mimic->multiplier * at + joint->mimic->offset;
      suggestion = leader + " = " + number_text(at) + ", " + name + " = " + number_text(follows);
    } else {
      const JointSlot slot = joint_slot(full, name);
      suggestion = name + " = " + number_text(std::min(std::max(0.0, slot.lower), slot.upper));
    }
    refuse_locked("URDF " + source + ": joint '" + name + "' is a mimic joint (of '" + leader +
                  "'); a mimic joint cannot be actuated on its own: lock it: locked_joints = {" +
                  suggestion + "}");
  }
  return locked;
}

std::atomic<long> parse_count{0};  // urdf_parse_count()

std::unique_ptr<PinocchioArm::Impl> build(const std::string& xml, const std::string& source,
                                          const Eigen::Vector3d& gravity,
                                          const Eigen::VectorXd& coulomb,
                                          const Eigen::VectorXd& viscous,
                                          const LockedJoints& locked) {
  check_finite(gravity, "gravity");
  check_finite(coulomb, "coulomb");
  check_finite(viscous, "viscous");
  parse_count.fetch_add(1, std::memory_order_relaxed);
  const ::urdf::ModelInterfaceSharedPtr tree = ::urdf::parseURDF(xml);
  if (!tree)
    refuse(source,
           "not a valid URDF (urdfdom could not parse it: its reason is printed on "
           "stderr; a joint type other than revolute, continuous, prismatic, fixed, "
           "floating or planar is one cause)");
  // Refuse what the arm cannot be: a joint the loop cannot actuate as one coordinate.
  for (const auto& [name, joint] : tree->joints_) {
    switch (joint->type) {
      case ::urdf::Joint::REVOLUTE:
      case ::urdf::Joint::CONTINUOUS:
      case ::urdf::Joint::PRISMATIC:
        if (joint->axis.x == 0.0 && joint->axis.y == 0.0 && joint->axis.z == 0.0)
          refuse(source, "joint '" + name + "' (which moves link '" + joint->child_link_name +
                             "') has a zero axis");
        break;
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
  impl->kinematics = std::make_shared<const char>('\0');
  pinocchio::Model full;
  try {
    pinocchio::urdf::buildModel(tree, full);  // mimic = false: a mimic joint is a joint of its own
  } catch (const std::exception& error) {
    refuse(source, std::string("Pinocchio could not build a model: ") + error.what());
  }
  impl->locked = resolve_locked(*tree, full, locked, source);
  check_links(*tree, impl->locked, source);
  if (impl->locked.empty()) {
    impl->model = full;
  } else {
    Eigen::VectorXd reference = pinocchio::neutral(full);
    std::vector<pinocchio::JointIndex> indices;
    for (const auto& [name, value] : impl->locked) {
      const JointSlot slot = joint_slot(full, name);
      indices.push_back(slot.index);
      if (slot.continuous) {
        reference[slot.iq] = std::cos(value);
        reference[slot.iq + 1] = std::sin(value);
      } else {
        reference[slot.iq] = value;
      }
    }
    try {
      pinocchio::buildReducedModel(full, indices, reference, impl->model);
    } catch (const std::exception& error) {
      refuse(source, std::string("Pinocchio could not lock the joints: ") + error.what());
    }
  }
  pinocchio::Model& model = impl->model;
  const int dof = model.njoints - 1;
  if (dof == 0)
    refuse(source, impl->locked.empty()
                       ? "no actuated joint (the arm needs at least one revolute, continuous or "
                         "prismatic joint)"
                       : "no free joint: every joint is locked");
  if (model.nv != dof)
    refuse(source, "Pinocchio's model has " + std::to_string(model.nv) + " velocities for " +
                       std::to_string(dof) + " joints; only one-coordinate joints are supported");
  check_bodies(model, source);
  model.gravity.linear(gravity);
  impl->model_without_gravity = model;
  impl->model_without_gravity.gravity.setZero();
  impl->gravity = gravity;

  impl->limits.lower.resize(dof);
  impl->limits.upper.resize(dof);
  impl->limits.velocity.resize(dof);
  impl->limits.effort.resize(dof);
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
    std::tie(impl->limits.lower[i], impl->limits.upper[i]) = position_limits(model, joint);
    impl->limits.velocity[i] = model.velocityLimit[iv];
    impl->limits.effort[i] = model.effortLimit[iv];
  }
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

long urdf_parse_count() { return parse_count.load(std::memory_order_relaxed); }

PinocchioArm::PinocchioArm(std::shared_ptr<const Impl> impl)
    : impl_(std::move(impl)), dof_(impl_->model.nv) {}

PinocchioArm::PinocchioArm(const std::string& urdf_path, const Eigen::Vector3d& gravity,
                           const Eigen::VectorXd& coulomb, const Eigen::VectorXd& viscous,
                           const LockedJoints& locked)
    : PinocchioArm(build(read_file(urdf_path), urdf_path, gravity, coulomb, viscous, locked)) {}

PinocchioArm PinocchioArm::from_xml(const std::string& xml, const Eigen::Vector3d& gravity,
                                    const Eigen::VectorXd& coulomb, const Eigen::VectorXd& viscous,
                                    const std::string& name, const LockedJoints& locked) {
  return PinocchioArm(build(xml, name, gravity, coulomb, viscous, locked));
}

std::string LockedJointsError::with_section(const std::string& section) const {
  std::string message = what();
  const std::string head = "locked_joints: ";
  if (message.rfind(head, 0) == 0)
    message = section + ".locked_joints: " + message.substr(head.size());
  const std::string hint = "lock it: locked_joints = {";
  const std::size_t at = message.find(hint);
  if (at != std::string::npos)
    message.replace(at, hint.size(), "lock it: [" + section + "] locked_joints = {");
  return message;
}

PinocchioArm PinocchioArm::with_gravity_and_friction(const Eigen::Vector3d& gravity,
                                                     const Eigen::VectorXd& coulomb,
                                                     const Eigen::VectorXd& viscous) const {
  check_finite(gravity, "gravity");
  check_finite(coulomb, "coulomb");
  check_finite(viscous, "viscous");
  Eigen::VectorXd coulomb_per_joint = per_joint(coulomb, dof_, impl_->source, "coulomb");
  Eigen::VectorXd viscous_per_joint = per_joint(viscous, dof_, impl_->source, "viscous");
  if (gravity == impl_->gravity && coulomb_per_joint == impl_->coulomb &&
      viscous_per_joint == impl_->viscous)
    return *this;
  auto impl = std::make_shared<Impl>(*impl_);
  impl->model.gravity.linear(gravity);  // as build() sets it (model_without_gravity: unchanged)
  impl->gravity = gravity;
  impl->coulomb = std::move(coulomb_per_joint);
  impl->viscous = std::move(viscous_per_joint);
  return PinocchioArm(std::move(impl));
}

PinocchioArm PinocchioArm::with_inertia_scaled(double scale) const {
  if (!std::isfinite(scale) || scale <= 0.0)
    throw std::invalid_argument("inertia_scale: must be finite and > 0, got " + number_text(scale));
  if (scale == 1.0) return *this;
  auto impl = std::make_shared<Impl>(*impl_);
  for (pinocchio::Model* model : {&impl->model, &impl->model_without_gravity})
    for (pinocchio::Inertia& inertia : model->inertias)
      inertia = pinocchio::Inertia(scale * inertia.mass(), inertia.lever(),
                                   scale * inertia.inertia().matrix());
  return PinocchioArm(std::move(impl));
}

PinocchioArm::PinocchioArm(const PinocchioArm& other) = default;
PinocchioArm& PinocchioArm::operator=(const PinocchioArm& other) = default;

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
const LockedJoints& PinocchioArm::locked_joints() const { return impl_->locked; }

void PinocchioArm::WorkspaceDeleter::operator()(WorkspaceData* workspace) const {
  delete workspace;
}

PinocchioArm::Workspace PinocchioArm::workspace() const {
  return Workspace(new WorkspaceData(impl_->model));
}

PinocchioArm::Terms PinocchioArm::make_terms() const {
  Terms terms;
  terms.workspace = workspace();
  terms.mass = Eigen::MatrixXd::Zero(dof_, dof_);
  terms.mass_inverse = Eigen::MatrixXd::Zero(dof_, dof_);
  terms.coriolis = Eigen::MatrixXd::Zero(dof_, dof_);
  terms.gravity = Eigen::VectorXd::Zero(dof_);
  terms.friction = Eigen::VectorXd::Zero(dof_);
  terms.residual = Eigen::VectorXd::Zero(dof_);
  return terms;
}

void PinocchioArm::EstimateDeleter::operator()(EstimateData* estimate) const { delete estimate; }

PinocchioArm::Estimate PinocchioArm::make_estimate() const {
  Estimate estimate(new EstimateData{impl_->model, impl_->coulomb, impl_->viscous});
  return estimate;
}

bool PinocchioArm::set_estimate(const Eigen::Ref<const Eigen::VectorXd>& pi,
                                const Eigen::Ref<const Eigen::VectorXd>& coulomb,
                                const Eigen::Ref<const Eigen::VectorXd>& viscous,
                                EstimateData& estimate) const {
  check_size(pi, parameter_count(), 1, "pi");
  check_size(coulomb, dof_, 1, "coulomb");
  check_size(viscous, dof_, 1, "viscous");
  for (int i = 0; i < dof_; ++i)
    if (!(pi[10 * i] > 0.0) || !std::isfinite(pi[10 * i])) return false;
  for (int i = 0; i < dof_; ++i)
    estimate.model.inertias[static_cast<pinocchio::JointIndex>(i + 1)] =
        pinocchio::Inertia::FromDynamicParameters(pi.segment<10>(10 * i));
  estimate.coulomb = coulomb;
  estimate.viscous = viscous;
  return true;
}

namespace {

// M (its upper triangle, in data.M, where pinocchio::crba writes it) and G from what
// pinocchio::computeCoriolisMatrix leaves in data (Pinocchio 4.1, pinned in pyproject.toml): the
// joints' motion subspaces in the world frame J, the composite inertia oYcrb_i of the bodies joint
// i carries (its backward pass adds each body's into its parent's) and Ag = oYcrb_i J_i, the
// same quantities CRBA's passes form. Then, as CRBA's backward step and RNEA at dq = ddq = 0:
//   M(i, j) = J_i^T Ag_j for j in i's subtree (from i's column on: Pinocchio's depth-first order)
//   G_i = J_i^T (oYcrb_i a_g), a_g = -gravity (the lift of the bodies joint i carries)
// In place of pinocchio::crba and computeGeneralizedGravity, each a forward pass of its own over
// the same kinematics (3-link arm: 170 + 240 ns against 35 here). Checked against both, and
// against Pinocchio's Python bindings, on arms, trees and random chains (tests/test_urdf_arm.py).
void mass_and_gravity_from_coriolis_pass(const pinocchio::Model& model, pinocchio::Data& data,
                                         Eigen::VectorXd& gravity) {
  const pinocchio::Motion lift(-model.gravity.linear(), Eigen::Vector3d::Zero());
  for (pinocchio::JointIndex i = 1; i < static_cast<pinocchio::JointIndex>(model.njoints); ++i) {
    const pinocchio::Force weight = data.oYcrb[i] * lift;
    const Eigen::Index first = model.idx_vs[i];
    const Eigen::Index end = first + data.nvSubtree[i];
    for (int c = 0; c < model.nvs[i]; ++c) {
      const Eigen::Index row = first + c;
      const Eigen::Matrix<double, 6, 1> column = data.J.col(row);
      for (Eigen::Index j = first; j < end; ++j)
        data.M(row, j) = column.dot(data.Ag.col(j).head<6>());
      gravity[row] = column.head<3>().dot(weight.linear()) + column.tail<3>().dot(weight.angular());
    }
  }
}

}  // namespace

void PinocchioArm::compute(const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& dq, Terms& terms,
                           const EstimateData* estimate) const {
  check_size(q, dof_, 1, "q");
  check_size(dq, dof_, 1, "dq");
  const Impl& s = *impl_;
  const pinocchio::Model& model = estimate != nullptr ? estimate->model : s.model;
  const Eigen::VectorXd& coulomb = estimate != nullptr ? estimate->coulomb : s.coulomb;
  const Eigen::VectorXd& viscous = estimate != nullptr ? estimate->viscous : s.viscous;
  WorkspaceData& w = *terms.workspace;
  pinocchio::Data& data = w.data;
  s.set_configuration(q, w.configuration);
  w.velocity = dq;
  // One pass over the bodies: the Coriolis matrix, then M (upper triangle, mirrored) and G from
  // what that pass leaves (mass_and_gravity_from_coriolis_pass).
  pinocchio::computeCoriolisMatrix(model, data, w.configuration, w.velocity);
  w.kinematics = s.kinematics.get();  // data.oMi, data.J at q (an estimate: the same joints)
  terms.coriolis = data.C;
  mass_and_gravity_from_coriolis_pass(model, data, terms.gravity);
  terms.mass = data.M.selfadjointView<Eigen::Upper>();
  // M^-1 from the Cholesky factor of M (M = L L^T, n^3 / 3 multiply-adds for the inverse: cheaper
  // than the articulated-body algorithm's pass over the bodies), its lower triangle mirrored. An M
  // that is not positive definite in floating point falls back to pinocchio::computeMinverse.
  // The factor and the inverse as LAPACK's potf2 and potri form them, in plain loops (a call of
  // Eigen's LLT or triangular solver per evaluation cost more than the n^3 / 3 multiply-adds of
  // a 3- or 6-joint arm): L column by column, L^-1 by forward substitution, then the lower
  // triangle of M^-1 = L^-T L^-1, mirrored.
  const Eigen::Index n = dof_;
  Eigen::MatrixXd& L = w.mass_factor;  // lower triangle: L
  bool positive = true;
  for (Eigen::Index j = 0; j < n; ++j) {
    double pivot = terms.mass(j, j);
    for (Eigen::Index l = 0; l < j; ++l) pivot -= L(j, l) * L(j, l);
    if (!(pivot > 0.0)) {  // also NaN
      positive = false;
      break;
    }
    L(j, j) = std::sqrt(pivot);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      double sum = terms.mass(i, j);
      for (Eigen::Index l = 0; l < j; ++l) sum -= L(i, l) * L(j, l);
      L(i, j) = sum / L(j, j);
    }
  }
  if (positive) {
    Eigen::MatrixXd& X = w.inverse_factor;  // lower triangle: L^-1
    for (Eigen::Index j = 0; j < n; ++j) {
      X(j, j) = 1.0 / L(j, j);
      for (Eigen::Index i = j + 1; i < n; ++i) {
        double sum = L(i, j) * X(j, j);
        for (Eigen::Index l = j + 1; l < i; ++l) sum += L(i, l) * X(l, j);
        X(i, j) = -sum / L(i, i);
      }
    }
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = j; i < n; ++i) {
        double sum = X(i, i) * X(i, j);
        for (Eigen::Index l = i + 1; l < n; ++l) sum += X(l, i) * X(l, j);
        terms.mass_inverse(i, j) = sum;
        terms.mass_inverse(j, i) = sum;
      }
  } else {
    pinocchio::computeMinverse(model, data, w.configuration);
    terms.mass_inverse = data.Minv.selfadjointView<Eigen::Upper>();
  }
  for (Eigen::Index i = 0; i < dof_; ++i)
    terms.friction[i] =
        coulomb[i] * static_cast<double>((dq[i] > 0.0) - (dq[i] < 0.0)) + viscous[i] * dq[i];
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
  Workspace workspace = this->workspace();
  mass_regressor(q, out, workspace);
}

void PinocchioArm::mass_regressor(const Eigen::Ref<const Eigen::VectorXd>& q,
                                  Eigen::Ref<Eigen::MatrixXd> out, Workspace& workspace) const {
  check_size(q, dof_, 1, "q");
  check_size(out, dof_, static_cast<Eigen::Index>(dof_) * parameter_count(), "out");
  const Impl& s = *impl_;
  WorkspaceData& w = *workspace;
  w.kinematics = nullptr;  // data is overwritten below
  s.set_configuration(q, w.configuration);
  const Eigen::Index n = dof_;
  for (Eigen::Index j = 0; j < n; ++j) {
    w.unit_acceleration.setZero();
    w.unit_acceleration[j] = 1.0;
    // Y(q, 0, e_j) pi = M(q) e_j without gravity: its column k is column j of M_k.
    const auto& regressor = pinocchio::computeJointTorqueRegressor(
        s.model_without_gravity, w.data, w.configuration, w.zero_velocity, w.unit_acceleration);
    for (Eigen::Index k = 0; k < parameter_count(); ++k) out.col(k * n + j) = regressor.col(k);
  }
}

}  // namespace adparm
