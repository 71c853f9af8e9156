// Standalone benchmark of the paper's closed loop (no Python, no test framework).
//
// Usage: adparm_bench [simulated_seconds] [extrapolation_points ...]
//   default: 110 s (the paper's claim time) and N = 0, 10, 50 points.
// Each N runs the paper's settings (paper_settings(), the basis adparm.paper_config() uses) for
// the given horizon, three times; the fastest run is reported. With points (fixed, drawn in
// [-1, 1]^4) the probing signal stays on, so the loop does the paper's work plus the points'.
// Then 16 independent paper runs go through Batch on 1 and on 2 threads.
//
// One machine-readable line per measurement (key=value, space separated):
//   bench=paper_loop points=N steps=n repeats=3 ns_per_step=x steps_per_second=y
//     ns_per_point_step=z heap_allocations=a final_critic_error=e status=finished
//   bench=batch runs=16 steps=n threads=t seconds=s ns_per_step=x speedup=r identical=1
// ns_per_point_step = (ns_per_step(N) - ns_per_step(0)) / N, from the same invocation.
// heap_allocations counts malloc calls during the timed loop (glibc only; -1 elsewhere or under
// AddressSanitizer, which owns malloc).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "adparm/batch.hpp"

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#define ADPARM_COUNT_MALLOC 1
extern "C" void* __libc_malloc(std::size_t size);
namespace {
bool counting = false;
long allocations = 0;
}  // namespace
// Interposes malloc for this executable (operator new and Eigen both end here).
extern "C" void* malloc(std::size_t size) {
  if (counting) ++allocations;
  return __libc_malloc(size);
}
#endif

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
  Eigen::Matrix<double, 8, 1> optimal;
  optimal << 4, 6, -8, 5, 2, 1, 2, 2;
  const Eigen::VectorXd weights =
      simulation.state().segment<8>(adparm::PaperClosedLoop::kCriticWeights);
  return (weights - optimal).norm() / optimal.norm();
}

LoopTiming time_loop(const adparm::Settings& settings) {
  adparm::AnySimulation simulation(settings);
  LoopTiming timing;
#ifdef ADPARM_COUNT_MALLOC
  allocations = 0;
  counting = true;
#endif
  const auto start = Clock::now();
  timing.steps = simulation.advance(simulation.steps());
  timing.seconds = seconds_since(start);
#ifdef ADPARM_COUNT_MALLOC
  counting = false;
  timing.heap_allocations = allocations;
#endif
  timing.critic_error = critic_error(simulation);
  timing.status = simulation.status();
  return timing;
}

double time_batch(const std::vector<adparm::Settings>& settings, int threads,
                  std::vector<Eigen::VectorXd>& final_states) {
  adparm::Batch<adparm::AnySimulation> batch(settings);
  const auto start = Clock::now();
  batch.advance(batch[0].steps(), threads);
  const double seconds = seconds_since(start);
  final_states.clear();
  for (std::size_t i = 0; i < batch.size(); ++i) final_states.push_back(batch[i].state());
  return seconds;
}

}  // namespace

int main(int argc, char** argv) {
  const double horizon = argc > 1 ? std::atof(argv[1]) : 110.0;
  std::vector<long> point_counts;
  for (int i = 2; i < argc; ++i) point_counts.push_back(std::atol(argv[i]));
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
  return all_finished && identical ? 0 : 1;
}
