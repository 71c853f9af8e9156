// The critic/actor bases phi and their Jacobians (eq. 19). A basis may depend on the desired joint
// position qd as well as on x = [e1; e2] (an augmented state [x; qd]); it then reports the part of
// d phi / dt that comes from qd moving, (d phi / d qd) dqd, which the HJB regressor omega needs.
// A basis offers kSize (K or Dynamic), kStateDim (2n or Dynamic), int size() const, Vector
// (BasisVector<kSize>), Jacobian (BasisMatrix<kSize, kStateDim>) and
//   evaluate(x, desired, phi, jacobian, desired_rate)
//   evaluate(x, desired, terms, phi, jacobian, desired_rate)
// and the loop takes it unchanged. The second form also receives the arm model's terms at the
// matching joint state (q = qd - e1), which the loop has computed anyway, so that a basis built
// on the arm (cos q2 of M(q)) need not evaluate them again. A basis that needs work buffers (the
// expression basis, a URDF arm's structured basis) declares Workspace and workspace() const, and
// takes the workspace as a last argument of the second form: evaluate_basis below, the loop's one
// call, passes it (the caller owns it: the loop's Data).
//
// PaperBasis: the paper's 8 functions in the ERRATA's ordering,
//   phi(x) = [x1^2, x2^2, x1 x2, x3^2, x3^2 cos x2, x4^2, x3 x4, x3 x4 cos x2]
// (cos x2 = cos q2 only when qd2 = 0). Its exact weights for V* = x^T blockdiag(K, M) x are
//   W* = [K11, K22, 2 K12, p1, 2 p3, p2, 2 p2, 2 p3]   (paper: [4, 6, -8, 5, 2, 1, 2, 2]).
//
// AugmentedBasis: the same functions over [x; qd] with cos x2 replaced by cos(qd2 - x2) = cos q2,
//   phi(x, qd) = [x1^2, x2^2, x1 x2, x3^2, x3^2 cos q2, x4^2, x3 x4, x3 x4 cos q2],
// so V*(x, qd) = e1^T K e1 + e2^T M(q) e2 is exact for any qd(t), constant or not, with the same
// W*. It equals PaperBasis when qd2 = 0 at all times (cos and sin of -x2 are exact).
#pragma once

#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "adparm/types.hpp"

namespace adparm {

// Sizes, types and the 8 functions shared by both bases; c is cos x2 or cos q2, dc_dx2 = d c / d
// x2.
struct QuadraticArmBasis {
  static constexpr int kSize = 8;
  static constexpr int kStateDim = 4;
  static constexpr int size() { return kSize; }
  using Vector = Eigen::Matrix<double, kSize, 1>;
  using Jacobian = Eigen::Matrix<double, kSize, kStateDim>;  // d phi / d x

 protected:
  static void functions(const Vec4& x, double c, double dc_dx2, Vector& phi, Jacobian& jacobian) {
    const double x1 = x[0], x2 = x[1], x3 = x[2], x4 = x[3];
    phi << x1 * x1, x2 * x2, x1 * x2, x3 * x3, x3 * x3 * c, x4 * x4, x3 * x4, x3 * x4 * c;
    jacobian << 2.0 * x1, 0.0, 0.0, 0.0,           //
        0.0, 2.0 * x2, 0.0, 0.0,                   //
        x2, x1, 0.0, 0.0,                          //
        0.0, 0.0, 2.0 * x3, 0.0,                   //
        0.0, x3 * x3 * dc_dx2, 2.0 * x3 * c, 0.0,  //
        0.0, 0.0, 0.0, 2.0 * x4,                   //
        0.0, 0.0, x4, x3,                          //
        0.0, x3 * x4 * dc_dx2, x4 * c, x3 * c;
  }
};

struct PaperBasis : QuadraticArmBasis {
  static void evaluate(const Vec4& x, const DesiredState&, Vector& phi, Jacobian& jacobian,
                       Vector& desired_rate) {
    functions(x, std::cos(x[1]), -std::sin(x[1]), phi, jacobian);
    desired_rate.setZero();
  }
  template <class Terms>
  static void evaluate(const Vec4& x, const DesiredState& desired, const Terms&, Vector& phi,
                       Jacobian& jacobian, Vector& desired_rate) {
    evaluate(x, desired, phi, jacobian, desired_rate);
  }
};

struct AugmentedBasis : QuadraticArmBasis {
  static void evaluate(const Vec4& x, const DesiredState& desired, Vector& phi, Jacobian& jacobian,
                       Vector& desired_rate) {
    const double q2 = desired.q[1] - x[1];
    evaluate(x, desired, std::cos(q2), std::sin(q2), phi, jacobian, desired_rate);
  }
  // With the two-link arm's terms at q = qd - e1: their cos q2 and sin q2.
  template <class Terms>
  static void evaluate(const Vec4& x, const DesiredState& desired, const Terms& terms, Vector& phi,
                       Jacobian& jacobian, Vector& desired_rate) {
    evaluate(x, desired, terms.cos_q2, terms.sin_q2, phi, jacobian, desired_rate);
  }

 private:
  static void evaluate(const Vec4& x, const DesiredState& desired, double cos_q2, double sin_q2,
                       Vector& phi, Jacobian& jacobian, Vector& desired_rate) {
    functions(x, cos_q2, sin_q2, phi, jacobian);  // d cos q2 / d x2 = sin q2
    // d phi / d qd2 = -d phi / d x2 for the two cos q2 functions
    desired_rate.setZero();
    desired_rate[4] = -x[2] * x[2] * sin_q2 * desired.dq[1];
    desired_rate[7] = -x[2] * x[3] * sin_q2 * desired.dq[1];
  }
};

// StructuredBasis (two-link arm): the e1 block of V* as monomials and the e2 block as the inertia
// parameters of M(q) = p1 M1 + p2 M2 + p3 M3 (M1 = [[1, 0], [0, 0]], M2 = [[0, 1], [1, 1]],
// M3 = [[2 c2, c2], [c2, 0]], c2 = cos q2, q = qd - e1):
//   phi(x, qd) = [x1^2, x1 x2, x2^2, e2^T M1 e2, e2^T M2 e2, e2^T M3(q) e2]
//              = [x1^2, x1 x2, x2^2, x3^2, 2 x3 x4 + x4^2, 2 c2 (x3^2 + x3 x4)],
// so V* = e1^T K e1 + e2^T M(q) e2 has W* = [K11, 2 K12, K22, p1, p2, p3] for any qd(t): the
// critic learns the arm's inertia parameters. d c2 / d x2 = sin q2 (q2 = qd2 - x2), and
// d phi / d qd2 = -d phi / d x2 for the last function.
struct StructuredBasis {
  static constexpr int kSize = 6;
  static constexpr int kStateDim = 4;
  static constexpr int size() { return kSize; }
  using Vector = Eigen::Matrix<double, kSize, 1>;
  using Jacobian = Eigen::Matrix<double, kSize, kStateDim>;

  static void evaluate(const Vec4& x, const DesiredState& desired, Vector& phi, Jacobian& jacobian,
                       Vector& desired_rate) {
    const double q2 = desired.q[1] - x[1];
    evaluate(x, desired, std::cos(q2), std::sin(q2), phi, jacobian, desired_rate);
  }
  // With the two-link arm's terms at q = qd - e1: their cos q2 and sin q2.
  template <class Terms>
  static void evaluate(const Vec4& x, const DesiredState& desired, const Terms& terms, Vector& phi,
                       Jacobian& jacobian, Vector& desired_rate) {
    evaluate(x, desired, terms.cos_q2, terms.sin_q2, phi, jacobian, desired_rate);
  }

 private:
  static void evaluate(const Vec4& x, const DesiredState& desired, double c, double s, Vector& phi,
                       Jacobian& jacobian, Vector& desired_rate) {
    const double x1 = x[0], x2 = x[1], x3 = x[2], x4 = x[3];
    const double quadratic = x3 * x3 + x3 * x4;  // e2^T M3 e2 / (2 c2)
    phi << x1 * x1, x1 * x2, x2 * x2, x3 * x3, 2.0 * x3 * x4 + x4 * x4, 2.0 * c * quadratic;
    jacobian << 2.0 * x1, 0.0, 0.0, 0.0,          //
        x2, x1, 0.0, 0.0,                         //
        0.0, 2.0 * x2, 0.0, 0.0,                  //
        0.0, 0.0, 2.0 * x3, 0.0,                  //
        0.0, 0.0, 2.0 * x4, 2.0 * x3 + 2.0 * x4,  //
        0.0, 2.0 * s * quadratic, 2.0 * c * (2.0 * x3 + x4), 2.0 * c * x3;
    desired_rate.setZero();
    desired_rate[5] = -2.0 * s * quadratic * desired.dq[1];
  }
};

// expression: a user-defined basis compiled from terms (expression_basis.hpp), carried in
// Settings::basis_program; it runs on the dynamic-size loop only (simulation.hpp).
// A basis' work buffers: its Workspace, or nothing for a basis without one.
template <class Basis, class = void>
struct BasisWorkspaceOf {
  struct type {};
  static type make(const Basis&) { return {}; }
};
template <class Basis>
struct BasisWorkspaceOf<Basis, std::void_t<typename Basis::Workspace>> {
  using type = typename Basis::Workspace;
  static type make(const Basis& basis) { return basis.workspace(); }
};
template <class Basis>
using BasisWorkspace = typename BasisWorkspaceOf<Basis>::type;
template <class Basis>
BasisWorkspace<Basis> basis_workspace(const Basis& basis) {
  return BasisWorkspaceOf<Basis>::make(basis);
}

// The basis seam's second form, with the basis' workspace if it has one.
template <class Basis, class X, class Desired, class Terms, class Vector, class Jacobian>
void evaluate_basis(const Basis& basis, const X& x, const Desired& desired, const Terms& terms,
                    Vector& phi, Jacobian& jacobian, Vector& desired_rate,
                    BasisWorkspace<Basis>& workspace) {
  if constexpr (std::is_empty_v<BasisWorkspace<Basis>>)
    basis.evaluate(x, desired, terms, phi, jacobian, desired_rate);
  else
    basis.evaluate(x, desired, terms, phi, jacobian, desired_rate, workspace);
}

// A basis of pairs (every function c_k x_a x_b of the error state: the quadratic family of the
// expression basis) may say so by a member pairs() (ExpressionBasis::Pairs: each function's row of
// d phi / d e2 as at most two terms); the loop's stacked extrapolation points then never form
// B_i = J_e2 M_i^-1 (ClosedLoop::learn_from_pairs). pairs() empty: not a basis of pairs.
template <class Basis, class = void>
struct HasPairs : std::false_type {};
template <class Basis>
struct HasPairs<Basis, std::void_t<decltype(std::declval<const Basis&>().pairs())>>
    : std::true_type {};

enum class BasisKind { paper, augmented, structured, expression };

// Calls f(Basis{}) with the basis type of `kind` (the binding and the bench pick a basis at run
// time; each basis is its own compiled loop). The expression basis is not a fixed type: callers
// handle it before (it throws here).
template <class F>
decltype(auto) with_basis(BasisKind kind, F&& f) {
  switch (kind) {
    case BasisKind::expression:
      throw std::invalid_argument("controller.basis: the expression basis has no fixed-size loop");
    case BasisKind::paper:
      return f(PaperBasis{});
    case BasisKind::structured:
      return f(StructuredBasis{});
    case BasisKind::augmented:
    default:
      return f(AugmentedBasis{});
  }
}

}  // namespace adparm
