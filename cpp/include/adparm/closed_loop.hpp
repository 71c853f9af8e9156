// The closed loop of Figure 1 as one ODE system for RK4 (fixed parameters here, evolving state
// apart):
//   state = [q (n), dq (n), Wc (K), Wa (K), Gamma (K x K, column-major), nu (n), J (1)]
// At each evaluation, with the desired state (qd, dqd, ddqd) of trajectory.hpp and
// x = [e1; e2] (error_system.hpp):
//   u_hat  = -1/2 R^-1 g^T (dphi/dx)^T Wa                         (eq. 20)
//            (with an input bound: -lambda tanh(D), input_bound.hpp)
//   eps    = HJB error, omega its regressor                       (eq. 21)
//   dWc, dGamma                                                   (eqs. 23-24)
//   dWa                                                           (eq. 26)
//   (with extrapolation points, each law also averages its term over them: extrapolation.hpp)
//   mu     = RISE feedback, dnu                                   (eqs. 27-28)
//   u      = the controller's input (controller.hpp; adp: u_hat + probe(t))
//   tau    = h_hat + mu - u     (g = [0; M^-1] convention; h_hat of the believed model, eq. 5)
//            the commanded torque; with actuator limits (Settings::torque_limits, not in the
//            paper) the drive applies it clipped, tau_i <- min(max(tau_i, -limit_i), limit_i)
//   ddq    from the plant (eq. 1) with the applied tau and the disturbance tau_d(t)
//   dJ     = x^T Q x + u^T R u  (the accumulated cost of eq. 10, integrated with the state; with an
//            input bound U(u) for u^T R u, input_bound.hpp).
// Anti-windup of RISE (not in the paper; ControlSettings::anti_windup, on by default): nu enters
// tau with gain +1 (eq. 27), and while joint i is clipped the plant does not see tau_i move, so
// integrating dnu_i towards the limit only stores torque that must be integrated back before the
// drive leaves the limit (windup: overshoot and a late recovery). Conditional integration
// (clamping; Astrom & Murray, Feedback Systems, chapter "PID Control", "Integrator windup"): on a
// joint clipped at +limit_i a positive dnu_i is set to 0, at -limit_i a negative one; the component
// that moves tau_i back inside the limits is kept, so the joint leaves saturation as soon as eq.
// (28) asks for it. Where no joint is clipped, eq. (28) is unchanged, and without limits nothing of
// this runs. The basis and the arm model are template parameters: a new one is a new type, not a
// new loop. Sizes: n = Arm::kDof joints and K = Basis::kSize functions, each fixed (the two-link
// fast path, n = 2, K = 8) or Eigen::Dynamic; then the loop's per-step vectors are bounded types
// (types.hpp), the arm's terms live in buffers sized once (Arm::init_terms), and a step allocates
// nothing.
// Online identification (identifier.hpp; Settings::identifier, off by default): the model the
// controller believes is then the identifier's estimate beta_hat, held over each step and updated
// after it (end_step); its arm, in Data, replaces the fixed model wherever the model appears (the
// feedforward h_hat, f_hat and g_hat of the HJB error along the trajectory and at the
// extrapolation points, hence the critic and the actor). Off, the loop computes exactly what it
// computed before (one branch per evaluation).
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>

#include "adparm/basis.hpp"
#include "adparm/controller.hpp"
#include "adparm/critic.hpp"
#include "adparm/extrapolation.hpp"
#include "adparm/hjb.hpp"
#include "adparm/identifier.hpp"
#include "adparm/positive_block.hpp"
#include "adparm/rise.hpp"
#include "adparm/rk4.hpp"
#include "adparm/settings.hpp"
#include "adparm/trajectory.hpp"
#include "adparm/vector_loop.hpp"

// GCC's and Clang's flatten (ClosedLoop::flattened_derivative) in optimised builds, but not under
// AddressSanitizer: instrumenting the flattened bodies had taken GCC 14 minutes and 7.8 GB for the
// bench (bench/sanitize.sh) when it was stopped; the sanitizer checks the same code, its calls not
// inlined.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ADPARM_ADDRESS_SANITIZER 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define ADPARM_ADDRESS_SANITIZER 1
#endif
#if (defined(__GNUC__) || defined(__clang__)) && defined(__OPTIMIZE__) && \
    !defined(ADPARM_ADDRESS_SANITIZER)
#define ADPARM_FLATTEN [[gnu::flatten]]
#else
#define ADPARM_FLATTEN
#endif

namespace adparm {

// de1 = -alpha1 e1 + e2 is stable only if every eigenvalue of alpha1 has a positive real part.
// 2 x 2: trace > 0 and det > 0, judged on alpha1 / max|entry| (no overflow), as in Python; n x n:
// the eigenvalues of alpha1 / max|entry|.
inline void check_hurwitz(const Eigen::MatrixXd& alpha1) {
  const double scale = alpha1.cwiseAbs().maxCoeff();
  bool hurwitz = scale > 0.0;
  if (hurwitz) {
    const Eigen::MatrixXd a = alpha1 / scale;
    if (a.rows() == 2)
      hurwitz = a(0, 0) + a(1, 1) > 0.0 && a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0) > 0.0;
    else
      hurwitz =
          (Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues().real().array() > 0.0).all();
  }
  if (!hurwitz)
    throw std::invalid_argument(
        "control.alpha1: every eigenvalue must have a positive real part (-alpha1 Hurwitz)");
}

template <class Arm, class Basis>
class ClosedLoop {
 public:
  using ArmType = Arm;
  using BasisType = Basis;
  static constexpr int kDof = Arm::kDof;
  static constexpr int kBasisSize = Basis::kSize;
  static constexpr bool kFixed = kDof != Dynamic && kBasisSize != Dynamic;
  // The AVX-512 evaluation of vector_loop.hpp: the two-link arm with the augmented basis.
  static constexpr bool kVectorLoop = ADPARM_VECTOR_LOOP && std::is_same_v<Arm, TwoLinkArm> &&
                                      std::is_same_v<Basis, AugmentedBasis>;
  static_assert(Basis::kStateDim == twice(kDof), "the basis must act on x = [e1; e2]");
  // Offsets into the state vector (fixed sizes; the *_offset() functions hold them for any size).
  static constexpr int kQ = 0;
  static constexpr int kDq = kFixed ? kQ + kDof : Dynamic;
  static constexpr int kCriticWeights = kFixed ? kDq + kDof : Dynamic;
  static constexpr int kActorWeights = kFixed ? kCriticWeights + kBasisSize : Dynamic;
  static constexpr int kGamma = kFixed ? kActorWeights + kBasisSize : Dynamic;
  static constexpr int kNu = kFixed ? kGamma + kBasisSize * kBasisSize : Dynamic;
  static constexpr int kCost = kFixed ? kNu + kDof : Dynamic;
  static constexpr int kStateSize = kFixed ? kCost + 1 : Dynamic;

  using State = Eigen::Matrix<double, kStateSize, 1>;  // VectorXd for dynamic sizes
  using Joint = JointVector<kDof>;
  using Error = ErrorVector<kDof>;
  using Desired = DesiredStateT<kDof>;
  using Errors = TrackingErrorsT<kDof>;
  using Weights = typename Basis::Vector;
  using Terms = typename Arm::Terms;
  using Covariance = typename Critic<Basis>::Covariance;
  using CovarianceMap = Eigen::Map<Covariance>;
  using ConstCovarianceMap = Eigen::Map<const Covariance>;
  using Point = HjbPoint<Basis, kDof>;
  using Evaluation = HjbEvaluation<Basis, kDof>;
  using IdentifierType = typename IdentifierOf<Arm>::type;
  static constexpr bool kIdentifies = IdentifierType::kAvailable;

  struct NoTerms {};

  struct TimeSignals {
    Joint disturbance;  // tau_d(t)
    Joint probe;        // probing signal (zero unless the controller learns)
    Desired desired;    // qd(t), dqd(t), ddqd(t)
  };

  // The loop's work buffers (Crocoddyl's Data beside its Model): sized once by make_data(), owned
  // by the caller (Simulation) and passed to the calls that write them; the loop itself stays
  // const during an evaluation.
  struct Data {
    Terms plant_terms, believed_terms;  // dynamic sizes (fixed sizes keep them on the stack)
    Terms point_terms;                  // the model's terms at an extrapolation point
    typename Critic<Basis>::Workspace critic;
    BasisWorkspace<Basis> basis;  // the basis' work buffers (basis.hpp)
    // Stacked extrapolation points (dynamic sizes, Extrapolation::stacked()): [B_i^T Wa,
    // B_i^T (Wa - Wc)] of every point (nN x 2) and the actor's coefficients c_i (nN).
    Eigen::MatrixXd point_products;
    Eigen::VectorXd point_coefficients;
    // The kernels' batched points (learn_from_points_batched): [Wa, Wa - Wc] (K x 2), R^-1 times
    // point_products (n x 2N) and -u_hat_i (n x N).
    Eigen::MatrixXd point_weights, point_projected, point_inputs;
    // A basis of pairs (learn_from_pairs): [S(Wa); S(Wa - Wc)] (2n x 2n), the kernels' scratch,
    // their outputs over the points (omega K x N when the critic's block lacks room, eps,
    // ||omega||^2, the actor's scale and R^-1 B_i^T (Wa - Wc) n x stride) and
    // sum_i x_i (M_i^-1 c_i)^T (2n x n).
    Eigen::MatrixXd pair_forms, pair_omega, pair_projected, pair_products;
    Eigen::VectorXd pair_scratch, pair_error, pair_norm, pair_scale;
    // The trajectory's sample with them (learns_through_pairs), in lane N: the kernels' tail
    // block (PairPoints::tail: the last points' lanes and the trajectory's x, M^-1, F, x^T Q x),
    // the samples' w_i eta_a1 (1/N for a point, 1 for the trajectory) and -u_hat (n x stride).
    Eigen::VectorXd pair_tail, pair_gains;
    Eigen::MatrixXd pair_inputs;
    std::int64_t pair_tail_generation = -1;  // the points' lanes copied at that generation
    // With identification: beta_hat and the history stack, and the error system of the arm of
    // beta_hat (the believed model during the current step).
    typename IdentifierType::Data identifier;
    // (optional: a URDF arm has no default)
    std::conditional_t<kIdentifies, std::optional<ErrorSystem<Arm>>, NoTerms> believed;
    // beta_hat changed at the last end_step (the points are prepared again at the next
    // begin_step); it is held until the stack is informative (without the gradient term)
    bool model_changed = false;
    Joint no_probe;  // zero: the probe once the identifier stopped it (identifier.stop_probe)
    // The low-rank RK4 step (step(), low_rank_steps()): each stage's u_s = Gamma_s omega_s
    // (K x 4) and gain g_s, the stage being evaluated (-1: an ordinary evaluation), the previous
    // stage's scale c (Gamma_s = Gamma - c g_p u_p u_p^T) and the step's Gamma.
    Eigen::MatrixXd stage_vectors;
    Eigen::Vector4d stage_gains = Eigen::Vector4d::Zero();
    int stage = -1;
    double stage_scale = 0.0;
    const double* step_covariance = nullptr;
    // Dynamic sizes: the points of a moving desired state (extrapolation.hpp)
    std::conditional_t<kDof == Dynamic, MovingPoints<Basis, kDof>, NoTerms> moving_points;
  };

  struct Outputs {
    Errors errors;
    Joint qd;                // desired position
    Joint tau;               // applied joint torque (clipped to the limits)
    Joint tau_commanded;     // the controller's torque h_hat + mu - u, before the clip
    Joint u;                 // applied input of the controller
    Joint u_hat;             // actor's input, eq. (20)
    Joint mu;                // RISE feedback, eq. (27)
    Joint probe;             // probing signal
    double hjb_error = 0.0;  // eq. (21)
  };

  // The plant, the model the controller believes (`model_is_plant`: the same arm, whose terms are
  // then computed once per evaluation) and the basis, built already (from Settings:
  // make_loop in any_simulation.hpp).
  ClosedLoop(const Settings& settings, const Arm& plant, const Arm& model, bool model_is_plant,
             const Basis& basis = Basis())
      : plant_(plant),
        model_is_plant_(model_is_plant),
        basis_(basis),
        dof_(checked_dof(plant, model, basis)),
        basis_size_(basis.size()),
        error_system_(model, checked_alpha1(settings, dof_)),
        cost_(settings.Q, settings.R, dof_, settings.input_bound, settings.e2_cost),
        critic_(settings.critic, basis_size_, settings.extrapolation.points > 0),
        actor_(settings.actor),
        controller_(settings.controller, dof_),
        trajectory_(settings.task.qd, dof_),
        extrapolation_(settings.extrapolation, trajectory_.is_constant(), model),
        probe_(settings.probe, dof_),
        torque_limits_(checked_torque_limits(settings.torque_limits, dof_)),
        limited_(settings.torque_limits.size() > 0 &&
                 (settings.torque_limits.array() < kInfinity).any()),
        anti_windup_(settings.control.anti_windup),
        gathers_(kBasisSize == Dynamic &&
                 (extrapolation_.enabled() || basis_size_ > 24 || critic_.kernels() != nullptr)),
        identifier_(make_identifier(settings, model)),
        identifies_(identifier_.enabled()),
        low_rank_(gathers_ && !extrapolation_.enabled() && controller_.learns()),
        lower_steps_(gathers_ && extrapolation_.enabled() && controller_.learns() &&
                     critic_.kernels() != nullptr),
        vector_(kVectorLoop && vector_loop_available()) {
    const Eigen::Index n = dof_, k = basis_size_;
    check_size(settings.disturbance, n, 1, "plant.disturbance");
    check_finite(settings.disturbance, "plant.disturbance");
    disturbance_.amplitude = settings.disturbance;
    check_size(settings.task.q0, n, 1, "task.q0");
    check_size(settings.task.dq0, n, 1, "task.dq0");
    check_finite(settings.task.q0, "task.q0");
    check_finite(settings.task.dq0, "task.dq0");
    check_size(settings.critic_weights, k, 1, "init.critic_weights");
    check_size(settings.actor_weights, k, 1, "init.actor_weights");
    check_finite(settings.critic_weights, "init.critic_weights");
    check_finite(settings.actor_weights, "init.actor_weights");
    const Joint q0 = settings.task.q0, dq0 = settings.task.dq0;
    const Errors initial = tracking_errors<kDof>(q0, dq0, trajectory_(0.0), error_system_.alpha1());
    rise_ = RiseT<kDof>(settings.control.rise, initial.e2);
    initial_state_.setZero(state_size());
    initial_state_.template segment<kDof>(kQ, n) = q0;
    initial_state_.template segment<kDof>(dq_offset(), n) = dq0;
    initial_state_.template segment<kBasisSize>(critic_offset(), k) = settings.critic_weights;
    initial_state_.template segment<kBasisSize>(actor_offset(), k) = settings.actor_weights;
    critic_.reset(covariance(initial_state_));
  }

  Eigen::Index dof() const { return size_of(kDof, dof_); }
  Eigen::Index basis_size() const { return size_of(kBasisSize, basis_size_); }
  Eigen::Index dq_offset() const { return dof(); }
  Eigen::Index critic_offset() const { return 2 * dof(); }
  Eigen::Index actor_offset() const { return critic_offset() + basis_size(); }
  Eigen::Index gamma_offset() const { return actor_offset() + basis_size(); }
  Eigen::Index nu_offset() const { return gamma_offset() + basis_size() * basis_size(); }
  Eigen::Index cost_offset() const { return nu_offset() + dof(); }
  Eigen::Index state_size() const { return cost_offset() + 1; }

  const State& initial_state() const { return initial_state_; }

  static MovingPoints<Basis, kDof>* moving_points(Data& data) {
    if constexpr (kDof == Dynamic)
      return &data.moving_points;
    else
      return nullptr;
  }

  Data make_data() const {
    Data data;
    plant_.init_terms(data.plant_terms);
    error_system_.model().init_terms(data.believed_terms);
    error_system_.model().init_terms(data.point_terms);
    data.critic = critic_.workspace();
    data.basis = basis_workspace(basis_);
    if (low_rank_) data.stage_vectors.setZero(basis_size(), 4);
    if (kBasisSize == Dynamic && extrapolation_.enabled()) {
      data.point_products.setZero(dof() * extrapolation_.size(), 2);
      data.point_coefficients.setZero(dof() * extrapolation_.size());
      data.point_weights.setZero(basis_size(), 2);
      data.point_projected.setZero(dof(), 2 * extrapolation_.size());
      data.point_inputs.setZero(dof(), extrapolation_.size());
      if constexpr (HasPairs<Basis>::value) {
        if (!basis_.pairs().empty()) {
          const Eigen::Index n = dof();
          const Eigen::Index stride =
              Extrapolation<Arm, Basis>::pair_stride_for(extrapolation_.size());
          data.pair_forms.setZero(2 * n, 2 * n);
          data.pair_omega.setZero(basis_size(), stride);
          data.pair_projected.setZero(stride, n);
          data.pair_products.setZero(2 * n, n);
          data.pair_scratch.setZero((2 * n * n + 6 * n) * 8);
          data.pair_error.setZero(stride);
          data.pair_norm.setZero(stride);
          data.pair_scale.setZero(stride);
          const long points = extrapolation_.size();
          data.pair_tail.setZero(PairPoints::kTailLanes * (2 * n + n * n + basis_size() + 1));
          data.pair_gains.setZero(stride);
          data.pair_gains.head(points).setConstant((1.0 / points) * actor_.settings().eta_a1);
          data.pair_gains[points] = actor_.settings().eta_a1;
          data.pair_inputs.setZero(stride, n);
        }
      }
    }
    if constexpr (kIdentifies) {
      if (identifies_) {
        data.identifier = identifier_.make_data();
        data.no_probe = Joint::Zero(dof());
        data.believed = ErrorSystem<Arm>(identifier_.arm(data.identifier), error_system_.alpha1());
      }
    }
    return data;
  }
  // Whether the loop identifies the model online (Settings::identifier.enabled).
  bool identifies() const { return identifies_; }
  // The identified parameters' count (the recorded beta_hat's width): 0 without identification.
  Eigen::Index parameter_count() const { return identifies_ ? identifier_.parameters() : 0; }
  const IdentifierType& identifier() const { return identifier_; }

  // After a step from (t, state), whose first stage gave `outputs` (the applied torque): the
  // identifier's sample and update of beta_hat (identifier.hpp), and the believed model of the
  // next step. Only with identification.
  void end_step(double t, double h, const State& state, const Outputs& outputs, Data& data) const {
    if constexpr (kIdentifies) {
      const Eigen::Index n = dof();
      const Joint q = state.template segment<kDof>(kQ, n);
      const Joint dq = state.template segment<kDof>(dq_offset(), n);
      const Desired desired = trajectory_(t);
      const auto& alpha1 = error_system_.alpha1();
      const Joint dq_r = desired.dq + alpha1 * outputs.errors.e1;    // dqd + alpha1 e1
      const Joint ddq_r = desired.ddq + alpha1 * (desired.dq - dq);  // ddqd + alpha1 de1
      if (identifier_.update(t, q, dq, outputs.tau, dq_r, ddq_r, outputs.errors.e2, h,
                             data.identifier)) {
        data.believed = ErrorSystem<Arm>(identifier_.arm(data.identifier), alpha1);
        data.model_changed = true;
      }
    }
  }
  const Arm& plant() const { return plant_; }
  // Whether some joint has a finite torque limit (otherwise the clip is skipped entirely).
  bool limited() const { return limited_; }
  const Basis& basis() const { return basis_; }
  const ErrorSystem<Arm>& error_system() const { return error_system_; }
  const QuadraticCostT<kDof>& cost() const { return cost_; }
  const Critic<Basis>& critic() const { return critic_; }
  const TrajectoryT<kDof>& trajectory() const { return trajectory_; }
  const Extrapolation<Arm, Basis>& extrapolation() const { return extrapolation_; }

  CovarianceMap covariance(State& x) const {
    return CovarianceMap(x.data() + gamma_offset(), basis_size(), basis_size());
  }
  ConstCovarianceMap covariance(const State& x) const {
    return ConstCovarianceMap(x.data() + gamma_offset(), basis_size(), basis_size());
  }

  // The time signals at t (the vector loop's sines on an AVX-512 CPU: every evaluation, the
  // recorded rows' too, sees the same bits whether a run advances in one go or in chunks).
  void time_signals(double t, TimeSignals& signals) const {
    if constexpr (kVectorLoop) {
      if (vector_) return vector_time_signals(t, signals);
    }
    portable_time_signals(t, signals);
  }
  void portable_time_signals(double t, TimeSignals& signals) const {
    signals.disturbance = disturbance_(t);
    signals.probe = controller_.learns() ? probe_(t) : Joint::Zero(dof());
    signals.desired = trajectory_(t);
  }

  // Called at the start of each step (and before the first evaluation): draws local
  // extrapolation points around the current error state, or prepares fixed ones once (with
  // identification, again after each step that changed beta_hat: the believed model is held over
  // the step and changes after it, end_step; a beta_hat held, as until the stack is informative,
  // keeps the points prepared, the same numbers).
  void begin_step(double t, const State& state, Data& data) {
    if constexpr (kIdentifies) {
      if (identifies_ && data.model_changed) {
        extrapolation_.model_changed();
        data.model_changed = false;
      }
    }
    if (!extrapolation_.needs_begin_step()) return;
    const ErrorSystem<Arm>& system = believed_system(data);
    const Eigen::Index n = dof();
    const Desired desired = trajectory_(t);
    const Errors errors = tracking_errors<kDof>(state.template segment<kDof>(kQ, n),
                                                state.template segment<kDof>(dq_offset(), n),
                                                desired, error_system_.alpha1());
    extrapolation_.begin_step(basis_, system, cost_, errors.x(), desired, data.point_terms,
                              data.basis);
  }

  // Whether step() takes low-rank steps: dynamic sizes, a learning controller, no extrapolation
  // points (one sample per evaluation, so each stage's dGamma is rank one) and more than 24
  // functions or dispatched kernels (measured: faster on the UR5's 55 and 78; at 8-21 functions
  // 1.05-1.10x per step with the kernels, within the noise or slower on the portable path, where
  // add_rates' unrolled products are cheap: there they keep rk4_step, bit for bit).
  bool low_rank_steps() const { return low_rank_; }
  // Whether step() takes lower_step: gathered blocks (extrapolation points) in the dispatched
  // kernels, a learning controller.
  bool lower_steps() const { return lower_steps_; }

  // One RK4 step from (t_begin, x) to (t_end, x_next) (x_next not x): rk4_step (rk4.hpp), or with
  // low_rank_steps() the same step with each stage's dGamma kept as (u_s, g_s) (Critic::
  // stage_rates): the stages' K x K rates and covariances are never formed, and Gamma_next is one
  // pass (Critic::low_rank_update). Equal to rk4_step up to round-off (the products associate
  // differently: the last bits of a run differ). With gathered blocks in the dispatched kernels,
  // lower_step: rk4_step's numbers bit for bit, Gamma summed on its lower triangle.
  void step(double t_begin, double t_end, const State& x, State& x_next,
            Rk4Workspace<ClosedLoop>& w, Outputs* outputs, Data& data) const {
    if constexpr (kBasisSize == Dynamic) {
      if (low_rank_) {
        low_rank_step(t_begin, t_end, x, x_next, w, outputs, data);
        return;
      }
      if (lower_steps_) {
        lower_step(t_begin, t_end, x, x_next, w, outputs, data);
        return;
      }
    }
    if constexpr (kVectorLoop) {
      if (vector_) return vector_step(t_begin, t_end, x, x_next, w, outputs, data);
    }
    rk4_step(*this, t_begin, t_end, x, x_next, w, outputs, data);
  }

  // The closed loop's right-hand side at one RK4 stage (evaluate_derivative). Fixed sizes (the
  // two-link paper loop): every call inside it inlined (flattened, below); dynamic sizes: the
  // same body, its calls left to the compiler.
  void derivative(const TimeSignals& signals, const State& state, State& rate, Outputs* outputs,
                  Data& data) const {
    if constexpr (kVectorLoop) {
      if (vector_) return vector_derivative(signals, state, rate, outputs, data);
    }
    if constexpr (kFixed)
      flattened_derivative(signals, state, rate, outputs, data);
    else
      evaluate_derivative(signals, state, rate, outputs, data);
  }

  // The probing signal applied: the time signal's, or zero once the identifier has stopped it
  // (identifier.stop_probe), only with Bellman-error extrapolation: without extrapolation points
  // the probe is the critic's only excitation, and it stays.
  const Joint& applied_probe(const TimeSignals& signals, const Data& data) const {
    if constexpr (kIdentifies) {
      if (identifies_ && data.identifier.probe_stopped && extrapolation_.enabled())
        return data.no_probe;
    }
    return signals.probe;
  }

 private:
  // derivative() with every call inside it inlined (Eigen's products and dot products, the arm's
  // terms, the basis, the critic's and actor's laws; not libm's sincos): the compiler then
  // schedules an evaluation as one body (measured on the paper loop: 1001 -> 925 ns per RK4 step,
  // the same bits). Fixed sizes only: the dynamic sizes' calls (the dense kernels, Pinocchio, the
  // expression basis) are large and stay calls.
  ADPARM_FLATTEN void flattened_derivative(const TimeSignals& signals, const State& state,
                                           State& rate, Outputs* outputs, Data& data) const {
    evaluate_derivative(signals, state, rate, outputs, data);
  }
  // The same built for AVX-512 + FMA (vector_loop.hpp), called only when vector_ (the CPU has
  // them): the sample's basis Jacobian products, eqs. (20)-(26) and the arm's sines in vector
  // registers, the rest of the body as above (compiled for that target: its sums may be fused).
  ADPARM_FLATTEN ADPARM_AVX512 void vector_derivative(const TimeSignals& signals,
                                                      const State& state, State& rate,
                                                      Outputs* outputs, Data& data) const {
    evaluate_derivative<true>(signals, state, rate, outputs, data);
  }

  // Critic::needs_reset, or its vector form (vector_loop.hpp: the same answer unless
  // lambda_min(Gamma) is within round-off of epsilon_T)
  bool needs_reset(const State& state, Data& data) const {
    if constexpr (kVectorLoop) {
      if (vector_) return vector_below(state);
    }
    return critic_.needs_reset(covariance(state), data.critic);
  }

  // x = [e1; e2] (errors.x()); in vector_derivative by one 32-byte store: GCC copies the
  // x of two 16-byte stores with one 32-byte load there, which waits for the stores to reach
  // the cache (no store forwarding), at the head of the evaluation's chain
  template <bool kVector>
  [[gnu::always_inline]] Error error_state(const Errors& errors) const {
    if constexpr (kVector && kVectorLoop) return vector_error_state(errors);
    return errors.x();
  }

#if ADPARM_VECTOR_LOOP
  ADPARM_AVX512 Error vector_error_state(const Errors& errors) const {
    Error x;
    if constexpr (kVectorLoop)
      _mm256_storeu_pd(x.data(),
                       _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(errors.e1.data())),
                                            _mm_loadu_pd(errors.e2.data()), 1));
    return x;
  }
  ADPARM_AVX512 bool vector_below(const State& state) const {
    return vector8::below(state.data() + gamma_offset(), critic_.settings().epsilon_T);
  }
  // rk4_step (rk4.hpp) with its sums in vector registers (the same bits) and vector_derivative.
  ADPARM_AVX512 void vector_step(double t_begin, double t_end, const State& x, State& x_next,
                                 Rk4Workspace<ClosedLoop>& w, Outputs* outputs, Data& data) const {
    static_assert(kStateSize == vector8::kStateSize, "vector_loop.hpp's state layout");
    const double h = t_end - t_begin;
    if (!(w.begin_time == t_begin)) vector_time_signals(t_begin, w.begin);
    vector_time_signals(t_begin + 0.5 * h, w.middle);
    vector_time_signals(t_end, w.end);
    vector_derivative(w.begin, x, w.k1, outputs, data);
    vector8::stage_sum(x.data(), w.k1.data(), 0.5 * h, w.stage.data());
    vector_derivative(w.middle, w.stage, w.k2, nullptr, data);
    vector8::stage_sum(x.data(), w.k2.data(), 0.5 * h, w.stage.data());
    vector_derivative(w.middle, w.stage, w.k3, nullptr, data);
    vector8::stage_sum(x.data(), w.k3.data(), h, w.stage.data());
    vector_derivative(w.end, w.stage, w.k4, nullptr, data);
    vector8::rk4_sum(x.data(), w.k1.data(), w.k2.data(), w.k3.data(), w.k4.data(), h / 6.0,
                     x_next.data());  // x_next may be x: entry by entry
    std::swap(w.begin, w.end);
    w.begin_time = t_end;
  }
  using VectorResult = std::conditional_t<kVectorLoop, vector8::Result8, NoTerms>;
  // The plant's terms (and the believed model's, own_model) at (q, dq), q's sines in a vector.
  ADPARM_AVX512 void compute_in_vectors(const Joint& q, const Joint& dq, const Arm& model,
                                        bool own_model, Terms& plant_terms,
                                        Terms& believed_terms) const {
    if constexpr (kVectorLoop) {
      vector8::V sine, cosine;
      vector8::sincos(_mm512_castpd128_pd512(_mm_set_pd(q[1], q[0])), sine, cosine);
      const double s1 = _mm512_cvtsd_f64(sine), c1 = _mm512_cvtsd_f64(cosine);
      const double s2 = _mm512_cvtsd_f64(vector8::lane<1>(sine));
      const double c2 = _mm512_cvtsd_f64(vector8::lane<1>(cosine));
      plant_.compute(dq, c1, s1, c2, s2, plant_terms);
      if (own_model) model.compute(dq, c1, s1, c2, s2, believed_terms);
    }
  }
  // time_signals with the sines of the disturbance and of up to 7 probing frequencies in one
  // vector sincos
  ADPARM_AVX512 void vector_time_signals(double t, TimeSignals& signals) const {
    if constexpr (kVectorLoop) {
      const Eigen::VectorXd& frequencies = probe_.frequencies();
      const Eigen::Index count = frequencies.size();
      if (count > 7) return portable_time_signals(t, signals);
      alignas(64) double sine[8], cosine[8];
      const __mmask8 lanes = static_cast<__mmask8>((1u << count) - 1u);
      const vector8::V time = _mm512_set1_pd(t);  // frequency k times t, then t (disturbance)
      const vector8::V angle = _mm512_mask_blend_pd(
          static_cast<__mmask8>(1u << count),
          _mm512_mul_pd(_mm512_maskz_loadu_pd(lanes, frequencies.data()), time), time);
      vector8::V s, c;
      vector8::sincos(angle, s, c);
      _mm512_store_pd(sine, s);
      _mm512_store_pd(cosine, c);
      for (Eigen::Index j = 0; j < dof(); ++j)  // SinusoidalDisturbanceT's
        signals.disturbance[j] =
            disturbance_.amplitude[j] * (j % 2 == 0 ? sine[count] : cosine[count]);
      signals.probe =
          controller_.learns() ? probe_.from_sines(t, sine, cosine) : Joint::Zero(dof());
      signals.desired = trajectory_(t);
    }
  }
  // eqs. (19)-(21) in vector registers (vector_loop.hpp), from the arm's terms at q
  ADPARM_AVX512 void evaluate_in_vectors(const Error& x, const Desired& desired, const Error& drift,
                                         const Terms& terms, double state_cost,
                                         const Weights& critic_weights,
                                         const Weights& actor_weights, Evaluation& hjb,
                                         VectorResult& result) const {
    if constexpr (kVectorLoop) {
      vector8::evaluate(x.data(), terms.cos_q2, terms.sin_q2, terms.mass_inverse.data(),
                        drift.data(), desired.dq[1], state_cost, critic_weights.data(),
                        actor_weights.data(), cost_.R().data(), cost_.R_inverse().data(), result);
      hjb.u_hat << result.u_hat[0], result.u_hat[1];
      _mm512_storeu_pd(hjb.omega.data(), result.omega);
      hjb.error = result.error;
      hjb.input_cost = result.input_cost;
    }
  }
  // dWc and dWa into `rate` in vector registers (vector_loop.hpp) when no e2 block is near its
  // margin (positive_block.hpp's common case: no projection); false (nothing written) otherwise.
  ADPARM_AVX512 bool rates_in_vectors(const Weights& critic_weights, const Weights& actor_weights,
                                      const Weights& critic_rate, const Weights& actor_gradient,
                                      const VectorResult& result, State& rate) const {
    if constexpr (kVectorLoop) {
      const ActorSettings& settings = actor_.settings();
      const double margin = settings.e2_margin;
      if (settings.positive_e2 && !(e2_block_above(critic_weights, 1.0, margin) &&
                                    e2_block_above(critic_weights, -1.0, margin) &&
                                    e2_block_above(actor_weights, 1.0, margin) &&
                                    e2_block_above(actor_weights, -1.0, margin)))
        return false;
      vector8::weight_rates(actor_weights.data(), critic_rate.data(), actor_gradient.data(),
                            result.difference, settings.eta_a2, settings.weight_bound,
                            rate.data() + critic_offset(), rate.data() + actor_offset());
      return true;
    }
    return false;
  }
  // eqs. (23)-(26)'s shares of this sample in vector registers (vector_loop.hpp)
  template <class Gamma, class GammaRate>
  ADPARM_AVX512 void learn_in_vectors(const VectorResult& result, const Gamma& gamma,
                                      Weights& critic_rate, GammaRate& gamma_rate,
                                      Weights& actor_gradient) const {
    if constexpr (kVectorLoop)
      vector8::learn(result, gamma.data(), 1.0, critic_.settings().eta_c, critic_.settings().nu,
                     actor_.settings().eta_a1, critic_rate.data(), gamma_rate.data(),
                     actor_gradient.data());
  }
#else  // no vector loop: never called (kVectorLoop false)
  Error vector_error_state(const Errors& errors) const { return errors.x(); }
  template <class... A>
  void compute_in_vectors(A&&...) const {}
  template <class... A>
  void vector_time_signals(A&&...) const {}
  template <class... A>
  bool rates_in_vectors(A&&...) const {
    return false;
  }
  bool vector_below(const State&) const { return false; }
  template <class... A>
  void vector_step(A&&...) const {}
  using VectorResult = NoTerms;
  template <class... A>
  void evaluate_in_vectors(A&&...) const {}
  template <class... A>
  void learn_in_vectors(A&&...) const {}
#endif

  // (always inlined: the dynamic sizes' derivative() is this body, as before the flattening)
  template <bool kVector = false>
  [[gnu::always_inline]] inline void evaluate_derivative(const TimeSignals& signals,
                                                         const State& state, State& rate,
                                                         Outputs* outputs, Data& data) const {
    const Eigen::Index n = dof(), k = basis_size();
    const Joint q = state.template segment<kDof>(kQ, n);
    const Joint dq = state.template segment<kDof>(dq_offset(), n);
    const Weights critic_weights = state.template segment<kBasisSize>(critic_offset(), k);
    const Weights actor_weights = state.template segment<kBasisSize>(actor_offset(), k);
    const Joint nu = state.template segment<kDof>(nu_offset(), n);
    const Desired& desired = signals.desired;
    const ErrorSystem<Arm>& system = believed_system(data);  // error_system_ without identification

    const Errors errors = tracking_errors<kDof>(q, dq, desired, error_system_.alpha1());
    const Error x = error_state<kVector>(errors);

    // fixed sizes: the terms on the stack; dynamic: in the buffers sized once
    [[maybe_unused]] std::conditional_t<kFixed, Terms, NoTerms> local_plant_terms,
        local_believed_terms;
    Terms& plant_terms = pick_terms(local_plant_terms, data.plant_terms);
    Terms& believed_terms = pick_terms(local_believed_terms, data.believed_terms);
    const bool own_model = !model_is_plant_ || identifies_;
    if constexpr (kVector && kVectorLoop) {  // sin and cos of q1, q2 in one vector sincos
      compute_in_vectors(q, dq, system.model(), own_model, plant_terms, believed_terms);
    } else {
      plant_.compute(q, dq, plant_terms);
      if (own_model) system.model().compute(q, dq, believed_terms);
    }
    const Terms& model_terms = own_model ? believed_terms : plant_terms;

    Point point;
    Evaluation hjb;
    // vector_derivative without an input bound: eqs. (20)-(26) of this sample in vector_loop.hpp
    constexpr bool kVectorPath = kVector && kVectorLoop;
    const bool vector_sample = kVectorPath && !cost_.bounded();
    [[maybe_unused]] VectorResult vector_result;
    // With the dispatched kernels (dynamic sizes): B^T [Wa, Wa - Wc] in one pass over B, then
    // eqs. (20)-(21) from B^T Wa and the actor's share (26) from B^T (Wa - Wc), as for the points.
    const DenseKernels* kernels = kBasisSize == Dynamic ? critic_.kernels() : nullptr;
    const Weights difference = actor_weights - critic_weights;
    Joint times_difference;
    // a basis of pairs at stacked points: this sample with the points (learn_from_pairs), its
    // basis not evaluated
    const bool through_pairs = learns_through_pairs();
    const Error drift = system.drift(x, model_terms);
    if (through_pairs) {
      point.state_cost = cost_.state_cost(x);
    } else if (vector_sample) {  // eqs. (19)-(21) in vector registers, the basis' products too
      point.state_cost = cost_.state_cost(x);
      evaluate_in_vectors(x, desired, drift, model_terms, point.state_cost, critic_weights,
                          actor_weights, hjb, vector_result);
    } else {
      prepare_hjb_point<Basis, kDof>(basis_, x, desired, drift, model_terms, cost_, point,
                                     data.basis, critic_.kernels());
      if (kernels != nullptr)
        evaluate_in_kernels(point, point.input_gradient.data(), critic_weights, actor_weights,
                            difference, hjb, times_difference);
      else
        evaluate_hjb(point, cost_, critic_weights, actor_weights, hjb);
    }

    Weights critic_rate = Weights::Zero(k);
    CovarianceMap gamma_rate(rate.data() + gamma_offset(), k, k);
    const bool low_rank = kBasisSize == Dynamic && data.stage >= 0;  // step(): no K x K rate
    // gathered with the kernels: flush() writes the whole rate (Critic::leave_rate_to_flush)
    const bool rate_by_flush =
        kBasisSize == Dynamic && gathers_ && controller_.learns() && critic_.kernels() != nullptr;
    if (rate_by_flush && !low_rank)
      critic_.leave_rate_to_flush(data.critic);
    else if (!low_rank)
      gamma_rate.setZero();
    bool rates_written = false;  // dWc and dWa written by rates_in_vectors
    if (controller_.learns()) {
      const ConstCovarianceMap gamma = covariance(state);
      Weights actor_gradient = Weights::Zero(k);
      // clang-format off
      const auto learn = [&](const Point& p, const Evaluation& e, double weight,
                             const Joint* product = nullptr)  // B^T (Wa - Wc), kernels
                             __attribute__((always_inline)) {  // (flatten left it a call)
        if constexpr (kBasisSize == Dynamic) {  // (23)-(24), gathered in blocks (critic.hpp)
          if (low_rank)
            low_rank_stage(e.omega, e.error, weight, critic_rate, data);
          else if (gathers_)
            critic_.gather(e.omega, e.error, gamma, weight, critic_rate, gamma_rate, data.critic);
          else
            critic_.add_rates(e.omega, e.error, gamma, weight, critic_rate, gamma_rate);
        } else {
          critic_.add_rates(e.omega, e.error, gamma, weight, critic_rate, gamma_rate);
        }
        if (product != nullptr) {  // (26): gradient -= B c in the kernels
          actor_share_in_kernels(p.input_gradient.data(), *product, e, weight, actor_gradient);
        } else {
          actor_.add_gradient(p.input_gradient, cost_.R_inverse(), cost_.bound(), e.u_hat, e.omega,
                              e.error, difference, weight, actor_gradient);  // (26)
        }
      };
      // clang-format on
      bool stacked = false;
      if constexpr (kBasisSize == Dynamic) {
        stacked = gathers_ && extrapolation_.stacked();
        bool paired = false;
        if constexpr (HasPairs<Basis>::value) {
          if (through_pairs) {  // the points, then this sample (lane N)
            learn_from_pairs(x, drift, model_terms.mass_inverse, point.state_cost, critic_weights,
                             actor_weights, difference, gamma, critic_rate, gamma_rate,
                             actor_gradient, hjb, data);
            paired = true;
          }
        }
        if (!paired) {
          learn(point, hjb, 1.0, kernels != nullptr ? &times_difference : nullptr);
          if (stacked)  // the same shares, with the points' products stacked
            learn_from_stacked_points(critic_weights, actor_weights, difference, gamma, critic_rate,
                                      gamma_rate, actor_gradient, data);
        }
      } else if (vector_sample) {
        learn_in_vectors(vector_result, gamma, critic_rate, gamma_rate, actor_gradient);
      } else {
        learn(point, hjb, 1.0, nullptr);
      }
      if (!stacked)
        extrapolation_.for_each(basis_, system, cost_, desired, critic_weights, actor_weights,
                                data.point_terms, data.basis, moving_points(data), learn);
      if constexpr (kBasisSize == Dynamic)
        if (!low_rank) critic_.flush(gamma, critic_rate, gamma_rate, data.critic);
      if constexpr (kVectorPath) {  // no projection due: the rates in vector registers
        if (vector_sample)
          rates_written = rates_in_vectors(critic_weights, actor_weights, critic_rate,
                                           actor_gradient, vector_result, rate);
      }
      if (!rates_written &&
          actor_.settings().positive_e2) {  // not in the paper: positive_block.hpp
        if constexpr (kBasisSize == Dynamic) {
          if (low_rank) {
            const ConstCovarianceMap step_gamma(data.step_covariance, k, k);
            const auto previous = data.stage_vectors.col(data.stage > 0 ? data.stage - 1 : 0);
            const double scale =
                data.stage > 0 ? data.stage_scale * data.stage_gains[data.stage - 1] : 0.0;
            using Metric = typename Critic<Basis>::template StageCovariance<ConstCovarianceMap,
                                                                            decltype(previous)>;
            critic_rate = keep_e2_block_positive(basis_, critic_weights, critic_rate,
                                                 actor_.settings().e2_margin,
                                                 Metric{step_gamma, previous, scale});
          }
        }
        if (!low_rank)
          critic_rate = keep_e2_block_positive(basis_, critic_weights, critic_rate,
                                               actor_.settings().e2_margin, gamma);
      }
      if (!rates_written)
        rate.template segment<kBasisSize>(actor_offset(), k) =
            actor_.weight_rate(basis_, actor_gradient, difference, actor_weights);  // eq. (26)
    } else {
      rate.template segment<kBasisSize>(actor_offset(), k).setZero();
    }
    if (!rates_written) rate.template segment<kBasisSize>(critic_offset(), k) = critic_rate;

    Joint mu = Joint::Zero(n);
    rate.template segment<kDof>(nu_offset(), n).setZero();
    if (controller_.uses_rise()) {
      mu = rise_.feedback(errors.e2, nu);                                            // eq. (27)
      rate.template segment<kDof>(nu_offset(), n) = rise_.integral_rate(errors.e2);  // eq. (28)
    }
    const Joint& probe = applied_probe(signals, data);
    const Joint u = controller_.input(errors, error_system_.alpha1(), cost_.R_inverse(),
                                      cost_.bound(), hjb.u_hat, probe);
    const Joint tau_commanded = system.feedforward(model_terms, dq, errors, desired) + mu - u;
    Joint tau = tau_commanded;
    if (limited_) {  // the drive's clip, and RISE's anti-windup (header comment)
      tau = tau_commanded.cwiseMax(-torque_limits_).cwiseMin(torque_limits_);
      if (anti_windup_ && controller_.uses_rise()) {
        for (Eigen::Index i = 0; i < n; ++i) {
          double& nu_rate = rate[nu_offset() + i];
          if ((tau_commanded[i] > torque_limits_[i] && nu_rate > 0.0) ||
              (tau_commanded[i] < -torque_limits_[i] && nu_rate < 0.0))
            nu_rate = 0.0;
        }
      }
    }

    rate.template segment<kDof>(kQ, n) = dq;
    rate.template segment<kDof>(dq_offset(), n) =
        plant_.acceleration(plant_terms, dq, tau, signals.disturbance);
    // eq. (10): x^T Q x + u^T R u; with an input bound and u = u_hat (an adp controller, no
    // probe) U(u_hat) of the policy's own terms, to round-off the same as input_cost(u)
    const bool policy_alone =
        cost_.bounded() && controller_.learns() && (probe.array() == 0.0).all();
    rate[cost_offset()] = point.state_cost + (policy_alone ? hjb.input_cost : cost_.input_cost(u));

    if (outputs != nullptr) {
      outputs->errors = errors;
      outputs->qd = desired.q;
      outputs->tau = tau;
      outputs->tau_commanded = tau_commanded;
      outputs->u = u;
      outputs->u_hat = hjb.u_hat;
      outputs->mu = mu;
      outputs->probe = probe;
      outputs->hjb_error = hjb.error;
    }
  }

 public:
  // Resets Gamma to gamma0 I when lambda_min(Gamma) < epsilon_T; returns whether it did.
  bool reset_covariance_if_needed(State& state, Data& data) const {
    if (!needs_reset(state, data)) return false;
    critic_.reset(covariance(state));
    return true;
  }
  // The same after a step from `previous` (the state one step before): dynamic sizes skip the
  // test's factorisation while a bound rules a reset out (Critic::needs_reset(previous, gamma)).
  bool reset_covariance_if_needed(const State& previous, State& state, Data& data) const {
    if constexpr (kBasisSize == Dynamic) {
      const State& current = state;
      if (!critic_.needs_reset(covariance(previous), covariance(current), data.critic))
        return false;
      critic_.reset(covariance(state));
      critic_.after_reset(data.critic);
      return true;
    } else {
      return reset_covariance_if_needed(state, data);
    }
  }

 private:
  // A low-rank stage's shares of eqs. (23)-(24) (Critic::stage_rates), its (u_s, g_s) kept.
  void low_rank_stage(const Weights& omega, double error, double weight, Weights& critic_rate,
                      Data& data) const {
    const Eigen::Index k = basis_size();
    const ConstCovarianceMap gamma(data.step_covariance, k, k);
    const int s = data.stage;
    const auto previous = data.stage_vectors.col(s > 0 ? s - 1 : 0);
    const double scale = s > 0 ? data.stage_scale * data.stage_gains[s - 1] : 0.0;
    data.stage_gains[s] = critic_.stage_rates(omega, error, gamma, previous, scale, weight,
                                              critic_rate, data.stage_vectors.col(s));
  }

  // rk4_step's time signals (rk4.hpp) in low_rank_step and lower_step: the step's begin (unless
  // the previous step's end), middle and end; after the step its end becomes the next begin.
  void step_signals(double t_begin, double t_end, Rk4Workspace<ClosedLoop>& w) const {
    if (!(w.begin_time == t_begin)) time_signals(t_begin, w.begin);
    time_signals(t_begin + 0.5 * (t_end - t_begin), w.middle);
    time_signals(t_end, w.end);
  }
  static void next_step_signals(double t_end, Rk4Workspace<ClosedLoop>& w) {
    std::swap(w.begin, w.end);
    w.begin_time = t_end;
  }

  // step() with low-rank stages: rk4_step's stages and sum on the state apart from Gamma
  // ([q, dq, Wc, Wa] before it, [nu, J] after it), Gamma's through (u_s, g_s).
  void low_rank_step(double t_begin, double t_end, const State& x, State& x_next,
                     Rk4Workspace<ClosedLoop>& w, Outputs* outputs, Data& data) const {
    const double h = t_end - t_begin;
    step_signals(t_begin, t_end, w);
    const Eigen::Index head = gamma_offset(), tail = nu_offset(), rest = state_size() - tail;
    const auto stage = [&](const State& k, double c) {
      w.stage.head(head) = x.head(head) + c * k.head(head);
      w.stage.segment(tail, rest) = x.segment(tail, rest) + c * k.segment(tail, rest);
    };
    data.step_covariance = x.data() + gamma_offset();
    data.stage = 0;
    derivative(w.begin, x, w.k1, outputs, data);
    data.stage = 1;
    data.stage_scale = 0.5 * h;
    stage(w.k1, 0.5 * h);
    derivative(w.middle, w.stage, w.k2, nullptr, data);
    data.stage = 2;
    stage(w.k2, 0.5 * h);
    derivative(w.middle, w.stage, w.k3, nullptr, data);
    data.stage = 3;
    data.stage_scale = h;
    stage(w.k3, h);
    derivative(w.end, w.stage, w.k4, nullptr, data);
    data.stage = -1;
    const auto sum = [&](Eigen::Index begin, Eigen::Index size) {
      x_next.segment(begin, size) =
          x.segment(begin, size) +
          (h / 6.0) * (w.k1.segment(begin, size) + 2.0 * w.k2.segment(begin, size) +
                       2.0 * w.k3.segment(begin, size) + w.k4.segment(begin, size));
    };
    sum(0, head);
    sum(tail, rest);
    const Eigen::Vector4d& g = data.stage_gains;
    const Eigen::Vector4d c = (h / 6.0) * Eigen::Vector4d(g[0], 2.0 * g[1], 2.0 * g[2], g[3]);
    critic_.low_rank_update(covariance(x), data.stage_vectors, c, covariance(x_next), data.critic);
    next_step_signals(t_end, w);
  }

  // step() with gathered blocks in the dispatched kernels (lower_steps_): rk4_step's stages and
  // sum, Gamma's on its lower triangle alone. Each stage's dGamma is symmetric and flush() leaves
  // it in the lower triangle (Critic::Workspace::mirror_rate false); a stage's Gamma_s and
  // Gamma_next are summed there, coefficient by coefficient as rk4_step, then mirrored
  // (DenseKernels::mirror_lower): the same bits as rk4_step on the mirrored rates (Gamma is
  // symmetric bit for bit), a mirror per stage as before, half the sums over Gamma.
  void lower_step(double t_begin, double t_end, const State& x, State& x_next,
                  Rk4Workspace<ClosedLoop>& w, Outputs* outputs, Data& data) const {
    const double h = t_end - t_begin;
    step_signals(t_begin, t_end, w);
    const Eigen::Index k = basis_size(), head = gamma_offset(), tail = nu_offset();
    const Eigen::Index rest = state_size() - tail;
    // The state's parts apart from Gamma's upper triangle: [q, dq, Wc, Wa], Gamma's columns
    // from the diagonal down, [nu, J]; `sum` on each (offset, size), then Gamma mirrored.
    const DenseKernels& kernels = *critic_.kernels();
    const auto parts = [&](State& out, const auto& sum) {
      sum(0, head);
      for (Eigen::Index j = 0; j < k; ++j) sum(head + j * (k + 1), k - j);
      sum(tail, rest);
      kernels.mirror_lower(k, out.data() + head, k);
    };
    const auto stage = [&](const State& rate, double c) {
      parts(w.stage, [&](Eigen::Index begin, Eigen::Index size) {
        kernels.stage_sum(size, x.data() + begin, rate.data() + begin, c, w.stage.data() + begin);
      });
    };
    {
      // the stages' rates stay in the lower triangle; mirror_rate is true again when the block
      // ends, also should a derivative throw (any later evaluation of this Data then mirrors)
      struct LowerRates {
        bool& mirror_rate;
        ~LowerRates() { mirror_rate = true; }
      } lower_rates{data.critic.mirror_rate};
      lower_rates.mirror_rate = false;
      derivative(w.begin, x, w.k1, outputs, data);
      stage(w.k1, 0.5 * h);
      derivative(w.middle, w.stage, w.k2, nullptr, data);
      stage(w.k2, 0.5 * h);
      derivative(w.middle, w.stage, w.k3, nullptr, data);
      stage(w.k3, h);
      derivative(w.end, w.stage, w.k4, nullptr, data);
    }
    parts(x_next, [&](Eigen::Index begin, Eigen::Index size) {
      kernels.rk4_sum(size, x.data() + begin, w.k1.data() + begin, w.k2.data() + begin,
                      w.k3.data() + begin, w.k4.data() + begin, h / 6.0, x_next.data() + begin);
    });
    next_step_signals(t_end, w);
  }

  // One sample (the trajectory's or a point's) in the dispatched kernels: B^T [Wa, Wa - Wc] in
  // one pass over its B (K x n, `input_gradient`: the point's own or its block of the stacked
  // [B_1 ... B_N]), eqs. (20)-(21) from B^T Wa (evaluate_hjb_from_product), and B^T (Wa - Wc)
  // into times_difference for the actor's share. No heap allocation (bounded Joint storage).
  void evaluate_in_kernels(const Point& point, const double* input_gradient,
                           const Weights& critic_weights, const Weights& actor_weights,
                           const Weights& difference, Evaluation& out,
                           Joint& times_difference) const {
    const Eigen::Index n = dof(), k = basis_size();
    Joint times_actor_weights(n);
    times_difference.resize(n);
    critic_.kernels()->transposed_products(k, n, input_gradient, k, actor_weights.data(),
                                           difference.data(), times_actor_weights.data(),
                                           times_difference.data());
    evaluate_hjb_from_product(point, cost_, critic_weights, times_actor_weights, out,
                              critic_.kernels(), input_gradient);
  }

  // That sample's share of the actor's gradient (eq. 26) in the kernels: gradient -= B c with
  // c = Actor::gradient_coefficients of B^T (Wa - Wc) (evaluate_in_kernels).
  void actor_share_in_kernels(const double* input_gradient, const Joint& times_difference,
                              const Evaluation& e, double weight, Weights& actor_gradient) const {
    const Eigen::Index n = dof(), k = basis_size();
    const Joint coefficients = actor_.gradient_coefficients(
        times_difference, cost_.R_inverse(), cost_.bound(), e.u_hat, e.omega, e.error, weight);
    critic_.kernels()->product(k, 1, n, input_gradient, k, coefficients.data(), 1, n,
                               actor_gradient.data(), k, true);
  }

  // Dynamic sizes, prepared extrapolation points (Extrapolation::stacked()): each point's shares
  // of eqs. (20)-(21), (23)-(24) and (26) as the trajectory's (learn in derivative()), with the
  // points' B = [B_1 ... B_N] (K x nN) side by side; the critic gathers the points' omega
  // (critic.hpp).
  //   - With the dispatched kernels (dense_kernels.hpp): point by point, the three products with
  //     B_i (B_i^T [Wa, Wa - Wc], omega_i = F_i + B_i u_i, gradient -= B_i c_i) one after the
  //     other, while B_i (K x n) is in the first-level cache: one pass over B per evaluation.
  //   - Eigen's portable products: [B^T Wa, B^T (Wa - Wc)] as two matrix-vector products over all
  //     points, the actor's gradient one (gradient -= B [c_1; ...; c_N]).
  template <class Gamma, class GammaRate>
  void learn_from_stacked_points(const Weights& critic_weights, const Weights& actor_weights,
                                 const Weights& difference, const Gamma& gamma,
                                 Weights& critic_rate, GammaRate& gamma_rate,
                                 Weights& actor_gradient, Data& data) const {
    const Eigen::Index n = dof();
    const Eigen::MatrixXd& stacked = extrapolation_.stacked_input_gradients();
    const Eigen::Index k = stacked.rows();
    const DenseKernels* kernels = critic_.kernels();  // nullptr: Eigen's (dense_kernels.hpp)
    const double weight = 1.0 / static_cast<double>(extrapolation_.size());
    Evaluation e;
    if (kernels != nullptr) {
      if (!cost_.bounded()) {
        learn_from_points_batched(critic_weights, actor_weights, difference, gamma, critic_rate,
                                  gamma_rate, actor_gradient, data);
        return;
      }
      Joint times_difference;
      for (long i = 0; i < extrapolation_.size(); ++i) {
        const double* input_gradient = stacked.data() + i * n * k;  // B_i
        evaluate_in_kernels(extrapolation_.prepared(i), input_gradient, critic_weights,
                            actor_weights, difference, e, times_difference);
        critic_.gather(e.omega, e.error, gamma, weight, critic_rate, gamma_rate, data.critic);
        actor_share_in_kernels(input_gradient, times_difference, e, weight, actor_gradient);
      }
      return;
    }
    data.point_products.col(0).noalias() = stacked.transpose() * actor_weights;
    data.point_products.col(1).noalias() = stacked.transpose() * difference;
    for (long i = 0; i < extrapolation_.size(); ++i) {
      const Point& p = extrapolation_.prepared(i);
      const Joint times_actor_weights = data.point_products.col(0).segment(i * n, n);
      evaluate_hjb_from_product(p, cost_, critic_weights, times_actor_weights, e);
      critic_.gather(e.omega, e.error, gamma, weight, critic_rate, gamma_rate, data.critic);
      const Joint times_difference = data.point_products.col(1).segment(i * n, n);
      data.point_coefficients.segment(i * n, n) = actor_.gradient_coefficients(
          times_difference, cost_.R_inverse(), cost_.bound(), e.u_hat, e.omega, e.error, weight);
    }
    actor_gradient.noalias() -= stacked * data.point_coefficients;  // (26), all points
  }

  // learn_from_stacked_points with the dense kernels and no input bound: the same shares, the
  // products with B^T and R^-1 as one kernel call over all points:
  //   [B_i^T Wa, B_i^T (Wa - Wc)] = [B_1 ... B_N]^T [Wa, Wa - Wc]         (one product, nN x 2)
  //   R^-1 of both (n x 2N), -u_hat_i = 0.5 R^-1 B_i^T Wa                    (eq. 20)
  // then point by point, B_i (K x n) in the first-level cache for both of its products:
  //   omega_i = F_i - B_i (-u_hat_i), written straight into the critic's gathered block, with
  //   Wc^T omega_i and ||omega_i||^2 in the same pass (DenseKernels::point_regressor)
  //   u_hat_i^T R u_hat_i = 0.5 (-u_hat_i)^T B_i^T Wa                      (R R^-1 = I)
  //   eps_i = x_i^T Q x_i + u_hat_i^T R u_hat_i + Wc^T omega_i               (eq. 21)
  //   gradient -= B_i c_i                                                    (eq. 26)
  // B's rows that are zero at every point (Extrapolation::stacked_first_row: a structured basis'
  // e1 block, 21 of the UR5's 55 functions) are left out of all three products (omega_i = F_i
  // there).
  // Equal to the point-by-point path up to round-off (the sums associate differently).
  template <class Gamma, class GammaRate>
  void learn_from_points_batched(const Weights& critic_weights, const Weights& actor_weights,
                                 const Weights& difference, const Gamma& gamma,
                                 Weights& critic_rate, GammaRate& gamma_rate,
                                 Weights& actor_gradient, Data& data) const {
    typename Critic<Basis>::Workspace& block = data.critic;
    const long points = extrapolation_.size();
    const DenseKernels* kernels = critic_.kernels();
    const Eigen::MatrixXd& stacked = extrapolation_.stacked_input_gradients();
    const double* transposed = extrapolation_.stacked_transposed_data();  // nN x K, aligned
    const Eigen::Index stride = extrapolation_.stacked_transposed_stride();
    const Eigen::MatrixXd& drift_rates = extrapolation_.stacked_drift_rates();
    const Eigen::VectorXd& state_costs = extrapolation_.stacked_state_costs();
    const Eigen::Index n = dof(), k = stacked.rows(), columns = stacked.cols();
    // B's rows outside [first, first + rows) are zero at every point: skipped
    const Eigen::Index first = extrapolation_.stacked_first_row();
    const Eigen::Index rows = extrapolation_.stacked_row_count();
    const double weight = 1.0 / static_cast<double>(points);
    data.point_weights.col(0) = actor_weights;
    data.point_weights.col(1) = difference;
    kernels->product(columns, 2, rows, transposed + first * stride, stride,
                     data.point_weights.data() + first, 1, k, data.point_products.data(), columns,
                     false);
    kernels->product(n, 2 * points, n, cost_.R_inverse().data(), n, data.point_products.data(), 1,
                     n, data.point_projected.data(), n, false);
    data.point_inputs = 0.5 * data.point_projected.leftCols(points);  // -u_hat_i
    for (long i = 0; i < points; ++i) {  // B_i read once: omega_i, then the actor's B_i c_i
      const double* input_gradient = stacked.data() + i * n * k;  // B_i
      double* omega = block.omegas.col(block.gathered).data();
      // omega_i = F_i - B_i (-u_hat_i), value = Wc^T omega_i, norm = ||omega_i||^2
      double value = 0.0, norm = 0.0;
      kernels->point_regressor(k, first, rows, n, input_gradient, k,
                               data.point_inputs.col(i).data(), drift_rates.col(i).data(),
                               critic_weights.data(), omega, &value, &norm);
      const double input_cost =
          0.5 * data.point_inputs.col(i).dot(data.point_products.col(0).segment(i * n, n));
      const double error = state_costs[i] + input_cost + value;         // (21)
      const double scale = actor_.gradient_scale(error, norm, weight);  // (26)
      double* coefficients = data.point_coefficients.data() + i * n;
      for (Eigen::Index j = 0; j < n; ++j)
        coefficients[j] = scale * data.point_projected(j, points + i);
      kernels->product(rows, 1, n, input_gradient + first, k, coefficients, 1, n,
                       actor_gradient.data() + first, k, true);  // (26), point i
      block.coefficients[block.gathered] = error;
      block.weights[block.gathered] = weight;
      critic_.gathered(gamma, critic_rate, gamma_rate, block);  // (23)-(24)
    }
  }

  // Whether derivative() learns from the trajectory's sample and the stacked points through a
  // basis of pairs (learn_from_pairs): dynamic sizes, the dispatched kernels, no input bound, the
  // critic gathering and the points of a constant desired state side by side.
  bool learns_through_pairs() const {
    if constexpr (kBasisSize == Dynamic && HasPairs<Basis>::value)
      return critic_.kernels() != nullptr && !cost_.bounded() && gathers_ && controller_.learns() &&
             extrapolation_.pairs_stacked();
    return false;
  }

  // learn_from_points_batched for a basis of pairs (basis.hpp, HasPairs; dense_kernels.hpp,
  // PairPoints), with the trajectory's sample: no B = J_e2 M^-1 is read or formed. J_e2(x)^T w =
  // S(w) x, with S's rows gathering c_k w_k by the basis' terms, so B_i^T w = M_i^-T S(w) x_i;
  // B_i y = J_e2(x_i) (M_i^-1 y), two terms a row; and sum_i B_i c_i = the same terms of
  // sum_i x_i (M_i^-1 c_i)^T. For the UR5's 78 quadratic functions about a third of the multiply-
  // adds of the stacked B's products, over the points' x_i, M_i^-1 and F_i (57 KB at 50 points)
  // instead of the stacked B and its transpose (374 KB). The trajectory's sample (x, its drift f,
  // M^-1 and x^T Q x; weight 1) goes with them, in lane N (the stride leaves one free:
  // Extrapolation::pair_stride_for), its inputs and the last points' in the kernels' tail block,
  // F = J f from the terms (phi_k = c_k x_a x_b: F_k = c_k (f_a x_b + x_a f_b)): its basis is not
  // evaluated, its share of eq. (26) is in the points' sum; `hjb` gets its u_hat, input cost and
  // eps. Equal to learn_from_points_batched and the sample's own evaluation up to round-off (other
  // sums; the trajectory's sample now after the points in the critic's block).
  template <class MassInverse, class Gamma, class GammaRate>
  void learn_from_pairs(const Error& x, const Error& drift, const MassInverse& mass_inverse,
                        double state_cost, const Weights& critic_weights,
                        const Weights& actor_weights, const Weights& difference, const Gamma& gamma,
                        Weights& critic_rate, GammaRate& gamma_rate, Weights& actor_gradient,
                        Evaluation& hjb, Data& data) const {
    typename Critic<Basis>::Workspace& block = data.critic;
    const auto& pairs = basis_.pairs();
    const long points = extrapolation_.size();
    const Eigen::Index n = dof(), k = basis_size(), stride = extrapolation_.pair_stride();
    Eigen::MatrixXd& forms = data.pair_forms;
    forms.setZero();
    for (Eigen::Index r = 0; r < k; ++r)
      for (int t = 0; t < 2; ++t) {
        const int z = pairs.term_z[2 * r + t];
        if (z < 0) continue;
        const int v = pairs.term_x[2 * r + t];
        forms(z, v) += pairs.coefficient[r] * actor_weights[r];
        forms(n + z, v) += pairs.coefficient[r] * difference[r];
      }
    // the tail block: lanes tail_offset ... N - 1 of the points' arrays (copied once per
    // preparation of the points), the trajectory's in lane N (the lanes after it stay zero); F from
    // the terms (term_x[2k] = b, term_x[2k + 1] = a)
    constexpr long lanes = PairPoints::kTailLanes;
    const long tail_offset = points / lanes * lanes;
    const long used =
        data.pair_tail_generation == extrapolation_.generation() ? 0 : points - tail_offset;
    data.pair_tail_generation = extrapolation_.generation();
    const long lane = points - tail_offset;
    double* tail = data.pair_tail.data();
    const auto fill = [&](long entry, const double* points_entry, double trajectory) {
      for (long l = 0; l < used; ++l) tail[entry * lanes + l] = points_entry[tail_offset + l];
      tail[entry * lanes + lane] = trajectory;
    };
    const Eigen::Index nx = 2 * n, nm = n * n;
    for (Eigen::Index v = 0; v < nx; ++v) fill(v, extrapolation_.pair_states().col(v).data(), x[v]);
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index r = 0; r < n; ++r)
        fill(nx + r + c * n, extrapolation_.pair_mass_inverses().col(r + c * n).data(),
             mass_inverse(r, c));
    for (Eigen::Index r = 0; r < k; ++r) {
      const int b = pairs.term_x[2 * r], a = pairs.term_x[2 * r + 1];
      fill(nx + nm + r, extrapolation_.pair_drift_rates().col(r).data(),
           pairs.coefficient[r] * (drift[a] * x[b] + x[a] * drift[b]));
    }
    fill(nx + nm + k, extrapolation_.pair_state_costs().data(), state_cost);

    const double weight = 1.0 / static_cast<double>(points);
    const long samples = points + 1;
    // the samples' omega_i straight into the critic's block when it has room for all of them
    const bool room = block.gathered + samples <= Critic<Basis>::kBlock;
    PairPoints problem{n,
                       k,
                       samples,
                       stride,
                       extrapolation_.pair_states().data(),
                       extrapolation_.pair_mass_inverses().data(),
                       extrapolation_.pair_drift_rates().data(),
                       extrapolation_.pair_state_costs().data(),
                       forms.data(),
                       cost_.R_inverse().data(),
                       critic_weights.data(),
                       pairs.term_x.data(),
                       pairs.term_z.data(),
                       pairs.coefficient.data(),
                       data.pair_scratch.data(),
                       room ? block.omegas.col(block.gathered).data() : data.pair_omega.data(),
                       room ? block.omegas.outerStride() : data.pair_omega.outerStride(),
                       data.pair_error.data(),
                       data.pair_norm.data(),
                       data.pair_projected.data(),
                       data.pair_gains.data(),
                       data.pair_scale.data(),
                       data.pair_inputs.data()};
    problem.tail = tail;
    problem.tail_offset = tail_offset;
    const DenseKernels& kernels = *critic_.kernels();
    kernels.pair_points(problem);  // eqs. (20)-(21) at every point and the trajectory's x
    hjb.u_hat = -data.pair_inputs.row(points).transpose();
    hjb.input_cost = cost_.input_cost(hjb.u_hat);
    hjb.error = data.pair_error[points];
    for (long i = 0; i < samples; ++i) {
      if (!room) block.omegas.col(block.gathered) = data.pair_omega.col(i);
      block.coefficients[block.gathered] = data.pair_error[i];
      block.weights[block.gathered] = i < points ? weight : 1.0;
      critic_.gathered(gamma, critic_rate, gamma_rate, block);  // (23)-(24)
    }
    kernels.pair_gradient(problem, data.pair_products.data());
    for (Eigen::Index r = 0; r < k; ++r) {  // (26), all samples: gradient -= sum_i B_i c_i
      double along = 0.0;
      for (int t = 0; t < 2; ++t) {
        const int z = pairs.term_z[2 * r + t];
        if (z >= 0) along += data.pair_products(pairs.term_x[2 * r + t], z);
      }
      actor_gradient[r] -= pairs.coefficient[r] * along;
    }
  }

  template <class Local>
  static Terms& pick_terms(Local& local, Terms& buffer) {
    if constexpr (kFixed)
      return local;
    else
      return buffer;
  }

  const ErrorSystem<Arm>& believed_system(const Data& data) const {
    if constexpr (kIdentifies) {
      if (identifies_) return *data.believed;
    }
    return error_system_;
  }

  static IdentifierType make_identifier(const Settings& settings, const Arm& model) {
    if constexpr (kIdentifies) {
      if (!settings.identifier.enabled) return IdentifierType();
      using Regressor = typename IdentifierType::RegressorType;
      return IdentifierType(settings.identifier, Regressor::of(model), model, settings.sim.dt);
    } else {
      if (settings.identifier.enabled)
        throw std::invalid_argument(
            "identifier.enabled: this arm has no regressor for the online identifier "
            "(identifier.hpp: IdentifierOf)");
      return IdentifierType();
    }
  }

  static Eigen::Index checked_dof(const Arm& plant, const Arm& model, const Basis& basis) {
    const Eigen::Index n = plant.dof();
    if (model.dof() != n)
      throw std::invalid_argument("model: the believed arm has " + std::to_string(model.dof()) +
                                  " joints, the plant " + std::to_string(n));
    check_dimensions(n, basis.size());
    return n;
  }

  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  // n limits > 0 (+inf: none on that joint), or none (empty: +inf on every joint).
  static Joint checked_torque_limits(const Eigen::VectorXd& limits, Eigen::Index n) {
    if (limits.size() == 0) return Joint::Constant(n, kInfinity);
    check_size(limits, n, 1, "plant.torque_limits");
    for (Eigen::Index i = 0; i < n; ++i)
      if (!(limits[i] > 0.0))  // NaN fails too
        throw std::invalid_argument("plant.torque_limits: joint " + std::to_string(i + 1) +
                                    ": each limit must be > 0 (N m; inf: no limit)");
    return limits;
  }

  static JointMatrix<kDof> checked_alpha1(const Settings& settings, Eigen::Index n) {
    check_size(settings.control.alpha1, n, n, "control.alpha1");
    check_finite(settings.control.alpha1, "control.alpha1");
    check_hurwitz(settings.control.alpha1);
    return settings.control.alpha1;
  }

  Arm plant_;
  bool model_is_plant_;
  Basis basis_;
  Eigen::Index dof_;
  Eigen::Index basis_size_;
  ErrorSystem<Arm> error_system_;
  QuadraticCostT<kDof> cost_;
  Critic<Basis> critic_;
  Actor<Basis, kDof> actor_;
  ControllerT<kDof> controller_;
  TrajectoryT<kDof> trajectory_;
  Extrapolation<Arm, Basis> extrapolation_;
  RiseT<kDof> rise_;
  SinusoidalDisturbanceT<kDof> disturbance_;
  ProbingSignalT<kDof> probe_;
  Joint torque_limits_;  // +inf where a joint has no limit
  bool limited_;
  bool anti_windup_;
  // Dynamic sizes: the critic gathers the samples of an evaluation (critic.hpp) when there are
  // extrapolation points, more than 24 functions or dispatched kernels (measured: a lone sample
  // of 8-21 functions 1.02-1.10x faster per step in the kernels than in add_rates); on the
  // portable path a small lone sample goes through add_rates, whose coefficient-wise products
  // beat a call of Eigen's matrix-vector kernel.
  bool gathers_;
  IdentifierType identifier_;  // the online identifier (identifier.hpp; disabled by default)
  bool identifies_;
  bool low_rank_;     // step() takes low-rank steps (low_rank_steps())
  bool lower_steps_;  // step() sums Gamma's lower triangle alone (lower_step)
  bool vector_;       // derivative() runs vector_derivative (kVectorLoop on an AVX-512 CPU)
  State initial_state_;
};

using PaperClosedLoop = ClosedLoop<TwoLinkArm, PaperBasis>;

}  // namespace adparm
