// The closed loop of Figure 1 as one ODE system for RK4 (fixed parameters here, evolving state
// apart):
//   state = [q (2), dq (2), Wc (N), Wa (N), Gamma (N x N, column-major), nu (2), J (1)]
// At each evaluation, with the desired state (qd, dqd, ddqd) of trajectory.hpp and
// x = [e1; e2] (error_system.hpp):
//   u_hat  = -1/2 R^-1 g^T (dphi/dx)^T Wa                         (eq. 20)
//   eps    = HJB error, omega its regressor                       (eq. 21)
//   dWc, dGamma                                                   (eqs. 23-24)
//   dWa                                                           (eq. 26)
//   (with extrapolation points, each law also averages its term over them: extrapolation.hpp)
//   mu     = RISE feedback, dnu                                   (eqs. 27-28)
//   u      = the controller's input (controller.hpp; adp: u_hat + probe(t))
//   tau    = h_hat + mu - u     (g = [0; M^-1] convention; h_hat of the believed model, eq. 5)
//   ddq    from the plant (eq. 1) with tau and the disturbance tau_d(t)
//   dJ     = x^T Q x + u^T R u  (the accumulated cost of eq. 10, integrated with the state).
// The basis and the arm model are template parameters: a new one is a new type, not a new loop.
#pragma once

#include "adparm/basis.hpp"
#include "adparm/controller.hpp"
#include "adparm/critic.hpp"
#include "adparm/extrapolation.hpp"
#include "adparm/hjb.hpp"
#include "adparm/positive_block.hpp"
#include "adparm/rise.hpp"
#include "adparm/settings.hpp"
#include "adparm/trajectory.hpp"

namespace adparm {

template <class Arm, class Basis>
class ClosedLoop {
 public:
  static constexpr int kDof = Arm::kDof;
  static constexpr int kBasisSize = Basis::kSize;
  static_assert(Basis::kStateDim == 2 * kDof, "the basis must act on x = [e1; e2]");
  // Offsets into the state vector.
  static constexpr int kQ = 0;
  static constexpr int kDq = kQ + kDof;
  static constexpr int kCriticWeights = kDq + kDof;
  static constexpr int kActorWeights = kCriticWeights + kBasisSize;
  static constexpr int kGamma = kActorWeights + kBasisSize;
  static constexpr int kNu = kGamma + kBasisSize * kBasisSize;
  static constexpr int kCost = kNu + kDof;
  static constexpr int kStateSize = kCost + 1;

  using State = Eigen::Matrix<double, kStateSize, 1>;
  using Weights = typename Basis::Vector;
  using Covariance = typename Critic<Basis>::Covariance;
  using CovarianceMap = Eigen::Map<Covariance>;
  using ConstCovarianceMap = Eigen::Map<const Covariance>;

  struct TimeSignals {
    Vec2 disturbance;      // tau_d(t)
    Vec2 probe;            // probing signal (zero unless the controller learns)
    DesiredState desired;  // qd(t), dqd(t), ddqd(t)
  };

  struct Outputs {
    TrackingErrors errors;
    Vec2 qd;                 // desired position
    Vec2 tau;                // applied joint torque
    Vec2 u;                  // applied input of the controller
    Vec2 u_hat;              // actor's input, eq. (20)
    Vec2 mu;                 // RISE feedback, eq. (27)
    Vec2 probe;              // probing signal
    double hjb_error = 0.0;  // eq. (21)
  };

  explicit ClosedLoop(const Settings& settings)
      : plant_(settings.plant, "plant"),
        model_is_plant_(settings.plant == settings.model),
        error_system_(Arm(settings.model, "model"), settings.control.alpha1),
        cost_(settings.Q, settings.R),
        critic_(settings.critic),
        actor_(settings.actor),
        controller_(settings.controller),
        trajectory_(settings.task.qd),
        extrapolation_(settings.extrapolation, trajectory_.is_constant()),
        disturbance_{settings.disturbance},
        probe_(settings.probe) {
    check_finite(settings.disturbance, "plant.disturbance");
    check_finite(settings.control.alpha1, "control.alpha1");
    check_hurwitz(settings.control.alpha1);
    check_finite(settings.task.q0, "task.q0");
    check_finite(settings.task.dq0, "task.dq0");
    check_size(settings.critic_weights, kBasisSize, 1, "init.critic_weights");
    check_size(settings.actor_weights, kBasisSize, 1, "init.actor_weights");
    check_finite(settings.critic_weights, "init.critic_weights");
    check_finite(settings.actor_weights, "init.actor_weights");
    const TrackingErrors initial = tracking_errors(settings.task.q0, settings.task.dq0,
                                                   trajectory_(0.0), settings.control.alpha1);
    rise_ = Rise(settings.control.rise, initial.e2);
    initial_state_.setZero();
    initial_state_.template segment<kDof>(kQ) = settings.task.q0;
    initial_state_.template segment<kDof>(kDq) = settings.task.dq0;
    initial_state_.template segment<kBasisSize>(kCriticWeights) = settings.critic_weights;
    initial_state_.template segment<kBasisSize>(kActorWeights) = settings.actor_weights;
    covariance(initial_state_) = critic_.initial_covariance();
  }

  const State& initial_state() const { return initial_state_; }
  const ErrorSystem<Arm>& error_system() const { return error_system_; }
  const QuadraticCost& cost() const { return cost_; }
  const Critic<Basis>& critic() const { return critic_; }
  const Trajectory& trajectory() const { return trajectory_; }
  const Extrapolation<Arm, Basis>& extrapolation() const { return extrapolation_; }

  // de1 = -alpha1 e1 + e2 is stable only if every eigenvalue of alpha1 has a positive real part:
  // trace > 0 and det > 0 (2 x 2), judged on alpha1 / max|entry| (no overflow), as in Python.
  static void check_hurwitz(const Mat2& alpha1) {
    const double scale = alpha1.cwiseAbs().maxCoeff();
    const Mat2 a = alpha1 / scale;
    if (!(scale > 0.0) || !(a(0, 0) + a(1, 1) > 0.0 && a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0) > 0.0))
      throw std::invalid_argument(
          "control.alpha1: every eigenvalue must have a positive real part (-alpha1 Hurwitz)");
  }

  static CovarianceMap covariance(State& x) { return CovarianceMap(x.data() + kGamma); }
  static ConstCovarianceMap covariance(const State& x) {
    return ConstCovarianceMap(x.data() + kGamma);
  }

  void time_signals(double t, TimeSignals& signals) const {
    signals.disturbance = disturbance_(t);
    signals.probe = controller_.learns() ? probe_(t) : Vec2::Zero();
    signals.desired = trajectory_(t);
  }

  // Called at the start of each step (and before the first evaluation): draws local
  // extrapolation points around the current error state, or prepares fixed ones once.
  void begin_step(double t, const State& state) {
    if (!extrapolation_.needs_begin_step()) return;
    const DesiredState desired = trajectory_(t);
    const TrackingErrors errors =
        tracking_errors(state.template segment<kDof>(kQ), state.template segment<kDof>(kDq),
                        desired, error_system_.alpha1());
    extrapolation_.begin_step(error_system_, cost_, errors.x(), desired);
  }

  void derivative(const TimeSignals& signals, const State& state, State& rate,
                  Outputs* outputs) const {
    const Vec2 q = state.template segment<kDof>(kQ);
    const Vec2 dq = state.template segment<kDof>(kDq);
    const Weights critic_weights = state.template segment<kBasisSize>(kCriticWeights);
    const Weights actor_weights = state.template segment<kBasisSize>(kActorWeights);
    const Vec2 nu = state.template segment<kDof>(kNu);
    const DesiredState& desired = signals.desired;

    const TrackingErrors errors = tracking_errors(q, dq, desired, error_system_.alpha1());
    const Vec4 x = errors.x();

    typename Arm::Terms plant_terms, believed_terms;
    plant_.compute(q, dq, plant_terms);
    if (!model_is_plant_) error_system_.model().compute(q, dq, believed_terms);
    const typename Arm::Terms& model_terms = model_is_plant_ ? plant_terms : believed_terms;

    HjbPoint<Basis, kDof> point;
    prepare_hjb_point<Basis, kDof>(x, desired, error_system_.drift(x, model_terms), model_terms,
                                   cost_, point);
    HjbEvaluation<Basis, kDof> hjb;
    evaluate_hjb(point, cost_, critic_weights, actor_weights, hjb);

    Weights critic_rate = Weights::Zero();
    CovarianceMap gamma_rate(rate.data() + kGamma);
    gamma_rate.setZero();
    if (controller_.learns()) {
      const ConstCovarianceMap gamma = covariance(state);
      const Weights difference = actor_weights - critic_weights;
      Weights actor_gradient = Weights::Zero();
      const auto learn = [&](const HjbPoint<Basis, kDof>& p, const HjbEvaluation<Basis, kDof>& e,
                             double weight) {
        critic_.add_rates(e.omega, e.error, gamma, weight, critic_rate, gamma_rate);  // (23)-(24)
        actor_.add_gradient(p.input_gradient, cost_.R_inverse(), e.omega, e.error, difference,
                            weight, actor_gradient);  // (26)
      };
      learn(point, hjb, 1.0);
      extrapolation_.for_each(error_system_, cost_, desired, critic_weights, actor_weights, learn);
      if (actor_.settings().positive_e2)  // not in the paper: positive_block.hpp
        critic_rate = keep_e2_block_positive<Basis>(critic_weights, critic_rate,
                                                    actor_.settings().e2_margin, gamma);
      rate.template segment<kBasisSize>(kActorWeights) =
          actor_.weight_rate(actor_gradient, difference, actor_weights);  // eq. (26)
    } else {
      rate.template segment<kBasisSize>(kActorWeights).setZero();
    }
    rate.template segment<kBasisSize>(kCriticWeights) = critic_rate;

    Vec2 mu = Vec2::Zero();
    rate.template segment<kDof>(kNu).setZero();
    if (controller_.uses_rise()) {
      mu = rise_.feedback(errors.e2, nu);                                 // eq. (27)
      rate.template segment<kDof>(kNu) = rise_.integral_rate(errors.e2);  // eq. (28)
    }
    const Vec2 u = controller_.input(errors, error_system_.alpha1(), cost_.R_inverse(), hjb.u_hat,
                                     signals.probe);
    const Vec2 tau = error_system_.feedforward(model_terms, dq, errors, desired) + mu - u;

    rate.template segment<kDof>(kQ) = dq;
    rate.template segment<kDof>(kDq) = Arm::acceleration(plant_terms, dq, tau, signals.disturbance);
    rate[kCost] = point.state_cost + cost_.input_cost(u);  // eq. (10): x^T Q x + u^T R u

    if (outputs != nullptr) {
      outputs->errors = errors;
      outputs->qd = desired.q;
      outputs->tau = tau;
      outputs->u = u;
      outputs->u_hat = hjb.u_hat;
      outputs->mu = mu;
      outputs->probe = signals.probe;
      outputs->hjb_error = hjb.error;
    }
  }

  // Resets Gamma to gamma0 I when lambda_min(Gamma) < epsilon_T; returns whether it did.
  bool reset_covariance_if_needed(State& state) const {
    if (!critic_.needs_reset(covariance(state))) return false;
    covariance(state) = critic_.initial_covariance();
    return true;
  }

 private:
  Arm plant_;
  bool model_is_plant_;
  ErrorSystem<Arm> error_system_;
  QuadraticCost cost_;
  Critic<Basis> critic_;
  Actor<Basis, Arm::kDof> actor_;
  Controller controller_;
  Trajectory trajectory_;
  Extrapolation<Arm, Basis> extrapolation_;
  Rise rise_;
  SinusoidalDisturbance disturbance_;
  ProbingSignal probe_;
  State initial_state_;
};

using PaperClosedLoop = ClosedLoop<TwoLinkArm, PaperBasis>;

}  // namespace adparm
