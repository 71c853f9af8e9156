// The update loop: fixed-step RK4 of the closed loop, covariance resetting between steps (eq. 24's
// reset rule), divergence detection, and recording of every record_every-th step. The run advances
// in chunks (advance()) so that a caller can show progress or stop between chunks; all buffers are
// allocated once, up front, so a step does no heap allocation.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <vector>

#include "adparm/closed_loop.hpp"
#include "adparm/rk4.hpp"

namespace adparm {

enum class RunStatus { running, finished, diverged };

// Lets another thread follow and stop a run while advance() works: `stop` is read before every
// step (advance returns at once when it is set) and `step` receives the step count after every
// step, so a stop request is acted on within one step, whatever a step costs.
struct RunControl {
  const std::atomic<bool>* stop = nullptr;
  std::atomic<long>* step = nullptr;
};

// One row per recorded step; every series is (rows x columns), row-major: one column (t,
// hjb_error, cost), one per joint or one per basis function (kRecordedSeries below).
struct Recording {
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Rows t;                                            // s
  Rows q, dq, qd, e1, e2, tau, u, u_hat, mu, probe;  // one column per joint
  Rows tau_commanded;                                // before the actuator limits' clip
  Rows critic_weights, actor_weights;                // one column per basis function
  Rows hjb_error;                                    // eq. (21)
  Rows cost;                                         // accumulated cost of eq. (10) from t = 0
  // With identification (identifier.hpp), else no columns: beta_hat, one column per parameter,
  // and the history stack's minimum singular value.
  Rows model_parameters, stack_singular_value, stack_uncertainty;
  Eigen::Index rows = 0;

  inline void allocate(Eigen::Index capacity, int dof, int basis_size, int parameters = 0);
  // A copy of the rows written (not of the whole capacity, which a long run interrupted early
  // leaves mostly unwritten).
  inline Recording written() const;
};

// The columns of a recorded series: identifier, one column with identification, none without;
// parameters, one per identified model parameter (none without identification).
enum class SeriesWidth { one, joints, basis, parameters, identifier };

struct RecordedSeries {
  const char* name;
  SeriesWidth width;
  Recording::Rows Recording::* member;

  Eigen::Index columns(Eigen::Index dof, Eigen::Index basis_size, Eigen::Index parameters) const {
    switch (width) {
      case SeriesWidth::one:
        return 1;
      case SeriesWidth::joints:
        return dof;
      case SeriesWidth::basis:
        return basis_size;
      case SeriesWidth::parameters:
        return parameters;
      default:
        return parameters > 0 ? 1 : 0;
    }
  }
};

// The one table of the recorded series, in the order Python shows them (adparm._core's
// RECORDED_SERIES and Simulation.recording() iterate it).
inline constexpr std::array<RecordedSeries, 19> kRecordedSeries = {{
    {"t", SeriesWidth::one, &Recording::t},
    {"q", SeriesWidth::joints, &Recording::q},
    {"dq", SeriesWidth::joints, &Recording::dq},
    {"qd", SeriesWidth::joints, &Recording::qd},
    {"e1", SeriesWidth::joints, &Recording::e1},
    {"e2", SeriesWidth::joints, &Recording::e2},
    {"tau", SeriesWidth::joints, &Recording::tau},
    {"tau_commanded", SeriesWidth::joints, &Recording::tau_commanded},
    {"u", SeriesWidth::joints, &Recording::u},
    {"u_hat", SeriesWidth::joints, &Recording::u_hat},
    {"mu", SeriesWidth::joints, &Recording::mu},
    {"probe", SeriesWidth::joints, &Recording::probe},
    {"critic_weights", SeriesWidth::basis, &Recording::critic_weights},
    {"actor_weights", SeriesWidth::basis, &Recording::actor_weights},
    {"hjb_error", SeriesWidth::one, &Recording::hjb_error},
    {"cost", SeriesWidth::one, &Recording::cost},
    {"model_parameters", SeriesWidth::parameters, &Recording::model_parameters},
    {"stack_singular_value", SeriesWidth::identifier, &Recording::stack_singular_value},
    {"stack_uncertainty", SeriesWidth::identifier, &Recording::stack_uncertainty},
}};

void Recording::allocate(Eigen::Index capacity, int dof, int basis_size, int parameters) {
  for (const RecordedSeries& series : kRecordedSeries)
    (this->*series.member).resize(capacity, series.columns(dof, basis_size, parameters));
}

Recording Recording::written() const {
  Recording out;
  out.rows = rows;
  for (const RecordedSeries& series : kRecordedSeries)
    out.*series.member = (this->*series.member).topRows(rows);
  return out;
}

template <class Arm, class Basis>
class Simulation {
 public:
  using System = ClosedLoop<Arm, Basis>;
  using State = typename System::State;

  // A loop built already (from Settings: AnySimulation and make_loop in any_simulation.hpp).
  Simulation(const Settings& settings, const Arm& plant, const Arm& model, bool model_is_plant,
             const Basis& basis = Basis())
      : Simulation(System(settings, plant, model, model_is_plant, basis), settings.sim) {}

  Simulation(System&& system, const SimSettings& sim)
      : system_(std::move(system)), data_(system_.make_data()), sim_(sim) {
    check_positive(sim_.T, "sim.T");
    check_positive(sim_.dt, "sim.dt");
    check_positive(sim_.divergence_bound, "sim.divergence_bound");
    if (sim_.record_every < 1) throw std::invalid_argument("sim.record_every: must be >= 1");
    // T / dt steps, rounded up (a ratio within 1e-12 of an integer counts as that integer); the
    // last step is shortened to end exactly at T. At least one: for dt far above T the ratio
    // underflows to 0, and a run of 0 steps would never reach step_ == steps_.
    const double steps = std::max(1.0, std::ceil(sim_.T / sim_.dt * (1.0 - 1e-12)));
    if (steps > 1e10) throw std::invalid_argument("sim.T / sim.dt: more than 1e10 steps");
    if (sim_.T > system_.trajectory().end_time() * (1.0 + 1e-12))
      throw std::invalid_argument("task.qd: the samples end before sim.T");
    steps_ = static_cast<long>(steps);
    states_[0] = system_.initial_state();
    states_[1] = states_[0];  // sizes every state buffer once
    record_rate_ = states_[0];
    saturated_time_.setZero(system_.dof());
    workspace_.resize(states_[0].size());
    system_.begin_step(0.0, states_[0], data_);
    reset_times_.reserve(1024);  // resets are rare; keeps push_back out of the allocator
    recording_.allocate(steps_ / sim_.record_every + 2, static_cast<int>(system_.dof()),
                        static_cast<int>(system_.basis_size()),
                        static_cast<int>(system_.parameter_count()));
    if (!record(0.0, states_[0])) stop_diverged(0.0);
  }

  // Advances at most max_steps steps; returns the number taken. The state alternates between two
  // buffers, so the last finite state survives a diverging step without a copy. A row due at a
  // step's end is written from the next step's first RK4 stage, which evaluates the outputs at
  // that very (t, state); the last row of a chunk is written before returning. A row whose
  // outputs are not finite (a torque or an HJB error that overflows while the state is still
  // finite) is not written: the run stops there as diverged, with state() and step() at that row.
  long advance(long max_steps, const RunControl& control = {}) {
    long taken = 0;
    while (status_ == RunStatus::running && taken < max_steps) {
      if (control.stop != nullptr && control.stop->load(std::memory_order_relaxed)) break;
      const double t_begin = step_ * sim_.dt;
      const double t_end = std::min((step_ + 1) * sim_.dt, sim_.T);
      const State& previous = states_[current_];
      State& state = states_[1 - current_];
      const bool row_due = row_due_;
      const bool limited = system_.limited();        // the step's start outputs give the clip
      const bool identifies = system_.identifies();  // the identifier samples the applied torque
      system_.step(t_begin, t_end, previous, state, workspace_,
                   row_due || limited || identifies ? &row_outputs_ : nullptr, data_);
      row_due_ = false;
      if (row_due && !record(t_begin, previous, row_outputs_)) {
        stop_diverged(t_begin);  // the step is not taken: state() stays at t_begin
        return taken;
      }
      ++step_;
      ++taken;
      if (identifies) system_.end_step(t_begin, t_end - t_begin, previous, row_outputs_, data_);
      if (limited) {  // a joint clipped at the step's start counts the whole step as saturated
        for (Eigen::Index i = 0; i < saturated_time_.size(); ++i)
          if (row_outputs_.tau[i] != row_outputs_.tau_commanded[i])
            saturated_time_[i] += t_end - t_begin;
      }
      if (diverged(state)) {
        status_ = RunStatus::diverged;
        divergence_time_ = t_end;
        // keep the last finite state as the final row (and as state()), if its outputs are finite
        if (!row_due && (step_ - 1) % sim_.record_every != 0) record(t_begin, previous);
        return taken;
      }
      current_ = 1 - current_;
      if (control.step != nullptr) control.step->store(step_, std::memory_order_relaxed);
      if (system_.reset_covariance_if_needed(previous, state, data_)) reset_times_.push_back(t_end);
      system_.begin_step(t_end, state, data_);  // for the next step (and the row recorded at t_end)
      if (step_ == steps_) {
        if (record(t_end, state))
          status_ = RunStatus::finished;
        else
          stop_diverged(t_end);
      } else if (step_ % sim_.record_every == 0) {
        row_due_ = true;
      }
    }
    if (row_due_) {  // the chunk ends on a row: write it now, the caller may read the recording
      row_due_ = false;
      if (!record(step_ * sim_.dt, states_[current_])) stop_diverged(step_ * sim_.dt);
    }
    return taken;
  }

  RunStatus status() const { return status_; }
  long steps() const { return steps_; }
  long step() const { return step_; }
  double divergence_time() const { return divergence_time_; }
  const std::vector<double>& reset_times() const { return reset_times_; }
  // Per joint, the time (s) its commanded torque lay beyond its limit: the steps whose start was
  // clipped, each counted whole (zeros without limits).
  const Eigen::VectorXd& saturated_time() const { return saturated_time_; }
  const State& state() const { return states_[current_]; }
  const System& system() const { return system_; }

  // The recording so far, trimmed to the rows written.
  Recording recording() const { return recording_.written(); }

 private:
  // Non-finite anywhere (a NaN or an infinity makes the sum non-finite; a finite state's sum
  // overflows only far beyond any bound), or |q|, |dq|, |Wc|, |Wa| above the bound.
  bool diverged(const State& state) const {
    const auto watched = state.template head<System::kGamma>(system_.gamma_offset());
    return !std::isfinite(state.sum()) || !(watched.cwiseAbs().maxCoeff() <= sim_.divergence_bound);
  }

  void stop_diverged(double t) {
    status_ = RunStatus::diverged;
    divergence_time_ = t;
  }

  static bool finite(const typename System::Outputs& o) {
    return o.errors.e1.allFinite() && o.errors.e2.allFinite() && o.qd.allFinite() &&
           o.tau.allFinite() && o.tau_commanded.allFinite() && o.u.allFinite() &&
           o.u_hat.allFinite() && o.mu.allFinite() && o.probe.allFinite() &&
           std::isfinite(o.hjb_error);
  }

  bool record(double t, const State& state) {
    system_.time_signals(t, record_signals_);
    system_.derivative(record_signals_, state, record_rate_, &row_outputs_, data_);
    return record(t, state, row_outputs_);
  }

  // Writes the row of (t, state) and returns true; writes nothing and returns false if an output
  // is not finite (the state itself is: the caller checked it).
  bool record(double t, const State& state, const typename System::Outputs& outputs) {
    if (!finite(outputs)) return false;
    Recording& r = recording_;
    const Eigen::Index i = r.rows++;
    r.t(i, 0) = t;
    const Eigen::Index n = system_.dof(), k = system_.basis_size();
    r.q.row(i) = state.template segment<System::kDof>(0, n).transpose();
    r.dq.row(i) = state.template segment<System::kDof>(system_.dq_offset(), n).transpose();
    r.qd.row(i) = outputs.qd.transpose();
    r.e1.row(i) = outputs.errors.e1.transpose();
    r.e2.row(i) = outputs.errors.e2.transpose();
    r.tau.row(i) = outputs.tau.transpose();
    r.tau_commanded.row(i) = outputs.tau_commanded.transpose();
    r.u.row(i) = outputs.u.transpose();
    r.u_hat.row(i) = outputs.u_hat.transpose();
    r.mu.row(i) = outputs.mu.transpose();
    r.probe.row(i) = outputs.probe.transpose();
    r.critic_weights.row(i) =
        state.template segment<System::kBasisSize>(system_.critic_offset(), k).transpose();
    r.actor_weights.row(i) =
        state.template segment<System::kBasisSize>(system_.actor_offset(), k).transpose();
    r.hjb_error(i, 0) = outputs.hjb_error;
    r.cost(i, 0) = state[system_.cost_offset()];
    if constexpr (System::kIdentifies) {
      if (system_.identifies()) {
        r.model_parameters.row(i) = data_.identifier.estimate.transpose();
        r.stack_singular_value(i, 0) = data_.identifier.min_singular_value;
        r.stack_uncertainty(i, 0) = data_.identifier.uncertainty;
      }
    }
    return true;
  }

  System system_;
  typename System::Data data_;  // the loop's work buffers
  SimSettings sim_;
  long steps_ = 0;
  long step_ = 0;
  State states_[2];  // the current state is states_[current_]
  int current_ = 0;
  Rk4Workspace<System> workspace_;
  bool row_due_ = false;  // a row is due at the current state (written by the next step)
  typename System::Outputs row_outputs_;
  State record_rate_;  // record()'s buffers (sized once)
  typename System::TimeSignals record_signals_;
  RunStatus status_ = RunStatus::running;
  double divergence_time_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> reset_times_;
  Eigen::VectorXd saturated_time_;  // s per joint
  Recording recording_;
};

using PaperSimulation = Simulation<TwoLinkArm, PaperBasis>;

}  // namespace adparm
