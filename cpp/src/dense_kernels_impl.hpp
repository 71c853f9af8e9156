// The dense kernels of dense_kernels.hpp, written once over an instruction set's vector type:
// included by each ISA's translation unit (dense_kernels_avx2.cpp, dense_kernels_avx512.cpp)
// inside an anonymous namespace, after it defines `Isa`:
//   kName, V, Mask, kWidth (doubles per V), kRowVectors and kColumns (a register block of C: rows
//   in vectors, columns), kRowPanels (the order of the blocks: blocked_product), zero(), load(p),
//   load(p, mask) (zero-filled), store(p, v), store(p, v, mask), broadcast(p), fma(a, b, c) = a b +
//   c, subtract(a, b) = a - b, add(a, b), multiply(a, b), divide(a, b), sqrt(a), mask(count),
//   sum(v), transpose(rows) (kWidth vectors, in place).
// Nothing here has external linkage and no standard header is included: every function compiled
// with the wider instruction set stays in its unit, so the linker can never hand it to a caller
// built for the portable one.
//
// Register blocks: C's rows in kRowVectors vectors (panels of rows: the last vector masked if the
// rows end in it; column blocks down all rows: then 2, then 1, then a masked one) x kColumns
// columns (one or two columns: 8 or 4 vectors), each
// entry's products summed in the order of the depth index from zero, then stored (C = sum),
// subtracted (C -= sum) or stored negated (C = 0 - sum: the bits of C -= sum on a zeroed C, without
// reading C): a fixed order, the same result on every call.

enum Mode { kStore, kSubtract, kNegate };

template <int kRowVectors, int kColumnCount, Mode kMode, bool kMasked>
inline void block(long depth, const double* a, long lda, const double* b, long b_depth_stride,
                  long b_column_stride, double* c, long ldc, Isa::Mask mask) {
  constexpr long w = Isa::kWidth;
  Isa::V sums[kRowVectors][kColumnCount];
  for (int r = 0; r < kRowVectors; ++r)
    for (int j = 0; j < kColumnCount; ++j) sums[r][j] = Isa::zero();
  for (long p = 0; p < depth; ++p) {
    const double* a_column = a + p * lda;
    Isa::V a_values[kRowVectors];
    for (int r = 0; r < kRowVectors; ++r)
      a_values[r] = kMasked && r == kRowVectors - 1 ? Isa::load(a_column + r * w, mask)
                                                    : Isa::load(a_column + r * w);
    const double* b_row = b + p * b_depth_stride;
    for (int j = 0; j < kColumnCount; ++j) {
      const Isa::V b_value = Isa::broadcast(b_row + j * b_column_stride);
      for (int r = 0; r < kRowVectors; ++r) sums[r][j] = Isa::fma(a_values[r], b_value, sums[r][j]);
    }
  }
  for (int j = 0; j < kColumnCount; ++j) {
    for (int r = 0; r < kRowVectors; ++r) {
      double* out = c + j * ldc + r * w;
      if (kMasked && r == kRowVectors - 1) {
        const Isa::V value = kMode == kSubtract ? Isa::subtract(Isa::load(out, mask), sums[r][j])
                             : kMode == kNegate ? Isa::subtract(Isa::zero(), sums[r][j])
                                                : sums[r][j];
        Isa::store(out, value, mask);
      } else {
        const Isa::V value = kMode == kSubtract ? Isa::subtract(Isa::load(out), sums[r][j])
                             : kMode == kNegate ? Isa::subtract(Isa::zero(), sums[r][j])
                                                : sums[r][j];
        Isa::store(out, value);
      }
    }
  }
}

// kColumnCount columns of C, rows row_begin ... m - 1.
template <int kColumnCount, Mode kMode>
inline void column_block(long m, long row_begin, long depth, const double* a, long lda,
                         const double* b, long b_depth_stride, long b_column_stride, double* c,
                         long ldc) {
  constexpr long w = Isa::kWidth;
  constexpr int rows = kColumnCount == 1 ? 8 : kColumnCount == 2 ? 4 : Isa::kRowVectors;
  long i = row_begin;
  for (; i + rows * w <= m; i += rows * w)
    block<rows, kColumnCount, kMode, false>(depth, a + i, lda, b, b_depth_stride, b_column_stride,
                                            c + i, ldc, Isa::Mask());
  if constexpr (rows >= 2) {  // the last rows in blocks of two vectors, the second one masked
    for (; i + 2 * w <= m; i += 2 * w)
      block<2, kColumnCount, kMode, false>(depth, a + i, lda, b, b_depth_stride, b_column_stride,
                                           c + i, ldc, Isa::Mask());
    if (m - i > w) {
      block<2, kColumnCount, kMode, true>(depth, a + i, lda, b, b_depth_stride, b_column_stride,
                                          c + i, ldc, Isa::mask(m - i - w));
      return;
    }
  }
  for (; i + w <= m; i += w)
    block<1, kColumnCount, kMode, false>(depth, a + i, lda, b, b_depth_stride, b_column_stride,
                                         c + i, ldc, Isa::Mask());
  if (i < m)
    block<1, kColumnCount, kMode, true>(depth, a + i, lda, b, b_depth_stride, b_column_stride,
                                        c + i, ldc, Isa::mask(m - i));
}

// The last n < kColumns columns: column_block<n>.
template <int kColumnCount, Mode kMode>
inline void last_columns(long n, long m, long row_begin, long depth, const double* a, long lda,
                         const double* b, long b_depth_stride, long b_column_stride, double* c,
                         long ldc) {
  if constexpr (kColumnCount > 0) {
    if (n == kColumnCount)
      column_block<kColumnCount, kMode>(m, row_begin, depth, a, lda, b, b_depth_stride,
                                        b_column_stride, c, ldc);
    else
      last_columns<kColumnCount - 1, kMode>(n, m, row_begin, depth, a, lda, b, b_depth_stride,
                                            b_column_stride, c, ldc);
  }
}

// n <= kColumns columns of a row panel: one block of n columns.
template <int kPanel, bool kMasked, Mode kMode, int kColumnCount>
inline void last_panel_columns(long n, long depth, const double* a, long lda, const double* b,
                               long b_depth_stride, long b_column_stride, double* c, long ldc,
                               Isa::Mask mask) {
  if constexpr (kColumnCount > 0) {
    if (n == kColumnCount)
      block<kPanel, kColumnCount, kMode, kMasked>(depth, a, lda, b, b_depth_stride, b_column_stride,
                                                  c, ldc, mask);
    else
      last_panel_columns<kPanel, kMasked, kMode, kColumnCount - 1>(
          n, depth, a, lda, b, b_depth_stride, b_column_stride, c, ldc, mask);
  }
}

// The size of the block that starts at j of n (columns, or vectors of rows): `full`, except that
// a last remainder under half a block is evened out with the block before it (8 + 3 columns become
// 6 + 5, 3 + 1 vectors 2 + 2): a short block runs well below the multiply-add rate.
inline long block_width(long j, long n, long full) {
  const long left = n - j;
  if (left <= full || left >= 2 * full) return left < full ? left : full;
  const long remainder = left - full;
  return 2 * remainder >= full ? full : (left + 1) / 2;
}

// The last `vectors` (1 ... kVectors) vectors of a panel: one block of n columns.
template <int kVectors, bool kMasked, Mode kMode>
inline void lower_part(long vectors, long n, long depth, const double* a, long lda, const double* b,
                       long b_depth_stride, long b_column_stride, double* c, long ldc,
                       Isa::Mask mask) {
  if constexpr (kVectors > 0) {
    if (vectors == kVectors)
      last_panel_columns<kVectors, kMasked, kMode, Isa::kColumns>(
          n, depth, a, lda, b, b_depth_stride, b_column_stride, c, ldc, mask);
    else
      lower_part<kVectors - 1, kMasked, kMode>(vectors, n, depth, a, lda, b, b_depth_stride,
                                               b_column_stride, c, ldc, mask);
  }
}

// One panel of C's rows, i ... i + kPanel w - 1 (the last vector masked if kMasked), across C's
// columns in blocks of kColumns (block_width); lower: only the column blocks that start above the
// panel's last row, each without the panel's vectors whose rows all lie above its first column
// (strictly upper entries: a fifth of the products at K = 78 in blocks of 3 x 8). The panel's rows
// of A (kPanel w x depth) stay in the first-level cache while B's columns stream past them.
template <int kPanel, bool kMasked, Mode kMode>
[[gnu::flatten]] inline void row_panel(long i, long rows, long n, long depth, const double* a,
                                       long lda, const double* b, long b_depth_stride,
                                       long b_column_stride, double* c, long ldc, bool lower,
                                       Isa::Mask mask) {
  for (long j = 0; j < n;) {
    if (lower && j >= i + rows) return;
    const long width = block_width(j, n, Isa::kColumns);
    // lower: the panel's vectors whose rows all lie above the block's first column are skipped
    const long skip = lower && j > i ? (j - i) / Isa::kWidth : 0;
    lower_part<kPanel, kMasked, kMode>(kPanel - skip, width, depth, a + i + skip * Isa::kWidth, lda,
                                       b + j * b_column_stride, b_depth_stride, b_column_stride,
                                       c + j * ldc + i + skip * Isa::kWidth, ldc, mask);
    j += width;
  }
}

// A panel of `vectors` (1 ... kVectors) vectors of rows from row i, the last one masked if the
// rows end in it.
template <int kVectors, Mode kMode>
inline void panel_of(long vectors, long i, long m, long n, long depth, const double* a, long lda,
                     const double* b, long b_depth_stride, long b_column_stride, double* c,
                     long ldc, bool lower) {
  constexpr long w = Isa::kWidth;
  if constexpr (kVectors > 1) {
    if (vectors < kVectors) {
      panel_of<kVectors - 1, kMode>(vectors, i, m, n, depth, a, lda, b, b_depth_stride,
                                    b_column_stride, c, ldc, lower);
      return;
    }
  }
  const long rows = m - i < kVectors * w ? m - i : kVectors * w;
  if (rows == kVectors * w)
    row_panel<kVectors, false, kMode>(i, rows, n, depth, a, lda, b, b_depth_stride, b_column_stride,
                                      c, ldc, lower, Isa::Mask());
  else
    row_panel<kVectors, true, kMode>(i, rows, n, depth, a, lda, b, b_depth_stride, b_column_stride,
                                     c, ldc, lower, Isa::mask(rows - (kVectors - 1) * w));
}

// C (m x n) = or -= A (m x depth) B (depth x n); lower: the entries on and below the diagonal
// (and some above it, in the blocks that reach it). Every entry's products are summed in the same
// order whatever the blocks, so the block shapes and their order change no bit of C.
//   - n >= kColumns and Isa::kRowPanels: panels of rows outermost (row_panel: A's panel stays in
//     the first-level cache; docs/design.md, "Panels of rows, kernels by the work"), the last
//     panels and column blocks evened out (block_width),
//   - else column blocks down all rows (column_block: one column 8 vectors a block, two 4).
template <Mode kMode>
void blocked_product(long m, long n, long depth, const double* a, long lda, const double* b,
                     long b_depth_stride, long b_column_stride, double* c, long ldc, bool lower) {
  if (n < Isa::kColumns || !Isa::kRowPanels) {
    long j = 0;
    for (; j + Isa::kColumns <= n; j += Isa::kColumns)
      column_block<Isa::kColumns, kMode>(m, lower ? j : 0, depth, a, lda, b + j * b_column_stride,
                                         b_depth_stride, b_column_stride, c + j * ldc, ldc);
    if (j < n)
      last_columns<Isa::kColumns - 1, kMode>(n - j, m, lower ? j : 0, depth, a, lda,
                                             b + j * b_column_stride, b_depth_stride,
                                             b_column_stride, c + j * ldc, ldc);
    return;
  }
  constexpr long w = Isa::kWidth;
  const long vectors = (m + w - 1) / w;
  for (long v = 0; v < vectors;) {  // panels of kRowVectors vectors, the last ones evened out
    const long count = block_width(v, vectors, Isa::kRowVectors);
    panel_of<Isa::kRowVectors, kMode>(count, v * w, m, n, depth, a, lda, b, b_depth_stride,
                                      b_column_stride, c, ldc, lower);
    v += count;
  }
}

void product(long m, long n, long depth, const double* a, long lda, const double* b,
             long b_depth_stride, long b_column_stride, double* c, long ldc, bool subtract) {
  if (subtract)
    blocked_product<kSubtract>(m, n, depth, a, lda, b, b_depth_stride, b_column_stride, c, ldc,
                               false);
  else
    blocked_product<kStore>(m, n, depth, a, lda, b, b_depth_stride, b_column_stride, c, ldc, false);
}

// C -= A B^T (or C = -(A B^T), overwrite): B^T's entry (p, j) is b[j + p * ldb].
void rank_update(long n, long depth, const double* a, long lda, const double* b, long ldb,
                 double* c, long ldc, bool lower, bool overwrite) {
  if (overwrite)
    blocked_product<kNegate>(n, n, depth, a, lda, b, ldb, 1, c, ldc, lower);
  else
    blocked_product<kSubtract>(n, n, depth, a, lda, b, ldb, 1, c, ldc, lower);
}

// y0[j] = A(:, j) . x0, y1[j] = A(:, j) . x1, four columns at a time (then two, then one).
template <int kColumnCount>
inline void transposed_block(long m, const double* a, long lda, const double* x0, const double* x1,
                             double* y0, double* y1, Isa::Mask tail) {
  constexpr long w = Isa::kWidth;
  Isa::V sums0[kColumnCount], sums1[kColumnCount];
  for (int j = 0; j < kColumnCount; ++j) sums0[j] = sums1[j] = Isa::zero();
  long i = 0;
  for (; i + w <= m; i += w) {
    const Isa::V v0 = Isa::load(x0 + i), v1 = Isa::load(x1 + i);
    for (int j = 0; j < kColumnCount; ++j) {
      const Isa::V column = Isa::load(a + j * lda + i);
      sums0[j] = Isa::fma(column, v0, sums0[j]);
      sums1[j] = Isa::fma(column, v1, sums1[j]);
    }
  }
  if (i < m) {
    const Isa::V v0 = Isa::load(x0 + i, tail), v1 = Isa::load(x1 + i, tail);
    for (int j = 0; j < kColumnCount; ++j) {
      const Isa::V column = Isa::load(a + j * lda + i, tail);
      sums0[j] = Isa::fma(column, v0, sums0[j]);
      sums1[j] = Isa::fma(column, v1, sums1[j]);
    }
  }
  for (int j = 0; j < kColumnCount; ++j) {
    y0[j] = Isa::sum(sums0[j]);
    y1[j] = Isa::sum(sums1[j]);
  }
}

void transposed_products(long m, long n, const double* a, long lda, const double* x0,
                         const double* x1, double* y0, double* y1) {
  const Isa::Mask tail = Isa::mask(m % Isa::kWidth);
  long j = 0;
  for (; j + 4 <= n; j += 4) transposed_block<4>(m, a + j * lda, lda, x0, x1, y0 + j, y1 + j, tail);
  for (; j + 2 <= n; j += 2) transposed_block<2>(m, a + j * lda, lda, x0, x1, y0 + j, y1 + j, tail);
  for (; j < n; ++j) transposed_block<1>(m, a + j * lda, lda, x0, x1, y0 + j, y1 + j, tail);
}

// Per column j: the dot product omega_j^T G_j in two vector sums (added, then summed across the
// lanes), g_j = weight_j eta_c / (1 + nu dot), coefficient_j *= g_j, scaled_j = g_j G_j.
void gains(long m, long n, const double* omega, long ldo, const double* gamma_omega, long ldg,
           const double* weight, double eta_c, double nu, double* coefficient, double* scaled,
           long lds) {
  constexpr long w = Isa::kWidth;
  const Isa::Mask tail = Isa::mask(m % w);
  for (long j = 0; j < n; ++j) {
    const double* o = omega + j * ldo;
    const double* g = gamma_omega + j * ldg;
    double* out = scaled + j * lds;
    Isa::V sum0 = Isa::zero(), sum1 = Isa::zero();
    long i = 0;
    for (; i + 2 * w <= m; i += 2 * w) {
      sum0 = Isa::fma(Isa::load(o + i), Isa::load(g + i), sum0);
      sum1 = Isa::fma(Isa::load(o + i + w), Isa::load(g + i + w), sum1);
    }
    if (i + w <= m) {
      sum0 = Isa::fma(Isa::load(o + i), Isa::load(g + i), sum0);
      i += w;
    }
    if (i < m) sum1 = Isa::fma(Isa::load(o + i, tail), Isa::load(g + i, tail), sum1);
    const double gain = weight[j] * eta_c / (1.0 + nu * Isa::sum(Isa::add(sum0, sum1)));
    coefficient[j] *= gain;
    const Isa::V gain_vector = Isa::broadcast(&gain);
    for (i = 0; i + w <= m; i += w)
      Isa::store(out + i, Isa::multiply(gain_vector, Isa::load(g + i)));
    if (i < m) Isa::store(out + i, Isa::multiply(gain_vector, Isa::load(g + i, tail)), tail);
  }
}

// Gamma_next = Gamma - D, D = sum_s c_s u_s u_s^T over the four columns u_s of u (n x 4, leading
// dimension ldu), column by column: d_j = sum_s (c_s u_s[j]) u_s in that order, the first term a
// product, the others fused multiply-adds; next may be gamma itself. Returns ||D||_F^2 over every
// entry, in two interleaved vector sums.
double low_rank_update(long n, const double* u, long ldu, const double* c, const double* gamma,
                       long ldg, double* next, long ldn) {
  constexpr long w = Isa::kWidth;
  const Isa::Mask tail = Isa::mask(n % w);
  const double* u0 = u;
  const double* u1 = u + ldu;
  const double* u2 = u + 2 * ldu;
  const double* u3 = u + 3 * ldu;
  Isa::V squares[2] = {Isa::zero(), Isa::zero()};
  for (long j = 0; j < n; ++j) {
    const double a0 = c[0] * u0[j], a1 = c[1] * u1[j], a2 = c[2] * u2[j], a3 = c[3] * u3[j];
    const Isa::V b0 = Isa::broadcast(&a0), b1 = Isa::broadcast(&a1);
    const Isa::V b2 = Isa::broadcast(&a2), b3 = Isa::broadcast(&a3);
    const double* g = gamma + j * ldg;
    double* out = next + j * ldn;
    long i = 0;
    int parity = 0;
    for (; i + w <= n; i += w, parity ^= 1) {
      Isa::V d = Isa::multiply(b0, Isa::load(u0 + i));
      d = Isa::fma(b1, Isa::load(u1 + i), d);
      d = Isa::fma(b2, Isa::load(u2 + i), d);
      d = Isa::fma(b3, Isa::load(u3 + i), d);
      Isa::store(out + i, Isa::subtract(Isa::load(g + i), d));
      squares[parity] = Isa::fma(d, d, squares[parity]);
    }
    if (i < n) {  // the last rows, masked (zero-filled lanes add nothing)
      Isa::V d = Isa::multiply(b0, Isa::load(u0 + i, tail));
      d = Isa::fma(b1, Isa::load(u1 + i, tail), d);
      d = Isa::fma(b2, Isa::load(u2 + i, tail), d);
      d = Isa::fma(b3, Isa::load(u3 + i, tail), d);
      Isa::store(out + i, Isa::subtract(Isa::load(g + i, tail), d), tail);
      squares[parity] = Isa::fma(d, d, squares[parity]);
    }
  }
  return Isa::sum(Isa::add(squares[0], squares[1]));
}

// C(i, j) = C(j, i) for i < j (C n x n): the strictly lower triangle copied onto the upper one in
// w x w tiles, each loaded by columns (rows past n masked), transposed in registers and stored as
// the columns of its mirror tile; a diagonal tile stores only its entries above the diagonal.
// Copies alone: the same bits as the entry-by-entry copy.
void mirror_lower(long n, double* c, long ldc) {
  constexpr long w = Isa::kWidth;
  for (long jb = 0; jb < n; jb += w) {
    const long columns = n - jb < w ? n - jb : w;
    for (long ib = jb; ib < n; ib += w) {
      const long rows = n - ib < w ? n - ib : w;
      Isa::V tile[w];
      for (long t = 0; t < w; ++t) {
        const double* column = c + (jb + t) * ldc + ib;
        tile[t] = t >= columns ? Isa::zero()
                  : rows == w  ? Isa::load(column)
                               : Isa::load(column, Isa::mask(rows));
      }
      Isa::transpose(tile);  // tile[t]: row ib + t, columns jb ... jb + w - 1
      if (ib == jb) {        // the diagonal tile: column jb + t above the diagonal, t entries
        for (long t = 1; t < columns; ++t)
          Isa::store(c + (jb + t) * ldc + jb, tile[t], Isa::mask(t));
      } else {  // below the diagonal: whole columns (columns == w here)
        for (long t = 0; t < rows; ++t) Isa::store(c + (ib + t) * ldc + jb, tile[t]);
      }
    }
  }
}

// One extrapolation point's regressor (hjb.hpp) and its two dot products in one pass over its
// rows: omega = f - B x, where B (m x n, column stride ldb) has nonzero rows only in [first, first
// + rows) (omega = f in the vectors outside them), then value = c . omega and norm = omega . omega.
// Each entry and each sum in the order of product (subtract, on a copy of f) and of
// transposed_products (omega; c and omega): the same bits as those two calls.
void point_regressor(long m, long first, long rows, long n, const double* b, long ldb,
                     const double* x, const double* f, const double* c, double* omega,
                     double* value, double* norm) {
  constexpr long w = Isa::kWidth;
  const long end = first + rows;
  Isa::V value_sum = Isa::zero(), norm_sum = Isa::zero();
  for (long i = 0; i < m; i += w) {
    const bool whole = i + w <= m;
    const Isa::Mask mask = whole ? Isa::Mask() : Isa::mask(m - i);
    Isa::V entry = whole ? Isa::load(f + i) : Isa::load(f + i, mask);
    if (i + w > first && i < end) {  // B's rows here are not all zero
      Isa::V product = Isa::zero();
      for (long j = 0; j < n; ++j) {
        const double* column = b + j * ldb + i;
        product = Isa::fma(whole ? Isa::load(column) : Isa::load(column, mask),
                           Isa::broadcast(x + j), product);
      }
      entry = Isa::subtract(entry, product);
    }
    if (whole)
      Isa::store(omega + i, entry);
    else
      Isa::store(omega + i, entry, mask);
    value_sum = Isa::fma(entry, whole ? Isa::load(c + i) : Isa::load(c + i, mask), value_sum);
    norm_sum = Isa::fma(entry, entry, norm_sum);
  }
  *value = Isa::sum(value_sum);
  *norm = Isa::sum(norm_sum);
}

// A product kept apart from the sum that uses it (an empty asm statement the compiler cannot see
// through): no fused multiply-add, which would round once instead of twice (these units are built
// with FMA, and GCC contracts a * b + c by default).
inline Isa::V rounded(Isa::V v) {
  asm("" : "+v"(v));
  return v;
}

// out = x + c r, entry by entry: fl(x + fl(c r)), as Eigen's x + c * r.
void stage_sum(long n, const double* x, const double* r, double c, double* out) {
  constexpr long w = Isa::kWidth;
  const Isa::V scale = Isa::broadcast(&c);
  long i = 0;
  for (; i + w <= n; i += w)
    Isa::store(out + i,
               Isa::add(Isa::load(x + i), rounded(Isa::multiply(scale, Isa::load(r + i)))));
  if (i < n) {
    const Isa::Mask tail = Isa::mask(n - i);
    Isa::store(
        out + i,
        Isa::add(Isa::load(x + i, tail), rounded(Isa::multiply(scale, Isa::load(r + i, tail)))),
        tail);
  }
}

// out = x + h6 (((r1 + 2 r2) + 2 r3) + r4), entry by entry in that order, as Eigen's
// x + (h / 6) * (k1 + 2 * k2 + 2 * k3 + k4).
template <bool kMasked>
inline Isa::V rk4_entries(const double* x, const double* r1, const double* r2, const double* r3,
                          const double* r4, Isa::V two, Isa::V h6, Isa::Mask mask) {
  const auto load = [mask](const double* p) { return kMasked ? Isa::load(p, mask) : Isa::load(p); };
  Isa::V sum = Isa::add(load(r1), rounded(Isa::multiply(two, load(r2))));
  sum = Isa::add(sum, rounded(Isa::multiply(two, load(r3))));
  sum = Isa::add(sum, load(r4));
  return Isa::add(load(x), rounded(Isa::multiply(h6, sum)));
}

void rk4_sum(long n, const double* x, const double* r1, const double* r2, const double* r3,
             const double* r4, double h6, double* out) {
  constexpr long w = Isa::kWidth;
  const double two_value = 2.0;
  const Isa::V two = Isa::broadcast(&two_value), scale = Isa::broadcast(&h6);
  long i = 0;
  for (; i + w <= n; i += w)
    Isa::store(out + i,
               rk4_entries<false>(x + i, r1 + i, r2 + i, r3 + i, r4 + i, two, scale, Isa::Mask()));
  if (i < n) {
    const Isa::Mask tail = Isa::mask(n - i);
    Isa::store(out + i, rk4_entries<true>(x + i, r1 + i, r2 + i, r3 + i, r4 + i, two, scale, tail),
               tail);
  }
}

// out(j, sum_c a(j, c) in(c)) for j < rows, c < depth, lane by lane: four rows at a time (four
// independent chains of multiply-adds, each entry summed in the order of c), then one by one.
template <class A, class In, class Out>
inline void lane_products(long rows, long depth, const A& a, const In& in, const Out& out) {
  long j = 0;
  for (; j + 4 <= rows; j += 4) {
    Isa::V s0 = Isa::zero(), s1 = Isa::zero(), s2 = Isa::zero(), s3 = Isa::zero();
    for (long c = 0; c < depth; ++c) {
      const Isa::V v = in(c);
      s0 = Isa::fma(a(j, c), v, s0);
      s1 = Isa::fma(a(j + 1, c), v, s1);
      s2 = Isa::fma(a(j + 2, c), v, s2);
      s3 = Isa::fma(a(j + 3, c), v, s3);
    }
    out(j, s0);
    out(j + 1, s1);
    out(j + 2, s2);
    out(j + 3, s3);
  }
  for (; j < rows; ++j) {
    Isa::V sum = Isa::zero();
    for (long c = 0; c < depth; ++c) sum = Isa::fma(a(j, c), in(c), sum);
    out(j, sum);
  }
}

// The inputs of the lanes from o on (PairPoints): the points' arrays (stride p.stride), or for
// the tail's lanes the tail block (stride kTailLanes).
struct Lanes {
  const double *x, *mass_inverse, *drift_rates, *state_costs;
  long stride;
};
inline Lanes lanes_at(const adparm::PairPoints& p, long o) {
  if (p.tail != nullptr && o >= p.tail_offset &&
      o < p.tail_offset + adparm::PairPoints::kTailLanes) {
    constexpr long lanes = adparm::PairPoints::kTailLanes;
    const long n = p.joints;
    const double* x = p.tail + (o - p.tail_offset);
    return {x, x + 2 * n * lanes, x + (2 * n + n * n) * lanes,
            x + (2 * n + n * n + p.functions) * lanes, lanes};
  }
  return {p.x + o, p.mass_inverse + o, p.drift_rates + o, p.state_costs + o, p.stride};
}

// The points of a basis of pairs (dense_kernels.hpp, PairPoints), kWidth points at a time, each
// lane a point: S x_i, M_i^-T of it (B_i^T Wa, B_i^T (Wa - Wc)), R^-1 of both, then
// z_i = M_i^-1 (-u_hat_i) and omega_i = F_i - J_e2(x_i) z_i, kWidth rows at a time, with
// Wc . omega_i and ||omega_i||^2 (each in two partial sums: even and odd rows). The per-point
// vectors live in `scratch` (kWidth lanes each; unaligned loads and stores).
void pair_points(const adparm::PairPoints& p) {
  constexpr long w = Isa::kWidth;
  const long n = p.joints, k = p.functions, stride = p.stride, nx = 2 * n, points = p.points;
  double* t = p.scratch;        // 2n: [S(Wa) x; S(Wa - Wc) x]
  double* y = t + nx * w;       // 2n: M^-T of each half: B^T Wa, B^T (Wa - Wc)
  double* inputs = y + nx * w;  // n: -u_hat = 0.5 R^-1 B^T Wa
  double* z = inputs + n * w;   // n + 1: M^-1 (-u_hat), then a zero vector (a row's absent term)
  const int *term_x = p.term_x, *term_z = p.term_z;
  const long omega_stride = p.omega_stride;
  const double *coefficient = p.coefficient, *critic_weights = p.critic_weights;
  const double half_value = 0.5, one_value = 1.0;
  const Isa::V half = Isa::broadcast(&half_value), one = Isa::broadcast(&one_value);
  Isa::store(z + n * w, Isa::zero());
  for (long o = 0; o < stride; o += w) {
    const Lanes in = lanes_at(p, o);
    const double *x = in.x, *mass_inverse = in.mass_inverse, *drift_rates = in.drift_rates;
    const long s = in.stride;
    lane_products(
        nx, nx, [&](long j, long v) { return Isa::broadcast(p.weight_forms + j + v * nx); },
        [&](long v) { return Isa::load(x + v * s); },
        [&](long j, Isa::V value) { Isa::store(t + j * w, value); });
    for (long part = 0; part < 2; ++part)  // (M^-T t)_j = sum_c M^-1 (c, j) t_c
      lane_products(
          n, n, [&](long j, long c) { return Isa::load(mass_inverse + (c + j * n) * s); },
          [&](long c) { return Isa::load(t + (part * n + c) * w); },
          [&](long j, Isa::V value) { Isa::store(y + (part * n + j) * w, value); });
    lane_products(
        n, n, [&](long j, long c) { return Isa::broadcast(p.r_inverse + j + c * n); },
        [&](long c) { return Isa::load(y + c * w); },
        [&](long j, Isa::V value) { Isa::store(inputs + j * w, Isa::multiply(half, value)); });
    if (p.inputs != nullptr)
      for (long j = 0; j < n; ++j) Isa::store(p.inputs + j * stride + o, Isa::load(inputs + j * w));
    lane_products(
        n, n, [&](long j, long c) { return Isa::broadcast(p.r_inverse + j + c * n); },
        [&](long c) { return Isa::load(y + (n + c) * w); },
        [&](long j, Isa::V value) { Isa::store(p.projected_difference + j * stride + o, value); });
    Isa::V input_cost = Isa::zero();
    for (long j = 0; j < n; ++j)
      input_cost = Isa::fma(Isa::load(inputs + j * w), Isa::load(y + j * w), input_cost);
    input_cost = Isa::multiply(half, input_cost);  // u^T R u = 0.5 (-u)^T B^T Wa
    lane_products(
        n, n, [&](long j, long c) { return Isa::load(mass_inverse + (j + c * n) * s); },
        [&](long c) { return Isa::load(inputs + c * w); },
        [&](long j, Isa::V value) { Isa::store(z + j * w, value); });
    // omega's rows r0 ... r0 + w - 1 over the lanes, F_r - c_r (x_a z_b' + x_b z_a') with the
    // row's two terms in J_e2 (an absent one reads z's zero vector: no branch), then transposed in
    // registers: each lane's (point's) w entries stored into its own column of omega (the lanes
    // after the last point not stored)
    Isa::V value0 = Isa::zero(), value1 = Isa::zero(), norm0 = Isa::zero(), norm1 = Isa::zero();
    const long lanes = points - o < w ? points - o : w;
    const auto row = [&](long r) {
      const int *xs = term_x + 2 * r, *zs = term_z + 2 * r;
      const long z0 = zs[0] < 0 ? n : zs[0], z1 = zs[1] < 0 ? n : zs[1];
      const Isa::V along = Isa::fma(Isa::load(x + xs[1] * s), Isa::load(z + z1 * w),
                                    Isa::multiply(Isa::load(x + xs[0] * s), Isa::load(z + z0 * w)));
      return Isa::subtract(Isa::load(drift_rates + r * s),
                           Isa::multiply(Isa::broadcast(coefficient + r), along));
    };
    for (long r0 = 0; r0 < k; r0 += w) {
      const long rows = k - r0 < w ? k - r0 : w;
      Isa::V tile[w];
      if (rows == w) {
#pragma GCC unroll 8
        for (long t = 0; t < w; t += 2) {
          tile[t] = row(r0 + t);
          tile[t + 1] = row(r0 + t + 1);
          value0 = Isa::fma(Isa::broadcast(critic_weights + r0 + t), tile[t], value0);
          value1 = Isa::fma(Isa::broadcast(critic_weights + r0 + t + 1), tile[t + 1], value1);
          norm0 = Isa::fma(tile[t], tile[t], norm0);
          norm1 = Isa::fma(tile[t + 1], tile[t + 1], norm1);
        }
      } else {
        for (long t = 0; t < w; ++t) {
          if (t >= rows) {
            tile[t] = Isa::zero();
            continue;
          }
          tile[t] = row(r0 + t);
          value0 = Isa::fma(Isa::broadcast(critic_weights + r0 + t), tile[t], value0);
          norm0 = Isa::fma(tile[t], tile[t], norm0);
        }
      }
      Isa::transpose(tile);  // tile[t]: point o + t's rows r0 ... r0 + w - 1
      double* out = p.omega + o * omega_stride + r0;
      if (rows == w && lanes == w) {
#pragma GCC unroll 8
        for (long t = 0; t < w; ++t) Isa::store(out + t * omega_stride, tile[t]);
      } else {
        const Isa::Mask mask = rows == w ? Isa::mask(0) : Isa::mask(rows);
        for (long t = 0; t < lanes; ++t) {
          if (rows == w)
            Isa::store(out + t * omega_stride, tile[t]);
          else
            Isa::store(out + t * omega_stride, tile[t], mask);
        }
      }
    }
    Isa::store(p.error + o,
               Isa::add(Isa::add(Isa::load(in.state_costs), input_cost), Isa::add(value0, value1)));
    Isa::store(p.norm + o, Isa::add(norm0, norm1));
    // the actor's scale of eq. (26), Actor::gradient_scale's operations: gain eps / sqrt(1 + norm)
    const Isa::V root = Isa::sqrt(Isa::add(one, Isa::add(norm0, norm1)));
    Isa::store(
        p.scale + o,
        Isa::divide(Isa::multiply(Isa::load(p.actor_gains + o), Isa::load(p.error + o)), root));
  }
}

// sum_i x_i (M_i^-1 c_i)^T with c_i = scale_i projected_difference_i (PairPoints): M_i^-1 c_i
// over the lanes into projected_difference (overwritten), then each entry's sum over the points.
void pair_gradient(const adparm::PairPoints& p, double* out) {
  constexpr long w = Isa::kWidth;
  const long n = p.joints, stride = p.stride, nx = 2 * n;
  double* c = p.scratch;  // n: c_i
  for (long o = 0; o < stride; o += w) {
    const Isa::V s = Isa::load(p.scale + o);
    for (long j = 0; j < n; ++j)
      Isa::store(c + j * w, Isa::multiply(s, Isa::load(p.projected_difference + j * stride + o)));
    const Lanes in = lanes_at(p, o);
    lane_products(
        n, n, [&](long j, long q) { return Isa::load(in.mass_inverse + (j + q * n) * in.stride); },
        [&](long q) { return Isa::load(c + q * w); },
        [&](long j, Isa::V value) { Isa::store(p.projected_difference + j * stride + o, value); });
  }
  const long points_end = p.tail != nullptr ? p.tail_offset : stride;  // then the tail's lanes
  for (long j = 0; j < n; ++j)
    for (long v = 0; v < nx; ++v) {
      const double *xv = p.x + v * stride, *mj = p.projected_difference + j * stride;
      Isa::V sum0 = Isa::zero(), sum1 = Isa::zero();
      long o = 0;
      for (; o + 2 * w <= points_end; o += 2 * w) {
        sum0 = Isa::fma(Isa::load(xv + o), Isa::load(mj + o), sum0);
        sum1 = Isa::fma(Isa::load(xv + o + w), Isa::load(mj + o + w), sum1);
      }
      for (; o < stride; o += w) {
        const Lanes in = lanes_at(p, o);
        sum0 = Isa::fma(Isa::load(in.x + v * in.stride), Isa::load(mj + o), sum0);
      }
      out[v + j * nx] = Isa::sum(Isa::add(sum0, sum1));
    }
}

// The set's table (dense_kernels.hpp), in the order of DenseKernels' members.
const adparm::DenseKernels kKernels{Isa::kName, product,         rank_update,  transposed_products,
                                    gains,      low_rank_update, mirror_lower, point_regressor,
                                    stage_sum,  rk4_sum,         pair_points,  pair_gradient};
