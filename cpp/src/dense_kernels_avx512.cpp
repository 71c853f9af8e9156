// The dense kernels (dense_kernels.hpp) for AVX-512: this file is compiled with -mavx512f -mfma
// (CMakeLists.txt) and only called after the CPU was found to have AVX-512F (dense_kernels.cpp).
#include <immintrin.h>

#include "adparm/dense_kernels.hpp"

namespace {

struct Isa {
  using V = __m512d;
  using Mask = __mmask8;
  static constexpr const char* kName = "avx512";
  static constexpr long kWidth = 8;
  static constexpr int kRowVectors = 3;
  static constexpr int kColumns = 8;  // 3 x 8 sums in 24 of the 32 registers
  // Products of kColumns or more columns in panels of rows (dense_kernels_impl.hpp's
  // blocked_product): measured 1.1-1.4x faster for K = 21..105, 51 samples. 3 x 8 against 2 x 6
  // (Gamma Omega and the rank-s update at K = 21, 28, 55, 78, 105, 51 samples): 1.10-1.14x.
  static constexpr bool kRowPanels = true;
  static V zero() { return _mm512_setzero_pd(); }
  static V load(const double* p) { return _mm512_loadu_pd(p); }
  static V load(const double* p, Mask mask) { return _mm512_maskz_loadu_pd(mask, p); }
  static void store(double* p, V v) { _mm512_storeu_pd(p, v); }
  static void store(double* p, V v, Mask mask) { _mm512_mask_storeu_pd(p, mask, v); }
  static V broadcast(const double* p) { return _mm512_set1_pd(*p); }
  static V fma(V a, V b, V c) { return _mm512_fmadd_pd(a, b, c); }
  static V subtract(V a, V b) { return _mm512_sub_pd(a, b); }
  static V add(V a, V b) { return _mm512_add_pd(a, b); }
  static V multiply(V a, V b) { return _mm512_mul_pd(a, b); }
  static V divide(V a, V b) { return _mm512_div_pd(a, b); }
  static V sqrt(V a) { return _mm512_sqrt_pd(a); }
  // The first `count` lanes (0 <= count < 8).
  static Mask mask(long count) { return static_cast<Mask>((1u << count) - 1u); }
  static double sum(V v) { return _mm512_reduce_add_pd(v); }
  // rows[t] becomes column t of the 8 x 8 matrix whose rows are rows[0 ... 7].
  static void transpose(V (&rows)[8]) {
    const V a0 = _mm512_unpacklo_pd(rows[0], rows[1]), a1 = _mm512_unpackhi_pd(rows[0], rows[1]);
    const V a2 = _mm512_unpacklo_pd(rows[2], rows[3]), a3 = _mm512_unpackhi_pd(rows[2], rows[3]);
    const V a4 = _mm512_unpacklo_pd(rows[4], rows[5]), a5 = _mm512_unpackhi_pd(rows[4], rows[5]);
    const V a6 = _mm512_unpacklo_pd(rows[6], rows[7]), a7 = _mm512_unpackhi_pd(rows[6], rows[7]);
    const V b0 = _mm512_shuffle_f64x2(a0, a2, 0x88), b1 = _mm512_shuffle_f64x2(a1, a3, 0x88);
    const V b2 = _mm512_shuffle_f64x2(a0, a2, 0xdd), b3 = _mm512_shuffle_f64x2(a1, a3, 0xdd);
    const V b4 = _mm512_shuffle_f64x2(a4, a6, 0x88), b5 = _mm512_shuffle_f64x2(a5, a7, 0x88);
    const V b6 = _mm512_shuffle_f64x2(a4, a6, 0xdd), b7 = _mm512_shuffle_f64x2(a5, a7, 0xdd);
    rows[0] = _mm512_shuffle_f64x2(b0, b4, 0x88);
    rows[1] = _mm512_shuffle_f64x2(b1, b5, 0x88);
    rows[2] = _mm512_shuffle_f64x2(b2, b6, 0x88);
    rows[3] = _mm512_shuffle_f64x2(b3, b7, 0x88);
    rows[4] = _mm512_shuffle_f64x2(b0, b4, 0xdd);
    rows[5] = _mm512_shuffle_f64x2(b1, b5, 0xdd);
    rows[6] = _mm512_shuffle_f64x2(b2, b6, 0xdd);
    rows[7] = _mm512_shuffle_f64x2(b3, b7, 0xdd);
  }
};

#include "dense_kernels_impl.hpp"

}  // namespace

namespace adparm::dense_kernels_avx512 {
const DenseKernels* table() { return &kKernels; }
}  // namespace adparm::dense_kernels_avx512
