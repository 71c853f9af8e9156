// adparm::PinocchioStructuredBasis and adparm::base_parameters (pinocchio_structured_basis.hpp).
#include "adparm/pinocchio_structured_basis.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <sstream>
#include <stdexcept>

#include "adparm/positive_block.hpp"
#include "pinocchio_arm_impl.hpp"

namespace adparm {

static_assert(!HasPaperE2Block<PinocchioStructuredBasis>::value,
              "the e2-block projection assumes the paper's layout; this basis has none");

namespace {

constexpr double kPi = 3.14159265358979323846;

const char* const kParameterNames[10] = {"m",    "mc_x", "mc_y", "mc_z", "I_xx",
                                         "I_xy", "I_yy", "I_xz", "I_yz", "I_zz"};

// The name of the body joint `joint` moves: its first body frame (the URDF's child link; links
// merged through fixed joints come after it), else the joint's name.
std::string body_name(const pinocchio::Model& model, pinocchio::JointIndex joint) {
  for (const auto& frame : model.frames)
    if (frame.type == pinocchio::BODY && frame.parentJoint == joint) return frame.name;
  return model.names[joint];
}

}  // namespace

BaseParameters base_parameters(const PinocchioArm& arm, int samples, std::uint64_t seed,
                               double tolerance) {
  if (samples < 1) throw std::invalid_argument("samples: must be at least 1");
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw std::invalid_argument("tolerance: must be in (0, 1)");
  const Eigen::Index n = arm.dof(), p = arm.parameter_count();
  const Eigen::Index entries = n * (n + 1) / 2;
  const PinocchioArm::Limits& limits = arm.limits();
  Eigen::VectorXd lower(n), upper(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    lower[j] = std::max(limits.lower[j], -kPi);
    upper[j] = std::min(limits.upper[j], kPi);
    if (!(upper[j] > lower[j])) {  // no usable range in the URDF
      lower[j] = -kPi;
      upper[j] = kPi;
    }
  }
  // the upper-triangle entries of every M_k at each pose, one column per parameter
  Eigen::MatrixXd stacked(samples * entries, p);
  Eigen::MatrixXd regressor(n, n * p);
  Eigen::VectorXd q(n);
  SplitMix64 random{seed};
  PinocchioArm::Workspace workspace = arm.workspace();
  for (Eigen::Index s = 0; s < samples; ++s) {
    for (Eigen::Index j = 0; j < n; ++j) q[j] = lower[j] + (upper[j] - lower[j]) * random.uniform();
    arm.mass_regressor(q, regressor, workspace);
    Eigen::Index row = s * entries;
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = i; j < n; ++j, ++row)
        for (Eigen::Index k = 0; k < p; ++k) stacked(row, k) = regressor(i, k * n + j);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(stacked);
  const Eigen::MatrixXd& packed = qr.matrixQR();
  const Eigen::Index diagonal = std::min(stacked.rows(), p);
  const double largest = diagonal > 0 ? std::abs(packed(0, 0)) : 0.0;
  Eigen::Index rank = 0;
  while (rank < diagonal && std::abs(packed(rank, rank)) > tolerance * largest) ++rank;
  if (rank == 0)
    throw std::invalid_argument("URDF " + arm.source() +
                                ": M(q) does not depend on any inertial parameter");
  const auto& pivots = qr.colsPermutation().indices();  // column pivots[i] went to place i
  // dependent columns = R11^-1 R12 in terms of the independent ones
  const Eigen::MatrixXd dependent = packed.topLeftCorner(rank, rank)
                                        .triangularView<Eigen::Upper>()
                                        .solve(packed.block(0, rank, rank, p - rank));
  std::vector<Eigen::Index> order(static_cast<std::size_t>(rank));
  std::iota(order.begin(), order.end(), Eigen::Index(0));
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index a, Eigen::Index b) { return pivots[a] < pivots[b]; });
  BaseParameters base;
  base.combination = Eigen::MatrixXd::Zero(rank, p);
  for (Eigen::Index b = 0; b < rank; ++b) {
    const Eigen::Index place = order[static_cast<std::size_t>(b)];
    base.columns.push_back(static_cast<int>(pivots[place]));
    base.combination(b, pivots[place]) = 1.0;
    for (Eigen::Index d = 0; d < p - rank; ++d)
      base.combination(b, pivots[rank + d]) = dependent(place, d);
  }
  base.values = base.combination * arm.inertial_parameters();
  return base;
}

std::vector<std::string> inertial_parameter_names(const PinocchioArm& arm) {
  const pinocchio::Model& model = arm.impl().model;
  std::vector<std::string> names;
  for (int i = 0; i < arm.dof(); ++i) {
    const std::string body = body_name(model, static_cast<pinocchio::JointIndex>(i + 1));
    for (const char* parameter : kParameterNames) names.push_back(parameter + (" " + body));
  }
  return names;
}

// The base parameters of one body: rows [begin, end) of the e2 block.
struct Group {
  pinocchio::JointIndex joint;
  Eigen::Index begin, end;
};

// The basis, copied as is.
struct PinocchioStructuredBasis::Impl {
  std::shared_ptr<const PinocchioArm::Impl> arm;  // model, set_configuration: the arm's, shared
  BaseParameters base;
  std::vector<std::string> names;
  std::vector<pinocchio::JointIndex> joint;  // per base parameter: the joint whose body it is
  std::vector<int> local;                    // per base parameter: its index 0..9 in that body
  std::vector<Group> groups;                 // the base parameters body by body
  bool one_coordinate_joints = true;         // every joint: nq = 1 or 2 (continuous), nv = 1

  explicit Impl(std::shared_ptr<const PinocchioArm::Impl> arm_impl) : arm(std::move(arm_impl)) {}

  // Whether kinematics marked with `token` (PinocchioArm::Impl::kinematics, WorkspaceData::
  // kinematics) are this basis' arm's: the same parsed URDF, one coordinate per joint.
  bool shares(const char* token) const {
    return one_coordinate_joints && token != nullptr && token == arm->kinematics.get();
  }
};

// The work space of one evaluation.
struct PinocchioStructuredBasis::WorkspaceData {
  PinocchioArm::WorkspaceData arm;  // pinocchio::Data, configuration and velocity
  // one body's rows: the gradients of 2 T_b in its local velocity, and the same in the world frame
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor, 10, 6> gradients, world_gradients;
  Eigen::VectorXd position;  // q = qd - e1

  WorkspaceData(const pinocchio::Model& model, Eigen::Index n)
      : arm(model),
        gradients(Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor, 10, 6>::Zero(10, 6)),
        world_gradients(gradients),
        position(Eigen::VectorXd::Zero(n)) {}
};

void PinocchioStructuredBasis::WorkspaceDeleter::operator()(WorkspaceData* workspace) const {
  delete workspace;
}

PinocchioStructuredBasis::Workspace PinocchioStructuredBasis::workspace() const {
  return Workspace(new WorkspaceData(impl_->arm->model, joints_));
}

PinocchioStructuredBasis::PinocchioStructuredBasis(const PinocchioArm& arm)
    : impl_(std::make_unique<Impl>(arm.shared_impl())), joints_(arm.dof()) {
  const int n = joints_;
  if (n > kMaxDof)
    throw std::invalid_argument("controller.basis: the structured basis of " + arm.source() +
                                " has " + std::to_string(n) + " joints; the core supports 1 to " +
                                std::to_string(kMaxDof) +
                                ": lock joints (plant.locked_joints) to learn on the others");
  Impl& s = *impl_;
  const pinocchio::Model& model = s.arm->model;
  for (pinocchio::JointIndex i = 1; i < static_cast<pinocchio::JointIndex>(model.njoints); ++i)
    s.one_coordinate_joints = s.one_coordinate_joints && model.nvs[i] == 1;
  s.base = adparm::base_parameters(arm);
  const int r = static_cast<int>(s.base.columns.size());
  size_ = e1_size() + r;
  if (size_ > kMaxBasisSize)
    throw std::invalid_argument("controller.basis: the structured basis of " + arm.source() +
                                " has " + std::to_string(size_) + " functions (" +
                                std::to_string(e1_size()) + " for e1 and " + std::to_string(r) +
                                " base inertial parameters); the core supports at most " +
                                std::to_string(kMaxBasisSize) +
                                ": lock joints (plant.locked_joints) to learn on the others");
  for (int i = 0; i < n; ++i)
    for (int j = i; j < n; ++j)
      s.names.push_back(i == j ? "e1_" + std::to_string(i + 1) + "^2"
                               : "e1_" + std::to_string(i + 1) + " e1_" + std::to_string(j + 1));
  const std::vector<std::string> parameters = inertial_parameter_names(arm);
  for (const int column : s.base.columns) {
    s.joint.push_back(static_cast<pinocchio::JointIndex>(column / 10 + 1));
    s.local.push_back(column % 10);
    s.names.push_back("e2'M_b e2 (" + parameters[static_cast<std::size_t>(column)] + ")");
  }
  for (std::size_t b = 0; b < s.joint.size(); ++b) {
    const Eigen::Index index = static_cast<Eigen::Index>(b);
    if (s.groups.empty() || s.groups.back().joint != s.joint[b])
      s.groups.push_back({s.joint[b], index, index});
    s.groups.back().end = index + 1;
  }
}

PinocchioStructuredBasis::PinocchioStructuredBasis(const PinocchioStructuredBasis& other)
    : impl_(std::make_unique<Impl>(*other.impl_)),
      joints_(other.joints_),
      size_(other.size_),
      check_blocks_(other.check_blocks_) {}

void PinocchioStructuredBasis::set_check_positions(
    const PinocchioArm& arm, const Eigen::Ref<const Eigen::MatrixXd>& positions) {
  const int n = joints_;
  if (arm.dof() != n || positions.rows() != n)
    throw std::invalid_argument("actor.e2_check_positions: expected " + std::to_string(n) +
                                " rows (one per joint), got " + std::to_string(positions.rows()));
  if (!positions.allFinite())
    throw std::invalid_argument("actor.e2_check_positions: every value must be finite");
  const BaseParameters& base = impl_->base;
  const Eigen::Index r = static_cast<Eigen::Index>(base.columns.size());
  Eigen::MatrixXd regressor(n, static_cast<Eigen::Index>(n) * arm.parameter_count());
  check_blocks_.assign(static_cast<std::size_t>(positions.cols()), Eigen::MatrixXd(n * n, r));
  PinocchioArm::Workspace workspace = arm.workspace();
  for (Eigen::Index s = 0; s < positions.cols(); ++s) {
    arm.mass_regressor(positions.col(s), regressor, workspace);
    for (Eigen::Index b = 0; b < r; ++b) {
      const auto M_b = regressor.middleCols(static_cast<Eigen::Index>(base.columns[b]) * n, n);
      check_blocks_[static_cast<std::size_t>(s)].col(b) =
          Eigen::Map<const Eigen::VectorXd>(Eigen::MatrixXd(M_b).data(), n * n);
    }
  }
}

PinocchioStructuredBasis& PinocchioStructuredBasis::operator=(
    const PinocchioStructuredBasis& other) {
  if (this != &other) {
    impl_ = std::make_unique<Impl>(*other.impl_);
    joints_ = other.joints_;
    size_ = other.size_;
    check_blocks_ = other.check_blocks_;
  }
  return *this;
}

PinocchioStructuredBasis::PinocchioStructuredBasis(PinocchioStructuredBasis&&) noexcept = default;
PinocchioStructuredBasis& PinocchioStructuredBasis::operator=(PinocchioStructuredBasis&&) noexcept =
    default;
PinocchioStructuredBasis::~PinocchioStructuredBasis() = default;

const BaseParameters& PinocchioStructuredBasis::base_parameters() const { return impl_->base; }
const std::vector<std::string>& PinocchioStructuredBasis::names() const { return impl_->names; }

Eigen::VectorXd PinocchioStructuredBasis::optimal_weights(
    const Eigen::Ref<const Eigen::MatrixXd>& K) const {
  Eigen::VectorXd W = optimal_weights(K, Eigen::VectorXd::Zero(10 * joints_));
  W.tail(size_ - e1_size()) = impl_->base.values;
  return W;
}

Eigen::VectorXd PinocchioStructuredBasis::optimal_weights(
    const Eigen::Ref<const Eigen::MatrixXd>& K,
    const Eigen::Ref<const Eigen::VectorXd>& inertial_parameters) const {
  check_size(K, joints_, joints_, "K");
  check_finite(K, "K");
  check_size(inertial_parameters, 10 * joints_, 1, "inertial_parameters");
  check_finite(inertial_parameters, "inertial_parameters");
  Eigen::VectorXd W(size_);
  int k = 0;
  for (int i = 0; i < joints_; ++i)
    for (int j = i; j < joints_; ++j) W[k++] = i == j ? K(i, i) : K(i, j) + K(j, i);
  W.tail(size_ - k) = impl_->base.combination * inertial_parameters;
  return W;
}

void PinocchioStructuredBasis::evaluate_at(
    const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& qd,
    const Eigen::Ref<const Eigen::VectorXd>& dqd, Eigen::Ref<Eigen::VectorXd> phi,
    Eigen::Ref<Eigen::MatrixXd> jacobian, Eigen::Ref<Eigen::VectorXd> desired_rate,
    Workspace& workspace, const PinocchioArm::Terms* arm_terms) const {
  const Eigen::Index n = joints_;
  check_size(x, 2 * n, 1, "x");
  check_size(qd, n, 1, "qd");
  check_size(dqd, n, 1, "dqd");
  check_size(phi, size_, 1, "phi");
  check_size(jacobian, size_, 2 * n, "jacobian");
  check_size(desired_rate, size_, 1, "desired_rate");
  const Impl& s = *impl_;
  const PinocchioArm::Impl& arm = *s.arm;
  WorkspaceData& w = *workspace;
  pinocchio::Data& data = w.arm.data;
  jacobian.setZero();
  desired_rate.setZero();

  // e1 block: e1_i e1_j, i <= j
  Eigen::Index k = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = i; j < n; ++j, ++k) {
      phi[k] = x[i] * x[j];
      jacobian(k, i) += x[j];
      jacobian(k, j) += x[i];
    }

  // e2 block: 2 T_b(q, e2) at q = qd - e1, from the placements oMi, the local velocities v, the
  // world Jacobian J and its rate dJ = ov x J: Pinocchio's computeJointJacobiansTimeVariation, or
  // oMi and J of the arm's terms at that q (their Coriolis pass) with v and dJ of v = e2 formed
  // from them as Pinocchio's forward step forms them (header comment)
  const PinocchioArm::WorkspaceData* shared = arm_terms != nullptr &&
                                                      arm_terms->workspace != nullptr &&
                                                      s.shares(arm_terms->workspace->kinematics)
                                                  ? arm_terms->workspace.get()
                                                  : nullptr;
  if (shared != nullptr) {
    const pinocchio::Data& kinematics = shared->data;
    for (pinocchio::JointIndex i = 1; i < static_cast<pinocchio::JointIndex>(arm.model.njoints);
         ++i) {
      const pinocchio::JointIndex parent = arm.model.parents[i];
      const Eigen::Index column = arm.model.idx_vs[i];
      const pinocchio::Motion along(kinematics.J.col(column) * x[n + column]);  // J_i e2_i
      data.ov[i] = parent > 0 ? data.ov[parent] + along : along;
      data.v[i] = kinematics.oMi[i].actInv(data.ov[i]);
      data.dJ.col(column) =
          data.ov[i].cross(pinocchio::Motion(kinematics.J.col(column))).toVector();
    }
  } else {
    w.position = qd - x.head(n);
    arm.set_configuration(w.position, w.arm.configuration);
    w.arm.velocity = x.tail(n);
    pinocchio::computeJointJacobiansTimeVariation(arm.model, data, w.arm.configuration,
                                                  w.arm.velocity);
  }
  const pinocchio::Data& kinematics = shared != nullptr ? shared->data : data;  // oMi, J
  for (const Group& group : s.groups) {
    const auto& velocity = data.v[group.joint];
    const pinocchio::SE3& placement = kinematics.oMi[group.joint];
    const Eigen::Index rows = group.end - group.begin;
    // per row, the gradient g of 2 T_b in the body's local velocity and the same in the world
    for (Eigen::Index b = 0; b < rows; ++b) {
      w.gradients.row(b) = energy_gradient(s.local[static_cast<std::size_t>(group.begin + b)],
                                           velocity.linear(), velocity.angular());
      w.world_gradients.row(b) = world_covector(placement, w.gradients.row(b));
    }
    const auto G = w.gradients.topRows(rows);
    phi.segment(k, rows).noalias() = 0.5 * G.lazyProduct(velocity.toVector());
    // G dv/dv and G dv/dq per supporting joint (world_covector); q = qd - e1: d phi / d e1 =
    // -G dv/dq, and the desired rate is G dv/dq dqd
    for_each_supporting_column(arm.model, group.joint, [&](Eigen::Index column) {
      const auto J = kinematics.J.col(column);
      const auto dJ = data.dJ.col(column);
      for (Eigen::Index b = 0; b < rows; ++b) {
        const double along_q = w.world_gradients.row(b).dot(dJ.transpose());
        jacobian(k + b, column) = -along_q;
        jacobian(k + b, n + column) = w.world_gradients.row(b).dot(J.transpose());
        desired_rate[k + b] += along_q * dqd[column];
      }
    });
    k += rows;
  }
}

bool PinocchioStructuredBasis::shares_kinematics(const PinocchioArm& arm) const {
  return impl_->shares(arm.impl().kinematics.get());
}

void PinocchioStructuredBasis::pinocchio_passes(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                const Eigen::Ref<const Eigen::VectorXd>& qd,
                                                Workspace& workspace) const {
  const Eigen::Index n = joints_;
  check_size(x, 2 * n, 1, "x");
  check_size(qd, n, 1, "qd");
  const Impl& s = *impl_;
  const PinocchioArm::Impl& arm = *s.arm;
  WorkspaceData& w = *workspace;
  w.position = qd - x.head(n);  // as evaluate_at
  arm.set_configuration(w.position, w.arm.configuration);
  w.arm.velocity = x.tail(n);
  pinocchio::computeJointJacobiansTimeVariation(arm.model, w.arm.data, w.arm.configuration,
                                                w.arm.velocity);
}

}  // namespace adparm
