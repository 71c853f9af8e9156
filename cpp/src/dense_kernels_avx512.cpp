// The dense kernels (dense_kernels.hpp) for AVX-512: this file is compiled with -mavx512f -mfma
// (CMakeLists.txt) and only called after the CPU was found to have AVX-512F (dense_kernels.cpp).
#include <immintrin.h>

#include "adparm/dense_kernels.hpp"

namespace {

struct Isa {
  using V = __m512d;
  using Mask = __mmask8;
  static constexpr long kWidth = 8;
  static constexpr int kRowVectors = 2;
  static constexpr int kColumns = 6;  // 2 x 6 sums in 12 of the 32 registers
  // Products of kColumns or more columns in panels of rows (dense_kernels_impl.hpp's
  // blocked_product): measured 1.1-1.4x faster for K = 21..105, 51 samples.
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
  // The first `count` lanes (0 <= count < 8).
  static Mask mask(long count) { return static_cast<Mask>((1u << count) - 1u); }
  static double sum(V v) { return _mm512_reduce_add_pd(v); }
};

#include "dense_kernels_impl.hpp"

const adparm::DenseKernels kKernels{"avx512", product,        rank_update, transposed_products,
                                    gains,    low_rank_update};

}  // namespace

namespace adparm::dense_kernels_avx512 {
const DenseKernels* table() { return &kKernels; }
}  // namespace adparm::dense_kernels_avx512
