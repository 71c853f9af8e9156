// Eigen types shared by the core and the argument checks used at its entry points.
//
// Sizes: the joint count n and the basis size K are template parameters of the loop. The two-link
// arm with its 8-function bases is the fixed-size fast path (n = 2, K = 8: Vec2, Mat2, ...). Any
// other size is Eigen::Dynamic, and then every vector and matrix the loop handles per step is a
// *bounded* dynamic type: Eigen::Matrix<double, Dynamic, ..., MaxRows, MaxCols> keeps its
// coefficients inline (no heap) up to kMaxDof joints and kMaxBasisSize basis functions, so a step
// does no heap allocation however the expressions are written. The loop's state vector (with the
// covariance Gamma, K^2 entries) is an ordinary VectorXd, sized once per run.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace adparm {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;
using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;
using Mat42 = Eigen::Matrix<double, 4, 2>;
constexpr int Dynamic = Eigen::Dynamic;

// The most joints and basis functions of a dynamic-size run (bounded storage, see above).
constexpr int kMaxDof = 12;
constexpr int kMaxBasisSize = 128;

// Size arithmetic that keeps Dynamic dynamic.
constexpr int twice(int n) { return n == Dynamic ? Dynamic : 2 * n; }
constexpr int bound(int n, int max) { return n == Dynamic ? max : n; }

template <int Rows, int Cols, int MaxRows, int MaxCols>
using BoundedMatrix =
    Eigen::Matrix<double, Rows, Cols, (Rows == 1 && Cols != 1) ? Eigen::RowMajor : Eigen::ColMajor,
                  bound(Rows, MaxRows), bound(Cols, MaxCols)>;

// n (joint), 2n (error state x = [e1; e2]) and K (basis) sized types; for fixed sizes these are
// exactly Vec2, Mat2, Vec4, Mat4, Eigen::Matrix<double, 8, 1>, ...
template <int N>
using JointVector = BoundedMatrix<N, 1, kMaxDof, 1>;
template <int N>
using JointMatrix = BoundedMatrix<N, N, kMaxDof, kMaxDof>;
template <int N>
using ErrorVector = BoundedMatrix<twice(N), 1, 2 * kMaxDof, 1>;
template <int N>
using ErrorMatrix = BoundedMatrix<twice(N), twice(N), 2 * kMaxDof, 2 * kMaxDof>;
template <int K>
using BasisVector = BoundedMatrix<K, 1, kMaxBasisSize, 1>;
template <int K, int Cols>
using BasisMatrix = BoundedMatrix<K, Cols, kMaxBasisSize, 2 * kMaxDof>;

// The size of a fixed or dynamic dimension: the compile-time value, or `runtime`.
constexpr Eigen::Index size_of(int compile_time, Eigen::Index runtime) {
  return compile_time == Dynamic ? runtime : compile_time;
}

// A joint-sized (or error-sized) matrix times a vector, a x, coefficient by coefficient
// (lazyProduct: each entry's sum over the columns in order, as Eigen's matrix-vector kernel sums
// it - the same runs bit for bit, checked on the portable and dispatched paths - without the
// kernel's call, which costs more than a 3 x 3 product). Fixed sizes too: in an expression such
// as (dqd - dq) + alpha1 e1, Eigen's product would be assigned apart (a = b; a += alpha1 e1, a
// function call of its own); the lazy product is one coefficient-wise pass with the same sums.
template <class Matrix, class Vector>
auto small_product(const Matrix& a, const Vector& x) {
  return a.lazyProduct(x);
}

// Throws std::invalid_argument unless 1 <= n <= kMaxDof (a dynamic joint count) and 1 <= k <=
// kMaxBasisSize.
inline void check_dimensions(Eigen::Index n, Eigen::Index k) {
  if (n < 1 || n > kMaxDof)
    throw std::invalid_argument("plant: the arm has " + std::to_string(n) +
                                " joints; the core supports 1 to " + std::to_string(kMaxDof));
  if (k < 1 || k > kMaxBasisSize)
    throw std::invalid_argument("controller.basis: " + std::to_string(k) +
                                " functions; the core supports 1 to " +
                                std::to_string(kMaxBasisSize));
}

// The desired joint state at one time: qd, dqd, ddqd (trajectory.hpp).
template <int N>
struct DesiredStateT {
  JointVector<N> q = JointVector<N>::Zero(size_of(N, 0));
  JointVector<N> dq = JointVector<N>::Zero(size_of(N, 0));
  JointVector<N> ddq = JointVector<N>::Zero(size_of(N, 0));
  DesiredStateT() = default;
  explicit DesiredStateT(Eigen::Index n)
      : q(JointVector<N>::Zero(n)), dq(JointVector<N>::Zero(n)), ddq(JointVector<N>::Zero(n)) {}
};
using DesiredState = DesiredStateT<2>;

// Throws std::invalid_argument (ValueError in Python) naming the argument whose size is wrong.
template <class Derived>
void check_size(const Eigen::DenseBase<Derived>& value, Eigen::Index rows, Eigen::Index cols,
                const char* name) {
  if (value.rows() != rows || value.cols() != cols) {
    std::ostringstream message;
    message << name << ": expected shape (" << rows << ", " << cols << "), got (" << value.rows()
            << ", " << value.cols() << ")";
    throw std::invalid_argument(message.str());
  }
}

// Throws std::invalid_argument naming the argument that holds a NaN or an infinity.
template <class Derived>
void check_finite(const Eigen::DenseBase<Derived>& value, const char* name) {
  if (!value.allFinite()) throw std::invalid_argument(std::string(name) + ": must be finite");
}

inline void check_finite(double value, const char* name) {
  if (!std::isfinite(value)) throw std::invalid_argument(std::string(name) + ": must be finite");
}

inline void check_positive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw std::invalid_argument(std::string(name) + ": must be a finite number > 0");
}

inline void check_non_negative(double value, const char* name) {
  if (!(value >= 0.0) || !std::isfinite(value))
    throw std::invalid_argument(std::string(name) + ": must be a finite number >= 0");
}

// sgn with sgn(0) = 0, applied elementwise (eq. 28 and the Coulomb friction).
inline Vec2 sign(const Vec2& v) {
  return Vec2((v[0] > 0.0) - (v[0] < 0.0), (v[1] > 0.0) - (v[1] < 0.0));
}
template <class Derived>
typename Derived::PlainObject sign(const Eigen::MatrixBase<Derived>& v) {
  return v.unaryExpr([](double a) { return static_cast<double>((a > 0.0) - (a < 0.0)); });
}

}  // namespace adparm
