// The dense kernels of the n-joint loop's critic (eqs. 23-24) and of its stacked extrapolation
// points (eq. 26), compiled for AVX2 + FMA and for AVX-512 in translation units of their own
// (cpp/src/dense_kernels_*.cpp) and chosen at run time, once per loop (Critic's constructor):
//   - product:  C (m x n) = A (m x depth) B (depth x n), or C -= A B        Gamma Omega; G c
//   - rank_update: C (n x n) -= A (n x depth) B (n x depth)^T, the lower triangle (and entries
//     up to a column block above it) or the whole matrix                  the rank-s dGamma
//   - transposed_products: y0 = A^T x0, y1 = A^T x1 (one pass over A)      B^T Wa, B^T (Wa - Wc)
//   - gains: the gathered samples' gains g_i and g_i Gamma omega_i           eqs. 23-24
// All column-major on raw pointers: no Eigen or Pinocchio type crosses into the code built for
// another instruction set (its inline functions would be merged with the portable build's at
// link time). The portable path is no table at all (nullptr): the callers keep Eigen's products,
// the same code and the same bits as before the kernels.
// The choice (select_dense_kernels): the environment variable ADPARM_KERNELS, read when a loop is
// built: "auto" or unset (AVX-512 if the CPU has AVX-512F, else AVX2 if it has AVX2 and FMA, else
// portable), "portable", "avx2" or "avx512" (an error if the CPU lacks it).
// The kernels sum each entry's products in a fixed order with fused multiply-adds: the same
// result on any thread count and run after run on one kernel set, and within round-off (not bit
// for bit) of the portable path and of the other kernel set.
#pragma once

namespace adparm {

struct DenseKernels {
  const char* name;  // "avx2" or "avx512"
  // C = A B (subtract false) or C -= A B (subtract true); B's entry (p, j) at
  // b[p * b_depth_stride + j * b_column_stride] (B itself: 1, ldb; a transpose: ldb, 1).
  void (*product)(long m, long n, long depth, const double* a, long lda, const double* b,
                  long b_depth_stride, long b_column_stride, double* c, long ldc, bool subtract);
  // C -= A B^T (C n x n, A and B n x depth): lower (its lower triangle; entries above it within
  // a column block are updated too, as in the whole product) or whole. overwrite: C = -(A B^T)
  // on those entries, C not read (the same bits as C -= A B^T on a zeroed C); the others are
  // left as they were.
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
};

// The kernels of ADPARM_KERNELS on this CPU (above); nullptr: the portable path. Throws
// std::invalid_argument for an unknown value or a kernel set this CPU cannot run.
const DenseKernels* select_dense_kernels();

// The name of a choice: "portable" for nullptr.
inline const char* dense_kernels_name(const DenseKernels* kernels) {
  return kernels == nullptr ? "portable" : kernels->name;
}

}  // namespace adparm
