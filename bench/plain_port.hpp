// A plain port of the paper's closed loop (bench/plain_port.cpp): the yardstick of issue 26's
// paper-loop target. Its own translation unit, built with the core's portable flags (-O3, no
// -march); nothing of adparm is shared with it, and only plain types cross this interface.
#pragma once

#include <vector>

namespace plain_port {

// The state's layout, as adparm's PaperClosedLoop: [q (2), dq (2), Wc (8), Wa (8), Gamma (8 x 8,
// column-major), nu (2), J (1)].
constexpr int kStateSize = 87;

struct Run {
  double state[kStateSize];         // the state after `steps` steps
  std::vector<double> reset_times;  // times of the covariance resets (s)
  long steps = 0;
  bool diverged = false;
};

// The paper's run (adparm::paper_settings(): two-link arm, 8 functions, probe, RISE, RK4 at dt =
// 1 ms) over `seconds` simulated seconds (ceil(seconds / dt) steps, the last one shortened).
void run(double seconds, Run& out);

}  // namespace plain_port
