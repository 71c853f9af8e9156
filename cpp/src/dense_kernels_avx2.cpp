// The dense kernels (dense_kernels.hpp) for AVX2 + FMA: this file is compiled with -mavx2 -mfma
// (CMakeLists.txt) and only called after the CPU was found to have both (dense_kernels.cpp).
#include <immintrin.h>

#include "adparm/dense_kernels.hpp"

namespace {

struct Isa {
  using V = __m256d;
  using Mask = __m256i;
  static constexpr const char* kName = "avx2";
  static constexpr long kWidth = 4;
  static constexpr int kRowVectors = 2;
  static constexpr int kColumns = 3;  // 2 x 3 sums (measured faster than 2 x 4 and 3 x 3)
  // Column blocks down all rows (dense_kernels_impl.hpp's blocked_product): panels of rows were
  // no faster here (0.95-1.05x, the rank-s update slower).
  static constexpr bool kRowPanels = false;
  static V zero() { return _mm256_setzero_pd(); }
  static V load(const double* p) { return _mm256_loadu_pd(p); }
  static V load(const double* p, Mask mask) { return _mm256_maskload_pd(p, mask); }
  static void store(double* p, V v) { _mm256_storeu_pd(p, v); }
  static void store(double* p, V v, Mask mask) { _mm256_maskstore_pd(p, mask, v); }
  static V broadcast(const double* p) { return _mm256_broadcast_sd(p); }
  static V fma(V a, V b, V c) { return _mm256_fmadd_pd(a, b, c); }
  static V subtract(V a, V b) { return _mm256_sub_pd(a, b); }
  static V add(V a, V b) { return _mm256_add_pd(a, b); }
  static V multiply(V a, V b) { return _mm256_mul_pd(a, b); }
  static V divide(V a, V b) { return _mm256_div_pd(a, b); }
  static V sqrt(V a) { return _mm256_sqrt_pd(a); }
  // The first `count` lanes (0 <= count < 4).
  static Mask mask(long count) {
    return _mm256_cmpgt_epi64(_mm256_set1_epi64x(count), _mm256_setr_epi64x(0, 1, 2, 3));
  }
  static double sum(V v) {  // (v0 + v2) + (v1 + v3)
    const __m128d pairs = _mm_add_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    return _mm_cvtsd_f64(_mm_add_sd(pairs, _mm_unpackhi_pd(pairs, pairs)));
  }
  // rows[t] becomes column t of the 4 x 4 matrix whose rows are rows[0 ... 3].
  static void transpose(V (&rows)[4]) {
    const V a0 = _mm256_unpacklo_pd(rows[0], rows[1]), a1 = _mm256_unpackhi_pd(rows[0], rows[1]);
    const V a2 = _mm256_unpacklo_pd(rows[2], rows[3]), a3 = _mm256_unpackhi_pd(rows[2], rows[3]);
    rows[0] = _mm256_permute2f128_pd(a0, a2, 0x20);
    rows[1] = _mm256_permute2f128_pd(a1, a3, 0x20);
    rows[2] = _mm256_permute2f128_pd(a0, a2, 0x31);
    rows[3] = _mm256_permute2f128_pd(a1, a3, 0x31);
  }
};

#include "dense_kernels_impl.hpp"

}  // namespace

namespace adparm::dense_kernels_avx2 {
const DenseKernels* table() { return &kKernels; }
}  // namespace adparm::dense_kernels_avx2
