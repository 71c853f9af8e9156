// Classical fixed-step Runge-Kutta 4 for any System offering
//   State, TimeSignals, Outputs,
//   time_signals(t, TimeSignals&) and derivative(const TimeSignals&, const State&, State&,
//   Outputs*, Data&...) (Data: the system's work buffers, if it has any, passed through).
// Signals that depend on time only (disturbance, probing) are evaluated once per distinct time: the
// two midpoint stages share them, and a step's end signals are the next step's start signals.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <utility>

namespace adparm {

template <class System>
struct Rk4Workspace {
  typename System::State k1, k2, k3, k4, stage;
  typename System::TimeSignals begin, middle, end;
  double begin_time = std::numeric_limits<double>::quiet_NaN();
  // Sizes the stage buffers once (dynamic-size states); a step then allocates nothing.
  void resize(Eigen::Index size) {
    k1.resize(size);
    k2.resize(size);
    k3.resize(size);
    k4.resize(size);
    stage.resize(size);
  }
};

// Advances x from t_begin to t_end (h = t_end - t_begin) into x_next, which may be x itself. If
// outputs is given, it receives the system's outputs at (t_begin, x) computed by the first stage.
template <class System, class... Data>
void rk4_step(const System& system, double t_begin, double t_end, const typename System::State& x,
              typename System::State& x_next, Rk4Workspace<System>& w,
              typename System::Outputs* outputs = nullptr, Data&... data) {
  const double h = t_end - t_begin;
  if (!(w.begin_time == t_begin)) system.time_signals(t_begin, w.begin);
  system.time_signals(t_begin + 0.5 * h, w.middle);
  system.time_signals(t_end, w.end);

  system.derivative(w.begin, x, w.k1, outputs, data...);
  w.stage = x + (0.5 * h) * w.k1;
  system.derivative(w.middle, w.stage, w.k2, nullptr, data...);
  w.stage = x + (0.5 * h) * w.k2;
  system.derivative(w.middle, w.stage, w.k3, nullptr, data...);
  w.stage = x + h * w.k3;
  system.derivative(w.end, w.stage, w.k4, nullptr, data...);
  x_next =
      x + (h / 6.0) * (w.k1 + 2.0 * w.k2 + 2.0 * w.k3 + w.k4);  // coefficient-wise: x may alias

  std::swap(w.begin, w.end);
  w.begin_time = t_end;
}

// In place: x advances from t_begin to t_end.
template <class System, class... Data>
void rk4_step(const System& system, double t_begin, double t_end, typename System::State& x,
              Rk4Workspace<System>& w, typename System::Outputs* outputs = nullptr, Data&... data) {
  rk4_step(system, t_begin, t_end, x, x, w, outputs, data...);
}

}  // namespace adparm
