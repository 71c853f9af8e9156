// Fixed-size Eigen types shared by the core and the argument checks used at its entry points.
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

// The desired joint state at one time: qd, dqd, ddqd (trajectory.hpp).
struct DesiredState {
  Vec2 q = Vec2::Zero();
  Vec2 dq = Vec2::Zero();
  Vec2 ddq = Vec2::Zero();
};

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

}  // namespace adparm
