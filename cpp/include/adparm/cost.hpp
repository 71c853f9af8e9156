// Quadratic cost of eqs. (10)-(11): r(x, u) = x^T Q x + u^T R u, with Q > 0 and R > 0 symmetric.
#pragma once

#include <Eigen/Cholesky>
#include <string>

#include "adparm/types.hpp"

namespace adparm {

// Throws std::invalid_argument unless the finite matrix is symmetric (to 1e-12, relative) and
// positive definite (it has a Cholesky factor), both judged on matrix / max|entry| so that no
// square overflows. Python's config applies the same test.
template <int N>
void check_symmetric_positive_definite(const Eigen::Matrix<double, N, N>& matrix,
                                       const char* name) {
  const double scale = matrix.cwiseAbs().maxCoeff();
  const Eigen::Matrix<double, N, N> scaled = matrix / scale;  // scale 0: refused below
  if (scale > 0.0 && !scaled.isApprox(scaled.transpose(), 1e-12))
    throw std::invalid_argument(std::string(name) + ": must be symmetric");
  if (!(scale > 0.0) || Eigen::LLT<Eigen::Matrix<double, N, N>>(scaled).info() != Eigen::Success)
    throw std::invalid_argument(std::string(name) + ": must be positive definite");
}

class QuadraticCost {
 public:
  QuadraticCost() = default;
  QuadraticCost(const Mat4& Q, const Mat2& R) : Q_(Q), R_(R) {
    check_finite(Q, "cost.Q");
    check_finite(R, "cost.R");
    check_symmetric_positive_definite(Q, "cost.Q");
    check_symmetric_positive_definite(R, "cost.R");
    R_inverse_ = Eigen::LLT<Mat2>(R).solve(Mat2::Identity());
  }

  const Mat4& Q() const { return Q_; }
  const Mat2& R() const { return R_; }
  const Mat2& R_inverse() const { return R_inverse_; }

  double state_cost(const Vec4& x) const { return x.dot(Q_ * x); }
  double input_cost(const Vec2& u) const { return u.dot(R_ * u); }
  double operator()(const Vec4& x, const Vec2& u) const { return state_cost(x) + input_cost(u); }

 private:
  Mat4 Q_ = Mat4::Identity();
  Mat2 R_ = Mat2::Identity();
  Mat2 R_inverse_ = Mat2::Identity();
};

}  // namespace adparm
