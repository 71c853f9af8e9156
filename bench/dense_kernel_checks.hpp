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
//   - stage_sum and rk4_sum equal bit for bit to the sums entry by entry, nothing written past n;
//   - pair_points and pair_gradient (a basis of pairs: random pairs c x_a x_b, squares, pairs
//     within e1) within 1e-10 of plain loops on each point's B_i = J_e2(x_i) M_i^-1 formed
//     entry by entry; nothing written outside the points' omega columns.
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
          // G = Gamma omega with omega^T G >= 0 (Gamma is positive definite): each entry of G
          // with its omega's sign, so that 1 + nu omega^T G >= 1 (a random sign could bring it
          // near 0, where the gain's relative round-off has no bound)
          const Buffer omegas = random_buffer(generator, ldb * n);
          Buffer gamma_omegas = random_buffer(generator, ldb * n);
          for (std::size_t e = 0; e < gamma_omegas.size(); ++e)
            gamma_omegas[e] = std::copysign(gamma_omegas[e], omegas[e]);
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

// pair_points and pair_gradient (dense_kernels.hpp, PairPoints) against each point's B_i formed
// entry by entry from random pairs and the plain products of eqs. (20), (21) and (26).
inline long check_pairs(const adparm::DenseKernels& k, std::mt19937& generator, long& failed) {
  long shapes = 0;
  const auto close = [](double a, double b) {
    return std::abs(a - b) <= 1e-10 * (1.0 + std::abs(b));
  };
  for (long n : {1L, 2L, 3L, 6L})
    for (long points : {1L, 5L, 8L, 13L, 50L})
      for (int tailed = 0; tailed < 2; ++tailed) {
        ++shapes;
        const long nx = 2 * n, functions = 3 * n + 4, stride = (points + 8) / 8 * 8;
        std::uniform_int_distribution<int> variable(0, static_cast<int>(nx) - 1);
        std::vector<int> term_x, term_z;
        Buffer coefficient = random_buffer(generator, functions);
        std::vector<int> first(static_cast<std::size_t>(functions)),
            second(static_cast<std::size_t>(functions));
        for (long r = 0; r < functions; ++r) {  // pairs (a, b), squares at every fourth
          const int a = variable(generator), b = r % 4 == 0 ? a : variable(generator);
          first[static_cast<std::size_t>(r)] = a;
          second[static_cast<std::size_t>(r)] = b;
          term_x.push_back(b);
          term_z.push_back(a >= n ? a - static_cast<int>(n) : -1);
          term_x.push_back(a);
          term_z.push_back(b >= n ? b - static_cast<int>(n) : -1);
        }
        Buffer x(static_cast<std::size_t>(nx * stride), 0.0);
        Buffer mass_inverse(static_cast<std::size_t>(n * n * stride), 0.0);
        Buffer drift(static_cast<std::size_t>(functions * stride), 0.0);
        Buffer costs(static_cast<std::size_t>(stride), 0.0);
        const Buffer values = random_buffer(generator, (nx + n * n + functions + 1) * points);
        std::size_t next = 0;
        for (long i = 0; i < points; ++i) {
          for (long v = 0; v < nx; ++v)
            x[static_cast<std::size_t>(v * stride + i)] = values[next++];
          for (long e = 0; e < n * n; ++e)
            mass_inverse[static_cast<std::size_t>(e * stride + i)] = values[next++];
          for (long r = 0; r < functions; ++r)
            drift[static_cast<std::size_t>(r * stride + i)] = values[next++];
          costs[static_cast<std::size_t>(i)] = std::abs(values[next++]);
        }
        const Buffer wa = random_buffer(generator, functions),
                     wd = random_buffer(generator, functions);
        const Buffer wc = random_buffer(generator, functions),
                     r_inverse = random_buffer(generator, n * n);
        Buffer forms(static_cast<std::size_t>(nx * nx), 0.0);  // S(Wa), S(Wd), as ClosedLoop forms
        for (long r = 0; r < functions; ++r)
          for (int t = 0; t < 2; ++t) {
            const int z = term_z[static_cast<std::size_t>(2 * r + t)];
            if (z < 0) continue;
            const long v = term_x[static_cast<std::size_t>(2 * r + t)];
            forms[static_cast<std::size_t>(z + v * nx)] +=
                coefficient[static_cast<std::size_t>(r)] * wa[static_cast<std::size_t>(r)];
            forms[static_cast<std::size_t>(n + z + v * nx)] +=
                coefficient[static_cast<std::size_t>(r)] * wd[static_cast<std::size_t>(r)];
          }
        const long omega_stride = functions + 3;
        Buffer omega(static_cast<std::size_t>(omega_stride * (points + 1)), 7.0);
        Buffer error(static_cast<std::size_t>(stride)), norm(static_cast<std::size_t>(stride));
        Buffer scale(static_cast<std::size_t>(stride)),
            projected(static_cast<std::size_t>(n * stride)),
            inputs_out(static_cast<std::size_t>(n * stride));
        Buffer scratch(static_cast<std::size_t>((2 * n * n + 6 * n) * 8)),
            out(static_cast<std::size_t>(nx * n));
        Buffer gains = random_buffer(generator, stride);  // w_i eta_a1, one per lane
        // tailed: the lanes from the last multiple of 8 on in a tail block (PairPoints::tail), and
        // NaN in the arrays there (never read)
        constexpr long lanes = adparm::PairPoints::kTailLanes;
        const long tail_offset = (points - 1) / lanes * lanes, entries = nx + n * n + functions + 1;
        Buffer tail(static_cast<std::size_t>(entries * lanes), 0.0);
        Buffer x_read = x, mass_inverse_read = mass_inverse, drift_read = drift, costs_read = costs;
        if (tailed != 0) {
          long entry = 0;
          for (Buffer* array : {&x_read, &mass_inverse_read, &drift_read, &costs_read}) {
            const long count = static_cast<long>(array->size()) / stride;
            for (long v = 0; v < count; ++v, ++entry)
              for (long l = 0; tail_offset + l < stride && l < lanes; ++l) {
                double& value = (*array)[static_cast<std::size_t>(v * stride + tail_offset + l)];
                tail[static_cast<std::size_t>(entry * lanes + l)] = value;
                value = NAN;
              }
          }
        }
        adparm::PairPoints problem{n,
                                   functions,
                                   points,
                                   stride,
                                   x_read.data(),
                                   mass_inverse_read.data(),
                                   drift_read.data(),
                                   costs_read.data(),
                                   forms.data(),
                                   r_inverse.data(),
                                   wc.data(),
                                   term_x.data(),
                                   term_z.data(),
                                   coefficient.data(),
                                   scratch.data(),
                                   omega.data(),
                                   omega_stride,
                                   error.data(),
                                   norm.data(),
                                   projected.data(),
                                   gains.data(),
                                   scale.data(),
                                   inputs_out.data()};
        if (tailed != 0) {
          problem.tail = tail.data();
          problem.tail_offset = tail_offset;
        }
        k.pair_points(problem);
        const Buffer projected_difference = projected;
        k.pair_gradient(problem, out.data());
        bool ok = true;
        Buffer gradient(static_cast<std::size_t>(functions), 0.0);
        for (long i = 0; i < points; ++i) {
          const auto at = [&](const Buffer& b, long e) {
            return b[static_cast<std::size_t>(e * stride + i)];
          };
          Buffer B(static_cast<std::size_t>(functions * n),
                   0.0);  // J_e2(x_i) M_i^-1, entry by entry
          for (long r = 0; r < functions; ++r) {
            const int a = first[static_cast<std::size_t>(r)],
                      b = second[static_cast<std::size_t>(r)];
            const double c = coefficient[static_cast<std::size_t>(r)];
            for (long j = 0; j < n; ++j) {
              double entry = 0.0;  // row r of J_e2 times column j of M^-1
              if (a >= n) entry += c * at(x, b) * at(mass_inverse, (a - n) + j * n);
              if (b >= n) entry += c * at(x, a) * at(mass_inverse, (b - n) + j * n);
              B[static_cast<std::size_t>(r + j * functions)] = entry;
            }
          }
          Buffer ya(static_cast<std::size_t>(n), 0.0), yd(static_cast<std::size_t>(n), 0.0);
          for (long j = 0; j < n; ++j)
            for (long r = 0; r < functions; ++r) {
              ya[static_cast<std::size_t>(j)] +=
                  B[static_cast<std::size_t>(r + j * functions)] * wa[static_cast<std::size_t>(r)];
              yd[static_cast<std::size_t>(j)] +=
                  B[static_cast<std::size_t>(r + j * functions)] * wd[static_cast<std::size_t>(r)];
            }
          Buffer inputs(static_cast<std::size_t>(n), 0.0),
              difference(static_cast<std::size_t>(n), 0.0);
          double input_cost = 0.0;
          for (long j = 0; j < n; ++j) {
            for (long c = 0; c < n; ++c) {
              inputs[static_cast<std::size_t>(j)] +=
                  0.5 * r_inverse[static_cast<std::size_t>(j + c * n)] *
                  ya[static_cast<std::size_t>(c)];
              difference[static_cast<std::size_t>(j)] +=
                  r_inverse[static_cast<std::size_t>(j + c * n)] * yd[static_cast<std::size_t>(c)];
            }
            ok = ok && close(projected_difference[static_cast<std::size_t>(j * stride + i)],
                             difference[static_cast<std::size_t>(j)]);
          }
          for (long j = 0; j < n; ++j)  // -u_hat_i, kept for the trajectory's sample (ClosedLoop)
            ok = ok && close(inputs_out[static_cast<std::size_t>(j * stride + i)],
                             inputs[static_cast<std::size_t>(j)]);
          for (long j = 0; j < n; ++j)
            input_cost +=
                0.5 * inputs[static_cast<std::size_t>(j)] * ya[static_cast<std::size_t>(j)];
          double value = 0.0, squared = 0.0;
          for (long r = 0; r < functions; ++r) {
            double entry = at(drift, r);
            for (long j = 0; j < n; ++j)
              entry -= B[static_cast<std::size_t>(r + j * functions)] *
                       inputs[static_cast<std::size_t>(j)];
            value += wc[static_cast<std::size_t>(r)] * entry;
            squared += entry * entry;
            ok = ok && close(omega[static_cast<std::size_t>(i * omega_stride + r)], entry);
          }
          for (long r = functions; r < omega_stride; ++r)
            ok = ok && omega[static_cast<std::size_t>(i * omega_stride + r)] == 7.0;
          const double eps = at(costs, 0) + input_cost + value;
          const double s = gains[static_cast<std::size_t>(i)] * eps / std::sqrt(1.0 + squared);
          ok = ok && close(error[static_cast<std::size_t>(i)], eps) &&
               close(norm[static_cast<std::size_t>(i)], squared) &&
               close(scale[static_cast<std::size_t>(i)], s);
          for (long r = 0; r < functions; ++r)
            for (long j = 0; j < n; ++j)
              gradient[static_cast<std::size_t>(r)] +=
                  B[static_cast<std::size_t>(r + j * functions)] * s *
                  difference[static_cast<std::size_t>(j)];
        }
        for (long r = points * omega_stride; r < (points + 1) * omega_stride; ++r)
          ok = ok && omega[static_cast<std::size_t>(r)] == 7.0;  // no column past the last point
        for (long r = 0; r < functions; ++r) {  // the caller's scatter of out (ClosedLoop)
          double along = 0.0;
          for (int t = 0; t < 2; ++t) {
            const int z = term_z[static_cast<std::size_t>(2 * r + t)];
            if (z >= 0)
              along += out[static_cast<std::size_t>(term_x[static_cast<std::size_t>(2 * r + t)] +
                                                    z * nx)];
          }
          ok = ok && close(coefficient[static_cast<std::size_t>(r)] * along,
                           gradient[static_cast<std::size_t>(r)]);
        }
        if (!ok) {
          ++failed;
          std::fprintf(stderr,
                       "check failed: dense kernel pair_points/pair_gradient (%ld, %ld, %d)\n", n,
                       points, tailed);
        }
      }
  return shapes;
}

// Every kernel set this CPU runs (ADPARM_KERNELS set in turn, then restored); returns the failures.
inline long check_dense_kernels() {
  const char* previous = std::getenv("ADPARM_KERNELS");
  const std::string saved = previous == nullptr ? "" : previous;
  long failed = 0;
  std::mt19937 generator(26), pair_generator(49);  // apart: the other checks' draws unchanged
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
    const long shapes = check_set(*kernels, generator, set_failed) +
                        check_pairs(*kernels, pair_generator, set_failed);
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
