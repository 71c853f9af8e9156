// Quadratic cost of eqs. (10)-(11): r(x, u) = x^T Q x + u^T R u, with Q >= 0 and R > 0 symmetric.
#pragma once

#include <Eigen/Cholesky>

#include "adparm/types.hpp"

namespace adparm {

class QuadraticCost {
 public:
  QuadraticCost() = default;
  QuadraticCost(const Mat4& Q, const Mat2& R) : Q_(Q), R_(R) {
    check_finite(Q, "cost.Q");
    check_finite(R, "cost.R");
    if (!Q.isApprox(Q.transpose(), 1e-12)) throw std::invalid_argument("cost.Q: must be symmetric");
    if (!R.isApprox(R.transpose(), 1e-12)) throw std::invalid_argument("cost.R: must be symmetric");
    Eigen::LLT<Mat2> chol(R);
    if (chol.info() != Eigen::Success)
      throw std::invalid_argument("cost.R: must be positive definite");
    R_inverse_ = chol.solve(Mat2::Identity());
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
