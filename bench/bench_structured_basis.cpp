// Standalone micro-benchmark of the structured basis of URDF arms
// (cpp/include/adparm/pinocchio_structured_basis.hpp; no Python).
//
// Usage: adparm_bench_structured_basis [evaluations]   (default 200000 per arm)
// For the planar 3-link and spatial 3-joint arms of examples/arms and example-robot-data's UR5
// (skipped without it), evaluate() through the loop's seam (bounded vectors, as the dynamic-size
// loop calls it) at 1024 random points (x in [-1, 1]^2n, qd in [-pi, pi]^n, dqd in [-1, 1]^n),
// cycling; the fastest of three repeats is reported. One line per arm:
//   bench=structured_basis arm=A joints=n functions=N ns_per_evaluation=x heap_allocations=a
// heap_allocations counts malloc calls during the timed loop (glibc's malloc interposed, or
// AddressSanitizer's allocation hook; -1 elsewhere); any allocation exits 1.
//
// Before timing, two checks (exit 1 on failure), one line per arm:
//   bench=structured_basis_checks arm=A hjb_relative=r copies_agree=0|1
// the HJB error of hjb.hpp (prepare_hjb_point, evaluate_hjb: the loop's own code) at W* for
// K = I, alpha1 = 2 I, R = I, Q = [[4 I, -I], [-I, I]] (the exact-solution conditions), relative
// to x^T Q x, must be below 1e-10 at every point; and a copy and a copy-assigned basis (each its
// own pinocchio::Data) must evaluate bit for bit as the original.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "adparm/cost.hpp"
#include "adparm/hjb.hpp"
#include "adparm/pinocchio_arm.hpp"
#include "adparm/pinocchio_structured_basis.hpp"
#include "heap_counter.hpp"

namespace {

using Clock = std::chrono::steady_clock;

using Basis = adparm::PinocchioStructuredBasis;
using Points = std::vector<adparm::ErrorVector<adparm::Dynamic>>;
using Desired = std::vector<adparm::DesiredStateT<adparm::Dynamic>>;

bool check(const std::string& name, const adparm::PinocchioArm& arm, const Basis& basis,
           const Points& xs, const Desired& desired) {
  const int n = arm.dof();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd Q(2 * n, 2 * n);
  Q << 4.0 * I, -I, -I, I;
  const adparm::QuadraticCostT<adparm::Dynamic> cost(Q, I, n);
  const Eigen::MatrixXd alpha1 = 2.0 * I;
  const Basis::Vector W = basis.optimal_weights(I);
  adparm::PinocchioArm::Terms terms = arm.make_terms();
  adparm::HjbPoint<Basis, adparm::Dynamic> point;
  adparm::HjbEvaluation<Basis, adparm::Dynamic> evaluation;
  adparm::BasisWorkspace<Basis> workspace = adparm::basis_workspace(basis);
  double worst = 0.0;
  for (std::size_t i = 0; i < 64; ++i) {
    const auto& x = xs[i];
    const Eigen::VectorXd e1 = x.head(n), e2 = x.tail(n);
    const Eigen::VectorXd q = desired[i].q - e1, dq = desired[i].dq - (e2 - alpha1 * e1);
    arm.compute(q, dq, terms);
    adparm::ErrorVector<adparm::Dynamic> drift(2 * n);
    drift << -alpha1 * e1 + e2, -terms.mass_inverse * (terms.coriolis * e2);
    adparm::prepare_hjb_point<Basis, adparm::Dynamic>(basis, x, desired[i], drift, terms, cost,
                                                      point, workspace);
    adparm::evaluate_hjb(point, cost, W, W, evaluation);
    worst = std::max(worst, std::abs(evaluation.error) / cost.state_cost(x));
  }
  Basis copy(basis), assigned(basis);
  assigned = copy;
  bool agree = true;
  Basis::Vector phi[3], rate[3];
  Basis::Jacobian jacobian[3];
  Basis::Workspace workspaces[3] = {basis.workspace(), copy.workspace(), assigned.workspace()};
  for (std::size_t i = 0; i < 64; ++i) {
    basis.evaluate(xs[i], desired[i], phi[0], jacobian[0], rate[0], workspaces[0]);
    copy.evaluate(xs[i], desired[i], phi[1], jacobian[1], rate[1], workspaces[1]);
    assigned.evaluate(xs[i], desired[i], phi[2], jacobian[2], rate[2], workspaces[2]);
    for (int k = 1; k < 3; ++k)
      agree = agree && phi[k] == phi[0] && jacobian[k] == jacobian[0] && rate[k] == rate[0];
  }
  std::printf("bench=structured_basis_checks arm=%s hjb_relative=%.3g copies_agree=%d\n",
              name.c_str(), worst, agree ? 1 : 0);
  return worst < 1e-10 && agree;
}

// 0: timed, no allocation; 1: a check failed or an allocation was seen.
int run(const std::string& name, const std::string& path, long evaluations) {
  const adparm::PinocchioArm arm(path);
  const adparm::PinocchioStructuredBasis basis(arm);
  const int n = arm.dof();
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  constexpr int kPoints = 1024;
  std::vector<adparm::ErrorVector<adparm::Dynamic>> xs(kPoints);
  std::vector<adparm::DesiredStateT<adparm::Dynamic>> desired(
      kPoints, adparm::DesiredStateT<adparm::Dynamic>(n));
  for (int i = 0; i < kPoints; ++i) {
    xs[static_cast<std::size_t>(i)].resize(2 * n);
    for (int k = 0; k < 2 * n; ++k) xs[static_cast<std::size_t>(i)][k] = unit(random);
    for (int k = 0; k < n; ++k) {
      desired[static_cast<std::size_t>(i)].q[k] = 3.14159265358979 * unit(random);
      desired[static_cast<std::size_t>(i)].dq[k] = unit(random);
    }
  }
  adparm::PinocchioStructuredBasis::Vector phi, rate;
  adparm::PinocchioStructuredBasis::Jacobian jacobian;
  if (!check(name, arm, basis, xs, desired)) return 1;
  adparm::PinocchioStructuredBasis::Workspace workspace = basis.workspace();
  double best = 1e300, checksum = 0.0;
  long seen = 0;
  for (int repeat = 0; repeat < 3; ++repeat) {
    start_counting();
    const auto start = Clock::now();
    for (long e = 0; e < evaluations; ++e) {
      const std::size_t i = static_cast<std::size_t>(e % kPoints);
      basis.evaluate(xs[i], desired[i], phi, jacobian, rate, workspace);
      checksum += phi[basis.size() - 1] + jacobian(0, 0) + rate[basis.size() - 1];
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    seen = std::max(seen, stop_counting());
    best = std::min(best, seconds);
  }
  std::printf(
      "bench=structured_basis arm=%s joints=%d functions=%d ns_per_evaluation=%.1f "
      "heap_allocations=%ld checksum=%.6g\n",
      name.c_str(), n, basis.size(), 1e9 * best / static_cast<double>(evaluations), seen, checksum);
  return seen > 0 ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  const long evaluations = argc > 1 ? std::atol(argv[1]) : 200000;
  const std::string arms = ADPARM_ARMS_DIR, robots = ADPARM_ROBOTS_DIR;
  int status = 0;
  status |= run("planar_3link", arms + "/planar_3link.urdf", evaluations);
  status |= run("spatial_3dof", arms + "/spatial_3dof.urdf", evaluations);
  if (!robots.empty())
    status |= run("ur5", robots + "/ur_description/urdf/ur5_robot.urdf", evaluations);
  else
    std::printf("bench=structured_basis arm=ur5 skipped (no example-robot-data)\n");
  return status;
}
