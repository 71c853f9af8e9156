// Quadratic cost of eqs. (10)-(11): r(x, u) = x^T Q x + u^T R u, with Q > 0 and R > 0 symmetric.
#pragma once

#include <Eigen/Cholesky>
#include <string>

#include "adparm/types.hpp"

namespace adparm {

// Throws std::invalid_argument unless the finite matrix is symmetric (to 1e-12, relative) and
// positive definite (it has a Cholesky factor), both judged on matrix / max|entry| so that no
// square overflows. Python's config applies the same test.
template <class Derived>
void check_symmetric_positive_definite(const Eigen::MatrixBase<Derived>& matrix, const char* name) {
  using Plain = typename Derived::PlainObject;
  const double scale = matrix.cwiseAbs().maxCoeff();
  const Plain scaled = matrix / scale;  // scale 0: refused below
  if (scale > 0.0 && !scaled.isApprox(scaled.transpose(), 1e-12))
    throw std::invalid_argument(std::string(name) + ": must be symmetric");
  if (!(scale > 0.0) || Eigen::LLT<Plain>(scaled).info() != Eigen::Success)
    throw std::invalid_argument(std::string(name) + ": must be positive definite");
}

// Q is 2n x 2n, R is n x n (n joints; N = n or Dynamic).
template <int N = 2>
class QuadraticCostT {
 public:
  using StateWeight = ErrorMatrix<N>;
  using InputWeight = JointMatrix<N>;
  QuadraticCostT() = default;
  QuadraticCostT(const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R, Eigen::Index n) {
    check_size(Q, 2 * n, 2 * n, "cost.Q");
    check_size(R, n, n, "cost.R");
    check_finite(Q, "cost.Q");
    check_finite(R, "cost.R");
    Q_ = Q;
    R_ = R;
    check_symmetric_positive_definite(Q_, "cost.Q");
    check_symmetric_positive_definite(R_, "cost.R");
    R_inverse_ = Eigen::LLT<InputWeight>(R_).solve(InputWeight::Identity(n, n));
  }

  const StateWeight& Q() const { return Q_; }
  const InputWeight& R() const { return R_; }
  const InputWeight& R_inverse() const { return R_inverse_; }

  double state_cost(const ErrorVector<N>& x) const { return x.dot(Q_ * x); }
  double input_cost(const JointVector<N>& u) const { return u.dot(R_ * u); }
  double operator()(const ErrorVector<N>& x, const JointVector<N>& u) const {
    return state_cost(x) + input_cost(u);
  }

 private:
  StateWeight Q_ = StateWeight::Identity(size_of(twice(N), 4), size_of(twice(N), 4));
  InputWeight R_ = InputWeight::Identity(size_of(N, 2), size_of(N, 2));
  InputWeight R_inverse_ = InputWeight::Identity(size_of(N, 2), size_of(N, 2));
};
using QuadraticCost = QuadraticCostT<2>;

}  // namespace adparm
