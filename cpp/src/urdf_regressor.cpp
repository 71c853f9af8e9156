// adparm::PinocchioRegressor (urdf_regressor.hpp): the URDF arm's regressors for the online
// identifier, through Pinocchio's joint torque regressor and velocity derivatives.
#include "adparm/urdf_regressor.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/regressor.hpp>
#include <stdexcept>
#include <string>

#include "adparm/pinocchio_structured_basis.hpp"
#include "pinocchio_arm_impl.hpp"

namespace adparm {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr int kGravitySamples = 100;        // poses of the gravity regressor's rank
constexpr double kGravityTolerance = 1e-9;  // |R_ii| > tolerance * the largest column norm
}  // namespace

// The table: which columns, the gravity directions, beta_model, the names and groups.
struct PinocchioRegressor::Impl {
  PinocchioArm arm;  // the believed model (its parsed model shared, const)
  int n = 0, r = 0, g = 0;
  std::vector<int> inertia_columns;    // S_M (r)
  Eigen::MatrixXd combination;         // [B_M; B_G] (r + g, 10 n)
  Eigen::MatrixXd gravity_directions;  // D (10 n, g)
  Eigen::VectorXd model_pi;            // the model's pi
  Eigen::VectorXd model_beta;          // beta_model
  std::vector<std::string> names;
  explicit Impl(const PinocchioArm& model) : arm(model) {}
};

struct PinocchioRegressor::WorkspaceData {
  PinocchioArm::WorkspaceData arm;  // pinocchio::Data, configuration, velocity, zero velocity
  Eigen::MatrixXd standard;         // Y_pi (n x 10 n)
  Eigen::VectorXd sum, difference, acceleration;
  Eigen::VectorXd pi;           // pi_hat of a candidate
  Eigen::VectorXd accepted_pi;  // pi_hat of the estimate
  Eigen::VectorXd accepted_coulomb, accepted_viscous;
  Eigen::LLT<Eigen::MatrixXd> mass_factor;
  PinocchioArm::Estimate estimate;

  WorkspaceData(const pinocchio::Model& model, Eigen::Index n)
      : arm(model),
        standard(Eigen::MatrixXd::Zero(n, 10 * n)),
        sum(Eigen::VectorXd::Zero(n)),
        difference(Eigen::VectorXd::Zero(n)),
        acceleration(Eigen::VectorXd::Zero(n)),
        pi(Eigen::VectorXd::Zero(10 * n)),
        accepted_pi(Eigen::VectorXd::Zero(10 * n)),
        accepted_coulomb(Eigen::VectorXd::Zero(n)),
        accepted_viscous(Eigen::VectorXd::Zero(n)),
        mass_factor(n) {}
};

void PinocchioRegressor::WorkspaceDeleter::operator()(WorkspaceData* workspace) const {
  delete workspace;
}

PinocchioRegressor::PinocchioRegressor(const PinocchioArm& arm) {
  auto impl = std::make_shared<Impl>(arm);
  const int n = arm.dof();
  const Eigen::Index p = arm.parameter_count();
  impl->n = n;
  const BaseParameters kinetic = base_parameters(arm);
  impl->r = static_cast<int>(kinetic.columns.size());
  impl->inertia_columns = kinetic.columns;
  // the gravity regressor at seeded poses within the joint limits (as base_parameters draws)
  const pinocchio::Model& model = arm.impl().model;
  PinocchioArm::WorkspaceData w(model);
  const PinocchioArm::Limits& limits = arm.limits();
  Eigen::MatrixXd stacked(kGravitySamples * n, p);
  Eigen::VectorXd q(n), zero = Eigen::VectorXd::Zero(n);
  SplitMix64 random{1};
  for (int s = 0; s < kGravitySamples; ++s) {
    for (int j = 0; j < n; ++j) {
      double lower = std::max(limits.lower[j], -kPi), upper = std::min(limits.upper[j], kPi);
      if (!(upper > lower)) {
        lower = -kPi;
        upper = kPi;
      }
      q[j] = lower + (upper - lower) * random.uniform();
    }
    arm.impl().set_configuration(q, w.configuration);
    stacked.middleRows(static_cast<Eigen::Index>(s) * n, n) =
        pinocchio::computeJointTorqueRegressor(model, w.data, w.configuration, zero, zero);
  }
  Eigen::MatrixXd selected(stacked.rows(), impl->r);
  for (int b = 0; b < impl->r; ++b) selected.col(b) = stacked.col(kinetic.columns[b]);
  const Eigen::MatrixXd residual = stacked - selected * kinetic.combination;  // R
  const double scale = stacked.colwise().norm().maxCoeff();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(residual);
  const Eigen::Index diagonal = std::min(residual.rows(), p);
  int g = 0;
  while (g < diagonal && scale > 0.0 && std::abs(qr.matrixQR()(g, g)) > kGravityTolerance * scale)
    ++g;
  std::vector<int> gravity_columns;
  for (int i = 0; i < g; ++i) gravity_columns.push_back(qr.colsPermutation().indices()[i]);
  std::sort(gravity_columns.begin(), gravity_columns.end());
  impl->g = g;
  const int total = impl->r + g + 2 * n;
  if (total > kMaxParameters)
    throw std::invalid_argument("identifier.enabled: the arm (" + arm.source() + ") has " +
                                std::to_string(total) +
                                " base parameters with friction; the identifier takes at most " +
                                std::to_string(kMaxParameters));
  impl->combination = Eigen::MatrixXd::Zero(impl->r + g, p);
  impl->combination.topRows(impl->r) = kinetic.combination;
  impl->gravity_directions = Eigen::MatrixXd::Zero(p, g);
  if (g > 0) {
    Eigen::MatrixXd columns(residual.rows(), g);
    for (int e = 0; e < g; ++e) columns.col(e) = residual.col(gravity_columns[e]);
    Eigen::MatrixXd gravity = columns.colPivHouseholderQr().solve(residual);  // B_G
    for (int e = 0; e < g; ++e) {  // exact identity on S_G, 0 on S_M
      gravity.col(gravity_columns[e]).setZero();
      gravity(e, gravity_columns[e]) = 1.0;
    }
    for (int b = 0; b < impl->r; ++b) gravity.col(kinetic.columns[b]).setZero();
    impl->combination.bottomRows(g) = gravity;
    for (int e = 0; e < g; ++e) {  // D: e_e - E_{S_M} B_M(:, e)
      impl->gravity_directions(gravity_columns[e], e) = 1.0;
      for (int b = 0; b < impl->r; ++b)
        impl->gravity_directions(kinetic.columns[b], e) -=
            kinetic.combination(b, gravity_columns[e]);
    }
  }
  const std::vector<std::string> standard = inertial_parameter_names(arm);
  for (int b = 0; b < impl->r; ++b) impl->names.push_back(standard[kinetic.columns[b]]);
  for (int e = 0; e < g; ++e) impl->names.push_back(standard[gravity_columns[e]]);
  for (int j = 0; j < n; ++j) impl->names.push_back("coulomb " + arm.joint_names()[j]);
  for (int j = 0; j < n; ++j) impl->names.push_back("viscous " + arm.joint_names()[j]);
  impl->model_pi = arm.inertial_parameters();
  impl_ = impl;
  impl->model_beta = beta_of(arm);
}

int PinocchioRegressor::dof() const { return impl_->n; }
int PinocchioRegressor::parameters() const { return impl_->r + impl_->g + 2 * impl_->n; }
int PinocchioRegressor::inertia_count() const { return impl_->r; }
int PinocchioRegressor::gravity_count() const { return impl_->g; }
const std::vector<std::string>& PinocchioRegressor::names() const { return impl_->names; }

ParameterGroup PinocchioRegressor::group(int i) const {
  return i < impl_->r              ? ParameterGroup::inertia
         : i < impl_->r + impl_->g ? ParameterGroup::gravity
                                   : ParameterGroup::friction;
}

Eigen::VectorXd PinocchioRegressor::beta_of(const PinocchioArm& arm) const {
  const Impl& s = *impl_;
  if (arm.dof() != s.n)
    throw std::invalid_argument("the arm has " + std::to_string(arm.dof()) + " joints, the model " +
                                std::to_string(s.n));
  Eigen::VectorXd beta(parameters());
  beta.head(s.r + s.g) = s.combination * arm.inertial_parameters();
  beta.segment(s.r + s.g, s.n) = arm.coulomb();
  beta.tail(s.n) = arm.viscous();
  return beta;
}

PinocchioRegressor::Workspace PinocchioRegressor::make_workspace(const Parameters& initial) const {
  const Impl& s = *impl_;
  Workspace workspace(new WorkspaceData(s.arm.impl().model, s.n));
  workspace->estimate = s.arm.make_estimate();
  workspace->accepted_pi = s.model_pi;
  workspace->accepted_coulomb = s.arm.coulomb();
  workspace->accepted_viscous = s.arm.viscous();
  const Joint q = Joint::Zero(s.n);
  if (!accept(initial, q, workspace))
    throw std::invalid_argument(
        "identifier.enabled: the believed model (model.urdf) has M(0) not positive definite");
  return workspace;
}

namespace {

// Y_pi P (the inertia and gravity columns of beta) into out's first r + g columns.
template <class Out>
void reduce(const PinocchioRegressor::Impl& s, const Eigen::MatrixXd& standard, Out& out) {
  for (int b = 0; b < s.r; ++b) out.col(b) = standard.col(s.inertia_columns[b]);
  if (s.g > 0) out.middleCols(s.r, s.g).noalias() = standard.lazyProduct(s.gravity_directions);
}

// F(dq)'s columns (coulomb, viscous), or zeros.
template <class Out>
void friction(const PinocchioRegressor::Impl& s, const PinocchioRegressor::Joint* dq, Out& out) {
  auto block = out.rightCols(2 * s.n);
  block.setZero();
  if (dq == nullptr) return;
  for (int j = 0; j < s.n; ++j) {
    const double v = (*dq)[j];
    block(j, j) = static_cast<double>((v > 0.0) - (v < 0.0));
    block(j, s.n + j) = v;
  }
}

}  // namespace

void PinocchioRegressor::regressor(const Joint& q, const Joint& dq, const Joint& ddq, Matrix& out,
                                   Workspace& workspace) const {
  const Impl& s = *impl_;
  WorkspaceData& w = *workspace;
  const pinocchio::Model& model = s.arm.impl().model;
  s.arm.impl().set_configuration(q, w.arm.configuration);
  w.arm.velocity = dq;
  w.acceleration = ddq;
  w.standard = pinocchio::computeJointTorqueRegressor(model, w.arm.data, w.arm.configuration,
                                                      w.arm.velocity, w.acceleration);
  out.resize(s.n, parameters());
  reduce(s, w.standard, out);
  friction(s, &dq, out);
}

void PinocchioRegressor::reference_regressor(const Joint& q, const Joint& dq, const Joint& v,
                                             const Joint& a, Matrix& out,
                                             Workspace& workspace) const {
  const Impl& s = *impl_;
  WorkspaceData& w = *workspace;
  const pinocchio::Model& model = s.arm.impl().model;
  pinocchio::Data& data = w.arm.data;
  s.arm.impl().set_configuration(q, w.arm.configuration);
  w.acceleration = a;
  w.standard =
      pinocchio::computeJointTorqueRegressor(model, data, w.arm.configuration, w.arm.zero_velocity,
                                             w.acceleration);  // M a + G
  w.sum = dq + v;
  w.difference = dq - v;
  w.acceleration.setZero();
  w.standard += 0.25 * pinocchio::computeJointTorqueRegressor(model, data, w.arm.configuration,
                                                              w.sum, w.acceleration);
  w.standard -= 0.25 * pinocchio::computeJointTorqueRegressor(model, data, w.arm.configuration,
                                                              w.difference, w.acceleration);
  out.resize(s.n, parameters());
  reduce(s, w.standard, out);
  friction(s, &dq, out);
}

void PinocchioRegressor::momentum_regressor(const Joint& q, const Joint& dq, Matrix& out,
                                            Workspace& workspace) const {
  const Impl& s = *impl_;
  WorkspaceData& w = *workspace;
  s.arm.impl().set_configuration(q, w.arm.configuration);
  w.acceleration = dq;  // M dq = Y_pi(q, 0, dq) without gravity
  w.standard = pinocchio::computeJointTorqueRegressor(s.arm.impl().model_without_gravity,
                                                      w.arm.data, w.arm.configuration,
                                                      w.arm.zero_velocity, w.acceleration);
  out.resize(s.n, parameters());
  reduce(s, w.standard, out);
  friction(s, nullptr, out);
}

void PinocchioRegressor::momentum_rate_regressor(const Joint& q, const Joint& dq, Matrix& out,
                                                 Workspace& workspace) const {
  const Impl& s = *impl_;
  WorkspaceData& w = *workspace;
  const pinocchio::Model& model = s.arm.impl().model;
  pinocchio::Data& data = w.arm.data;
  s.arm.impl().set_configuration(q, w.arm.configuration);
  w.acceleration.setZero();
  w.standard = pinocchio::computeJointTorqueRegressor(model, data, w.arm.configuration,
                                                      w.arm.zero_velocity, w.acceleration);  // G
  // - dT/dq: per body, - 1/2 g_k dv/dq for its 10 parameters (world_covector: g_k dv/dq_j is
  // oMi.act(g_k) . dJ_j for each supporting joint j)
  w.arm.velocity = dq;
  pinocchio::computeJointJacobiansTimeVariation(model, data, w.arm.configuration, w.arm.velocity);
  for (int i = 0; i < s.n; ++i) {
    const pinocchio::JointIndex joint = static_cast<pinocchio::JointIndex>(i + 1);
    const auto& velocity = data.v[joint];
    for (int k = 0; k < 10; ++k) {
      const Eigen::Matrix<double, 1, 6> gradient = world_covector(
          data.oMi[joint], energy_gradient(k, velocity.linear(), velocity.angular()));
      for_each_supporting_column(model, joint, [&](Eigen::Index j) {
        w.standard(j, 10 * i + k) -= 0.5 * gradient.dot(data.dJ.col(j).transpose());
      });
    }
  }
  out.resize(s.n, parameters());
  reduce(s, w.standard, out);
  friction(s, &dq, out);
}

bool PinocchioRegressor::accept(const Parameters& next, const Joint& q,
                                Workspace& workspace) const {
  const Impl& s = *impl_;
  WorkspaceData& w = *workspace;
  if (!next.allFinite()) return false;
  // pi_hat = pi_model + P (beta_hat - beta_model)
  w.pi = s.model_pi;
  for (int b = 0; b < s.r; ++b) w.pi[s.inertia_columns[b]] += next[b] - s.model_beta[b];
  for (int e = 0; e < s.g; ++e)
    w.pi += (next[s.r + e] - s.model_beta[s.r + e]) * s.gravity_directions.col(e);
  PinocchioArm::EstimateData& estimate = *w.estimate;
  const auto coulomb = next.segment(s.r + s.g, s.n);
  const auto viscous = next.tail(s.n);
  if (!s.arm.set_estimate(w.pi, coulomb, viscous, estimate)) return false;
  // M_hat(q) positive definite at the step's q
  s.arm.impl().set_configuration(q, w.arm.configuration);
  pinocchio::crba(estimate.model, w.arm.data, w.arm.configuration);
  Eigen::MatrixXd& M = w.arm.data.M;  // CRBA's upper triangle, mirrored
  for (Eigen::Index j = 0; j < s.n; ++j)
    for (Eigen::Index i = j + 1; i < s.n; ++i) M(i, j) = M(j, i);
  w.mass_factor.compute(M);
  if (w.mass_factor.info() != Eigen::Success) {  // back to the estimate's
    s.arm.set_estimate(w.accepted_pi, w.accepted_coulomb, w.accepted_viscous, estimate);
    return false;
  }
  w.accepted_pi = w.pi;
  w.accepted_coulomb = coulomb;
  w.accepted_viscous = viscous;
  return true;
}

UrdfLoopArm PinocchioRegressor::arm(const Parameters& /*estimate*/,
                                    const Workspace& workspace) const {
  return UrdfLoopArm(UrdfLoopArm(impl_->arm), workspace->estimate.get());
}

}  // namespace adparm
