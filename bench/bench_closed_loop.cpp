// Standalone benchmark of the paper's closed loop (no Python, no test framework).
// Usage: adparm_bench [simulated_seconds] [extrapolation_points]   (default 110 and 0)
// With extrapolation points (fixed, in [-1, 1]^4) the probing signal stays on, so the loop does
// the same work as the paper's plus the points. Prints one machine-readable line:
//   bench=paper_loop points=<N> steps=<n> ns_per_step=<x> steps_per_second=<y>
//   final_critic_error=<z> status=<finished|diverged>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "adparm/simulation.hpp"

int main(int argc, char** argv) {
  adparm::Settings settings = adparm::paper_settings();
  settings.sim.T = argc > 1 ? std::atof(argv[1]) : 110.0;
  settings.extrapolation.points = argc > 2 ? std::atol(argv[2]) : 0;
  adparm::PaperSimulation simulation(settings);
  const auto start = std::chrono::steady_clock::now();
  const long steps = simulation.advance(simulation.steps());
  const auto stop = std::chrono::steady_clock::now();
  const double seconds = std::chrono::duration<double>(stop - start).count();
  adparm::PaperBasis::Vector optimal;
  optimal << 4, 6, -8, 5, 2, 1, 2, 2;
  const auto& state = simulation.state();
  const double critic_error =
      (state.segment<8>(adparm::PaperClosedLoop::kCriticWeights) - optimal).norm() / optimal.norm();
  std::printf(
      "bench=paper_loop points=%ld steps=%ld ns_per_step=%.1f steps_per_second=%.0f "
      "final_critic_error=%.4g status=%s\n",
      settings.extrapolation.points, steps, 1e9 * seconds / steps, steps / seconds, critic_error,
      simulation.status() == adparm::RunStatus::finished ? "finished" : "diverged");
  return simulation.status() == adparm::RunStatus::finished ? 0 : 1;
}
