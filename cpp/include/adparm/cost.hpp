// Quadratic cost of eqs. (10)-(11): r(x, u) = x^T Q x + u^T R u, with Q > 0 and R > 0 symmetric;
// with an input bound (cost.input_bound), u^T R u becomes the constrained-input cost U(u) and, with
// e2_cost = logcosh, the e2 block of x^T Q x its ln cosh form (input_bound.hpp).
#pragma once

#include <Eigen/Cholesky>
#include <string>

#include "adparm/input_bound.hpp"
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
  // `input_bound`: lambda (n entries, or empty: no bound); `e2_cost`: logcosh needs a bound.
  QuadraticCostT(const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R, Eigen::Index n,
                 const Eigen::VectorXd& input_bound = Eigen::VectorXd(),
                 E2Cost e2_cost = E2Cost::quadratic) {
    check_size(Q, 2 * n, 2 * n, "cost.Q");
    check_size(R, n, n, "cost.R");
    check_finite(Q, "cost.Q");
    check_finite(R, "cost.R");
    Q_ = Q;
    R_ = R;
    check_symmetric_positive_definite(Q_, "cost.Q");
    check_symmetric_positive_definite(R_, "cost.R");
    R_inverse_ = Eigen::LLT<InputWeight>(R_).solve(InputWeight::Identity(n, n));
    bound_ = InputBoundT<N>(input_bound, e2_cost, Q, R, n);
  }

  const StateWeight& Q() const { return Q_; }
  const InputWeight& R() const { return R_; }
  const InputWeight& R_inverse() const { return R_inverse_; }
  const InputBoundT<N>& bound() const { return bound_; }
  bool bounded() const { return bound_.bounded(); }

  double state_cost(const ErrorVector<N>& x) const {
    if (!bound_.logcosh()) return x.dot(small_product(Q_, x));
    // e1^T Q11 e1 + 2 e1^T Q12 e2 + the ln cosh e2 term (input_bound.hpp)
    const Eigen::Index n = x.size() / 2;
    const auto e1 = x.template segment<N>(0, n);
    const auto e2 = x.template segment<N>(n, n);
    const JointVector<N> Q1_x = Q_.template topLeftCorner<N, N>(n, n) * e1 +
                                2.0 * (Q_.template topRightCorner<N, N>(n, n) * e2);
    return e1.dot(Q1_x) + bound_.e2_cost(e2);
  }
  // u^T R u, or U(u) with an input bound. Dynamic sizes: R u coefficient-based (lazyProduct), no
  // call of Eigen's matrix-vector kernel (once per extrapolation point); fixed sizes as before.
  double input_cost(const JointVector<N>& u) const {
    if (bound_.bounded()) return bound_.input_cost(u);
    if constexpr (N == Dynamic) return u.dot(R_.lazyProduct(u));
    return u.dot(R_ * u);
  }
  double operator()(const ErrorVector<N>& x, const JointVector<N>& u) const {
    return state_cost(x) + input_cost(u);
  }

 private:
  StateWeight Q_ = StateWeight::Identity(size_of(twice(N), 4), size_of(twice(N), 4));
  InputWeight R_ = InputWeight::Identity(size_of(N, 2), size_of(N, 2));
  InputWeight R_inverse_ = InputWeight::Identity(size_of(N, 2), size_of(N, 2));
  InputBoundT<N> bound_{};
};
using QuadraticCost = QuadraticCostT<2>;

}  // namespace adparm
