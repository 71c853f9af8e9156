// adparm_bench --checks: the dense kernels (dense_kernels.hpp) of every set this CPU runs (AVX2,
// AVX-512), on random shapes, against plain loops and against their own documented bit-for-bit
// claims (run by bench/sanitize.sh under AddressSanitizer):
//   - product (C = A B, C -= A B, B or B^T) and rank_update (lower, whole, overwrite) within
//     1e-12 of a plain triple loop; a product equal bit for bit to the same product one column at
//     a time, and the lower rank update to the whole one on the lower triangle (each entry's sum in
//     the same order whatever the blocks);
//   - mirror_lower equal to the entry-by-entry copy; nothing written past C;
//   - point_regressor equal bit for bit to its three steps (a copy of f, product subtracting the
//     rows [first, first + rows), transposed_products of omega with c and with itself);
//   - transposed_products and gains within 1e-12 of plain loops;
//   - stage_sum and rk4_sum equal bit for bit to the sums entry by entry, nothing written past n.
// Prints "bench=check run=dense_kernels set=NAME shapes=n failed=f ok=1" per set.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "adparm/dense_kernels.hpp"

namespace dense_kernel_checks {

using Buffer = std::vector<double>;

inline Buffer random_buffer(std::mt19937& generator, long size) {
  std::uniform_real_distribution<double> draw(-1.0, 1.0);
  Buffer values(static_cast<std::size_t>(size));
  for (double& value : values) value = draw(generator);
  return values;
}

inline bool near(double a, double b) { return std::abs(a - b) <= 1e-12 * (1.0 + std::abs(b)); }

// The checks of one kernel set; returns the number of shapes checked, counts failures.
inline long check_set(const adparm::DenseKernels& k, std::mt19937& generator, long& failed) {
  long shapes = 0;
  const auto expect = [&failed](bool ok, const char* what, long a, long b, long c) {
    if (ok) return;
    ++failed;
    std::fprintf(stderr, "check failed: dense kernel %s (%ld, %ld, %ld)\n", what, a, b, c);
  };
  for (long m = 1; m <= 41; m += 4)
    for (long n : {1L, 3L, 7L, 8L, 11L, 19L, 51L})
      for (long depth : {1L, 6L, 23L}) {
        ++shapes;
        const long lda = m + 1, ldc = m + 3;
        const Buffer a = random_buffer(generator, lda * depth);
        const Buffer b = random_buffer(generator, depth * n);
        Buffer c = random_buffer(generator, ldc * n + 8);
        Buffer expected = c, by_column = c;
        for (long j = 0; j < n; ++j)
          for (long i = 0; i < m; ++i) {
            double sum = 0.0;
            for (long p = 0; p < depth; ++p) sum += a[i + p * lda] * b[p + j * depth];
            expected[i + j * ldc] -= sum;
          }
        k.product(m, n, depth, a.data(), lda, b.data(), 1, depth, c.data(), ldc, true);
        for (long j = 0; j < n; ++j)
          k.product(m, 1, depth, a.data(), lda, b.data() + j * depth, 1, depth,
                    by_column.data() + j * ldc, ldc, true);
        bool close = true;
        for (long j = 0; j < n; ++j)
          for (long i = 0; i < m; ++i) close = close && near(c[i + j * ldc], expected[i + j * ldc]);
        expect(close, "product", m, n, depth);
        expect(c == by_column, "product by columns (bits)", m, n, depth);
        // rank_update: C (m x m) -= A B^T, lower and whole, and overwrite
        const Buffer left = random_buffer(generator, lda * depth);
        const Buffer right = random_buffer(generator, lda * depth);
        Buffer lower = random_buffer(generator, ldc * m + 8);
        Buffer whole = lower, negated = lower;
        k.rank_update(m, depth, left.data(), lda, right.data(), lda, lower.data(), ldc, true,
                      false);
        k.rank_update(m, depth, left.data(), lda, right.data(), lda, negated.data(), ldc, true,
                      true);
        Buffer reference = whole;
        k.rank_update(m, depth, left.data(), lda, right.data(), lda, whole.data(), ldc, false,
                      false);
        bool rank_close = true, rank_bits = true, negated_close = true;
        for (long j = 0; j < m; ++j)
          for (long i = j; i < m; ++i) {
            double sum = 0.0;
            for (long p = 0; p < depth; ++p) sum += left[i + p * lda] * right[j + p * lda];
            rank_close = rank_close && near(whole[i + j * ldc], reference[i + j * ldc] - sum);
            rank_bits = rank_bits && lower[i + j * ldc] == whole[i + j * ldc];
            // -(A B^T) written: the bits of 0 - sum, whatever was there
            negated_close = negated_close && near(negated[i + j * ldc], -sum);
          }
        expect(rank_close, "rank_update", m, depth, 0);
        expect(rank_bits, "rank_update lower = whole (bits)", m, depth, 0);
        expect(negated_close, "rank_update overwrite", m, depth, 0);
        expect(lower[ldc * m] == reference[ldc * m], "rank_update past C", m, depth, 0);
        // mirror_lower
        Buffer mirrored = random_buffer(generator, ldc * m + 8);
        Buffer copied = mirrored;
        for (long j = 1; j < m; ++j)
          for (long i = 0; i < j; ++i) copied[i + j * ldc] = copied[j + i * ldc];
        k.mirror_lower(m, mirrored.data(), ldc);
        expect(mirrored == copied, "mirror_lower", m, ldc, 0);
      }
  // point_regressor, transposed_products and gains on a point's shapes
  for (long m = 1; m <= 41; m += 2)
    for (long n : {1L, 2L, 6L, 7L})
      for (long first = 0; first < m; first += 5)
        for (long rows = 1; first + rows <= m; rows += 6) {
          ++shapes;
          const long ldb = m + 2;
          Buffer b = random_buffer(generator, ldb * n);
          for (long j = 0; j < n; ++j)
            for (long i = 0; i < m; ++i)
              if (i < first || i >= first + rows) b[i + j * ldb] = 0.0;
          const Buffer x = random_buffer(generator, n), f = random_buffer(generator, m);
          const Buffer c = random_buffer(generator, m);
          Buffer omega(static_cast<std::size_t>(m) + 8, 7.0), steps(static_cast<std::size_t>(m));
          double value = 0.0, norm = 0.0, step_value = 0.0, step_norm = 0.0;
          k.point_regressor(m, first, rows, n, b.data(), ldb, x.data(), f.data(), c.data(),
                            omega.data(), &value, &norm);
          steps = f;
          k.product(rows, 1, n, b.data() + first, ldb, x.data(), 1, n, steps.data() + first, m,
                    true);
          k.transposed_products(m, 1, steps.data(), m, c.data(), steps.data(), &step_value,
                                &step_norm);
          bool same = value == step_value && norm == step_norm && omega[m] == 7.0;
          for (long i = 0; i < m; ++i) same = same && omega[i] == steps[i];
          expect(same, "point_regressor = its steps (bits)", m, n, first * 1000 + rows);
          double plain_value = 0.0, plain_norm = 0.0;
          for (long i = 0; i < m; ++i) {
            double entry = f[i];
            for (long j = 0; j < n; ++j) entry -= b[i + j * ldb] * x[j];
            plain_value += c[i] * entry;
            plain_norm += entry * entry;
          }
          expect(near(value, plain_value) && near(norm, plain_norm), "point_regressor", m, n,
                 first * 1000 + rows);
          // transposed_products: y0 = B^T x0, y1 = B^T x1 (m x n)
          const Buffer x0 = random_buffer(generator, m), x1 = random_buffer(generator, m);
          Buffer y0(static_cast<std::size_t>(n)), y1(static_cast<std::size_t>(n));
          k.transposed_products(m, n, b.data(), ldb, x0.data(), x1.data(), y0.data(), y1.data());
          bool transposed_close = true;
          for (long j = 0; j < n; ++j) {
            double sum0 = 0.0, sum1 = 0.0;
            for (long i = 0; i < m; ++i) {
              sum0 += b[i + j * ldb] * x0[i];
              sum1 += b[i + j * ldb] * x1[i];
            }
            transposed_close = transposed_close && near(y0[j], sum0) && near(y1[j], sum1);
          }
          expect(transposed_close, "transposed_products", m, n, 0);
          // gains on n columns of omega and G = Gamma omega
          const Buffer omegas = random_buffer(generator, ldb * n);
          const Buffer gamma_omegas = random_buffer(generator, ldb * n);
          Buffer weights = random_buffer(generator, n), coefficients = random_buffer(generator, n);
          for (double& weight : weights) weight = std::abs(weight);
          Buffer scaled(static_cast<std::size_t>(ldb * n));
          const Buffer before = coefficients;
          const double eta_c = 1.5, nu = 0.25;
          k.gains(m, n, omegas.data(), ldb, gamma_omegas.data(), ldb, weights.data(), eta_c, nu,
                  coefficients.data(), scaled.data(), ldb);
          bool gains_close = true;
          for (long j = 0; j < n; ++j) {
            double dot = 0.0;
            for (long i = 0; i < m; ++i) dot += omegas[i + j * ldb] * gamma_omegas[i + j * ldb];
            const double gain = weights[j] * eta_c / (1.0 + nu * dot);
            gains_close = gains_close && near(coefficients[j], before[j] * gain);
            for (long i = 0; i < m; ++i)
              gains_close =
                  gains_close && near(scaled[i + j * ldb], gain * gamma_omegas[i + j * ldb]);
          }
          expect(gains_close, "gains", m, n, 0);
        }
  // stage_sum and rk4_sum equal bit for bit to the same sums entry by entry (this file is built
  // without FMA: each product rounded before its sum), the entries past n untouched
  for (long n = 0; n <= 41; ++n) {
    ++shapes;
    const Buffer x = random_buffer(generator, n), r1 = random_buffer(generator, n);
    const Buffer r2 = random_buffer(generator, n), r3 = random_buffer(generator, n);
    const Buffer r4 = random_buffer(generator, n);
    Buffer stage = random_buffer(generator, n + 8), end = random_buffer(generator, n + 8);
    const Buffer stage_before = stage, end_before = end;
    const double c = 0.37, h6 = 0.001 / 6.0;
    k.stage_sum(n, x.data(), r1.data(), c, stage.data());
    k.rk4_sum(n, x.data(), r1.data(), r2.data(), r3.data(), r4.data(), h6, end.data());
    bool same = true;
    for (long i = 0; i < n; ++i) {
      const std::size_t e = static_cast<std::size_t>(i);
      same = same && stage[e] == x[e] + c * r1[e] &&
             end[e] == x[e] + h6 * (((r1[e] + 2.0 * r2[e]) + 2.0 * r3[e]) + r4[e]);
    }
    for (long i = n; i < n + 8; ++i) {
      const std::size_t e = static_cast<std::size_t>(i);
      same = same && stage[e] == stage_before[e] && end[e] == end_before[e];
    }
    expect(same, "stage_sum/rk4_sum", n, 0, 0);
  }
  return shapes;
}

// Every kernel set this CPU runs (ADPARM_KERNELS set in turn, then restored); returns the failures.
inline long check_dense_kernels() {
  const char* previous = std::getenv("ADPARM_KERNELS");
  const std::string saved = previous == nullptr ? "" : previous;
  long failed = 0;
  std::mt19937 generator(26);
  for (const char* name : {"avx2", "avx512"}) {
    setenv("ADPARM_KERNELS", name, 1);
    const adparm::DenseKernels* kernels = nullptr;
    try {
      kernels = adparm::select_dense_kernels(true);
    } catch (const std::invalid_argument&) {  // this CPU (or build) lacks the set
      std::printf("bench=check run=dense_kernels set=%s skipped=unsupported ok=1\n", name);
      continue;
    }
    long set_failed = 0;
    const long shapes = check_set(*kernels, generator, set_failed);
    std::printf("bench=check run=dense_kernels set=%s shapes=%ld failed=%ld ok=%d\n", name, shapes,
                set_failed, set_failed == 0 ? 1 : 0);
    failed += set_failed;
  }
  if (previous == nullptr)
    unsetenv("ADPARM_KERNELS");
  else
    setenv("ADPARM_KERNELS", saved.c_str(), 1);
  return failed;
}

}  // namespace dense_kernel_checks
