// Standalone benchmark of the paper's closed loop (no Python, no test framework).
//
// Usage: adparm_bench [--checks] [simulated_seconds] [extrapolation_points ...]
//   default: 110 s (the paper's claim time) and N = 0, 10, 50 points.
//        adparm_bench --urdf [simulated_seconds] [extrapolation_points ...]
//   only the URDF arms in the closed loop (below); default 2 s and N = 0, 50.
// Each N runs the paper's settings (paper_settings(), the basis adparm.paper_config() uses) for
// the given horizon, three times; the fastest run is reported. With points (fixed, drawn in
// [-1, 1]^4) the probing signal stays on, so the loop does the paper's work plus the points'.
// Then 16 independent paper runs go through Batch on 1 and on 2 threads.
//
// One machine-readable line per measurement (key=value, space separated):
//   bench=paper_loop points=N steps=n repeats=3 ns_per_step=x steps_per_second=y
//     ns_per_point_step=z heap_allocations=a final_critic_error=e status=finished
//   bench=limited_loop limits=60,15 steps=n repeats=3 ns_per_step=x unlimited_ns_per_step=y
//     ratio=x/y heap_allocations=0 status=finished
//     the paper loop with actuator limits (Settings::torque_limits) against it without,
//     alternating in the same invocation
//   bench=dynamic_two_link points=N steps=n repeats=3 ns_per_step=x heap_allocations=0 ...
//     the same runs through the dynamic-size loop (Settings::dynamic_sizes)
//   bench=expression_quadratic functions=10 points=0 steps=n repeats=3 ns_per_step=x
//     heap_allocations=0 ... the paper run with the quadratic expression basis (dynamic sizes)
//   bench=bounded_loop sizes=S points=0 steps=n repeats=3 ns_per_step=x unbounded_ns_per_step=y
//     ratio=r heap_allocations=0 ... the paper run with an input bound (input_bound.hpp)
//   bench=batch runs=16 steps=n threads=t seconds=s ns_per_step=x speedup=r identical=1
//   bench=pinocchio_arm arm=NAME dof=n computes=c ns_per_compute=x heap_allocations=a
//     PinocchioArm::compute (M, C, G, M^-1, F through Pinocchio) on examples/arms/planar_3link.urdf
//     and example-robot-data's UR5 (skipped=... when that package is not found at build time);
//     any heap allocation inside compute fails the bench.
//   bench=urdf_loop arm=NAME dof=n basis=B functions=K points=N steps=s repeats=3
//     ns_per_step=x heap_allocations=0 status=finished
//     the closed loop of a URDF arm (PinocchioArm, dynamic sizes) with the quadratic expression
//     basis (B = quadratic) and the structured basis (B = structured, PinocchioStructuredBasis),
//     a set-point and N fixed extrapolation points (urdf_settings below): the planar 3-link arm
//     and the UR5, N = 0 and 50, over min(simulated_seconds, 2 s); a run that does not finish or
//     allocates in its steps fails the bench. bench/urdf_speed.py times the same 3-link cases in
//     NumPy + Pinocchio's Python bindings against these lines. After each, its profile:
//   bench=urdf_profile arm=NAME basis=B points=N ns_per_step=x arm_computes_per_step=c
//     arm_terms_ns_per_step=a basis_pinocchio_ns_per_step=b pinocchio_share=(a+b)/x
//     heap_allocations_per_step=0 measured=replayed_states
//     the share of the step spent in Pinocchio, measured by replaying: one more run of the same
//     case records (q, dq) of every arm compute() of its steps (c per RK4 step: one per stage;
//     a recorded row reuses the next step's first stage), then PinocchioArm::compute (M, C, G,
//     M^-1, F) is timed over those states alone (a), and for the structured basis its Pinocchio
//     pass (computeJointJacobiansTimeVariation, PinocchioStructuredBasis::pinocchio_passes) at the
//     same states (b; 0 for the quadratic basis, and for the structured basis when it reuses the
//     arm's kinematics, as the loop's does), fastest of 3 each, divided by the loop's best
//     step time x. Before them
//   bench=dense_kernels name=avx512|avx2|portable single_sample=avx512|avx2|portable
//     the critic's dense kernels these loops run with points (name) and without (single_sample)
//     (dense_kernels.hpp; ADPARM_KERNELS chooses).
// ns_per_point_step = (ns_per_step(N) - ns_per_step(0)) / N, from the same invocation.
// heap_allocations counts malloc calls during the timed loop (bench/heap_counter.hpp: glibc's
// malloc interposed, or AddressSanitizer's allocation hook; -1 elsewhere).
//
// --checks (for bench/sanitize.sh, untimed) then also runs what the measurements leave out, over
// the same horizon, and exits 1 if any check fails:
//   bench=check run=NAME status=S steps=n rows=r ok=1
//     each in chunks of 7 and 13 steps, compared bit for bit with a one-shot run: local and grid
//     extrapolation points, the paper basis with a model error, sinusoid and spline tracking with
//     points, the structured basis tracking with points, the rise, pd and optimal controllers, a
//     run that diverges (dt = 4 ms); then dynamic-size runs (Settings::dynamic_sizes) the same way;
//   bench=check run=dynamic_vs_fixed points=N rows=r difference=d ok=1
//     the paper run (and tracking with 6 points) through both paths: max relative difference
//     <= 1e-9 (round-off of differently associated sums, amplified by the learning laws);
//   bench=check run=batch_threads ... 16 runs on 3 worker threads against one by one;
//   bench=check run=batch_stream_stop ... the same runs streamed (window 2), stopped after 4 ended;
//     the part-way and unstarted runs, advanced to the end, equal one-by-one runs;
//   bench=checks invalid_settings=k refused=k failed=f
//     k invalid Settings (and a Batch with one, and threads = 0), each expected to throw
//     std::invalid_argument; f counts the failures of the whole section;
//   bench=check run=dense_kernels set=avx2|avx512 shapes=n failed=f ok=1
//     the dense kernels of each set this CPU runs on random shapes, against plain loops and their
//     bit-for-bit claims (bench/dense_kernel_checks.hpp);
//   bench=check run=lower_step arm=A basis=B steps=n ok=1
//     ClosedLoop::step with gathered blocks in the kernels (lower_step: Gamma summed on its lower
//     triangle) equal bit for bit to rk4_step, step after step.
#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "adparm/any_simulation.hpp"
#include "adparm/batch.hpp"
#include "adparm/dense_kernels.hpp"
#include "adparm/pinocchio_arm.hpp"
#include "adparm/pinocchio_structured_basis.hpp"
#include "adparm/urdf_loop_arm.hpp"
#include "dense_kernel_checks.hpp"
#include "heap_counter.hpp"
#include "plain_port.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

const char* status_name(adparm::RunStatus status) {
  switch (status) {
    case adparm::RunStatus::finished:
      return "finished";
    case adparm::RunStatus::diverged:
      return "diverged";
    default:
      return "running";
  }
}

struct LoopTiming {
  long steps = 0;
  double seconds = 0.0;
  long heap_allocations = -1;
  double critic_error = 0.0;
  adparm::RunStatus status = adparm::RunStatus::running;
};

// ||Wc - W*|| / ||W*|| with the paper's W* (ERRATA), at the end of the run.
double critic_error(const adparm::AnySimulation& simulation) {
  if (simulation.state().size() != adparm::PaperClosedLoop::kStateSize)
    return std::numeric_limits<double>::quiet_NaN();  // another basis: no known W*
  Eigen::Matrix<double, 8, 1> optimal;
  optimal << 4, 6, -8, 5, 2, 1, 2, 2;
  const Eigen::VectorXd weights =
      simulation.state().segment(adparm::PaperClosedLoop::kCriticWeights, 8);
  return (weights - optimal).norm() / optimal.norm();
}

// The quadratic expression basis (all x_i x_j, i <= j: 10 functions for two joints), as
// python/adparm/bases.py compiles "quadratic", with the initial weights of x^T blockdiag(I, M(0)) x
// on the paper's arm (M(0) = [[7, 2], [2, 1]]).
void use_quadratic_expression_basis(adparm::Settings& s) {
  using Op = adparm::ExpressionOp;
  s.basis = adparm::BasisKind::expression;
  s.basis_program = {};
  const auto add = [&](Op op, double argument) {
    s.basis_program.opcodes.push_back(static_cast<int>(op));
    s.basis_program.arguments.push_back(argument);
  };
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) {
      add(Op::variable, i);
      if (i == j) {
        add(Op::power, 2.0);
      } else {
        add(Op::variable, j);
        add(Op::multiply, 0.0);
      }
      add(Op::store, 0.0);
    }
  s.critic_weights.resize(10);  // (0,0) (0,1) (0,2) (0,3) (1,1) (1,2) (1,3) (2,2) (2,3) (3,3)
  s.critic_weights << 1, 0, 0, 0, 1, 0, 0, 7, 4, 1;
  s.actor_weights = s.critic_weights;
}

// One whole run of `simulation`, timed, its heap allocations counted.
template <class Simulation>
LoopTiming time_run(Simulation& simulation) {
  LoopTiming timing;
  start_counting();
  const auto start = Clock::now();
  timing.steps = simulation.advance(simulation.steps());
  timing.seconds = seconds_since(start);
  timing.heap_allocations = stop_counting();
  timing.status = simulation.status();
  return timing;
}

LoopTiming time_loop(const adparm::Settings& settings) {
  adparm::AnySimulation simulation(settings);
  LoopTiming timing = time_run(simulation);
  timing.critic_error = critic_error(simulation);
  return timing;
}

double time_batch(const std::vector<adparm::Settings>& settings, int threads,
                  std::vector<Eigen::VectorXd>& final_states) {
  adparm::Batch<adparm::AnySimulation> batch(settings);
  const auto start = Clock::now();
  const auto runs = batch.run_all(threads);
  const double seconds = seconds_since(start);
  final_states.clear();
  for (const auto& run : runs) final_states.push_back(run->state());
  return seconds;
}

// PinocchioArm::compute at states that change every call, fastest of 3 repeats.
bool time_pinocchio_arm(const char* name, const std::string& path) {
  const adparm::PinocchioArm arm(path, Eigen::Vector3d(0.0, 0.0, -9.81),
                                 Eigen::VectorXd::Constant(1, 0.1),
                                 Eigen::VectorXd::Constant(1, 0.2));
  adparm::PinocchioArm::Terms terms = arm.make_terms();
  Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(arm.dof(), -0.5, 0.7);
  Eigen::VectorXd dq = Eigen::VectorXd::LinSpaced(arm.dof(), 0.3, -0.4);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(arm.dof()), ddq = tau;
  constexpr long computes = 20000;
  double best = 0.0;
  long heap_allocations = -1;
  double checksum = 0.0;
  for (int r = 0; r < 3; ++r) {
    start_counting();
    const auto start = Clock::now();
    for (long i = 0; i < computes; ++i) {
      q.array() += 1e-4;
      arm.compute(q, dq, terms);
      arm.acceleration(terms, dq, tau, tau, ddq);
      checksum += ddq[0];
    }
    const double seconds = seconds_since(start);
    heap_allocations = std::max(heap_allocations, stop_counting());
    if (r == 0 || seconds < best) best = seconds;
  }
  // A copy has its own work space and gives the same terms.
  const adparm::PinocchioArm copy = arm;
  adparm::PinocchioArm::Terms copy_terms = copy.make_terms();
  arm.compute(q, dq, terms);
  copy.compute(q, dq, copy_terms);
  const bool same = copy_terms.mass == terms.mass && copy_terms.coriolis == terms.coriolis &&
                    copy_terms.gravity == terms.gravity &&
                    copy_terms.mass_inverse == terms.mass_inverse &&
                    copy_terms.friction == terms.friction;
  if (!same) std::fprintf(stderr, "check failed: a copy of the %s arm gives other terms\n", name);
  std::printf(
      "bench=pinocchio_arm arm=%s dof=%d computes=%ld ns_per_compute=%.1f heap_allocations=%ld "
      "finite=%d\n",
      name, arm.dof(), computes, 1e9 * best / computes, heap_allocations,
      std::isfinite(checksum) ? 1 : 0);
  std::fflush(stdout);
  return heap_allocations <= 0 && std::isfinite(checksum) && same;
}

bool time_pinocchio_arms() {
  bool ok = time_pinocchio_arm("planar_3link", std::string(ADPARM_ARMS_DIR) + "/planar_3link.urdf");
  const std::string robots = ADPARM_ROBOTS_DIR;
  if (robots.empty()) {
    std::printf("bench=pinocchio_arm arm=ur5 skipped=example-robot-data_not_found\n");
  } else {
    ok = time_pinocchio_arm("ur5", robots + "/ur_description/urdf/ur5_robot.urdf") && ok;
  }
  return ok;
}

// URDF arms in the closed loop ------------------------------------------------------------------
//
// The core's loop arm of a URDF (urdf_loop_arm.hpp: PinocchioArm behind the Arm concept).
using LoopArm = adparm::UrdfLoopArm;

// Simulated seconds of each URDF loop case (its own default: a step of the 6-joint arm with 50
// points costs about a thousand paper steps).
constexpr double kUrdfHorizon = 2.0;

// The quadratic expression basis of n joints: every x_i x_j (i <= j) of x = [e1; e2] (2n), in
// the order of python/adparm/bases.py's quadratic_terms (21 functions for 3 joints, 78 for 6).
adparm::ExpressionProgram quadratic_program(int joints) {
  using Op = adparm::ExpressionOp;
  adparm::ExpressionProgram program;
  const auto add = [&](Op op, double argument) {
    program.opcodes.push_back(static_cast<int>(op));
    program.arguments.push_back(argument);
  };
  for (int i = 0; i < 2 * joints; ++i)
    for (int j = i; j < 2 * joints; ++j) {
      add(Op::variable, i);
      if (i == j) {
        add(Op::power, 2.0);
      } else {
        add(Op::variable, j);
        add(Op::multiply, 0.0);
      }
      add(Op::store, 0.0);
    }
  return program;
}

// A basis of the URDF loop cases: its name, the basis for an arm, and the weights of
// x^T blockdiag(I, M(qd)) x (qd = 0), the default initial value of Python's expression bases
// (the actor then starts at u_hat = -R^-1 e2, which stabilises). Another basis is another such
// struct and one line in run_urdf_loops() (StructuredCase below).
struct QuadraticCase {
  using Basis = adparm::ExpressionLoopBasis;
  static const char* name() { return "quadratic"; }
  static Basis basis(const adparm::PinocchioArm& arm) {
    return Basis(arm.dof(), quadratic_program(arm.dof()));
  }
  static Eigen::VectorXd initial_weights(const adparm::PinocchioArm& arm) {
    const int n = arm.dof();
    adparm::PinocchioArm::Terms terms = arm.make_terms();
    arm.compute(Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n), terms);
    Eigen::MatrixXd P = Eigen::MatrixXd::Identity(2 * n, 2 * n);
    P.bottomRightCorner(n, n) = terms.mass;
    Eigen::VectorXd weights(n * (2 * n + 1));
    Eigen::Index k = 0;
    for (int i = 0; i < 2 * n; ++i)
      for (int j = i; j < 2 * n; ++j) weights[k++] = i == j ? P(i, i) : P(i, j) + P(j, i);
    return weights;
  }
};

// The structured basis of the arm (pinocchio_structured_basis.hpp: e1_i e1_j and e2^T M_b(q) e2
// per base inertial parameter; 13 functions on the planar 3-link arm, 55 on the UR5), from
// Python's default initial weights, W* = [entries of K = I; the arm's base parameters]
// (optimal_weights(I)), exact under urdf_settings' cost.
struct StructuredCase {
  using Basis = adparm::PinocchioStructuredBasis;
  static const char* name() { return "structured"; }
  static Basis basis(const adparm::PinocchioArm& arm) { return Basis(arm); }
  static Eigen::VectorXd initial_weights(const adparm::PinocchioArm& arm) {
    return Basis(arm).optimal_weights(Eigen::MatrixXd::Identity(arm.dof(), arm.dof()));
  }
};

// The settings of the URDF loop cases (n joints; bench/urdf_speed.py builds the same for its
// NumPy + Pinocchio loop): a set-point qd = 0 from q0 = 0.2 rad on every joint at rest, no RISE
// (controller.rise = false), no probing signal, no disturbance, K = I, alpha1 = 2 I, R = I and
// the cost under which V* = e1^T K e1 + e2^T M(q) e2 is exact (Q11 = K alpha1 + alpha1^T K,
// Q12 = -K, Q22 = R^-1), the paper's actor gains (eta_a1 = 0.01, eta_a2 = 1) and critic gains
// (nu = 1, gamma0 = 100) except eta_c = 1 (with the paper's 800 the quadratic basis, which cannot
// represent V* = e1^T K e1 + e2^T M(q) e2, diverges within 1.3 s on the 3-link arm; a step's work
// does not depend on the gains), epsilon_T = 1e-3 (Python's default with extrapolation), N fixed
// extrapolation points in [-1, 1]^2n (seed 0), RK4 at dt = 1 ms.
adparm::Settings urdf_settings(int n, long points, double horizon) {
  adparm::Settings s = adparm::paper_settings();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  s.disturbance = Eigen::VectorXd::Zero(n);
  s.task.q0 = Eigen::VectorXd::Constant(n, 0.2);
  s.task.dq0 = Eigen::VectorXd::Zero(n);
  s.task.qd.offset = Eigen::VectorXd::Zero(n);
  s.control.alpha1 = 2.0 * I;
  s.R = I;
  s.Q.resize(2 * n, 2 * n);
  s.Q << 4.0 * I, -I, -I, I;
  s.controller.rise = false;
  s.controller.kp = 50.0 * I;
  s.controller.kd = 10.0 * I;
  s.probe.until = 0.0;
  s.probe.frequencies.resize(0);
  s.probe.amplitude.resize(n, 0);
  s.probe.phases.resize(n, 0);
  s.critic.eta_c = 1.0;
  s.critic.epsilon_T = 1e-3;
  s.extrapolation.points = points;
  s.extrapolation.box = Eigen::VectorXd::Ones(2 * n);
  s.extrapolation.mode = adparm::ExtrapolationMode::fixed;
  s.extrapolation.seed = 0;
  s.sim.T = horizon;
  return s;
}

// The loop arm of the cases' profile (below): UrdfLoopArm, appending q and dq of every compute()
// call to `calls` (reserved before the run; the run that records is not timed).
class RecordingArm : public LoopArm {
 public:
  RecordingArm(const LoopArm& arm, std::vector<double>* calls) : LoopArm(arm), calls_(calls) {}
  void compute(const Joint& q, const Joint& dq, Terms& terms) const {
    calls_->insert(calls_->end(), q.data(), q.data() + q.size());
    calls_->insert(calls_->end(), dq.data(), dq.data() + dq.size());
    LoopArm::compute(q, dq, terms);
  }

 private:
  std::vector<double>* calls_;
};

// The Pinocchio part of a case's step, replayed: the (q, dq) of every arm compute() of a run
// through the same loop (recorded by RecordingArm; the loop is deterministic, so these are the
// timed runs' states), then PinocchioArm::compute (M, C, G, M^-1, F) over them, and for the
// structured basis its Pinocchio passes (PinocchioStructuredBasis::pinocchio_passes) at the same
// states' x = [e1; e2] (the loop evaluates the basis once per compute(); fixed points are
// prepared before the run) when it runs them (not when it reuses the arm's kinematics: 0), each
// the fastest of `repeats`. Seconds per run.
struct PinocchioReplay {
  long calls = 0;  // -1: the recording run stopped early (reported, not replayed)
  double arm_seconds = 0.0;
  double basis_seconds = 0.0;
};

template <class Case>
PinocchioReplay replay_pinocchio(const adparm::Settings& settings, const adparm::PinocchioArm& arm,
                                 const typename Case::Basis& basis, int repeats) {
  using Simulation = adparm::Simulation<RecordingArm, typename Case::Basis>;
  const int n = arm.dof();
  std::vector<double> calls;
  const RecordingArm recording_arm(LoopArm(arm), &calls);
  Simulation simulation(settings, recording_arm, recording_arm, true, basis);
  calls.clear();  // the fixed points' preparation, before the run
  calls.reserve(static_cast<std::size_t>(2 * n) * 5 * static_cast<std::size_t>(simulation.steps()));
  simulation.advance(simulation.steps());
  PinocchioReplay replay;
  const long steps = simulation.step();
  const adparm::RunStatus status = simulation.status();
  replay.calls = static_cast<long>(calls.size()) / (2 * n);
  if (steps != simulation.steps() || status != adparm::RunStatus::finished) {
    std::printf("bench=urdf_profile recording_run steps=%ld of=%ld status=%s calls=%ld failed=1\n",
                steps, simulation.steps(), status_name(status), replay.calls);
    replay.calls = -1;
    return replay;
  }
  adparm::PinocchioArm::Terms terms = arm.make_terms();
  Eigen::VectorXd x(2 * n);
  const Eigen::VectorXd qd = settings.task.qd.offset;  // constant: dqd = 0
  double checksum = 0.0;
  for (int r = 0; r < repeats; ++r) {
    auto start = Clock::now();
    for (long i = 0; i < replay.calls; ++i) {
      const Eigen::Map<const Eigen::VectorXd> q(calls.data() + 2 * n * i, n);
      const Eigen::Map<const Eigen::VectorXd> dq(calls.data() + 2 * n * i + n, n);
      arm.compute(q, dq, terms);
      checksum += terms.mass_inverse(0, 0);
    }
    double seconds = seconds_since(start);
    if (r == 0 || seconds < replay.arm_seconds) replay.arm_seconds = seconds;
    // the structured basis runs a Pinocchio pass of its own unless it reuses the arm's kinematics
    // (PinocchioStructuredBasis::shares_kinematics: the loop's case; then 0)
    if constexpr (std::is_same_v<typename Case::Basis, adparm::PinocchioStructuredBasis>) {
      if (basis.shares_kinematics(arm)) continue;
      auto workspace = basis.workspace();
      start = Clock::now();
      for (long i = 0; i < replay.calls; ++i) {
        const Eigen::Map<const Eigen::VectorXd> q(calls.data() + 2 * n * i, n);
        const Eigen::Map<const Eigen::VectorXd> dq(calls.data() + 2 * n * i + n, n);
        x.head(n) = qd - q;                                     // e1
        x.tail(n) = -dq + settings.control.alpha1 * x.head(n);  // e2 (dqd = 0)
        basis.pinocchio_passes(x, qd, workspace);
      }
      seconds = seconds_since(start);
      if (r == 0 || seconds < replay.basis_seconds) replay.basis_seconds = seconds;
    }
  }
  if (!std::isfinite(checksum)) replay.calls = -1;
  return replay;
}

// The settings of a case: urdf_settings with the basis' initial weights.
template <class Case>
adparm::Settings case_settings(const adparm::PinocchioArm& arm, long points, double horizon) {
  adparm::Settings settings = urdf_settings(arm.dof(), points, horizon);
  settings.critic_weights = Case::initial_weights(arm);
  settings.actor_weights = settings.critic_weights;
  return settings;
}

// The timed runs of a case (best of `repeats`, into `best`) and its bench=urdf_loop line. Not
// inlined: bench/compare_urdf.py's callgrind mode counts the instructions of each call alone.
template <class Case>
[[gnu::noinline]] bool time_urdf_loop(const char* arm_name, const adparm::PinocchioArm& arm,
                                      long points, double horizon, int repeats, LoopTiming& best) {
  using Simulation = adparm::Simulation<LoopArm, typename Case::Basis>;
  const adparm::Settings settings = case_settings<Case>(arm, points, horizon);
  const LoopArm loop_arm(arm);
  const typename Case::Basis basis = Case::basis(arm);
  for (int r = 0; r < repeats; ++r) {
    Simulation simulation(settings, loop_arm, loop_arm, true, basis);
    const LoopTiming timing = time_run(simulation);
    if (r == 0 || timing.seconds < best.seconds) best = timing;
  }
  std::printf(
      "bench=urdf_loop arm=%s dof=%d basis=%s functions=%d points=%ld steps=%ld repeats=%d "
      "ns_per_step=%.1f heap_allocations=%ld status=%s\n",
      arm_name, arm.dof(), Case::name(), basis.size(), points, best.steps, repeats,
      1e9 * best.seconds / std::max(best.steps, 1L), best.heap_allocations,
      status_name(best.status));
  std::fflush(stdout);
  return best.status == adparm::RunStatus::finished && best.heap_allocations <= 0;
}

// The bench=urdf_profile line of a case timed by time_urdf_loop (`best`): Pinocchio's calls
// replayed (replay_pinocchio) and the heap allocations per step.
template <class Case>
bool profile_urdf_loop(const char* arm_name, const adparm::PinocchioArm& arm, long points,
                       double horizon, int repeats, const LoopTiming& best) {
  const adparm::Settings settings = case_settings<Case>(arm, points, horizon);
  const typename Case::Basis basis = Case::basis(arm);
  const PinocchioReplay replay = replay_pinocchio<Case>(settings, arm, basis, repeats);
  const double steps = static_cast<double>(std::max(best.steps, 1L));
  std::printf(
      "bench=urdf_profile arm=%s basis=%s points=%ld ns_per_step=%.1f arm_computes_per_step=%.2f "
      "arm_terms_ns_per_step=%.1f basis_pinocchio_ns_per_step=%.1f pinocchio_share=%.3f "
      "heap_allocations_per_step=%g measured=replayed_states\n",
      arm_name, Case::name(), points, 1e9 * best.seconds / steps,
      static_cast<double>(replay.calls) / steps, 1e9 * replay.arm_seconds / steps,
      1e9 * replay.basis_seconds / steps,
      (replay.arm_seconds + replay.basis_seconds) / best.seconds,
      best.heap_allocations < 0 ? -1.0 : static_cast<double>(best.heap_allocations) / steps);
  std::fflush(stdout);
  return replay.calls > 0;
}

template <class Case>
bool time_and_profile_urdf_loop(const char* arm_name, const adparm::PinocchioArm& arm, long points,
                                double horizon, int repeats) {
  LoopTiming best;
  const bool timed = time_urdf_loop<Case>(arm_name, arm, points, horizon, repeats, best);
  return profile_urdf_loop<Case>(arm_name, arm, points, horizon, repeats, best) && timed;
}

// The planar 3-link arm (examples/arms) and example-robot-data's UR5 in the closed loop, each
// with every N of `point_counts`. Friction: viscous 0.1 N m s / rad on every joint, no Coulomb;
// gravity [0, 0, -9.81].
bool run_urdf_loops(double horizon, const std::vector<long>& point_counts, int repeats) {
  std::vector<std::pair<const char*, std::string>> arms = {
      {"planar_3link", std::string(ADPARM_ARMS_DIR) + "/planar_3link.urdf"}};
  const std::string robots = ADPARM_ROBOTS_DIR;
  if (robots.empty())
    std::printf("bench=urdf_loop arm=ur5 skipped=example-robot-data_not_found\n");
  else
    arms.emplace_back("ur5", robots + "/ur_description/urdf/ur5_robot.urdf");
  std::printf("bench=dense_kernels name=%s single_sample=%s\n",
              adparm::dense_kernels_name(adparm::select_dense_kernels(true)),
              adparm::dense_kernels_name(adparm::select_dense_kernels(false)));
  bool ok = true;
  // e.g. "ur5:quadratic" (both point counts) or "ur5:quadratic:0" (one case, for profiling)
  const char* only = std::getenv("ADPARM_BENCH_ONLY");
  const auto wanted = [&](const char* arm_name, const char* basis, long points) {
    if (only == nullptr) return true;
    const std::string name = std::string(arm_name) + ":" + basis;
    return only == name || only == name + ":" + std::to_string(points);
  };
  for (const auto& [name, path] : arms) {
    const adparm::PinocchioArm arm(path, Eigen::Vector3d(0.0, 0.0, -9.81), Eigen::VectorXd(),
                                   Eigen::VectorXd::Constant(1, 0.1));
    for (const long points : point_counts) {
      if (wanted(name, "quadratic", points))
        ok = time_and_profile_urdf_loop<QuadraticCase>(name, arm, points, horizon, repeats) && ok;
      if (wanted(name, "structured", points))
        ok = time_and_profile_urdf_loop<StructuredCase>(name, arm, points, horizon, repeats) && ok;
    }
  }
  return ok;
}

// --checks ------------------------------------------------------------------------------------

int failures = 0;

void fail(const std::string& what) {
  ++failures;
  std::fprintf(stderr, "check failed: %s\n", what.c_str());
}

bool same(const adparm::Recording& a, const adparm::Recording& b) {
  bool equal = a.rows == b.rows;
  for (const adparm::RecordedSeries& series : adparm::kRecordedSeries)
    equal = equal && a.*series.member == b.*series.member;
  return equal;
}

// Runs `settings` in chunks of 7 and 13 steps in turn (chunks end on recorded rows and between
// them) and in one go; both must give the same state and recording, with the expected status.
void check_run(const char* name, const adparm::Settings& settings, adparm::RunStatus expected) {
  adparm::AnySimulation whole(settings), chunked(settings);
  whole.advance(whole.steps());
  for (long chunk = 7; chunked.status() == adparm::RunStatus::running; chunk = 20 - chunk)
    chunked.advance(chunk);
  const adparm::Recording recording = chunked.recording();
  const bool finite = chunked.state().allFinite() && recording.q.allFinite() &&
                      recording.critic_weights.allFinite() && recording.cost.allFinite();
  const bool ok = chunked.status() == expected && whole.status() == expected &&
                  chunked.state() == whole.state() && same(recording, whole.recording()) &&
                  chunked.reset_times() == whole.reset_times() && finite && recording.rows > 1;
  std::printf("bench=check run=%s status=%s steps=%ld rows=%ld ok=%d\n", name,
              status_name(chunked.status()), chunked.step(), static_cast<long>(recording.rows),
              ok ? 1 : 0);
  std::fflush(stdout);
  if (!ok) fail(name);
}

// The plain port (bench/plain_port.cpp) against adparm's paper loop over max(horizon, 2 s): the
// same reset times and, per block of the state (q, dq, Wc, Wa, Gamma, nu, J), the largest
// difference relative to the block's largest entry at most 1e-9 (round-off of differently
// written sums, amplified by the critic: Gamma falls from gamma0 = 100 to epsilon_T = 1e-6 within
// about 43 ms before each reset; measured: 2e-15 after 20 steps, 4e-11 after 2000, 9e-10 after
// 10000).
void check_paper_port(double horizon) {
  adparm::Settings settings = adparm::paper_settings();
  settings.sim.T = std::max(horizon, 2.0);
  adparm::AnySimulation simulation(settings);
  simulation.advance(simulation.steps());
  plain_port::Run port;
  plain_port::run(settings.sim.T, port);
  const Eigen::VectorXd state = simulation.state();
  const int blocks[][2] = {{0, 2}, {2, 2}, {4, 8}, {12, 8}, {20, 64}, {84, 2}, {86, 1}};
  double difference = 0.0;
  for (const auto& block : blocks) {
    double largest = 0.0, block_difference = 0.0;
    for (int i = block[0]; i < block[0] + block[1]; ++i) {
      largest = std::max(largest, std::abs(state[i]));
      block_difference = std::max(block_difference, std::abs(state[i] - port.state[i]));
    }
    difference =
        std::max(difference, largest > 0.0 ? block_difference / largest : block_difference);
  }
  const bool same_resets = port.reset_times == simulation.reset_times();
  const bool ok = state.size() == plain_port::kStateSize &&
                  simulation.status() == adparm::RunStatus::finished && !port.diverged &&
                  port.steps == simulation.steps() && same_resets && difference <= 1e-9;
  std::printf(
      "bench=check run=paper_port status=%s steps=%ld port_steps=%ld port_diverged=%d resets=%zu "
      "port_resets=%zu same_reset_times=%d difference=%.3g ok=%d\n",
      status_name(simulation.status()), simulation.steps(), port.steps, port.diverged ? 1 : 0,
      simulation.reset_times().size(), port.reset_times.size(), same_resets ? 1 : 0, difference,
      ok ? 1 : 0);
  std::fflush(stdout);
  if (!ok) fail("paper_port");
}

// ClosedLoop::step's lower_step (extrapolation points, the dispatched kernels: Gamma summed on
// its lower triangle, then mirrored) against rk4_step on a twin loop: the same state, bit for bit,
// after each of 40 steps of the planar 3-link arm with 10 points (the state is compared whole:
// Gamma's upper triangle too).
template <class Case>
void check_lower_step(const adparm::PinocchioArm& arm) {
  using Loop = adparm::ClosedLoop<LoopArm, typename Case::Basis>;
  const adparm::Settings settings = case_settings<Case>(arm, 10, 0.05);
  const LoopArm loop_arm(arm);
  Loop lower(settings, loop_arm, loop_arm, true, Case::basis(arm));
  Loop plain(settings, loop_arm, loop_arm, true, Case::basis(arm));
  if (!lower.lower_steps()) {
    std::printf("bench=check run=lower_step arm=planar_3link basis=%s skipped=portable_kernels\n",
                Case::name());
    return;
  }
  auto lower_data = lower.make_data();
  auto plain_data = plain.make_data();
  adparm::Rk4Workspace<Loop> lower_workspace, plain_workspace;
  typename Loop::State x = lower.initial_state(), y = x, x_next = x, y_next = x;
  lower_workspace.resize(x.size());
  plain_workspace.resize(x.size());
  const double dt = settings.sim.dt;
  long steps = 0;
  bool ok = true;
  for (; steps < 40 && ok; ++steps) {
    const double t = steps * dt;
    lower.begin_step(t, x, lower_data);
    plain.begin_step(t, y, plain_data);
    lower.step(t, t + dt, x, x_next, lower_workspace, nullptr, lower_data);
    adparm::rk4_step(plain, t, t + dt, y, y_next, plain_workspace, nullptr, plain_data);
    x.swap(x_next);
    y.swap(y_next);
    ok = x == y && x.allFinite();
  }
  std::printf("bench=check run=lower_step arm=planar_3link basis=%s steps=%ld ok=%d\n",
              Case::name(), steps, ok ? 1 : 0);
  std::fflush(stdout);
  if (!ok) fail("lower_step");
}

// qd1 a cubic on [0, end/2] continued by a line with the same position and velocity on
// [end/2, end] (two spline intervals); qd2 = -0.2.
adparm::TrajectorySettings spline(double end) {
  adparm::TrajectorySettings qd;
  qd.kind = adparm::TrajectoryKind::spline;
  qd.breaks.resize(3);
  qd.breaks << 0.0, 0.5 * end, end;
  qd.coefficients.setZero(2, 8);
  qd.coefficients.row(0) << 0.01, -0.02, 0.05, 0.1, 0, 0, 0, -0.2;
  const double s = 0.5 * end;  // the second interval continues the first's position and velocity
  qd.coefficients.row(1) << 0, 0, 0.05 + 2 * -0.02 * s + 3 * 0.01 * s * s,
      ((0.01 * s - 0.02) * s + 0.05) * s + 0.1, 0, 0, 0, -0.2;
  return qd;
}

adparm::TrajectorySettings sinusoid() {
  adparm::TrajectorySettings qd;
  qd.kind = adparm::TrajectoryKind::sinusoid;
  qd.offset = adparm::Vec2(0.1, -0.1);
  qd.amplitude.setConstant(2, 2, 0.1);
  qd.frequency.resize(2, 2);
  qd.frequency << 1.0, 2.0, 0.5, 3.0;
  qd.phase.setZero(2, 2);
  return qd;
}

// The covariance test (Critic::needs_reset: lambda_min(Gamma) < epsilon_T, by the pivots of a
// factorisation of Gamma - epsilon_T I) against the eigenvalues it was built from: Gamma = Q
// diag(l) Q^T with Q random orthogonal, l log-uniform in [1e-7, 100] and its least set to epsilon_T
// (1 +- 1e-3) or left above it, at the paper's 8 functions (fixed size), 13, 21 and 24 (the loop of
// the small sizes) and 30 and 78 (left-looking Cholesky). Forming Gamma and factoring it move
// lambda_min by about 1e-13, a hundredth of the 1e-9 between it and epsilon_T: every answer must
// be the eigenvalues'. A NaN off the diagonal must ask for a reset.
template <class Basis>
void check_covariance_test_size(Eigen::Index n, std::mt19937& random) {
  adparm::CriticSettings settings;
  settings.epsilon_T = 1e-6;
  const adparm::Critic<Basis> critic(settings, n, false);
  auto workspace = critic.workspace();
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(std::log(1e-7), std::log(100.0));
  int wrong = 0, below = 0;
  constexpr int kTrials = 120;
  for (int trial = 0; trial < kTrials; ++trial) {
    Eigen::MatrixXd a(n, n);
    for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = normal(random);
    const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(a).householderQ();
    Eigen::VectorXd l(n);
    for (Eigen::Index i = 0; i < n; ++i) l[i] = std::exp(uniform(random));
    // trial % 3: 0, the least 1e-3 under epsilon_T; 1, 1e-3 above it; 2, all at 2 epsilon_T or more
    const int kind = trial % 3;
    const bool expected = kind == 0;
    for (Eigen::Index i = 0; i < n; ++i) l[i] = std::max(l[i], 2.0 * settings.epsilon_T);
    if (kind < 2) l[trial % n] = settings.epsilon_T * (expected ? 1.0 - 1e-3 : 1.0 + 1e-3);
    Eigen::MatrixXd gamma = q * l.asDiagonal() * q.transpose();
    gamma = (0.5 * (gamma + gamma.transpose())).eval();
    below += expected;
    if (critic.needs_reset(gamma, workspace) != expected) ++wrong;
  }
  Eigen::MatrixXd gamma = 10.0 * Eigen::MatrixXd::Identity(n, n);
  gamma(n - 1, 0) = gamma(0, n - 1) = std::numeric_limits<double>::quiet_NaN();
  const bool nan_resets = critic.needs_reset(gamma, workspace);
  const bool ok = wrong == 0 && nan_resets && below > 0 && below < kTrials;
  std::printf(
      "bench=check run=covariance_test functions=%ld trials=%d below=%d wrong=%d "
      "nan_resets=%d ok=%d\n",
      static_cast<long>(n), kTrials, below, wrong, nan_resets ? 1 : 0, ok ? 1 : 0);
  if (!ok) fail("covariance_test functions=" + std::to_string(n));
}

void check_covariance_test() {
  std::mt19937 random(26);
  check_covariance_test_size<adparm::PaperBasis>(8, random);
  for (const Eigen::Index n : {8, 13, 21, 24, 30, 78})
    check_covariance_test_size<adparm::ExpressionLoopBasis>(n, random);
}

void check_runs(double horizon) {
  using adparm::Settings;
  Settings base = adparm::paper_settings();
  base.sim.T = horizon;
  const auto variant = [&](const std::function<void(Settings&)>& change) {
    Settings s = base;
    change(s);
    return s;
  };
  constexpr auto finished = adparm::RunStatus::finished;
  check_run("local_points", variant([](Settings& s) {
              s.extrapolation.points = 10;
              s.extrapolation.mode = adparm::ExtrapolationMode::local;
              s.extrapolation.seed = 7;
            }),
            finished);
  check_run("torque_limits", variant([](Settings& s) {
              s.torque_limits = adparm::Vec2(60.0, 15.0);
              s.sim.record_every = 3;
            }),
            finished);
  check_run("torque_limits_dynamic", variant([](Settings& s) {
              s.torque_limits = adparm::Vec2(60.0, std::numeric_limits<double>::infinity());
              s.dynamic_sizes = true;
            }),
            finished);
  check_run("grid_points", variant([](Settings& s) {
              s.extrapolation.points = 16;
              s.extrapolation.mode = adparm::ExtrapolationMode::grid;
            }),
            finished);
  check_run("paper_basis_model_error", variant([](Settings& s) {
              s.basis = adparm::BasisKind::paper;
              std::get<adparm::TwoLinkArms>(s.arm).model.p1 = 4.5;
              std::get<adparm::TwoLinkArms>(s.arm).model.viscous = 0.2;
              s.probe.ramp = 0.1;
              s.sim.record_every = 7;
            }),
            finished);
  check_run("sinusoid_points", variant([](Settings& s) {
              s.task.qd = sinusoid();
              s.extrapolation.points = 4;
            }),
            finished);
  check_run("spline_points", variant([&](Settings& s) {
              s.task.qd = spline(horizon);
              s.extrapolation.points = 3;
              s.extrapolation.mode = adparm::ExtrapolationMode::local;
            }),
            finished);
  check_run("structured_basis_points", variant([](Settings& s) {
              s.basis = adparm::BasisKind::structured;
              s.critic_weights.resize(6);
              s.critic_weights << 1, 0, 1, 5, 1, 1;  // K = I, the arm's inertia p
              s.actor_weights = s.critic_weights;
              s.probe.until = 0.0;
              s.extrapolation.points = 8;
              s.task.qd = sinusoid();
            }),
            finished);
  check_run("rise", variant([](Settings& s) { s.controller.kind = adparm::ControllerKind::rise; }),
            finished);
  check_run("pd", variant([](Settings& s) {
              s.controller.kind = adparm::ControllerKind::pd;
              s.controller.rise = false;
            }),
            finished);
  check_run("optimal",
            variant([](Settings& s) { s.controller.kind = adparm::ControllerKind::optimal; }),
            finished);
  check_run("diverges", variant([&](Settings& s) {
              s.sim.dt = 0.004;  // RK4 outside its stability region: diverges at step 5
              s.sim.T = std::max(horizon, 1.0);
              s.sim.record_every = 3;
            }),
            adparm::RunStatus::diverged);

  // The dynamic-size loop (Settings::dynamic_sizes): chunked against one-shot, and against the
  // fixed-size path (round-off: the sums of dynamic-size reductions associate differently).
  check_run("dynamic_local_points", variant([](Settings& s) {
              s.dynamic_sizes = true;
              s.extrapolation.points = 5;
              s.extrapolation.mode = adparm::ExtrapolationMode::local;
            }),
            finished);
  check_run("dynamic_sinusoid_paper_basis", variant([](Settings& s) {
              s.dynamic_sizes = true;
              s.basis = adparm::BasisKind::paper;
              s.task.qd = sinusoid();
              s.extrapolation.points = 4;
              std::get<adparm::TwoLinkArms>(s.arm).model.p1 = 4.5;
            }),
            finished);
  check_run("expression_quadratic_points", variant([](Settings& s) {
              use_quadratic_expression_basis(s);
              s.extrapolation.points = 6;
              s.task.qd = sinusoid();
            }),
            finished);
  for (const bool points : {false, true}) {
    Settings fixed = variant([&](Settings& s) {
      s.extrapolation.points = points ? 6 : 0;
      if (points) s.task.qd = sinusoid();
    });
    Settings dynamic = fixed;
    dynamic.dynamic_sizes = true;
    adparm::AnySimulation a(fixed), b(dynamic);
    a.advance(a.steps());
    b.advance(b.steps());
    const adparm::Recording ra = a.recording(), rb = b.recording();
    const auto relative = [](const auto& x, const auto& y) {
      return (x - y).cwiseAbs().maxCoeff() / std::max(1.0, x.cwiseAbs().maxCoeff());
    };
    const double difference =
        std::max({relative(ra.q, rb.q), relative(ra.critic_weights, rb.critic_weights),
                  relative(ra.actor_weights, rb.actor_weights), relative(ra.tau, rb.tau),
                  relative(ra.hjb_error, rb.hjb_error), relative(a.state(), b.state())});
    const bool ok = ra.rows == rb.rows && a.status() == b.status() &&
                    a.reset_times() == b.reset_times() && difference <= 1e-9;
    std::printf("bench=check run=dynamic_vs_fixed points=%d rows=%ld difference=%.3g ok=%d\n",
                points ? 6 : 0, static_cast<long>(ra.rows), difference, ok ? 1 : 0);
    if (!ok) fail("dynamic_vs_fixed");
  }

  // 16 runs in chunks on 3 threads (more than the 2 cores: runs move between threads) against
  // the same runs one by one.
  std::vector<Settings> settings;
  for (int i = 0; i < 16; ++i)
    settings.push_back(variant([i](Settings& s) {
      s.task.q0 += adparm::Vec2(0.01 * i, -0.005 * i);
      s.extrapolation.points = i % 3;
      s.basis = i % 2 ? adparm::BasisKind::paper : adparm::BasisKind::augmented;
    }));
  adparm::Batch<adparm::AnySimulation> batch(settings);
  const auto runs = batch.run_all(3);
  bool ok = true;
  for (std::size_t i = 0; i < settings.size(); ++i) {
    adparm::AnySimulation alone(settings[i]);
    alone.advance(alone.steps());
    ok = ok && runs[i]->status() == adparm::RunStatus::finished &&
         runs[i]->state() == alone.state() && same(runs[i]->recording(), alone.recording());
  }
  std::printf("bench=check run=batch_threads status=%s steps=%ld rows=%ld ok=%d\n",
              status_name(runs[0]->status()), runs[0]->step(),
              static_cast<long>(runs[0]->recording().rows), ok ? 1 : 0);
  if (!ok) fail("batch_threads");
  // A streamed batch (window 2, taking each run as it ends) stopped part-way, then resumed run by
  // run: the stopped runs continue to the same numbers, the never-started ones are built by take().
  adparm::Batch<adparm::AnySimulation> stream(settings, 2);
  stream.start(2);
  std::size_t seen = 0;
  bool stream_ok = true;
  while (seen < 4 && !stream.done()) {
    for (std::size_t i : stream.wait(1.0)) {
      auto run = stream.take(i);
      adparm::AnySimulation alone(settings[i]);
      alone.advance(alone.steps());
      stream_ok = stream_ok && run->state() == alone.state();
      ++seen;
    }
  }
  stream.stop();
  for (std::size_t i : stream.wait(0.0)) stream.take(i);
  for (std::size_t i = 0; i < settings.size(); ++i) {
    std::unique_ptr<adparm::AnySimulation> run;
    try {
      run = stream.take(i);
    } catch (const std::logic_error&) {
      continue;  // already taken above
    }
    run->advance(run->steps());
    adparm::AnySimulation alone(settings[i]);
    alone.advance(alone.steps());
    stream_ok =
        stream_ok && run->state() == alone.state() && same(run->recording(), alone.recording());
  }
  std::printf("bench=check run=batch_stream_stop seen=%zu ok=%d\n", seen, stream_ok ? 1 : 0);
  if (!stream_ok) fail("batch_stream_stop");
}

// Each invalid setting must be refused with std::invalid_argument: not accepted, not another
// exception, not an abort (an Eigen assertion or a sanitizer finding ends the program).
void check_invalid_settings() {
  using adparm::Settings;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<const char*, std::function<void(Settings&)>>> cases = {
      {"sim.T zero", [](Settings& s) { s.sim.T = 0.0; }},
      {"sim.T nan", [&](Settings& s) { s.sim.T = nan; }},
      {"sim.dt negative", [](Settings& s) { s.sim.dt = -1e-3; }},
      {"sim.dt inf", [&](Settings& s) { s.sim.dt = inf; }},
      {"sim.T/dt too many steps", [](Settings& s) { s.sim.T = 1e8; }},
      {"sim.record_every zero", [](Settings& s) { s.sim.record_every = 0; }},
      {"sim.divergence_bound zero", [](Settings& s) { s.sim.divergence_bound = 0.0; }},
      {"init.critic_weights size", [](Settings& s) { s.critic_weights.resize(7); }},
      {"init.actor_weights size", [](Settings& s) { s.actor_weights = Eigen::VectorXd::Ones(9); }},
      {"init.critic_weights empty", [](Settings& s) { s.critic_weights.resize(0); }},
      {"init.actor_weights nan", [&](Settings& s) { s.actor_weights[3] = nan; }},
      {"task.q0 nan", [&](Settings& s) { s.task.q0[1] = nan; }},
      {"task.dq0 inf", [&](Settings& s) { s.task.dq0[0] = -inf; }},
      {"plant.disturbance inf", [&](Settings& s) { s.disturbance[0] = inf; }},
      {"plant.p2 zero", [](Settings& s) { std::get<adparm::TwoLinkArms>(s.arm).plant.p2 = 0.0; }},
      {"plant M not positive definite",
       [](Settings& s) { std::get<adparm::TwoLinkArms>(s.arm).plant.p1 = 1.5; }},
      {"model.p3 nan", [&](Settings& s) { std::get<adparm::TwoLinkArms>(s.arm).model.p3 = nan; }},
      {"cost.Q asymmetric", [](Settings& s) { s.Q(0, 1) += 1.0; }},
      {"cost.R not positive definite", [](Settings& s) { s.R(1, 1) = -1.0; }},
      {"cost.R nan", [&](Settings& s) { s.R(0, 0) = nan; }},
      {"control.alpha1 nan", [&](Settings& s) { s.control.alpha1(1, 0) = nan; }},
      {"control.ks negative", [](Settings& s) { s.control.rise.ks = -1.0; }},
      {"critic.gamma0 zero", [](Settings& s) { s.critic.gamma0 = 0.0; }},
      {"critic.epsilon_T above gamma0", [](Settings& s) { s.critic.epsilon_T = 200.0; }},
      {"critic.eta_c negative", [](Settings& s) { s.critic.eta_c = -1.0; }},
      {"actor.weight_bound zero", [](Settings& s) { s.actor.weight_bound = 0.0; }},
      {"actor.e2_margin negative", [](Settings& s) { s.actor.e2_margin = -1.0; }},
      {"controller rise without rise",
       [](Settings& s) {
         s.controller.kind = adparm::ControllerKind::rise;
         s.controller.rise = false;
       }},
      {"controller.kp nan", [&](Settings& s) { s.controller.kp(0, 0) = nan; }},
      {"extrapolation.points negative", [](Settings& s) { s.extrapolation.points = -1; }},
      {"extrapolation grid not m^4",
       [](Settings& s) {
         s.extrapolation.points = 5;
         s.extrapolation.mode = adparm::ExtrapolationMode::grid;
       }},
      {"extrapolation.box zero", [](Settings& s) { s.extrapolation.box[2] = 0.0; }},
      {"probe.amplitude size", [](Settings& s) { s.probe.amplitude.resize(2, 3); }},
      {"probe.phases size", [](Settings& s) { s.probe.phases.resize(2, 0); }},
      {"probe.frequencies nan", [&](Settings& s) { s.probe.frequencies[2] = nan; }},
      {"probe.ramp negative", [](Settings& s) { s.probe.ramp = -1.0; }},
      {"task.qd sinusoid frequency size",
       [](Settings& s) {
         s.task.qd = sinusoid();
         s.task.qd.frequency.resize(2, 1);
       }},
      {"task.qd spline no interval",
       [](Settings& s) {
         s.task.qd = spline(s.sim.T);
         s.task.qd.coefficients.resize(0, 8);
       }},
      {"task.qd spline breaks size",
       [](Settings& s) {
         s.task.qd = spline(s.sim.T);
         s.task.qd.breaks.resize(2);
       }},
      {"task.qd spline decreasing",
       [](Settings& s) {
         s.task.qd = spline(s.sim.T);
         s.task.qd.breaks[1] = -1.0;
       }},
      {"task.qd spline ends before sim.T", [](Settings& s) { s.task.qd = spline(0.5 * s.sim.T); }},
      {"task.q0 size", [](Settings& s) { s.task.q0.resize(3); }},
      {"task.dq0 size", [](Settings& s) { s.task.dq0.resize(1); }},
      {"task.qd offset size", [](Settings& s) { s.task.qd.offset.setZero(3); }},
      {"plant.disturbance size", [](Settings& s) { s.disturbance.setZero(0); }},
      {"cost.Q size", [](Settings& s) { s.Q = Eigen::MatrixXd::Identity(6, 6); }},
      {"cost.R size", [](Settings& s) { s.R = Eigen::MatrixXd::Identity(3, 3); }},
      {"control.alpha1 size", [](Settings& s) { s.control.alpha1.setIdentity(2, 3); }},
      {"controller.kd size", [](Settings& s) { s.controller.kd.setIdentity(1, 1); }},
      {"extrapolation.box size", [](Settings& s) { s.extrapolation.box.setOnes(6); }},
      {"probe.amplitude rows", [](Settings& s) { s.probe.amplitude.setOnes(3, 4); }},
      {"task.qd spline coefficients size",
       [](Settings& s) {
         s.task.qd = spline(s.sim.T);
         s.task.qd.coefficients.setZero(2, 12);
       }},
      {"dynamic: cost.R size",
       [](Settings& s) {
         s.dynamic_sizes = true;
         s.R = Eigen::MatrixXd::Identity(3, 3);
       }},
      {"dynamic: init.actor_weights size",
       [](Settings& s) {
         s.dynamic_sizes = true;
         s.actor_weights.setOnes(9);
       }},
      {"expression: empty basis_program",
       [](Settings& s) {
         use_quadratic_expression_basis(s);
         s.basis_program = {};
       }},
      {"expression: basis_program.arguments size",
       [](Settings& s) {
         use_quadratic_expression_basis(s);
         s.basis_program.arguments.pop_back();
       }},
      {"expression: variable out of range",
       [](Settings& s) {
         use_quadratic_expression_basis(s);
         s.basis_program.arguments[0] = 6.0;
       }},
      {"expression: init.critic_weights size",
       [](Settings& s) {
         use_quadratic_expression_basis(s);
         s.critic_weights.setOnes(8);
       }},
      {"dynamic: control.alpha1 not Hurwitz",
       [](Settings& s) {
         s.dynamic_sizes = true;
         s.control.alpha1 = -Eigen::MatrixXd::Identity(2, 2);
       }},
      {"dynamic: extrapolation grid not m^4",
       [](Settings& s) {
         s.dynamic_sizes = true;
         s.extrapolation.points = 8;
         s.extrapolation.mode = adparm::ExtrapolationMode::grid;
       }},
  };
  int refused = 0;
  for (const auto& [name, change] : cases) {
    Settings settings = adparm::paper_settings();
    settings.sim.T = 1.0;
    change(settings);
    try {
      adparm::AnySimulation simulation(settings);
      fail(std::string(name) + ": accepted");
    } catch (const std::invalid_argument&) {
      ++refused;
    } catch (const std::exception& error) {
      fail(std::string(name) + ": threw " + error.what());
    }
  }
  int batch_cases = 0;
  // A Batch names the run whose settings are invalid, and refuses threads = 0.
  std::vector<adparm::Settings> settings(3, adparm::paper_settings());
  for (auto& s : settings) s.sim.T = 0.01;
  settings[1].sim.dt = 0.0;
  ++batch_cases;
  try {
    adparm::Batch<adparm::AnySimulation> batch(settings);
    fail("batch with invalid settings[1]: accepted");
  } catch (const std::invalid_argument& error) {
    if (std::strncmp(error.what(), "settings[1]: ", 13) == 0)
      ++refused;
    else
      fail(std::string("batch with invalid settings[1]: message ") + error.what());
  }
  settings[1].sim.dt = 1e-3;
  ++batch_cases;
  try {
    adparm::Batch<adparm::AnySimulation> batch(settings);
    batch.start(0);
    fail("batch threads = 0: accepted");
  } catch (const std::invalid_argument&) {
    ++refused;
  }
  std::printf("bench=checks invalid_settings=%d refused=%d failed=%d\n",
              static_cast<int>(cases.size()) + batch_cases, refused, failures);
}

void usage() {
  std::fprintf(stderr,
               "usage: adparm_bench [--checks] [simulated_seconds] [points ...]\n"
               "       adparm_bench --urdf [simulated_seconds] [points ...]\n"
               "       adparm_bench --paper-port [simulated_seconds] [pairs]\n");
}

}  // namespace

int run(double horizon, std::vector<long> point_counts, bool checks);
int run_urdf(double horizon, std::vector<long> point_counts);
int run_paper_port(double horizon, long pairs);

int main(int argc, char** argv) {
  bool checks = false, urdf = false, port = false;
  std::vector<const char*> arguments;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--checks") == 0)
      checks = true;
    else if (std::strcmp(argv[i], "--urdf") == 0)
      urdf = true;
    else if (std::strcmp(argv[i], "--paper-port") == 0)
      port = true;
    else
      arguments.push_back(argv[i]);
  }
  if (checks + urdf + port > 1) {
    usage();
    return 2;
  }
  double horizon = urdf ? kUrdfHorizon : port ? 10.0 : 110.0;
  std::vector<long> point_counts;
  for (std::size_t i = 0; i < arguments.size(); ++i) {
    char* end = nullptr;
    if (i == 0) {
      horizon = std::strtod(arguments[i], &end);
    } else {
      point_counts.push_back(std::strtol(arguments[i], &end, 10));
    }
    if (end == arguments[i] || *end != '\0') {
      usage();
      return 2;
    }
  }
  if (port && point_counts.size() > 1) {
    usage();
    return 2;
  }
  try {
    if (port) return run_paper_port(horizon, point_counts.empty() ? 9 : point_counts[0]);
    return urdf ? run_urdf(horizon, point_counts) : run(horizon, point_counts, checks);
  } catch (const std::exception& error) {  // e.g. invalid_argument for a horizon <= 0
    std::fprintf(stderr, "adparm_bench: %s\n", error.what());
    return 2;
  }
}

// --urdf: the URDF loop cases alone, N = 0 and 50 unless points are given.
int run_urdf(double horizon, std::vector<long> point_counts) {
  if (point_counts.empty()) point_counts = {0, 50};
  return run_urdf_loops(horizon, point_counts, 3) ? 0 : 1;
}

// --paper-port: adparm's paper loop (N = 0, as bench=paper_loop) and the plain port
// (bench/plain_port.cpp) in `pairs` interleaved pairs (A B, then B A, ...), each side the best of 3
// runs of `horizon` simulated seconds within its pair; per pair and as medians: ns per step of each
// and ratio = port / adparm (above 1: adparm is faster).
int run_paper_port(double horizon, long pairs) {
  if (pairs < 1) throw std::invalid_argument("--paper-port: pairs must be >= 1");
  adparm::Settings settings = adparm::paper_settings();
  settings.sim.T = horizon;
  const auto time_adparm = [&] {
    const LoopTiming timing = time_loop(settings);
    if (timing.status != adparm::RunStatus::finished || timing.heap_allocations > 0)
      throw std::runtime_error("--paper-port: adparm's run did not finish or allocated");
    return 1e9 * timing.seconds / timing.steps;
  };
  plain_port::Run port;
  const auto time_port = [&] {
    const auto start = Clock::now();
    plain_port::run(horizon, port);
    const double seconds = seconds_since(start);
    if (port.diverged) throw std::runtime_error("--paper-port: the port's run diverged");
    return 1e9 * seconds / port.steps;
  };
  std::vector<double> adparm_ns, port_ns, ratios;
  for (long pair = 0; pair < pairs; ++pair) {
    double best_adparm = 0.0, best_port = 0.0;
    for (int r = 0; r < 3; ++r) {
      double a, b;
      if (pair % 2 == 0) {
        a = time_adparm();
        b = time_port();
      } else {
        b = time_port();
        a = time_adparm();
      }
      best_adparm = r == 0 ? a : std::min(best_adparm, a);
      best_port = r == 0 ? b : std::min(best_port, b);
    }
    adparm_ns.push_back(best_adparm);
    port_ns.push_back(best_port);
    ratios.push_back(best_port / best_adparm);
    std::printf(
        "bench=paper_port pair=%ld order=%s steps=%ld adparm_ns_per_step=%.1f "
        "port_ns_per_step=%.1f "
        "ratio=%.3f\n",
        pair + 1, pair % 2 == 0 ? "adparm,port" : "port,adparm", port.steps, best_adparm, best_port,
        best_port / best_adparm);
    std::fflush(stdout);
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  };
  std::printf(
      "bench=paper_port_median pairs=%ld adparm_ns_per_step=%.1f port_ns_per_step=%.1f "
      "ratio=%.3f ratio_min=%.3f ratio_max=%.3f kernels=%s evaluation=%s\n",
      pairs, median(adparm_ns), median(port_ns), median(ratios),
      *std::min_element(ratios.begin(), ratios.end()),
      *std::max_element(ratios.begin(), ratios.end()),
      adparm::dense_kernels_name(adparm::select_dense_kernels()),
      adparm::vector_loop_available() ? "avx512" : "portable");  // vector_loop.hpp
  return 0;
}

int run(double horizon, std::vector<long> point_counts, bool checks) {
  if (point_counts.empty()) point_counts = {0, 10, 50};
  constexpr int repeats = 3;
  bool all_finished = true;

  double baseline_ns = -1.0;
  for (const long points : point_counts) {
    adparm::Settings settings = adparm::paper_settings();
    settings.sim.T = horizon;
    settings.extrapolation.points = points;
    LoopTiming best;
    for (int r = 0; r < repeats; ++r) {
      const LoopTiming timing = time_loop(settings);
      if (r == 0 || timing.seconds < best.seconds) best = timing;
    }
    const double ns_per_step = 1e9 * best.seconds / best.steps;
    if (points == 0) baseline_ns = ns_per_step;
    const double per_point =
        points > 0 && baseline_ns > 0.0 ? (ns_per_step - baseline_ns) / points : 0.0;
    std::printf(
        "bench=paper_loop points=%ld steps=%ld repeats=%d ns_per_step=%.1f "
        "steps_per_second=%.0f ns_per_point_step=%.1f heap_allocations=%ld "
        "final_critic_error=%.4g status=%s\n",
        points, best.steps, repeats, ns_per_step, best.steps / best.seconds, per_point,
        best.heap_allocations, best.critic_error, status_name(best.status));
    std::fflush(stdout);
    all_finished = all_finished && best.status == adparm::RunStatus::finished;
  }

  // Actuator limits (Settings::torque_limits, closed_loop.hpp): the paper loop with limits of 60
  // and 15 N m, which its probe drives both joints into about 40 % of the time, against the same
  // loop without limits, alternating, best of `repeats` each; no allocation per step.
  {
    adparm::Settings limited = adparm::paper_settings();
    limited.sim.T = horizon;
    limited.torque_limits = adparm::Vec2(60.0, 15.0);
    adparm::Settings unlimited = limited;
    unlimited.torque_limits.resize(0);
    LoopTiming best_limited, best_unlimited;
    for (int r = 0; r < repeats; ++r) {
      const LoopTiming free_run = time_loop(unlimited);
      const LoopTiming limited_run = time_loop(limited);
      if (r == 0 || free_run.seconds < best_unlimited.seconds) best_unlimited = free_run;
      if (r == 0 || limited_run.seconds < best_limited.seconds) best_limited = limited_run;
    }
    const double limited_ns = 1e9 * best_limited.seconds / best_limited.steps;
    const double unlimited_ns = 1e9 * best_unlimited.seconds / best_unlimited.steps;
    std::printf(
        "bench=limited_loop limits=60,15 steps=%ld repeats=%d ns_per_step=%.1f "
        "unlimited_ns_per_step=%.1f ratio=%.3f heap_allocations=%ld status=%s\n",
        best_limited.steps, repeats, limited_ns, unlimited_ns, limited_ns / unlimited_ns,
        best_limited.heap_allocations, status_name(best_limited.status));
    std::fflush(stdout);
    all_finished = all_finished && best_limited.status == adparm::RunStatus::finished;
    all_finished = all_finished && best_limited.heap_allocations <= 0;
  }

  // The constrained-input loop (input_bound.hpp): the paper's run with lambda = 20 N m per joint
  // and the ln cosh e2 cost (the paper's Q22 is diagonal), fixed sizes and dynamic sizes, each
  // timed alternately with the same unbounded run; ratio = bounded / unbounded ns per step.
  for (const bool dynamic : {false, true}) {
    adparm::Settings unbounded = adparm::paper_settings();
    unbounded.sim.T = horizon;
    unbounded.dynamic_sizes = dynamic;
    adparm::Settings bounded = unbounded;
    bounded.input_bound = Eigen::VectorXd::Constant(2, 20.0);
    bounded.e2_cost = adparm::E2Cost::logcosh;
    LoopTiming best_unbounded, best_bounded;
    for (int r = 0; r < repeats; ++r) {
      const LoopTiming a = time_loop(unbounded);
      const LoopTiming b = time_loop(bounded);
      if (r == 0 || a.seconds < best_unbounded.seconds) best_unbounded = a;
      if (r == 0 || b.seconds < best_bounded.seconds) best_bounded = b;
    }
    const double ns_unbounded = 1e9 * best_unbounded.seconds / best_unbounded.steps;
    const double ns_bounded = 1e9 * best_bounded.seconds / best_bounded.steps;
    std::printf(
        "bench=bounded_loop sizes=%s points=0 steps=%ld repeats=%d ns_per_step=%.1f "
        "unbounded_ns_per_step=%.1f ratio=%.3f heap_allocations=%ld status=%s\n",
        dynamic ? "dynamic" : "fixed", best_bounded.steps, repeats, ns_bounded, ns_unbounded,
        ns_bounded / ns_unbounded, best_bounded.heap_allocations, status_name(best_bounded.status));
    std::fflush(stdout);
    all_finished = all_finished && best_bounded.status == adparm::RunStatus::finished;
    all_finished = all_finished && best_bounded.heap_allocations <= 0;
  }

  // The same paper loop through the dynamic-size path (n and K = Eigen::Dynamic, bounded types,
  // buffers sized once): its cost over the fixed-size fast path, and no allocation per step.
  for (const long points : point_counts) {
    adparm::Settings settings = adparm::paper_settings();
    settings.sim.T = horizon;
    settings.extrapolation.points = points;
    settings.dynamic_sizes = true;
    LoopTiming best;
    for (int r = 0; r < repeats; ++r) {
      const LoopTiming timing = time_loop(settings);
      if (r == 0 || timing.seconds < best.seconds) best = timing;
    }
    std::printf(
        "bench=dynamic_two_link points=%ld steps=%ld repeats=%d ns_per_step=%.1f "
        "heap_allocations=%ld final_critic_error=%.4g status=%s\n",
        points, best.steps, repeats, 1e9 * best.seconds / best.steps, best.heap_allocations,
        best.critic_error, status_name(best.status));
    std::fflush(stdout);
    all_finished = all_finished && best.status == adparm::RunStatus::finished;
    all_finished = all_finished && best.heap_allocations <= 0;
  }

  // The expression basis in the loop (dynamic sizes): the quadratic family, 10 functions, on the
  // paper's run without points; no allocation per step.
  {
    adparm::Settings settings = adparm::paper_settings();
    settings.sim.T = horizon;
    use_quadratic_expression_basis(settings);
    LoopTiming best;
    for (int r = 0; r < repeats; ++r) {
      const LoopTiming timing = time_loop(settings);
      if (r == 0 || timing.seconds < best.seconds) best = timing;
    }
    std::printf(
        "bench=expression_quadratic functions=10 points=0 steps=%ld repeats=%d ns_per_step=%.1f "
        "heap_allocations=%ld status=%s\n",
        best.steps, repeats, 1e9 * best.seconds / best.steps, best.heap_allocations,
        status_name(best.status));
    std::fflush(stdout);
    all_finished = all_finished && best.status == adparm::RunStatus::finished;
    all_finished = all_finished && best.heap_allocations <= 0;
  }

  // 16 paper runs from different initial positions, on 1 and 2 threads.
  constexpr int runs = 16;
  std::vector<adparm::Settings> batch_settings;
  for (int i = 0; i < runs; ++i) {
    adparm::Settings settings = adparm::paper_settings();
    settings.sim.T = horizon;
    settings.task.q0 += adparm::Vec2(0.01 * i, -0.005 * i);
    batch_settings.push_back(settings);
  }
  std::vector<Eigen::VectorXd> serial_states, parallel_states;
  const double serial = time_batch(batch_settings, 1, serial_states);
  const double parallel = time_batch(batch_settings, 2, parallel_states);
  const bool identical = serial_states == parallel_states;
  const long steps = adparm::AnySimulation(batch_settings[0]).steps();
  for (const auto& [threads, seconds] : {std::pair{1, serial}, std::pair{2, parallel}}) {
    std::printf(
        "bench=batch runs=%d steps=%ld threads=%d seconds=%.4f ns_per_step=%.1f speedup=%.2f "
        "identical=%d\n",
        runs, steps, threads, seconds, 1e9 * seconds / (static_cast<double>(runs) * steps),
        serial / seconds, identical ? 1 : 0);
  }
  std::fflush(stdout);  // a LeakSanitizer report at exit ends the program without flushing
  bool arms_ok = time_pinocchio_arms();
  // The URDF arms in the closed loop: N = 0 and 50 over at most kUrdfHorizon (best of 3); under
  // --checks (the sanitizers) N = 0 and 10 over 0.05 s, once.
  if (checks)
    arms_ok = run_urdf_loops(std::min(horizon, 0.05), {0, 10}, 1) && arms_ok;
  else
    arms_ok = run_urdf_loops(std::min(horizon, kUrdfHorizon), {0, 50}, 3) && arms_ok;
  if (checks) {
    check_runs(horizon);
    check_covariance_test();
    check_paper_port(horizon);
    const adparm::PinocchioArm planar(std::string(ADPARM_ARMS_DIR) + "/planar_3link.urdf",
                                      Eigen::Vector3d(0.0, 0.0, -9.81), Eigen::VectorXd(),
                                      Eigen::VectorXd::Constant(1, 0.1));
    check_lower_step<QuadraticCase>(planar);
    check_lower_step<StructuredCase>(planar);
    check_invalid_settings();
    failures += static_cast<int>(dense_kernel_checks::check_dense_kernels());
    std::fflush(stdout);
  }
  return all_finished && identical && arms_ok && failures == 0 ? 0 : 1;
}
