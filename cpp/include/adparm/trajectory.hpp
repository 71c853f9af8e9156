// The desired joint trajectory qd(t) with its first two derivatives, which the feedforward h of
// eq. (5) needs in full (ERRATA: h = M (ddqd + alpha1 de1) + C (dqd + alpha1 e1) + G + F):
//   constant:  qd = offset
//   sinusoid:  qd_j(t) = offset_j + sum_k amplitude_jk sin(frequency_jk t + phase_jk)
//   spline:    a piecewise cubic in t (Python fits it to samples with scipy's CubicSpline);
//              interval i covers [breaks_i, breaks_{i+1}] and holds, per joint j, the coefficients
//              c_0..c_3 of qd_j = c_0 s^3 + c_1 s^2 + c_2 s + c_3, s = t - breaks_i, in columns
//              4 j .. 4 j + 3 of `coefficients` (n joints: 4 n columns). Outside [breaks_0,
//              breaks_n] the trajectory is evaluated at the nearest end (a simulation refuses sim.T
//              beyond the last break).
#pragma once

#include <algorithm>
#include <limits>

#include "adparm/types.hpp"

namespace adparm {

enum class TrajectoryKind { constant, sinusoid, spline };

// Sizes for n joints; sinusoid: k sinusoids per joint; spline: m intervals.
struct TrajectorySettings {
  TrajectoryKind kind = TrajectoryKind::constant;
  Eigen::VectorXd offset = Eigen::VectorXd::Zero(2);  // rad, n
  Eigen::MatrixXd amplitude;                          // rad, n x k (sinusoid)
  Eigen::MatrixXd frequency;                          // rad/s, n x k (sinusoid)
  Eigen::MatrixXd phase;                              // rad, n x k (sinusoid)
  Eigen::VectorXd breaks;                             // s, increasing, m + 1 (spline)
  Eigen::MatrixXd coefficients;                       // m x 4n (spline)
};

template <int N = 2>
class TrajectoryT {
 public:
  using Desired = DesiredStateT<N>;
  TrajectoryT() = default;
  TrajectoryT(const TrajectorySettings& settings, Eigen::Index dof)
      : settings_(settings), dof_(dof) {
    check_size(settings.offset, dof, 1, "task.qd");
    check_finite(settings.offset, "task.qd");
    offset_ = settings.offset;
    if (settings.kind == TrajectoryKind::sinusoid) {
      const Eigen::Index n = settings.amplitude.cols();
      check_size(settings.amplitude, dof, n, "task.qd.amplitude");
      check_finite(settings.amplitude, "task.qd.amplitude");
      check_size(settings.frequency, dof, n, "task.qd.frequency");
      check_finite(settings.frequency, "task.qd.frequency");
      check_size(settings.phase, dof, n, "task.qd.phase");
      check_finite(settings.phase, "task.qd.phase");
    } else if (settings.kind == TrajectoryKind::spline) {
      const Eigen::Index n = settings.coefficients.rows();
      if (n < 1) throw std::invalid_argument("task.qd: a spline needs at least one interval");
      check_size(settings.coefficients, n, 4 * dof, "task.qd.coefficients");
      check_size(settings.breaks, n + 1, 1, "task.qd.t");
      check_finite(settings.breaks, "task.qd.t");
      check_finite(settings.coefficients, "task.qd.coefficients");
      for (Eigen::Index i = 0; i < n; ++i)
        if (!(settings.breaks[i + 1] > settings.breaks[i]))
          throw std::invalid_argument("task.qd.t: sample times must be strictly increasing");
    }
  }

  const TrajectorySettings& settings() const { return settings_; }
  bool is_constant() const { return settings_.kind == TrajectoryKind::constant; }

  // The last time at which the trajectory is defined (infinite unless it is a spline).
  double end_time() const {
    return settings_.kind == TrajectoryKind::spline ? settings_.breaks[settings_.breaks.size() - 1]
                                                    : std::numeric_limits<double>::infinity();
  }

  Eigen::Index dof() const { return dof_; }

  Desired operator()(double t) const {
    Desired d(dof_);
    d.q = offset_;
    if (settings_.kind == TrajectoryKind::sinusoid) {
      for (Eigen::Index k = 0; k < settings_.amplitude.cols(); ++k) {
        for (Eigen::Index j = 0; j < dof_; ++j) {
          const double a = settings_.amplitude(j, k), w = settings_.frequency(j, k);
          const double angle = w * t + settings_.phase(j, k);
          const double s = std::sin(angle), c = std::cos(angle);
          d.q[j] += a * s;
          d.dq[j] += a * w * c;
          d.ddq[j] -= a * w * w * s;
        }
      }
    } else if (settings_.kind == TrajectoryKind::spline) {
      const Eigen::VectorXd& b = settings_.breaks;
      const Eigen::Index n = settings_.coefficients.rows();
      const double clamped = std::min(std::max(t, b[0]), b[n]);
      // interval i with b_i <= t < b_{i+1} (the last one includes its right end)
      const Eigen::Index i = std::min<Eigen::Index>(
          n - 1, std::max<Eigen::Index>(
                     0, std::upper_bound(b.data(), b.data() + n + 1, clamped) - b.data() - 1));
      const double s = clamped - b[i];
      for (Eigen::Index j = 0; j < dof_; ++j) {
        const auto c = settings_.coefficients.row(i).template segment<4>(4 * j);
        d.q[j] = ((c[0] * s + c[1]) * s + c[2]) * s + c[3];
        d.dq[j] = (3.0 * c[0] * s + 2.0 * c[1]) * s + c[2];
        d.ddq[j] = 6.0 * c[0] * s + 2.0 * c[1];
      }
    }
    return d;
  }

 private:
  TrajectorySettings settings_{};
  Eigen::Index dof_ = size_of(N, 2);
  JointVector<N> offset_ = JointVector<N>::Zero(size_of(N, 2));
};
using Trajectory = TrajectoryT<2>;

}  // namespace adparm
