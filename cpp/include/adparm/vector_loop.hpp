// The two-link loop with the augmented basis (8 functions, 2 joints: the paper loop) evaluated in
// AVX-512 registers. Built for AVX-512 + FMA by their target attribute only (the rest of the
// library and the wheel stay portable), chosen at run time (vector_loop_available: the CPU has
// AVX-512F/DQ/VL, and ADPARM_KERNELS is not "portable" or "avx2"), used by ClosedLoop's
// vector_step / vector_derivative:
//   - the sample's basis Jacobian J, B = J_e2 M^-1 and the drift part of omega in registers
//     (built by permutations of x, never through memory), eqs. (20)-(21), and the critic's and
//     actor's shares (23)-(26): Gamma as eight registers (its columns), dot products reduced
//     four at a time, the actor's square root and division started before the critic's chain;
//   - sin and cos of q1, q2 in one vector sincos, and of the probe's frequencies and the
//     disturbance's t in another (libm's calls: 18 per step);
//   - RK4's sums on the 87 entries in pieces that match the state's layout (the derivative's
//     stores are forwarded to them), and the covariance test by fraction-free elimination.
// The portable evaluation keeps its code and bits. This one differs in the last bits (fused
// multiply-adds, another summation order, its own sincos within 2 ulp of libm's): the final
// state of a 30 s paper run differs from the portable one by as much as a 1e-15 relative change
// of q0(0) makes (about 1e-13 relative, Gamma 7e-12 of its largest entry). RK4's sums keep the
// portable bits; the covariance test gives the portable answer unless lambda_min(Gamma) is within
// round-off of epsilon_T.
#pragma once

#include <cmath>
#include <cstdlib>
#include <cstring>

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__) && \
    !defined(ADPARM_NO_VECTOR_LOOP)
#define ADPARM_VECTOR_LOOP 1
#include <immintrin.h>
#define ADPARM_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,fma")))
#else
#define ADPARM_VECTOR_LOOP 0
#define ADPARM_AVX512
#endif

namespace adparm {

// Whether the vector evaluation runs: an AVX-512 CPU, unless ADPARM_KERNELS says portable or avx2
// (dense_kernels.hpp's variable: the same switch for every loop).
inline bool vector_loop_available() {
#if ADPARM_VECTOR_LOOP
  const char* requested = std::getenv("ADPARM_KERNELS");
  if (requested != nullptr &&
      (std::strcmp(requested, "portable") == 0 || std::strcmp(requested, "avx2") == 0))
    return false;
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

#if ADPARM_VECTOR_LOOP
namespace vector8 {

using V = __m512d;

ADPARM_AVX512 inline V load(const double* p) { return _mm512_loadu_pd(p); }
ADPARM_AVX512 inline V broadcast(double x) { return _mm512_set1_pd(x); }
// Lane j of v in every lane.
template <int j>
ADPARM_AVX512 inline V lane(V v) {
  return _mm512_permutexvar_pd(_mm512_set1_epi64(j), v);
}

// [sum a, sum b, sum c, sum d]: four dot products' reductions in one tree (3 levels).
ADPARM_AVX512 inline __m256d sum4(V a, V b, V c, V d) {
  const V ab = _mm512_add_pd(_mm512_unpacklo_pd(a, b), _mm512_unpackhi_pd(a, b));  // 128-bit
  const V cd = _mm512_add_pd(_mm512_unpacklo_pd(c, d), _mm512_unpackhi_pd(c, d));  // blocks
  const V half = _mm512_add_pd(_mm512_shuffle_f64x2(ab, cd, _MM_SHUFFLE(2, 0, 2, 0)),
                               _mm512_shuffle_f64x2(ab, cd, _MM_SHUFFLE(3, 1, 3, 1)));
  const V total = _mm512_add_pd(half, _mm512_shuffle_f64x2(half, half, _MM_SHUFFLE(2, 3, 0, 1)));
  // blocks 0 and 2 of total: [sum a, sum b], [sum c, sum d]
  return _mm256_insertf128_pd(_mm512_castpd512_pd256(total), _mm512_extractf64x2_pd(total, 2), 1);
}

// a + b and a - b never fused with a product before them (GCC contracts the plain intrinsics'
// a * b + c into a fused multiply-add under -ffp-contract=fast, C++'s default): the sums that
// keep the portable path's bits.
ADPARM_AVX512 inline V add(V a, V b) { return _mm512_add_round_pd(a, b, _MM_FROUND_CUR_DIRECTION); }
ADPARM_AVX512 inline double add(double a, double b) {
  return _mm_cvtsd_f64(_mm_add_round_sd(_mm_set_sd(a), _mm_set_sd(b), _MM_FROUND_CUR_DIRECTION));
}
ADPARM_AVX512 inline V subtract(V a, V b) {
  return _mm512_sub_round_pd(a, b, _MM_FROUND_CUR_DIRECTION);
}

// c -= a b (8 entries)
ADPARM_AVX512 inline void subtract_product(double* c, V a, V b) {
  _mm512_storeu_pd(c, _mm512_fnmadd_pd(a, b, load(c)));
}

// The index vector of a permutation, lane 0 first.
ADPARM_AVX512 inline __m512i index(long a, long b, long c, long d, long e, long f, long g, long h) {
  return _mm512_set_epi64(h, g, f, e, d, c, b, a);
}

ADPARM_AVX512 inline double sum(V v) {
  const __m256d a = _mm256_add_pd(_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd(v, 1));
  const __m128d b = _mm_add_pd(_mm256_castpd256_pd128(a), _mm256_extractf128_pd(a, 1));
  return _mm_cvtsd_f64(_mm_add_sd(b, _mm_unpackhi_pd(b, b)));
}

// Gamma omega, Gamma column-major (8 x 8): four independent pairs of multiply-adds, then a tree.
ADPARM_AVX512 inline V covariance_product(const double* gamma, V omega) {
  const V p01 =
      _mm512_fmadd_pd(load(gamma + 8), lane<1>(omega), _mm512_mul_pd(load(gamma), lane<0>(omega)));
  const V p23 = _mm512_fmadd_pd(load(gamma + 24), lane<3>(omega),
                                _mm512_mul_pd(load(gamma + 16), lane<2>(omega)));
  const V p45 = _mm512_fmadd_pd(load(gamma + 40), lane<5>(omega),
                                _mm512_mul_pd(load(gamma + 32), lane<4>(omega)));
  const V p67 = _mm512_fmadd_pd(load(gamma + 56), lane<7>(omega),
                                _mm512_mul_pd(load(gamma + 48), lane<6>(omega)));
  return _mm512_add_pd(_mm512_add_pd(p01, p23), _mm512_add_pd(p45, p67));
}

// The sample of an evaluation, eqs. (19)-(26) without an input bound, for the augmented basis
// (basis.hpp) on the two-link arm: its 8 functions' Jacobian J (8 x 4) as four registers built by
// permutations of x = [x1, x2, x3, x4] (none of it through memory),
//   J = [[2 x1, 0, 0, 0], [0, 2 x2, 0, 0], [x2, x1, 0, 0], [0, 0, 2 x3, 0],
//        [0, x3^2 s, 2 x3 c, 0], [0, 0, 0, 2 x4], [0, 0, x4, x3], [0, x3 x4 s, x4 c, x3 c]]
// (c, s = cos q2, sin q2), then B = J_e2 M^-1 (8 x 2: two registers) and the drift part of omega
// F = (d phi / dqd) dqd + J f (hjb.hpp).
struct Result8 {
  V b0, b1;         // the columns of B
  V omega;          // F + B u_hat
  V difference;     // Wa - Wc
  double u_hat[2];  // eq. (20)
  double input_cost;
  double error;                    // eq. (21)
  double projected_difference[2];  // R^-1 B^T (Wa - Wc)
  double omega_norm;               // omega^T omega
};

// In: x, c and s, M^-1 (2 x 2, column-major), the drift f(x) (4), dqd2 (the desired velocity of
// joint 2), x^T Q x, Wc, Wa, R and R^-1 (2 x 2, column-major).
// u_hat = -1/2 R^-1 B^T Wa, omega = F + B u_hat, eps = x^T Q x + u^T R u + Wc^T omega (20)-(21);
// B^T (Wa - Wc) for the actor (26) from the same reduction as B^T Wa.
ADPARM_AVX512 inline void evaluate(const double* x, double c, double s, const double* mass_inverse,
                                   const double* f, double dqd2, double state_cost,
                                   const double* critic_weights, const double* actor_weights,
                                   const double* R, const double* R_inverse, Result8& r) {
  const V X = _mm512_castpd256_pd512(_mm256_set_pd(x[3], x[2], x[1], x[0]));
  const V ones = broadcast(1.0);
  const V cosine = _mm512_mask_blend_pd(0x90, ones, broadcast(c));  // c in lanes 4 and 7
  // the columns of J: x's entries picked, times constants (and c, x s)
  const V j0 = _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0x05, index(0, 0, 1, 0, 0, 0, 0, 0), X),
                             _mm512_set_pd(0, 0, 0, 0, 0, 1, 0, 2));
  const V xs = _mm512_permutexvar_pd(index(0, 0, 0, 0, 2, 0, 0, 3), _mm512_mul_pd(X, broadcast(s)));
  const V j1 = _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0x96, index(0, 1, 0, 0, 2, 0, 0, 2), X),
                             _mm512_mask_blend_pd(0x90, _mm512_set_pd(0, 0, 0, 0, 0, 1, 2, 0), xs));
  const V j2 = _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xd8, index(0, 0, 0, 2, 2, 0, 3, 3), X),
                             _mm512_mul_pd(_mm512_set_pd(1, 1, 0, 2, 2, 0, 0, 0), cosine));
  const V j3 = _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xe0, index(0, 0, 0, 0, 0, 3, 2, 2), X),
                             _mm512_mul_pd(_mm512_set_pd(1, 1, 2, 0, 0, 0, 0, 0), cosine));
  // B = J_e2 M^-1
  r.b0 = _mm512_fmadd_pd(j3, broadcast(mass_inverse[1]),
                         _mm512_mul_pd(j2, broadcast(mass_inverse[0])));
  r.b1 = _mm512_fmadd_pd(j3, broadcast(mass_inverse[3]),
                         _mm512_mul_pd(j2, broadcast(mass_inverse[2])));
  // F = -(d phi / d x2) dqd2 on the two cos q2 functions + J f
  const V desired_rate = _mm512_maskz_mul_pd(0x90, j1, broadcast(-dqd2));
  const V drift_rate = _mm512_add_pd(
      _mm512_fmadd_pd(j1, broadcast(f[1]), _mm512_fmadd_pd(j0, broadcast(f[0]), desired_rate)),
      _mm512_fmadd_pd(j3, broadcast(f[3]), _mm512_mul_pd(j2, broadcast(f[2]))));
  const V b0 = r.b0, b1 = r.b1;
  const V wa = load(actor_weights), wc = load(critic_weights);
  r.difference = _mm512_sub_pd(wa, wc);
  const __m256d t = sum4(_mm512_mul_pd(b0, wa), _mm512_mul_pd(b1, wa),
                         _mm512_mul_pd(b0, r.difference), _mm512_mul_pd(b1, r.difference));
  const double bt0 = _mm256_cvtsd_f64(t);  // B^T Wa, B^T (Wa - Wc)
  const double bt1 = _mm256_cvtsd_f64(_mm256_permute_pd(t, 1));
  const __m128d upper = _mm256_extractf128_pd(t, 1);
  const double bt2 = _mm_cvtsd_f64(upper), bt3 = _mm_cvtsd_f64(_mm_unpackhi_pd(upper, upper));
  const double* Ri = R_inverse;
  const double u0 = -0.5 * (Ri[0] * bt0 + Ri[2] * bt1);
  const double u1 = -0.5 * (Ri[1] * bt0 + Ri[3] * bt1);
  r.u_hat[0] = u0;
  r.u_hat[1] = u1;
  r.projected_difference[0] = Ri[0] * bt2 + Ri[2] * bt3;
  r.projected_difference[1] = Ri[1] * bt2 + Ri[3] * bt3;
  const V omega =
      _mm512_fmadd_pd(b1, broadcast(u1), _mm512_fmadd_pd(b0, broadcast(u0), drift_rate));
  r.omega = omega;
  r.input_cost = u0 * (R[0] * u0 + R[2] * u1) + u1 * (R[1] * u0 + R[3] * u1);
  const __m256d dots = sum4(_mm512_mul_pd(wc, omega), _mm512_mul_pd(omega, omega),
                            _mm512_setzero_pd(), _mm512_setzero_pd());  // Wc^T omega, |omega|^2
  r.error = state_cost + r.input_cost + _mm256_cvtsd_f64(dots);
  r.omega_norm = _mm256_cvtsd_f64(_mm256_permute_pd(dots, 1));
}

// eqs. (23)-(24): with G = Gamma omega and g = w eta_c / (1 + nu omega^T G),
//   critic_rate -= g eps G,  gamma_rate -= g G G^T  (gamma_rate column-major, 8 x 8);
// eq. (26)'s share: actor_gradient -= w eta_a1 eps / sqrt(1 + omega^T omega) B R^-1 B^T (Wa - Wc).
ADPARM_AVX512 inline void learn(const Result8& r, const double* gamma, double weight, double eta_c,
                                double nu, double eta_a1, double* critic_rate, double* gamma_rate,
                                double* actor_gradient) {
  // the actor's scale first: its square root and division overlap the critic's chain
  const double scale = weight * eta_a1 * r.error / std::sqrt(1.0 + r.omega_norm);
  const V g = covariance_product(gamma, r.omega);
  const double gain = weight * eta_c / (1.0 + nu * sum(_mm512_mul_pd(r.omega, g)));
  _mm512_storeu_pd(critic_rate, _mm512_fnmadd_pd(broadcast(gain * r.error), g, load(critic_rate)));
  const V scaled = _mm512_mul_pd(broadcast(gain), g);  // column j -= (g G) G_j
  subtract_product(gamma_rate, scaled, lane<0>(g));
  subtract_product(gamma_rate + 8, scaled, lane<1>(g));
  subtract_product(gamma_rate + 16, scaled, lane<2>(g));
  subtract_product(gamma_rate + 24, scaled, lane<3>(g));
  subtract_product(gamma_rate + 32, scaled, lane<4>(g));
  subtract_product(gamma_rate + 40, scaled, lane<5>(g));
  subtract_product(gamma_rate + 48, scaled, lane<6>(g));
  subtract_product(gamma_rate + 56, scaled, lane<7>(g));
  const V share =
      _mm512_fmadd_pd(r.b1, broadcast(scale * r.projected_difference[1]),
                      _mm512_mul_pd(r.b0, broadcast(scale * r.projected_difference[0])));
  _mm512_storeu_pd(actor_gradient, _mm512_sub_pd(load(actor_gradient), share));
}

// sin and cos of 8 angles (|angle| up to about 1e5): the nearest multiple q of pi/2 taken off
// in two parts with fused multiply-adds, then Cephes' minimax polynomials on [-pi/4, pi/4] (about
// 1 ulp, as libm's) and the quadrant's swap and signs.
ADPARM_AVX512 inline void sincos(V angle, V& sine, V& cosine) {
  const V q = _mm512_roundscale_pd(_mm512_mul_pd(angle, broadcast(0.63661977236758134308)),
                                   _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  V r = _mm512_fnmadd_pd(q, broadcast(1.5707963267948966), angle);  // pi/2 = high + low
  r = _mm512_fnmadd_pd(q, broadcast(6.123233995736766e-17), r);
  const V z = _mm512_mul_pd(r, r);
  V ps = broadcast(1.58962301576546568060e-10);
  ps = _mm512_fmadd_pd(ps, z, broadcast(-2.50507477628578072866e-8));
  ps = _mm512_fmadd_pd(ps, z, broadcast(2.75573136213857245213e-6));
  ps = _mm512_fmadd_pd(ps, z, broadcast(-1.98412698295895385996e-4));
  ps = _mm512_fmadd_pd(ps, z, broadcast(8.33333333332211858878e-3));
  ps = _mm512_fmadd_pd(ps, z, broadcast(-1.66666666666666307295e-1));
  const V s = _mm512_fmadd_pd(_mm512_mul_pd(r, z), ps, r);  // r + r z P(z)
  V pc = broadcast(-1.13585365213876817300e-11);
  pc = _mm512_fmadd_pd(pc, z, broadcast(2.08757008419747316778e-9));
  pc = _mm512_fmadd_pd(pc, z, broadcast(-2.75573141792967388112e-7));
  pc = _mm512_fmadd_pd(pc, z, broadcast(2.48015872888517045348e-5));
  pc = _mm512_fmadd_pd(pc, z, broadcast(-1.38888888888730564116e-3));
  pc = _mm512_fmadd_pd(pc, z, broadcast(4.16666666666665929218e-2));
  const V c =
      _mm512_fmadd_pd(_mm512_mul_pd(z, z), pc,
                      _mm512_fnmadd_pd(broadcast(0.5), z, broadcast(1.0)));  // 1 - z/2 + z^2 Q
  const __m512i n = _mm512_cvtpd_epi64(q);  // the quadrant, mod 4 below
  const __mmask8 swap = _mm512_test_epi64_mask(n, _mm512_set1_epi64(1));
  const __mmask8 sine_negative = _mm512_test_epi64_mask(n, _mm512_set1_epi64(2));
  const __mmask8 cosine_negative =
      _mm512_test_epi64_mask(_mm512_add_epi64(n, _mm512_set1_epi64(1)), _mm512_set1_epi64(2));
  const V sign = broadcast(-0.0);
  sine = _mm512_mask_blend_pd(swap, s, c);
  cosine = _mm512_mask_blend_pd(swap, c, s);
  sine = _mm512_mask_xor_pd(sine, sine_negative, sine, sign);
  cosine = _mm512_mask_xor_pd(cosine, cosine_negative, cosine, sign);
}

// RK4's sums on the loop's state (rk4.hpp), in pieces that match its layout [q, dq (2 + 2), Wc (8),
// Wa (8), Gamma (8 x 8), nu (2), J (1)]: each piece is read and written by one load or store
// of its size, as the derivative reads and writes it (a load that spans two stores waits until
// they reach the cache; one within a store is forwarded from it). out = x + c r, and the step's
// end out = x + h6 (((r1 + 2 r2) + 2 r3) + r4); products then sums, no fused multiply-add: the
// bits of Eigen's expressions on the portable path.
constexpr int kStateSize = 87;
constexpr int kGammaEnd = 84;  // Gamma's last entry + 1; 8-entry pieces from 4 to here

ADPARM_AVX512 inline __m128d add(__m128d a, __m128d b) { return _mm_maskz_add_pd(0x3, a, b); }

ADPARM_AVX512 inline void stage_sum(const double* x, const double* r, double c, double* out) {
  const V cv = broadcast(c);
  const __m128d c2 = _mm_set1_pd(c);
  for (int i : {0, 2, kGammaEnd})
    _mm_storeu_pd(out + i, add(_mm_loadu_pd(x + i), _mm_mul_pd(c2, _mm_loadu_pd(r + i))));
  for (int i = 4; i < kGammaEnd; i += 8)
    _mm512_storeu_pd(out + i, add(load(x + i), _mm512_mul_pd(cv, load(r + i))));
  out[kStateSize - 1] = add(x[kStateSize - 1], c * r[kStateSize - 1]);
}

ADPARM_AVX512 inline V rk4_sum8(V x, V r1, V r2, V r3, V r4, V h6) {
  const V two = broadcast(2.0);
  const V sum = add(add(add(r1, _mm512_mul_pd(two, r2)), _mm512_mul_pd(two, r3)), r4);
  return add(x, _mm512_mul_pd(h6, sum));
}
ADPARM_AVX512 inline __m128d rk4_sum2(const double* x, const double* r1, const double* r2,
                                      const double* r3, const double* r4, double h6) {
  const __m128d two = _mm_set1_pd(2.0);
  const __m128d sum = add(add(add(_mm_loadu_pd(r1), _mm_mul_pd(two, _mm_loadu_pd(r2))),
                              _mm_mul_pd(two, _mm_loadu_pd(r3))),
                          _mm_loadu_pd(r4));
  return add(_mm_loadu_pd(x), _mm_mul_pd(_mm_set1_pd(h6), sum));
}

ADPARM_AVX512 inline void rk4_sum(const double* x, const double* r1, const double* r2,
                                  const double* r3, const double* r4, double h6, double* out) {
  const V h = broadcast(h6);
  for (int i : {0, 2, kGammaEnd})
    _mm_storeu_pd(out + i, rk4_sum2(x + i, r1 + i, r2 + i, r3 + i, r4 + i, h6));
  for (int i = 4; i < kGammaEnd; i += 8)
    _mm512_storeu_pd(
        out + i, rk4_sum8(load(x + i), load(r1 + i), load(r2 + i), load(r3 + i), load(r4 + i), h));
  const int i = kStateSize - 1;
  out[i] = add(x[i], h6 * add(add(add(r1[i], 2.0 * r2[i]), 2.0 * r3[i]), r4[i]));
}

// The weights' rates when neither e2 block is near its margin (positive_block.hpp: no
// projection): dWc = the critic's rate as learned, and eq. (26)'s
// dWa = proj{gradient - eta_a2 (Wa - Wc)} with proj the ball ||Wa|| <= weight_bound (actor.hpp).
ADPARM_AVX512 inline void weight_rates(const double* actor_weights, const double* critic_rate,
                                       const double* actor_gradient, V difference, double eta_a2,
                                       double weight_bound, double* critic_out, double* actor_out) {
  _mm512_storeu_pd(critic_out, load(critic_rate));
  const V wa = load(actor_weights);
  V rate = _mm512_fnmadd_pd(broadcast(eta_a2), difference, load(actor_gradient));
  const __m256d dots = sum4(_mm512_mul_pd(wa, wa), _mm512_mul_pd(wa, rate), _mm512_setzero_pd(),
                            _mm512_setzero_pd());  // ||Wa||^2, Wa^T rate
  const double norm_squared = _mm256_cvtsd_f64(dots);
  const double outward = _mm256_cvtsd_f64(_mm256_permute_pd(dots, 1));
  if (norm_squared >= weight_bound * weight_bound && outward > 0.0)
    rate = _mm512_fnmadd_pd(broadcast(outward / norm_squared), wa, rate);
  _mm512_storeu_pd(actor_out, rate);
}

// Critic::below for K = 8 (critic.hpp): lambda_min(Gamma) < threshold, Gamma - threshold I in
// eight registers (its columns), by fraction-free (Bareiss) elimination: step j makes every
// later column i  (p_j c_i - c_j(i) c_j) / p_(j-1),  so that the pivots p_j are the leading
// principal minors, all positive exactly when the matrix is positive definite (Sylvester), as
// the portable test's L D L^T pivots. The division by p_(j-1) is known a step ahead: no
// division on the chain from one pivot to the next (the portable test has one per pivot). The
// answer is the portable test's except when lambda_min is within round-off of the threshold.
ADPARM_AVX512 inline bool below(const double* gamma, double threshold) {
  V c[8];
  const V t = broadcast(threshold);
#pragma GCC unroll 8
  for (int j = 0; j < 8; ++j)
    c[j] = _mm512_mask_sub_pd(load(gamma + 8 * j), static_cast<__mmask8>(1u << j),
                              load(gamma + 8 * j), t);
  V previous_inverse = broadcast(1.0);  // 1 / p_(j-1)
#pragma GCC unroll 8
  for (int j = 0; j < 8; ++j) {
    const V pivot = _mm512_permutexvar_pd(_mm512_set1_epi64(j), c[j]);
    const double p = _mm512_cvtsd_f64(pivot);
    if (!(p > 0.0)) return true;  // also catches NaN
#pragma GCC unroll 8
    for (int i = j + 1; i < 8; ++i) {
      const V entry = _mm512_permutexvar_pd(_mm512_set1_epi64(i), c[j]);
      c[i] =
          _mm512_mul_pd(_mm512_fmsub_pd(pivot, c[i], _mm512_mul_pd(entry, c[j])), previous_inverse);
    }
    previous_inverse = broadcast(1.0 / p);
  }
  return false;
}

}  // namespace vector8
#endif

}  // namespace adparm
