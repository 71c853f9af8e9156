// The critic/actor basis phi(x) and its Jacobian (eq. 19), for the paper's 8 functions in the
// ERRATA's ordering:
//   phi(x) = [x1^2, x2^2, x1 x2, x3^2, x3^2 cos x2, x4^2, x3 x4, x3 x4 cos x2]
// (cos x2 = cos q2 because qd = 0). Its exact weights for V* = x^T blockdiag(K, M) x are
//   W* = [K11, K22, 2 K12, p1, 2 p3, p2, 2 p2, 2 p3]   (paper: [4, 6, -8, 5, 2, 1, 2, 2]).
// Another basis offers kSize, kStateDim, Vector, Jacobian and evaluate(); the loop takes it
// unchanged.
#pragma once

#include <cmath>

#include "adparm/types.hpp"

namespace adparm {

struct PaperBasis {
  static constexpr int kSize = 8;
  static constexpr int kStateDim = 4;
  using Vector = Eigen::Matrix<double, kSize, 1>;
  using Jacobian = Eigen::Matrix<double, kSize, kStateDim>;  // d phi / d x

  static void evaluate(const Vec4& x, Vector& phi, Jacobian& jacobian) {
    const double x1 = x[0], x2 = x[1], x3 = x[2], x4 = x[3];
    const double c = std::cos(x2);
    const double s = std::sin(x2);
    phi << x1 * x1, x2 * x2, x1 * x2, x3 * x3, x3 * x3 * c, x4 * x4, x3 * x4, x3 * x4 * c;
    jacobian << 2.0 * x1, 0.0, 0.0, 0.0,       //
        0.0, 2.0 * x2, 0.0, 0.0,               //
        x2, x1, 0.0, 0.0,                      //
        0.0, 0.0, 2.0 * x3, 0.0,               //
        0.0, -x3 * x3 * s, 2.0 * x3 * c, 0.0,  //
        0.0, 0.0, 0.0, 2.0 * x4,               //
        0.0, 0.0, x4, x3,                      //
        0.0, -x3 * x4 * s, x4 * c, x3 * c;
  }
};

}  // namespace adparm
