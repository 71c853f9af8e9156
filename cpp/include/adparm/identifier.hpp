// The online identifier of the arm's base inertial parameters beta (issue 25, stage 1; guide
// "Unknown dynamics"). The arm's dynamics are linear in beta:
//   M(q) ddq + C(q, dq) dq + G(q) + F(dq) = Y(q, dq, ddq) beta                      (eq. 1)
// and so is the feedforward of eq. (5), with dq_r = dqd + alpha1 e1, ddq_r = ddqd + alpha1 de1:
//   h = M ddq_r + C(q, dq) dq_r + G + F(dq) = Y_r(q, dq, dq_r, ddq_r) beta  (Slotine & Li 1987).
// Measurable form (no ddq): with dM/dt = C + C^T (C from the Christoffel symbols),
//   M ddq + C dq = d/dt (M dq) - C^T dq, so over a window [t - T, t] (tau_d = 0)
//   int tau dt = [M dq]_{t-T}^{t} + int (G + F - C^T dq) dt = Y_w beta,                (I1)
//   Y_w = Y_M(t) - Y_M(t - T) + int Y_N dt,  Y_M beta = M dq,  Y_N beta = G + F - C^T dq,
// in q, dq and the applied tau only. Each closed window is a sample (Y_j, b_j) for a history
// stack of at most `history_size` samples (Chowdhary & Johnson 2010, concurrent learning;
// Kamalapurkar et al. 2016): while the stack is not full a sample is added; then it replaces the
// stored sample whose replacement most increases the stack's minimum singular value
//   sigma_min = sqrt(lambda_min(S)),  S = sum_j Y_j^T Y_j   (over the identified parameters),
// and is dropped when no replacement increases it. The adaptive law
//   d beta_hat / dt = Gamma [Y_r^T e2 + k sum_j Y_j^T (b_j - Y_j beta_hat)]            (I2)
// is the gradient term of Slotine & Li (only with gradient_term, off by default: see the
// setting) (from V = e2^T M e2 / 2 + beta_tilde^T Gamma^-1
// beta_tilde / 2 with M de2 = -C e2 + Y_r (beta - beta_hat) + ... in this project's sign
// convention, error_system.hpp) plus the concurrent-learning term, which is used only while
// sigma_min >= singular_value_threshold (the rank condition: the stack then determines beta).
// Gamma = gain I on the identified parameters, 0 on the others (held at the model's values).
//
// Not in the issue: the predicted error of the stack's estimate. With m = n x (samples) equations
// and P identified parameters, the least-squares estimate beta_s of the stack has, were the
// equations' misfit white noise, the covariance (r / (m - P)) S^-1, r the residual
// sum_j |b_j - Y_j beta_s|^2 (e.g. Ljung, System Identification, 1999, sec. 7.4); so
//   uncertainty = sqrt(r / (m - P) trace(S^-1)) / |beta_s|                            (I3)
// predicts its relative error (measured within a factor of 2-4 of the actual one with the
// paper's disturbance, guide "Unknown dynamics"). It is computed when a window closes, defined
// (finite) from m >= 2 P, and the stack is informative while sigma_min >= threshold and
// uncertainty <= max_uncertainty: an estimate the disturbance biases is not used (beta_hat stays
// where it is) instead of being jumped to.
//
// Discretisation (a digital adaptive law at the loop's rate): beta_hat is held over each RK4
// step (zero-order hold) and updated after it from the sample at the step's start: the gradient
// term explicitly (forward Euler), the concurrent-learning term implicitly (backward Euler),
//   (I + h Gamma k S) beta_new = beta_hat + h Gamma (Y_r^T e2 + k sum_j Y_j^T b_j),
// stable for any k (the implicit step tends to the stack's least-squares solution). An update
// that would make M_hat(q) indefinite for some q is not taken (a crude projection). beta_hat and
// the stack are the identifier's evolving state, in its Data; the Identifier holds the fixed
// parameters. Nothing allocates after make_data().
//
// Not in the paper: the probing signal slows the critic (guide "Unknown dynamics", measured on the
// UR5), so with stop_probe the identifier marks the probe stopped (for good) once the stack is
// informative and beta_hat has changed by at most `tolerance` of its norm over the last
// history_size closed windows; the loop then applies no probe, with extrapolation points only
// (without them the probe is the critic's only excitation).
//
// A Regressor (the arm's: TwoLinkRegressor below, PinocchioRegressor in urdf_regressor.hpp)
// gives, for its arm: kDof, kParameters (or Dynamic, bounded by kMaxParameters), its Workspace
// (the evolving scratch its regressors need, in the identifier's Data), beta of an arm, the
// group of each parameter (inertia, gravity, friction), the regressors Y_r, Y_M, Y_N written
// into the caller's matrix, accept(beta, q) (whether an update is taken, and for an arm that
// keeps one, its estimated model written) and the arm of an estimate. A new arm's identifier is
// its Regressor and one IdentifierOf entry; a loop whose arm has none refuses
// identifier.enabled.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "adparm/arm_model.hpp"
#include "adparm/types.hpp"

namespace adparm {

struct IdentifierSettings {
  bool enabled = false;
  double gain = 0.01;  // Gamma = gain I (I2)
  // Not in the paper: whether (I2) holds the gradient term Gamma Y_r^T e2. Off by default: e2 is
  // driven by the probe and the ADP input as much as by the model error, and before the stack is
  // informative the term alone drifts beta_hat (guide "Unknown dynamics": on a light random
  // chain it made M_hat's smallest eigenvalue 34 times the plant's, and the run diverged when
  // the stack's term corrected it); the stack's term identifies without it
  bool gradient_term = false;
  double concurrent_gain = 1e6;            // k (I2)
  long history_size = 20;                  // samples in the stack
  double window = 0.2;                     // T of (I1), s
  double singular_value_threshold = 0.01;  // sigma_min under which the stack is not used
  // Not in the issue: the stack is used only while its least-squares estimate's predicted error
  // (relative, by norm; header comment) is at most this: an unmodelled torque (a disturbance,
  // friction not identified) makes its equations disagree
  double max_uncertainty = 0.05;
  bool inertia = true;  // which parameters are identified
  bool gravity = true;
  bool friction = false;
  // Not in the paper (the probe slows the critic; guide "Unknown dynamics"): switch the probing
  // signal off for good once the stack is informative and beta_hat (its identified parameters)
  // has moved by at most `tolerance` of its norm over the last history_size windows (the loop
  // applies it only with extrapolation points, ClosedLoop::applied_probe)
  bool stop_probe = true;
  double tolerance = 0.01;
};

enum class ParameterGroup { inertia, gravity, friction };

// The two-link arm of arm_model.hpp: beta = (p1, p2, p3, g1, g2, coulomb, viscous).
struct TwoLinkRegressor {
  static constexpr int kDof = 2;
  static constexpr int kParameters = 7;
  static constexpr int kMaxParameters = 7;
  using Arm = TwoLinkArm;
  using Parameters = Eigen::Matrix<double, kParameters, 1>;
  using Matrix = Eigen::Matrix<double, kDof, kParameters>;
  struct Workspace {};  // the regressors are closed-form

  // The Regressor concept (header comment), over the static functions below.
  static TwoLinkRegressor of(const TwoLinkArm& /*model*/) { return {}; }
  static Parameters beta(const TwoLinkArm& arm) { return beta(arm.parameters()); }
  int parameters() const { return kParameters; }
  Workspace make_workspace(const Parameters& /*initial*/) const { return {}; }
  void reference_regressor(const Vec2& q, const Vec2& dq, const Vec2& v, const Vec2& a, Matrix& out,
                           Workspace& /*workspace*/) const {
    out = reference_regressor(q, dq, v, a);
  }
  void momentum_regressor(const Vec2& q, const Vec2& dq, Matrix& out, Workspace&) const {
    out = momentum_regressor(q, dq);
  }
  void momentum_rate_regressor(const Vec2& q, const Vec2& dq, Matrix& out, Workspace&) const {
    out = momentum_rate_regressor(q, dq);
  }
  // M(q) positive definite for every q2 (physical).
  bool accept(const Parameters& next, const Vec2& /*q*/, Workspace& /*workspace*/) const {
    return physical(next);
  }
  Arm arm(const Parameters& estimate, const Workspace& /*workspace*/) const {
    return Arm::unchecked(arm_parameters(estimate));
  }

  static Parameters beta(const TwoLinkArmParameters& p) {
    Parameters b;
    b << p.p1, p.p2, p.p3, p.g1, p.g2, p.coulomb, p.viscous;
    return b;
  }
  static TwoLinkArmParameters arm_parameters(const Parameters& b) {
    return {b[0], b[1], b[2], b[3], b[4], b[5], b[6]};
  }
  static TwoLinkArmParameters arm_parameters(const TwoLinkArm& arm) { return arm.parameters(); }
  // M(q) positive definite for every q2 (TwoLinkArm's check), and finite.
  static bool physical(const Parameters& b) {
    return b.allFinite() && b[1] > 0.0 && b[0] * b[1] - b[1] * b[1] - b[2] * b[2] > 0.0;
  }
  static ParameterGroup group(int i) {
    return i < 3   ? ParameterGroup::inertia
           : i < 5 ? ParameterGroup::gravity
                   : ParameterGroup::friction;
  }

  // Y(q, dq, ddq) beta = M ddq + C dq + G + F (eq. 1).
  static Matrix regressor(const Vec2& q, const Vec2& dq, const Vec2& ddq) {
    return reference_regressor(q, dq, dq, ddq);
  }

  // Y_r beta = M ddq_r + C(q, dq) dq_r + G + F(dq) (eq. 5's h, with v = dq_r, a = ddq_r).
  static Matrix reference_regressor(const Vec2& q, const Vec2& dq, const Vec2& v, const Vec2& a) {
    const double c2 = std::cos(q[1]), s2 = std::sin(q[1]);
    Matrix Y;
    Y.col(0) << a[0], 0.0;
    Y.col(1) << a[1], a[0] + a[1];
    Y.col(2) << c2 * (2.0 * a[0] + a[1]) - s2 * (dq[1] * v[0] + (dq[0] + dq[1]) * v[1]),
        c2 * a[0] + s2 * dq[0] * v[0];
    gravity_and_friction(q, dq, Y);
    return Y;
  }

  // Y_M beta = M(q) dq.
  static Matrix momentum_regressor(const Vec2& q, const Vec2& dq) {
    const double c2 = std::cos(q[1]);
    Matrix Y = Matrix::Zero();
    Y.col(0) << dq[0], 0.0;
    Y.col(1) << dq[1], dq[0] + dq[1];
    Y.col(2) << c2 * (2.0 * dq[0] + dq[1]), c2 * dq[0];
    return Y;
  }

  // Y_N beta = G + F - C^T dq (C^T dq = p3 sin q2 [0; -(dq1 + dq2) dq1]).
  static Matrix momentum_rate_regressor(const Vec2& q, const Vec2& dq) {
    Matrix Y = Matrix::Zero();
    Y(1, 2) = std::sin(q[1]) * dq[0] * (dq[0] + dq[1]);
    gravity_and_friction(q, dq, Y);
    return Y;
  }

 private:
  static void gravity_and_friction(const Vec2& q, const Vec2& dq, Matrix& Y) {
    const double c1 = std::cos(q[0]), c12 = std::cos(q[0] + q[1]);
    Y.col(3) << c1, 0.0;
    Y.col(4) << c12, c12;
    Y.col(5) = sign(dq);
    Y.col(6) = dq;
  }
};

// The identifier of an arm with no Regressor yet (URDF arms in this stage): never enabled.
struct NoIdentifier {
  static constexpr bool kAvailable = false;
  static constexpr int kParameters = 0;
  struct Data {};
  bool enabled() const { return false; }
  Eigen::Index parameters() const { return 0; }
};

template <class Regressor>
class Identifier {
 public:
  using RegressorType = Regressor;
  static constexpr bool kAvailable = true;
  static constexpr int kDof = Regressor::kDof;
  static constexpr int kParameters = Regressor::kParameters;  // or Dynamic
  static constexpr int kMaxParameters = Regressor::kMaxParameters;
  using Parameters = typename Regressor::Parameters;
  using Matrix = typename Regressor::Matrix;
  using Joint = JointVector<kDof>;
  // P x P, bounded (no heap) for a dynamic count
  using ParameterMatrix =
      Eigen::Matrix<double, kParameters, kParameters, 0, kMaxParameters, kMaxParameters>;
  // the identified parameters' square block of a ParameterMatrix (bounded: no heap)
  using Block =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxParameters, kMaxParameters>;
  using Arm = typename Regressor::Arm;
  using Workspace = typename Regressor::Workspace;

  struct Sample {  // one window of (I1): Y_j beta = b_j
    Matrix regressor;
    Joint torque;
  };

  // beta_hat, the stack and the open window: the identifier's evolving state (sized by
  // make_data).
  struct Data {
    Parameters estimate;                                          // beta_hat
    std::vector<Sample, Eigen::aligned_allocator<Sample>> stack;  // capacity history_size
    ParameterMatrix information;                                  // S = sum Y_j^T Y_j
    Parameters projection;                                        // sum Y_j^T b_j
    double min_singular_value = 0.0;  // sigma_min of the stack (identified parameters)
    double uncertainty = std::numeric_limits<double>::infinity();  // (I3)
    bool informative = false;                                      // sigma_min >= threshold now
    bool ever_informative = false;
    // the implicit step's factor of I + h Gamma k S, for the step h it was computed with (again
    // only when the stack or h changes)
    Eigen::LLT<ParameterMatrix> implicit;
    double implicit_step = 0.0;
    long samples = 0;  // windows closed
    // the open window
    long window_samples = 0;  // samples taken in it (0: none yet)
    double previous_time = 0.0;
    Matrix momentum_start;
    Matrix rate_integral;
    Joint torque_integral;
    Matrix previous_rate;
    Joint previous_torque;
    Matrix scratch;       // a regressor being computed
    Workspace workspace;  // the regressor's (e.g. Pinocchio's data and the estimated model)
    // stop_probe: beta_hat when the current run of calm windows began, their count, and whether
    // the probe is off (for good)
    Parameters calm_estimate;
    long calm_windows = 0;
    bool probe_stopped = false;
  };

  Identifier() = default;

  // `regressor`: the believed model's (its beta, beta_hat(0)); `dt`: the loop's step (the
  // window holds round(window / dt) steps).
  Identifier(const IdentifierSettings& settings, Regressor regressor, const Arm& model, double dt)
      : settings_(settings), regressor_(std::move(regressor)), initial_(regressor_.beta(model)) {
    if (!settings.enabled) return;
    check_positive(settings.gain, "identifier.gain");
    if (!(settings.concurrent_gain >= 0.0) || !std::isfinite(settings.concurrent_gain))
      throw std::invalid_argument("identifier.concurrent_gain: must be >= 0 and finite");
    if (settings.history_size < 1 || settings.history_size > 100000)
      throw std::invalid_argument("identifier.history_size: must be in [1, 100000]");
    check_positive(settings.window, "identifier.window");
    if (!(settings.singular_value_threshold >= 0.0) ||
        !std::isfinite(settings.singular_value_threshold))
      throw std::invalid_argument("identifier.singular_value_threshold: must be >= 0 and finite");
    if (!settings.inertia && !settings.gravity && !settings.friction)
      throw std::invalid_argument(
          "identifier.inertia, gravity, friction: at least one group must be identified");
    if (!(settings.max_uncertainty > 0.0))
      throw std::invalid_argument("identifier.max_uncertainty: must be > 0");
    if (!(settings.tolerance > 0.0) || !std::isfinite(settings.tolerance))
      throw std::invalid_argument("identifier.tolerance: must be > 0 and finite");
    window_steps_ = std::max(1L, std::lround(settings.window / dt));
    for (int i = 0; i < parameters(); ++i) {
      const ParameterGroup g = regressor_.group(i);
      selected_[i] = (g == ParameterGroup::inertia && settings.inertia) ||
                     (g == ParameterGroup::gravity && settings.gravity) ||
                     (g == ParameterGroup::friction && settings.friction);
      if (selected_[i]) index_[identified_++] = i;
    }
    if (identified_ == 0)
      throw std::invalid_argument(
          "identifier.inertia, gravity, friction: the arm has no parameter in the groups "
          "identified");
  }

  bool enabled() const { return settings_.enabled; }
  const IdentifierSettings& settings() const { return settings_; }
  const Regressor& regressor() const { return regressor_; }
  // P, the base parameters' count (the recorded beta_hat's width).
  Eigen::Index parameters() const { return regressor_.parameters(); }

  Data make_data() const {
    const Eigen::Index p = parameters(), n = initial_dof();
    Data data;
    data.estimate = initial_;
    data.calm_estimate = initial_;
    data.stack.reserve(static_cast<std::size_t>(std::max(1L, settings_.history_size)));
    data.information.setZero(p, p);
    data.projection.setZero(p);
    data.implicit = Eigen::LLT<ParameterMatrix>(p);
    data.momentum_start.setZero(n, p);
    data.rate_integral.setZero(n, p);
    data.torque_integral.setZero(n);
    data.previous_rate.setZero(n, p);
    data.previous_torque.setZero(n);
    data.scratch.setZero(n, p);
    data.workspace = regressor_.make_workspace(initial_);
    return data;
  }

  // The arm of the estimate (update() keeps the estimate physical as the Regressor judges).
  Arm arm(const Data& data) const { return regressor_.arm(data.estimate, data.workspace); }

  // After a step: the sample at its start t (q, dq, the applied tau), the reference dq_r, ddq_r
  // and e2 there; h the step's length. Closes a window when due, then updates beta_hat (I2).
  // Returns whether beta_hat changed.
  bool update(double t, const Joint& q, const Joint& dq, const Joint& tau, const Joint& dq_r,
              const Joint& ddq_r, const Joint& e2, double h, Data& data) const {
    sample(t, q, dq, tau, data);
    const Eigen::Index p = parameters();
    Parameters gradient = Parameters::Zero(p);
    if (settings_.gradient_term) {
      regressor_.reference_regressor(q, dq, dq_r, ddq_r, data.scratch, data.workspace);
      gradient.noalias() = data.scratch.transpose() * e2;
    }
    const double gain = settings_.gain;
    Parameters next = data.estimate;
    if (data.informative) {  // implicit step of the concurrent-learning term
      const double k = h * gain * settings_.concurrent_gain;
      if (!(data.implicit_step == h)) {
        ParameterMatrix A = ParameterMatrix::Identity(p, p);
        for (Eigen::Index i = 0; i < p; ++i)
          for (Eigen::Index j = 0; j < p; ++j)
            if (selected_[i] && selected_[j]) A(i, j) += k * data.information(i, j);
        data.implicit.compute(A);
        data.implicit_step = h;
      }
      Parameters rhs = data.estimate;
      for (Eigen::Index i = 0; i < p; ++i) {
        if (!selected_[i]) continue;
        rhs[i] += h * gain * gradient[i] + k * data.projection[i];
        for (Eigen::Index j = 0; j < p; ++j)
          if (!selected_[j]) rhs[i] -= k * data.information(i, j) * data.estimate[j];
      }
      next = data.implicit.solve(rhs);
    } else if (settings_.gradient_term) {
      for (Eigen::Index i = 0; i < p; ++i)
        if (selected_[i]) next[i] += h * gain * gradient[i];
    } else {
      return false;  // beta_hat held until the stack is informative
    }
    if (!regressor_.accept(next, q, data.workspace) || next == data.estimate) return false;
    data.estimate = next;
    return true;
  }

 private:
  // Whether `estimate` differs from `reference` by more than `tolerance` of the reference's norm
  // (over the identified parameters).
  bool moved(const Parameters& estimate, const Parameters& reference) const {
    double change = 0.0, size = 0.0;
    for (int a = 0; a < identified_; ++a) {
      const Eigen::Index i = index_[a];
      const double d = estimate[i] - reference[i];
      change += d * d;
      size += reference[i] * reference[i];
    }
    return change > settings_.tolerance * settings_.tolerance * size;
  }

  // stop_probe, at each closed window: counts the windows over which beta_hat stayed within
  // `tolerance` of its value when they began, while the stack is informative.
  void settle(Data& data) const {
    if (!settings_.stop_probe || data.probe_stopped) return;
    if (!data.informative || moved(data.estimate, data.calm_estimate)) {
      data.calm_estimate = data.estimate;
      data.calm_windows = 0;
      return;
    }
    data.probe_stopped = ++data.calm_windows >= settings_.history_size;
  }

  Eigen::Index initial_dof() const {
    if constexpr (kDof == Dynamic)
      return regressor_.dof();
    else
      return kDof;
  }

  // Trapezoidal integrals of (I1) over the open window; closes it after window_steps_ steps.
  void sample(double t, const Joint& q, const Joint& dq, const Joint& tau, Data& data) const {
    regressor_.momentum_rate_regressor(q, dq, data.scratch, data.workspace);
    const Matrix& rate = data.scratch;
    if (data.window_samples == 0) {
      open_window(t, q, dq, tau, data);
      return;
    }
    const double h = t - data.previous_time;
    data.torque_integral += (0.5 * h) * (data.previous_torque + tau);
    data.rate_integral += (0.5 * h) * (data.previous_rate + rate);
    data.previous_time = t;
    data.previous_torque = tau;
    data.previous_rate = rate;
    if (++data.window_samples <= window_steps_) return;
    Sample closed;
    regressor_.momentum_regressor(q, dq, data.scratch, data.workspace);
    closed.regressor = data.scratch - data.momentum_start + data.rate_integral;
    closed.torque = data.torque_integral;
    add(closed, data);
    settle(data);
    regressor_.momentum_rate_regressor(q, dq, data.scratch, data.workspace);
    open_window(t, q, dq, tau, data);
  }

  // Opens a window at t; data.scratch holds Y_N there.
  void open_window(double t, const Joint& q, const Joint& dq, const Joint& tau, Data& data) const {
    data.window_samples = 1;
    data.previous_time = t;
    data.previous_torque = tau;
    data.previous_rate = data.scratch;
    regressor_.momentum_regressor(q, dq, data.momentum_start, data.workspace);
    data.rate_integral.setZero();
    data.torque_integral.setZero();
  }

  // The swap-in rule (header comment), then S, sum Y^T b and sigma_min again.
  void add(const Sample& sample, Data& data) const {
    ++data.samples;
    const Eigen::Index p = parameters();
    if (static_cast<long>(data.stack.size()) < settings_.history_size) {
      data.stack.push_back(sample);  // within the capacity reserved by make_data
    } else {
      const ParameterMatrix own = sample.regressor.transpose() * sample.regressor;
      double best = data.min_singular_value;
      long best_index = -1;
      for (std::size_t j = 0; j < data.stack.size(); ++j) {
        const Matrix& old = data.stack[j].regressor;
        const double value = min_singular_value(data.information - old.transpose() * old + own);
        if (value > best) {
          best = value;
          best_index = static_cast<long>(j);
        }
      }
      if (best_index < 0) return;
      data.stack[static_cast<std::size_t>(best_index)] = sample;
    }
    data.information.setZero(p, p);
    data.projection.setZero(p);
    for (const Sample& s : data.stack) {
      data.information.noalias() += s.regressor.transpose() * s.regressor;
      data.projection.noalias() += s.regressor.transpose() * s.torque;
    }
    data.min_singular_value = min_singular_value(data.information);
    data.uncertainty = uncertainty(data);
    data.implicit_step = 0.0;  // the factor is stale
    data.informative = data.min_singular_value >= settings_.singular_value_threshold &&
                       data.min_singular_value > 0.0 &&
                       data.uncertainty <= settings_.max_uncertainty;
    data.ever_informative = data.ever_informative || data.informative;
  }

  // (I3) of the stack in `data` (information and projection current), the parameters not
  // identified held at beta_hat's values; infinity while m < 2 P or S is singular.
  double uncertainty(const Data& data) const {
    using Column = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxParameters, 1>;
    const double infinite = std::numeric_limits<double>::infinity();
    const Eigen::Index n = initial_dof();
    const long equations = static_cast<long>(data.stack.size()) * static_cast<long>(n);
    if (data.min_singular_value <= 0.0 || equations < 2L * identified_) return infinite;
    Column rhs(identified_);
    for (int a = 0; a < identified_; ++a) {
      const Eigen::Index i = index_[a];
      rhs[a] = data.projection[i];
      for (Eigen::Index j = 0; j < parameters(); ++j)
        if (!selected_[j]) rhs[a] -= data.information(i, j) * data.estimate[j];
    }
    const Eigen::LLT<Block> factor(identified_block(data.information));
    if (factor.info() != Eigen::Success) return infinite;
    const Column solution = factor.solve(rhs);
    double residual = 0.0;  // r, summed over the stack's equations
    for (const Sample& sample : data.stack) {
      for (Eigen::Index row = 0; row < n; ++row) {
        double misfit = sample.torque[row];
        for (Eigen::Index j = 0; j < parameters(); ++j)
          if (!selected_[j]) misfit -= sample.regressor(row, j) * data.estimate[j];
        for (int a = 0; a < identified_; ++a)
          misfit -= sample.regressor(row, index_[a]) * solution[a];
        residual += misfit * misfit;
      }
    }
    const Block inverse = factor.solve(Block::Identity(identified_, identified_));
    const double size = solution.norm();
    if (!(size > 0.0)) return infinite;
    return std::sqrt(residual / static_cast<double>(equations - identified_) * inverse.trace()) /
           size;
  }

  // sqrt(lambda_min) of S's block of the identified parameters (a bounded matrix: no heap).
  double min_singular_value(const ParameterMatrix& S) const {
    const Eigen::SelfAdjointEigenSolver<Block> solver(identified_block(S), Eigen::EigenvaluesOnly);
    return std::sqrt(std::max(0.0, solver.eigenvalues()[0]));
  }

  // S's block of the identified parameters (both (I3) and sigma_min are over it).
  Block identified_block(const ParameterMatrix& S) const {
    Block block(identified_, identified_);
    for (int a = 0; a < identified_; ++a)
      for (int b = 0; b < identified_; ++b) block(a, b) = S(index_[a], index_[b]);
    return block;
  }

  IdentifierSettings settings_{};
  Regressor regressor_{};
  Parameters initial_{};
  long window_steps_ = 1;
  bool selected_[kMaxParameters] = {};
  int index_[kMaxParameters] = {};  // the identified parameters' indices, identified_ of them
  int identified_ = 0;
};

// The identifier of each arm type (a new arm's identifier: its Regressor and one entry here).
template <class Arm>
struct IdentifierOf {
  using type = NoIdentifier;
};
template <>
struct IdentifierOf<TwoLinkArm> {
  using type = Identifier<TwoLinkRegressor>;
};

}  // namespace adparm
