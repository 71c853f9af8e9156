// The dense kernels of the n-joint loop's critic (eqs. 23-24) and of its stacked extrapolation
// points (eq. 26), compiled for AVX2 + FMA and for AVX-512 in translation units of their own
// (cpp/src/dense_kernels_*.cpp) and chosen at run time, once per loop (Critic's constructor):
//   - product:  C (m x n) = A (m x depth) B (depth x n), or C -= A B        Gamma Omega; G c
//   - rank_update: C (n x n) -= A (n x depth) B (n x depth)^T, the lower triangle (and entries
//     up to a column block above it) or the whole matrix                  the rank-s dGamma
//   - transposed_products: y0 = A^T x0, y1 = A^T x1 (one pass over A)      B^T Wa, B^T (Wa - Wc)
//   - gains: the gathered samples' gains g_i and g_i Gamma omega_i           eqs. 23-24
//   - low_rank_update: Gamma - sum of four rank-one terms, and their norm    RK4 without points
//   - mirror_lower: the lower triangle copied onto the upper one               the rank-s dGamma
//   - point_regressor: omega = f - B x, c . omega and ||omega||^2               eqs. 21-22, a point
//   - stage_sum, rk4_sum: RK4's sums on the state, as Eigen's, bit for bit        lower_step
//   - pair_points, pair_gradient: the points' shares for a basis of pairs          eqs. 20-26
//     (PairPoints below), B_i = J_e2(x_i) M_i^-1 never formed
// All column-major on raw pointers: no Eigen or Pinocchio type crosses into the code built for
// another instruction set (its inline functions would be merged with the portable build's at
// link time). The portable path is no table at all (nullptr): the callers keep Eigen's products,
// the same code and the same bits as before the kernels.
// The choice (select_dense_kernels): the environment variable ADPARM_KERNELS, read when a loop is
// built: "auto" or unset (below), "portable", "avx2" or "avx512" (an error if the CPU lacks it).
// auto: for a loop whose critic gathers blocks of samples (extrapolation points: K x K x s
// products) AVX-512 if the CPU has AVX-512F; for one sample per evaluation (rank-one products)
// AVX2 first: on an AVX-512 CPU (Sapphire Rapids) every such bench case ran faster with the AVX2
// set (3-link and UR5, quadratic and structured basis: 4-7 %), the 512-bit instructions' cost to
// the clock and to the surrounding code outweighing their few short products. Then the other
// set, else portable.
// The kernels sum each entry's products in a fixed order with fused multiply-adds: the same
// result on any thread count and run after run on one kernel set, and within round-off (not bit
// for bit) of the portable path and of the other kernel set.
#pragma once

namespace adparm {

// The extrapolation points of a basis of pairs (every function phi_k = c_k x_a x_b of the error
// state, a = b allowed: the quadratic family; Extrapolation::pairs), arrays over the points side
// by side: entry v of point i at [v * stride + i], stride a multiple of 8 (the lanes after the
// last point zero). Each function's row of d phi / d e2 has at most two terms, term t (0, 1):
// d phi_k / d e2 z = coefficient[k] * sum_t x[term_x[2k + t]] z[term_z[2k + t]] (term_z < 0:
// none), so that B_i y = J_e2(x_i) M_i^-1 y and B_i^T w = M_i^-T S(w) x_i, where the rows of S
// (n x 2n) gather c_k w_k by those terms (ClosedLoop::learn_from_pairs).
struct PairPoints {
  long joints, functions, points, stride;  // n, K, N, the points' stride
  const double* x;                         // 2n x stride: the points x_i
  const double* mass_inverse;              // n^2 x stride: M_i^-1 (r, c) as entry r + c n
  const double* drift_rates;               // K x stride: F_i = (d phi / dx) f + (d phi / d qd) dqd
  const double* state_costs;               // stride: x_i^T Q x_i
  const double* weight_forms;              // 2n x 2n, column-major: rows [S(Wa); S(Wa - Wc)]
  const double* r_inverse;                 // n x n, column-major
  const double* critic_weights;            // K: Wc
  const int* term_x;                       // 2K
  const int* term_z;                       // 2K (< 0: no term)
  const double* coefficient;               // K
  double* scratch;                         // (2 n^2 + 6 n) x 8 doubles (8: AVX-512's width)
  double* omega;                 // out: omega_i = F_i + B_i u_hat_i (K) at omega + i omega_stride
  long omega_stride;             // >= K
  double* error;                 // out, stride: eq. 21's eps_i
  double* norm;                  // out, stride: ||omega_i||^2
  double* projected_difference;  // out, n x stride: R^-1 B_i^T (Wa - Wc) (pair_gradient's)
  const double* actor_gains;     // stride: w_i eta_a1 (Actor::gradient_scale)
  double* scale;                 // out, stride: eq. 26's w_i eta_a1 eps_i / sqrt(1 + ||omega_i||^2)
  double* inputs = nullptr;  // out, n x stride: -u_hat_i = 0.5 R^-1 B_i^T Wa (nullptr: not kept)
  // nullptr, or the inputs of lanes tail_offset ... tail_offset + kTailLanes - 1 (tail_offset a
  // multiple of 8, the lanes within stride) in a block of their own instead of x, mass_inverse,
  // drift_rates and state_costs: entry v of lane l at [v * kTailLanes + l], x (2n), M^-1 (n^2),
  // F (K) and x^T Q x (1) one after the other (ClosedLoop: the last points and the trajectory)
  const double* tail = nullptr;
  long tail_offset = 0;
  static constexpr long kTailLanes = 8;
};

struct DenseKernels {
  const char* name;  // "avx2" or "avx512"
  // C = A B (subtract false) or C -= A B (subtract true); B's entry (p, j) at
  // b[p * b_depth_stride + j * b_column_stride] (B itself: 1, ldb; a transpose: ldb, 1).
  void (*product)(long m, long n, long depth, const double* a, long lda, const double* b,
                  long b_depth_stride, long b_column_stride, double* c, long ldc, bool subtract);
  // C -= A B^T (C n x n, A and B n x depth): lower (its lower triangle; some entries above it,
  // in the register blocks that reach it, are updated too, as in the whole product) or whole.
  // overwrite: C = -(A B^T) on those entries, C not read (the same bits as C -= A B^T on a zeroed
  // C); the others are left as they were.
  void (*rank_update)(long n, long depth, const double* a, long lda, const double* b, long ldb,
                      double* c, long ldc, bool lower, bool overwrite);
  // y0 = A^T x0, y1 = A^T x1 (A m x n).
  void (*transposed_products)(long m, long n, const double* a, long lda, const double* x0,
                              const double* x1, double* y0, double* y1);
  // The critic's gains of n gathered samples (critic.hpp, eqs. 23-24): for each column j of
  // omega and G = Gamma omega (m x n each), g_j = weight_j eta_c / (1 + nu omega_j^T G_j), then
  // coefficient_j *= g_j and scaled_j = g_j G_j.
  void (*gains)(long m, long n, const double* omega, long ldo, const double* gamma_omega, long ldg,
                const double* weight, double eta_c, double nu, double* coefficient, double* scaled,
                long lds);
  // The low-rank RK4 step's end (critic.hpp, Critic::low_rank_update): next = gamma - D (n x n,
  // next may be gamma), D = sum_s c_s u_s u_s^T over the four columns of u (n x 4); returns
  // ||D||_F^2.
  double (*low_rank_update)(long n, const double* u, long ldu, const double* c, const double* gamma,
                            long ldg, double* next, long ldn);
  // C(i, j) = C(j, i) for i < j (C n x n): the rank-s update's lower triangle mirrored
  // (Critic::flush), in tiles transposed in registers; copies only (the same bits as any copy).
  void (*mirror_lower)(long n, double* c, long ldc);
  // An extrapolation point's regressor omega = f - B x (m entries; B m x n, column stride ldb,
  // nonzero only in rows [first, first + rows): omega = f outside them) and value = c . omega,
  // norm = omega . omega, in one pass (ClosedLoop::learn_from_points_batched). The same bits as
  // product (subtract, rows [first, first + rows), on a copy of f) then transposed_products.
  void (*point_regressor)(long m, long first, long rows, long n, const double* b, long ldb,
                          const double* x, const double* f, const double* c, double* omega,
                          double* value, double* norm);
  // RK4's sums on n entries (ClosedLoop::lower_step): a stage's out = x + c r, and the step's end
  // out = x + h6 (((r1 + 2 r2) + 2 r3) + r4), each a product then a sum, no fused multiply-add:
  // the same bits as Eigen's expressions of rk4_step (rk4.hpp) on the portable path.
  void (*stage_sum)(long n, const double* x, const double* r, double c, double* out);
  void (*rk4_sum)(long n, const double* x, const double* r1, const double* r2, const double* r3,
                  const double* r4, double h6, double* out);
  // The points of a basis of pairs (PairPoints): u_hat_i = -0.5 R^-1 B_i^T Wa (eq. 20), omega_i,
  // eps_i = x_i^T Q x_i + u_hat_i^T R u_hat_i + Wc^T omega_i (eq. 21), ||omega_i||^2, the actor's
  // scale and R^-1 B_i^T (Wa - Wc) (eq. 26).
  void (*pair_points)(const PairPoints& points);
  // The actor's share of the points of a basis of pairs (eq. 26), after pair_points: with c_i =
  // scale_i R^-1 B_i^T (Wa - Wc), sum_i B_i c_i is J_e2's terms of P = sum_i x_i (M_i^-1 c_i)^T:
  // out (2n x n, column-major) = P. Overwrites projected_difference (with M_i^-1 c_i).
  void (*pair_gradient)(const PairPoints& points, double* out);
};

// The kernels of ADPARM_KERNELS on this CPU for a loop that gathers blocks of samples or not
// (`blocks`; auto, above); nullptr: the portable path. Throws std::invalid_argument for an unknown
// value or a kernel set this CPU cannot run.
const DenseKernels* select_dense_kernels(bool blocks = true);

// The name of a choice: "portable" for nullptr.
inline const char* dense_kernels_name(const DenseKernels* kernels) {
  return kernels == nullptr ? "portable" : kernels->name;
}

}  // namespace adparm
