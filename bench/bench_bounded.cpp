// The constrained-input loop against the unconstrained one on a shared, loaded machine: the paper's
// run (T = 10 s, the fixed-size two-link loop, probing on) with input_bound = 20 N m and the ln
// cosh e2 cost, and without, advanced alternately in chunks of 500 steps; each chunk's time is the
// minimum over R repetitions (default 15), so that another job's time slices drop out (adparm_bench
// times whole runs, which a load of 4-7 on 2 cores spreads by 2x).
//
// Usage: adparm_bench_bounded [repetitions]
//   unbounded_ns_per_step=x bounded_ns_per_step=y ratio=y/x
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "adparm/any_simulation.hpp"
using Loop = adparm::ClosedLoop<adparm::TwoLinkArm, adparm::AugmentedBasis>;
using Sim = adparm::Simulation<adparm::TwoLinkArm, adparm::AugmentedBasis>;
int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::atoi(argv[1]) : 15;
  adparm::Settings u = adparm::paper_settings();
  u.sim.T = 10.0;
  adparm::Settings b = u;
  b.input_bound = Eigen::VectorXd::Constant(2, 20.0);
  b.e2_cost = adparm::E2Cost::logcosh;
  const int chunks = 20, chunk = 500;
  std::vector<double> tu(chunks, 1e9), tb(chunks, 1e9);
  for (int r = 0; r < reps; ++r) {
    Sim su(adparm::make_loop<Loop>(u), u.sim), sb(adparm::make_loop<Loop>(b), b.sim);
    for (int c = 0; c < chunks; ++c) {
      for (int which = 0; which < 2; ++which) {
        Sim& s = (which == (r & 1)) ? su : sb;  // alternate which goes first
        const auto t0 = std::chrono::steady_clock::now();
        s.advance(chunk);
        const double dt =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::vector<double>& t = (&s == &su) ? tu : tb;
        if (dt < t[c]) t[c] = dt;
      }
    }
  }
  double su_ = 0, sb_ = 0;
  for (int c = 0; c < chunks; ++c) {
    su_ += tu[c];
    sb_ += tb[c];
  }
  const double steps = double(chunks) * chunk;
  std::printf("unbounded_ns_per_step=%.1f bounded_ns_per_step=%.1f ratio=%.4f\n", 1e9 * su_ / steps,
              1e9 * sb_ / steps, sb_ / su_);
}
