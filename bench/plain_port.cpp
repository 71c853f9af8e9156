// A plain port of the paper's closed loop (issue 26's yardstick): the same laws as adparm's
// PaperClosedLoop with paper_settings() - exact linearization (eqs. 4-9), the critic (eqs. 23-24
// with the covariance reset), the actor (eq. 26 with its projections), RISE (eqs. 27-28), the
// probe, RK4 at dt = 1 ms, 8 basis functions - written as a textbook implementation: fixed-size
// Eigen matrices, M^-1 by .inverse(), a right-hand side f(t, x) that computes everything it needs
// at each of RK4's four evaluations (time signals included), sin(w t + p) as written, Eigen's LLT
// for the covariance test, products associated as matrix-vector products (Gamma omega once; B (R^-1
// (B^T v))). No hand tricks. Built with the core's portable flags (-O3, no -march).
// It records nothing (adparm writes a row every 10 steps). adparm_bench --checks compares it with
// adparm's loop; adparm_bench --paper-port times the two in interleaved pairs.
#include "plain_port.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace plain_port {
namespace {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;
using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;
using Vec8 = Eigen::Matrix<double, 8, 1>;
using Mat8 = Eigen::Matrix<double, 8, 8>;
using Mat84 = Eigen::Matrix<double, 8, 4>;
using Mat82 = Eigen::Matrix<double, 8, 2>;
using State = Eigen::Matrix<double, kStateSize, 1>;

// paper_settings() (cpp/include/adparm/settings.hpp) and the defaults it keeps.
struct Paper {
  // arm (arm_model.hpp), plant = model
  double p1 = 5.0, p2 = 1.0, p3 = 1.0, g1 = 9.8 * 1.2, g2 = 9.8, coulomb = -0.1, viscous = 0.0;
  Vec2 disturbance{0.1, 0.1};
  Vec2 q0{0.1598, 0.2257};
  Mat2 alpha1 = (Mat2() << 15.6, 10.6, 10.6, 10.4).finished();
  Mat4 Q = (Mat4() << 40, 2, -4, 4, 2, 40, 4, -6, -4, 4, 4, 0, 4, -6, 0, 4).finished();
  Mat2 R = 0.25 * Mat2::Identity();
  Mat2 R_inverse = R.inverse();
  double ks = 10.0, alpha2 = 1.0, beta1 = 0.5;                                 // RISE
  double eta_c = 800.0, nu = 1.0, gamma0 = 100.0, epsilon_T = 1e-6;            // critic
  double eta_a1 = 0.01, eta_a2 = 1.0, weight_bound = 100.0, e2_margin = 0.01;  // actor
  double probe_until = 100.0;
  Vec4 probe_frequencies{1.0, 2.7, 5.3, 9.1};
  Vec2 probe_amplitude{71.0, 23.0};  // the same on each of the 4 sinusoids
  Vec4 probe_phases{0.0, 1.0, 2.0, 3.0};
  double dt = 1e-3;
  double divergence_bound = 1e6;
};

Vec2 sign(const Vec2& v) { return Vec2((v[0] > 0) - (v[0] < 0), (v[1] > 0) - (v[1] < 0)); }

// lambda_min of the e2 block P(c) of the weights (positive_block.hpp) and its gradient.
// Written out here on purpose, not positive_block.hpp's: the core projects only after a
// square-root-free test (e2_block_above) rules the common case out; with the core's projection
// the port ran 1012 instead of 1487 ns per step (2026-12-05, 11 pairs): the yardstick would
// carry adparm's own trick.
double e2_lambda_min(const Vec8& W, double c, Vec8& gradient) {
  const double a = W[3] + c * W[4], d = W[5], b = 0.5 * (W[6] + c * W[7]);
  const double mean = 0.5 * (a + d), half = 0.5 * (a - d);
  const double radius = std::sqrt(half * half + b * b);
  const double lambda = mean - radius;
  double v1 = 1.0, v2 = 0.0;
  if (radius > 0.0) {
    if (half <= 0.0) {
      v1 = d - lambda;
      v2 = -b;
    } else {
      v1 = -b;
      v2 = a - lambda;
    }
    const double norm = std::hypot(v1, v2);
    v1 /= norm;
    v2 /= norm;
  }
  gradient.setZero();
  gradient[3] = v1 * v1;
  gradient[4] = c * v1 * v1;
  gradient[5] = v2 * v2;
  gradient[6] = v1 * v2;
  gradient[7] = c * v1 * v2;
  return lambda;
}

// The projection keeping lambda_min(P(+-1)) >= margin, in the metric `metric` (positive_block.hpp).
Vec8 keep_e2_positive(const Vec8& W, const Vec8& rate, double margin, const Mat8& metric) {
  Vec8 n[2], metric_n[2];
  bool active[2];
  double floor[2];
  for (int i = 0; i < 2; ++i) {
    const double lambda = e2_lambda_min(W, i == 0 ? 1.0 : -1.0, n[i]);
    active[i] = lambda <= margin;
    floor[i] = 100.0 * (margin - lambda);
    metric_n[i] = metric * n[i];
  }
  if (!active[0] && !active[1]) return rate;
  const auto violates = [&](int i, const Vec8& r) { return active[i] && n[i].dot(r) < floor[i]; };
  if (!violates(0, rate) && !violates(1, rate)) return rate;
  for (int i = 0; i < 2; ++i) {
    if (!violates(i, rate)) continue;
    const Vec8 projected =
        rate + ((floor[i] - n[i].dot(rate)) / n[i].dot(metric_n[i])) * metric_n[i];
    if (!violates(1 - i, projected)) return projected;
  }
  const double g00 = n[0].dot(metric_n[0]), g11 = n[1].dot(metric_n[1]);
  const double g01 = n[0].dot(metric_n[1]);
  const double det = g00 * g11 - g01 * g01;
  const double r0 = floor[0] - n[0].dot(rate), r1 = floor[1] - n[1].dot(rate);
  if (!(det > 1e-12 * g00 * g11)) return rate + (r0 / g00) * metric_n[0];
  const double mu0 = (g11 * r0 - g01 * r1) / det, mu1 = (g00 * r1 - g01 * r0) / det;
  return rate + mu0 * metric_n[0] + mu1 * metric_n[1];
}

class Loop {
 public:
  Loop() {
    const Vec2 e1 = -p_.q0;  // qd = 0, dq0 = 0
    e2_initial_ = p_.alpha1 * e1;
  }

  State initial_state() const {
    State x = State::Zero();
    x.segment<2>(0) = p_.q0;
    x.segment<8>(4).setOnes();   // Wc
    x.segment<8>(12).setOnes();  // Wa
    Eigen::Map<Mat8>(x.data() + 20) = p_.gamma0 * Mat8::Identity();
    return x;
  }

  // The closed loop's right-hand side at (t, x).
  State f(double t, const State& state) const {
    const Vec2 q = state.segment<2>(0), dq = state.segment<2>(2);
    const Vec8 Wc = state.segment<8>(4), Wa = state.segment<8>(12);
    const Mat8 Gamma = Eigen::Map<const Mat8>(state.data() + 20);
    const Vec2 nu = state.segment<2>(84);

    // desired state: the set-point qd = 0
    const Vec2 qd = Vec2::Zero(), dqd = Vec2::Zero(), ddqd = Vec2::Zero();
    // errors (eqs. 6-7)
    const Vec2 e1 = qd - q;
    const Vec2 e2 = (dqd - dq) + p_.alpha1 * e1;
    Vec4 x;
    x << e1, e2;

    // the arm (eq. 1)
    const double c2 = std::cos(q[1]), s2 = std::sin(q[1]);
    Mat2 M;
    M << p_.p1 + 2.0 * p_.p3 * c2, p_.p2 + p_.p3 * c2, p_.p2 + p_.p3 * c2, p_.p2;
    const Mat2 M_inverse = M.inverse();
    Mat2 C;
    C << -p_.p3 * s2 * dq[1], -p_.p3 * s2 * (dq[0] + dq[1]), p_.p3 * s2 * dq[0], 0.0;
    const Vec2 G(p_.g1 * std::cos(q[0]) + p_.g2 * std::cos(q[0] + q[1]),
                 p_.g2 * std::cos(q[0] + q[1]));
    const Vec2 F = p_.coulomb * sign(dq) + p_.viscous * dq;

    // error system (eq. 9): f(x), g(x) = [0; M^-1]
    Vec4 drift;
    drift << -p_.alpha1 * e1 + e2, -M_inverse * (C * e2);
    Eigen::Matrix<double, 4, 2> g = Eigen::Matrix<double, 4, 2>::Zero();
    g.bottomRows<2>() = M_inverse;

    // the basis (augmented: cos q2 of the arm) and its Jacobian
    const double x1 = x[0], x2 = x[1], x3 = x[2], x4 = x[3];
    Mat84 dphi;
    dphi << 2 * x1, 0, 0, 0,              //
        0, 2 * x2, 0, 0,                  //
        x2, x1, 0, 0,                     //
        0, 0, 2 * x3, 0,                  //
        0, x3 * x3 * s2, 2 * x3 * c2, 0,  //
        0, 0, 0, 2 * x4,                  //
        0, 0, x4, x3,                     //
        0, x3 * x4 * s2, x4 * c2, x3 * c2;
    Vec8 dphi_dqd = Vec8::Zero();  // (d phi / d qd) dqd
    dphi_dqd[4] = -x3 * x3 * s2 * dqd[1];
    dphi_dqd[7] = -x3 * x4 * s2 * dqd[1];

    // actor (eq. 20) and HJB error (eq. 21)
    const Mat82 B = dphi * g;
    const Vec2 u_hat = -0.5 * p_.R_inverse * B.transpose() * Wa;
    const Vec8 omega = dphi * (drift + g * u_hat) + dphi_dqd;
    const double state_cost = x.dot(p_.Q * x);
    const double eps = state_cost + u_hat.dot(p_.R * u_hat) + Wc.dot(omega);

    // critic (eqs. 23-24)
    const Vec8 Gamma_omega = Gamma * omega;
    const double rho = 1.0 + p_.nu * omega.dot(Gamma_omega);
    Vec8 dWc = -p_.eta_c * Gamma_omega * eps / rho;
    const Mat8 dGamma = -p_.eta_c * Gamma_omega * Gamma_omega.transpose() / rho;  // Gamma = Gamma^T
    dWc = keep_e2_positive(Wc, dWc, p_.e2_margin, Gamma);

    // actor (eq. 26) with proj{}
    const Vec8 difference = Wa - Wc;
    const Vec8 gradient = -p_.eta_a1 / std::sqrt(1.0 + omega.dot(omega)) * eps *
                          (B * (p_.R_inverse * (B.transpose() * difference)));
    Vec8 dWa = gradient - p_.eta_a2 * difference;
    dWa = keep_e2_positive(Wa, dWa, p_.e2_margin, Mat8::Identity());
    if (Wa.squaredNorm() >= p_.weight_bound * p_.weight_bound && Wa.dot(dWa) > 0.0)
      dWa -= Wa.dot(dWa) / Wa.squaredNorm() * Wa;

    // RISE (eqs. 27-28)
    const Vec2 mu = (p_.ks + 1.0) * (e2 - e2_initial_) + nu;
    const Vec2 dnu = (p_.ks + 1.0) * p_.alpha2 * e2 + p_.beta1 * sign(e2);

    // probe, input, torque (feedforward of eq. 5), disturbance
    Vec2 probe = Vec2::Zero();
    if (t < p_.probe_until)
      for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 2; ++j)
          probe[j] +=
              p_.probe_amplitude[j] * std::sin(p_.probe_frequencies[k] * t + p_.probe_phases[k]);
    const Vec2 u = u_hat + probe;
    const Vec2 de1 = dqd - dq;
    const Vec2 h = M * (ddqd + p_.alpha1 * de1) + C * (dqd + p_.alpha1 * e1) + G + F;
    const Vec2 tau = h + mu - u;
    const Vec2 tau_d(p_.disturbance[0] * std::sin(t), p_.disturbance[1] * std::cos(t));
    const Vec2 ddq = M_inverse * (tau - C * dq - G - F - tau_d);

    State rate;
    rate << dq, ddq, dWc, dWa, Eigen::Map<const Eigen::Matrix<double, 64, 1>>(dGamma.data()), dnu,
        state_cost + u.dot(p_.R * u);
    return rate;
  }

  // lambda_min(Gamma) < epsilon_T: Gamma - epsilon_T I has no Cholesky factor.
  bool needs_reset(const State& x) const {
    const Mat8 Gamma = Eigen::Map<const Mat8>(x.data() + 20);
    return Eigen::LLT<Mat8>(Gamma - p_.epsilon_T * Mat8::Identity()).info() != Eigen::Success;
  }

  void reset(State& x) const { Eigen::Map<Mat8>(x.data() + 20) = p_.gamma0 * Mat8::Identity(); }

  bool diverged(const State& x) const {
    return !std::isfinite(x.sum()) || !(x.head<20>().cwiseAbs().maxCoeff() <= p_.divergence_bound);
  }

  const Paper& paper() const { return p_; }

 private:
  Paper p_;
  Vec2 e2_initial_;
};

}  // namespace

void run(double seconds, Run& out) {
  const Loop loop;
  const double dt = loop.paper().dt;
  const long steps = static_cast<long>(std::max(1.0, std::ceil(seconds / dt * (1.0 - 1e-12))));
  State x = loop.initial_state();
  out.reset_times.clear();
  out.diverged = false;
  long step = 0;
  for (; step < steps; ++step) {  // classical RK4
    const double t = step * dt;
    const double t_end = std::min((step + 1) * dt, seconds);
    const double h = t_end - t;
    const State k1 = loop.f(t, x);
    const State k2 = loop.f(t + 0.5 * h, x + 0.5 * h * k1);
    const State k3 = loop.f(t + 0.5 * h, x + 0.5 * h * k2);
    const State k4 = loop.f(t_end, x + h * k3);
    const State next = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    if (loop.diverged(next)) {
      out.diverged = true;
      break;
    }
    x = next;
    if (loop.needs_reset(x)) {
      loop.reset(x);
      out.reset_times.push_back(t_end);
    }
  }
  out.steps = step;
  for (int i = 0; i < kStateSize; ++i) out.state[i] = x[i];
}

}  // namespace plain_port
