// Standalone micro-benchmark of the expression basis (cpp/include/adparm/expression_basis.hpp)
// against the hand-written two-link bases of basis.hpp (no Python).
//
// Usage: adparm_bench_basis [--checks] [evaluations]   (default 2000000 per basis)
// The paper's 8 functions, written as an expression program, are evaluated at 1024 random points
// (x in [-1, 1]^4, qd in [-1, 1]^2, dqd in [-1, 1]^2), cycling, as are PaperBasis and
// AugmentedBasis; the fastest of three repeats is reported. One line per measurement:
//   bench=basis basis=B engine=hand_written|expression functions=N joints=n ns_per_evaluation=x
//     heap_allocations=a [ratio=r]
// ratio = ns of the expression basis / ns of the hand-written one, from the same invocation;
// heap_allocations counts malloc calls during the timed expression loop (glibc's malloc
// interposed, or AddressSanitizer's allocation hook; -1 elsewhere). Then the quadratic family (all
// x_i x_j, i <= j) for n = 2, 3, 6.
//
// Before timing, the expression bases must reproduce PaperBasis and AugmentedBasis bit for bit
// (phi, d phi / dx, desired rate) at every point, through both forms of the seam (with and without
// the arm's terms), and evaluate without a heap allocation; else exit 1. --checks
// (bench/sanitize.sh) then also feeds invalid programs and sizes, each expected to throw
// std::invalid_argument:
//   bench=basis_checks invalid=k refused=k failed=f
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "adparm/basis.hpp"
#include "adparm/expression_basis.hpp"
#include "heap_counter.hpp"

namespace {

using adparm::ExpressionBasis;
using adparm::ExpressionInstruction;
using adparm::ExpressionOp;
using Clock = std::chrono::steady_clock;
using Program = std::vector<ExpressionInstruction>;

// Postfix helpers. Variables z = [x1..x2n, qd1..qdn], 0-based.
ExpressionInstruction var(int i) { return {ExpressionOp::variable, static_cast<double>(i)}; }
ExpressionInstruction op(ExpressionOp o, double a = 0.0) { return {o, a}; }

// The paper's 8 functions (basis.hpp's order); cos of x2 (paper) or of q2 = qd2 - x2 (augmented).
Program paper_program(bool augmented) {
  auto square = [](int i) { return Program{var(i), op(ExpressionOp::power, 2)}; };
  auto product = [](int i, int j) { return Program{var(i), var(j), op(ExpressionOp::multiply)}; };
  const Program angle =
      augmented ? Program{var(5), var(1), op(ExpressionOp::subtract)} : Program{var(1)};
  Program cosine = angle;
  cosine.push_back(op(ExpressionOp::cos));
  std::vector<Program> functions = {square(0), square(1), product(0, 1), square(2),
                                    square(2), square(3), product(2, 3), product(2, 3)};
  for (int f : {4, 7}) {
    functions[f].insert(functions[f].end(), cosine.begin(), cosine.end());
    functions[f].push_back(op(ExpressionOp::multiply));
  }
  Program program;
  for (const Program& f : functions) {
    program.insert(program.end(), f.begin(), f.end());
    program.push_back(op(ExpressionOp::store));
  }
  return program;
}

Program quadratic_program(int joints) {
  Program program;
  for (int i = 0; i < 2 * joints; ++i)
    for (int j = i; j < 2 * joints; ++j) {
      if (i == j) {
        program.insert(program.end(), {var(i), op(ExpressionOp::power, 2)});
      } else {
        program.insert(program.end(), {var(i), var(j), op(ExpressionOp::multiply)});
      }
      program.push_back(op(ExpressionOp::store));
    }
  return program;
}

struct Points {
  std::vector<Eigen::VectorXd> x, qd, dqd;
};

Points random_points(int joints, int count, unsigned seed) {
  std::mt19937_64 generator(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  auto draw = [&](int size) {
    Eigen::VectorXd v(size);
    for (int i = 0; i < size; ++i) v[i] = uniform(generator);
    return v;
  };
  Points points;
  for (int i = 0; i < count; ++i) {
    points.x.push_back(draw(2 * joints));
    points.qd.push_back(draw(joints));
    points.dqd.push_back(draw(joints));
  }
  return points;
}

double sink = 0.0;  // keeps the timed evaluations alive

// Fastest of three repeats of `evaluations` calls of f(i), in ns per call.
template <class F>
double time_ns(long evaluations, const F& f) {
  double best = 1e300;
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto start = Clock::now();
    for (long i = 0; i < evaluations; ++i) f(i);
    best = std::min(best, std::chrono::duration<double>(Clock::now() - start).count());
  }
  return best * 1e9 / static_cast<double>(evaluations);
}

struct Buffers {
  Eigen::VectorXd phi, rate;
  Eigen::MatrixXd jacobian;
  explicit Buffers(const ExpressionBasis& b)
      : phi(b.size()), rate(b.size()), jacobian(b.size(), b.state_dim()) {}
};

// The expression basis against a hand-written one at every point, bit for bit; returns the
// number of points that differ.
template <class Basis>
int compare(ExpressionBasis& expression, const Points& points) {
  Buffers out(expression);
  int differing = 0;
  for (std::size_t i = 0; i < points.x.size(); ++i) {
    adparm::DesiredState desired;
    desired.q = points.qd[i];
    desired.dq = points.dqd[i];
    const adparm::Vec4 x = points.x[i];
    typename Basis::Vector phi, rate;
    typename Basis::Jacobian jacobian;
    Basis::evaluate(x, desired, phi, jacobian, rate);
    expression.evaluate(points.x[i], desired, out.phi, out.jacobian, out.rate);
    if (!(out.phi.array() == phi.array()).all() ||
        !(out.jacobian.array() == jacobian.array()).all() ||
        !(out.rate.array() == rate.array()).all())
      ++differing;
    // the seam's second form (with the arm's terms, unused) into fixed-size outputs
    struct NoTerms {
    } terms;
    typename Basis::Vector phi2, rate2;
    typename Basis::Jacobian jacobian2;
    expression.evaluate(points.x[i], desired, terms, phi2, jacobian2, rate2);
    if (phi2 != phi || jacobian2 != jacobian || rate2 != rate) ++differing;
  }
  return differing;
}

template <class Basis>
double time_hand_written(long evaluations, const Points& points) {
  std::vector<adparm::DesiredState> desired(points.x.size());
  std::vector<adparm::Vec4> xs(points.x.size());
  for (std::size_t i = 0; i < xs.size(); ++i) {
    desired[i].q = points.qd[i];
    desired[i].dq = points.dqd[i];
    xs[i] = points.x[i];
  }
  typename Basis::Vector phi, rate;
  typename Basis::Jacobian jacobian;
  const long mask = static_cast<long>(xs.size()) - 1;
  const double ns = time_ns(evaluations, [&](long i) {
    Basis::evaluate(xs[i & mask], desired[i & mask], phi, jacobian, rate);
    sink += phi[7] + jacobian(7, 1) + rate[7];
  });
  return ns;
}

double time_expression(ExpressionBasis& basis, long evaluations, const Points& points,
                       long& heap_allocations) {
  Buffers out(basis);
  ExpressionBasis::Workspace workspace = basis.workspace();
  const long mask = static_cast<long>(points.x.size()) - 1;
  const int last = basis.size() - 1;
  start_counting();
  const double ns = time_ns(evaluations, [&](long i) {
    basis.evaluate(points.x[i & mask], points.qd[i & mask], points.dqd[i & mask], out.phi,
                   out.jacobian, out.rate, nullptr, workspace);
    sink += out.phi[last] + out.jacobian(last, 1) + out.rate[last];
  });
  heap_allocations = stop_counting();
  return ns;
}

int failures = 0;

void expect_refused(const char* name, const std::function<void()>& f, int& tried, int& refused) {
  ++tried;
  try {
    f();
    std::printf("bench=basis_check case=%s refused=0\n", name);
    ++failures;
  } catch (const std::invalid_argument& error) {
    ++refused;
    std::printf("bench=basis_check case=%s refused=1 message=\"%s\"\n", name, error.what());
  }
}

void run_checks() {
  int tried = 0, refused = 0;
  const auto build = [](int joints, Program program) {
    return [joints, program] { ExpressionBasis basis(joints, program); };
  };
  expect_refused("unknown_opcode", build(2, {{static_cast<ExpressionOp>(42), 0.0}}), tried,
                 refused);
  expect_refused("variable_out_of_range", build(2, {var(6), op(ExpressionOp::store)}), tried,
                 refused);
  expect_refused("variable_negative", build(2, {var(-1), op(ExpressionOp::store)}), tried, refused);
  expect_refused("variable_not_integer",
                 build(2, {op(ExpressionOp::variable, 1.5), op(ExpressionOp::store)}), tried,
                 refused);
  expect_refused("stack_underflow", build(2, {var(0), op(ExpressionOp::multiply)}), tried, refused);
  expect_refused("store_two_values", build(2, {var(0), var(1), op(ExpressionOp::store)}), tried,
                 refused);
  expect_refused("unstored_values", build(2, {var(0), op(ExpressionOp::store), var(1)}), tried,
                 refused);
  expect_refused("empty_program", build(2, {}), tried, refused);
  expect_refused("not_finite_constant",
                 build(2, {op(ExpressionOp::constant, NAN), op(ExpressionOp::store)}), tried,
                 refused);
  expect_refused("zero_joints", build(0, {var(0), op(ExpressionOp::store)}), tried, refused);
  ExpressionBasis basis(2, paper_program(true));
  Buffers out(basis);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(4), q = Eigen::VectorXd::Zero(2);
  const Eigen::VectorXd wrong = Eigen::VectorXd::Zero(3);
  ExpressionBasis::Workspace workspace = basis.workspace();
  expect_refused(
      "x_size",
      [&] { basis.evaluate(wrong, q, q, out.phi, out.jacobian, out.rate, nullptr, workspace); },
      tried, refused);
  expect_refused(
      "qd_size",
      [&] { basis.evaluate(x, wrong, q, out.phi, out.jacobian, out.rate, nullptr, workspace); },
      tried, refused);
  expect_refused(
      "jacobian_size",
      [&] {
        Eigen::MatrixXd jacobian(8, 3);
        basis.evaluate(x, q, q, out.phi, jacobian, out.rate, nullptr, workspace);
      },
      tried, refused);
  expect_refused(
      "workspace_of_another_basis",
      [&] {
        ExpressionBasis other(2, quadratic_program(2));
        ExpressionBasis::Workspace w = other.workspace();
        w.values.resize(0);
        basis.evaluate(x, q, q, out.phi, out.jacobian, out.rate, nullptr, w);
      },
      tried, refused);
  std::printf("bench=basis_checks invalid=%d refused=%d failed=%d\n", tried, refused,
              tried - refused);
}

int run(long evaluations, bool checks) {
  const int kPoints = 1024;  // a power of two (the timed loops cycle with a mask)
  const Points points = random_points(2, kPoints, 7);
#ifdef ADPARM_COUNT_MALLOC
  {  // the counter sees a known allocation (else a 0 below would prove nothing)
    start_counting();
    std::vector<double>* probe = new std::vector<double>(16);
    const long seen = stop_counting();
    delete probe;
    std::printf("bench=basis_malloc_counter allocations_seen=%ld\n", seen);
    if (seen < 1) ++failures;
  }
#endif
  ExpressionBasis paper(2, paper_program(false)), augmented(2, paper_program(true));
  const int paper_differing = compare<adparm::PaperBasis>(paper, points);
  const int augmented_differing = compare<adparm::AugmentedBasis>(augmented, points);
  std::printf("bench=basis_exact basis=paper points=%d differing=%d\n", kPoints, paper_differing);
  std::printf("bench=basis_exact basis=augmented points=%d differing=%d\n", kPoints,
              augmented_differing);
  if (paper_differing || augmented_differing) ++failures;

  struct Case {
    const char* name;
    ExpressionBasis* basis;
    double (*hand_written)(long, const Points&);
  };
  const Case cases[] = {{"paper", &paper, &time_hand_written<adparm::PaperBasis>},
                        {"augmented", &augmented, &time_hand_written<adparm::AugmentedBasis>}};
  for (const Case& c : cases) {
    const double hand = c.hand_written(evaluations, points);
    long heap = 0;
    const double expression = time_expression(*c.basis, evaluations, points, heap);
    std::printf(
        "bench=basis basis=%s engine=hand_written functions=8 joints=2 ns_per_evaluation=%.2f\n",
        c.name, hand);
    std::printf(
        "bench=basis basis=%s engine=expression functions=8 joints=2 ns_per_evaluation=%.2f "
        "heap_allocations=%ld ratio=%.2f\n",
        c.name, expression, heap, expression / hand);
    if (heap > 0) ++failures;
  }
  for (int joints : {2, 3, 6}) {
    ExpressionBasis quadratic(joints, quadratic_program(joints));
    const Points p = random_points(joints, kPoints, 11);
    long heap = 0;
    const double ns = time_expression(quadratic, evaluations / 4, p, heap);
    std::printf(
        "bench=basis basis=quadratic engine=expression functions=%d joints=%d "
        "ns_per_evaluation=%.2f heap_allocations=%ld\n",
        quadratic.size(), joints, ns, heap);
    if (heap > 0) ++failures;
  }
  if (checks) run_checks();
  if (sink == 12345.678) std::printf("%g\n", sink);
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  bool checks = false;
  long evaluations = 2000000;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--checks") == 0) {
      checks = true;
      continue;
    }
    char* end = nullptr;
    evaluations = std::strtol(argv[i], &end, 10);
    if (end == argv[i] || *end != '\0' || evaluations < 1) {
      std::fprintf(stderr, "usage: adparm_bench_basis [--checks] [evaluations]\n");
      return 2;
    }
  }
  try {
    return run(evaluations, checks);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "adparm_bench_basis: %s\n", error.what());
    return 2;
  }
}
