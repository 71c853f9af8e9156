// Bellman-error extrapolation: the model f, g is known, so the HJB error of eq. (21) can be
// evaluated at N extra states x_i as well as along the trajectory. The critic and actor laws
// (eqs. 23, 24, 26) then gain the average of their terms over the points,
//   dWc    = -eta_c Gamma [omega eps / rho + (1/N) sum_i omega_i eps_i / rho_i]
//   dGamma = -eta_c Gamma [omega omega^T / rho + (1/N) sum_i omega_i omega_i^T / rho_i] Gamma
//   dWa    = proj{-eta_a1 [B R^-1 B^T (Wa - Wc) eps / sqrt(1 + omega^T omega) + (1/N) sum_i ...]
//                 - eta_a2 (Wa - Wc)}
// which is what lets the critic converge without a probing signal (model-based learning for
// approximate optimal regulation). The points, in x = [e1; e2], are
//   fixed  N points drawn once, uniform in the box centre + [-box, box]
//   grid   a regular grid of m points per axis over the box (N = m^4)
//   local  N points drawn at the start of every step, uniform in x(t_k) + centre + [-box, box]
// (`centre`, 0 by default, moves the box off x = 0: a URDF arm's derived box spans each joint's
// range within its limits, which is not symmetric about qd.)
// and each is evaluated with the current desired state (qd, dqd). Draws use MT19937 seeded with
// `seed`, in the order of NumPy's legacy RandomState(seed).random_sample((N, 2n)), each mapped to
// centre + box * (2 u - 1); so the points are reproducible, also from Python. (n joints: x has 2n
// entries, the grid has m^(2n) points.) For a constant desired state the weight-free part of each
// point (HjbPoint) is computed when the points are drawn, not at every evaluation.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "adparm/hjb.hpp"

namespace adparm {

enum class ExtrapolationMode { fixed, grid, local };

struct ExtrapolationSettings {
  long points = 0;                                 // N; 0 turns extrapolation off
  Eigen::VectorXd box = Eigen::VectorXd::Ones(4);  // half-widths in x = [e1; e2], 2n
  Eigen::VectorXd centre;                          // the box's centre in x, 2n (empty: 0)
  ExtrapolationMode mode = ExtrapolationMode::fixed;
  std::uint32_t seed = 0;
};

// Uniform numbers in [0, 1) from MT19937, as NumPy's RandomState.random_sample draws them.
class UniformDraws {
 public:
  explicit UniformDraws(std::uint32_t seed = 0) : generator_(seed) {}
  double operator()() {
    const double a = static_cast<double>(generator_() >> 5);
    const double b = static_cast<double>(generator_() >> 6);
    return (a * 67108864.0 + b) / 9007199254740992.0;
  }

 private:
  std::mt19937 generator_;
};

// The points of a moving desired state (or of local points), prepared at one desired state:
// ClosedLoop's Data owns them. RK4's second and third stages share their time, and the fourth
// the next step's first: prepared again only when the desired state (bit for bit) or the points
// (Extrapolation::generation) change, so the numbers are those of preparing at every evaluation.
// Sized on the first preparation (allocates once).
template <class Basis, int Dof>
struct MovingPoints {
  std::vector<HjbPoint<Basis, Dof>, Eigen::aligned_allocator<HjbPoint<Basis, Dof>>> points;
  DesiredStateT<Dof> desired;
  std::int64_t generation = -1;  // none prepared yet

  bool holds(const DesiredStateT<Dof>& other, std::uint32_t current) const {
    return generation == static_cast<std::int64_t>(current) && desired.q.size() == other.q.size() &&
           (desired.q.array() == other.q.array()).all() &&
           (desired.dq.array() == other.dq.array()).all() &&
           (desired.ddq.array() == other.ddq.array()).all();
  }
};

template <class Arm, class Basis>
class Extrapolation {
 public:
  static constexpr int kDof = Arm::kDof;
  using Point = HjbPoint<Basis, kDof>;
  using Evaluation = HjbEvaluation<Basis, kDof>;
  using Error = ErrorVector<kDof>;
  using Desired = DesiredStateT<kDof>;
  using Points = std::vector<Error, Eigen::aligned_allocator<Error>>;

  Extrapolation() = default;
  // `constant_desired`: the desired state never changes, so points can be prepared once. `model`:
  // the believed arm (its joint count sizes the points).
  Extrapolation(const ExtrapolationSettings& settings, bool constant_desired, const Arm& model)
      : settings_(settings), draws_(settings.seed), constant_desired_(constant_desired) {
    const Eigen::Index dim = 2 * Eigen::Index(model.dof());
    if (settings.points < 0) throw std::invalid_argument("extrapolation.points: must be >= 0");
    if (settings.points > 1000000)  // Python's MAX_POINTS
      throw std::invalid_argument("extrapolation.points: must be <= 1000000");
    check_size(settings.box, dim, 1, "extrapolation.box");
    check_finite(settings.box, "extrapolation.box");
    if (!(settings.box.array() > 0.0).all())
      throw std::invalid_argument("extrapolation.box: half-widths must be > 0");
    box_ = settings.box;
    if (settings.centre.size() == 0) {
      centre_ = Error::Zero(dim);
    } else {
      check_size(settings.centre, dim, 1, "extrapolation.centre");
      check_finite(settings.centre, "extrapolation.centre");
      centre_ = settings.centre;
    }
    shifted_ = centre_;
    const long n = settings.points;
    points_.assign(n, Error::Zero(dim));
    prepared_.resize(n);
    if (settings.mode == ExtrapolationMode::grid) {
      const long m = std::lround(std::pow(static_cast<double>(n), 1.0 / static_cast<double>(dim)));
      long total = 1;
      for (Eigen::Index axis = 0; axis < dim; ++axis) {
        total *= m;  // m^dim, or stops above N (no overflow)
        if (total > n) break;
      }
      if (total != n)
        throw std::invalid_argument("extrapolation.points: grid mode needs N = m^" +
                                    std::to_string(dim) + " points");
      for (long i = 0; i < n; ++i) {
        long rest = i;
        for (Eigen::Index axis = dim - 1; axis >= 0; --axis) {  // the last axis varies fastest
          const long k = rest % m;
          rest /= m;
          points_[i][axis] =
              centre_[axis] +
              (m == 1 ? 0.0 : box_[axis] * (2.0 * static_cast<double>(k) / (m - 1) - 1.0));
        }
      }
    } else if (settings.mode == ExtrapolationMode::fixed) {
      draw(centre_);
    }
  }

  long size() const { return settings_.points; }
  bool enabled() const { return settings_.points > 0; }
  // Whether begin_step() has work: local points to draw, or fixed points not yet prepared for a
  // constant desired state.
  bool needs_begin_step() const {
    return enabled() &&
           (settings_.mode == ExtrapolationMode::local || (constant_desired_ && !prepared_valid_));
  }
  const Points& points() const { return points_; }
  // The believed model changed (online identification): prepared points are prepared again at
  // the next begin_step.
  void model_changed() {
    prepared_valid_ = false;
    ++generation_;
  }
  // Changes whenever the points or the believed model do (MovingPoints).
  std::uint32_t generation() const { return generation_; }

  // Start of a step at error state x: draws new local points; prepares points that are fixed for
  // the step when the desired state is constant. `terms`: a buffer of the model's terms at a point
  // (Arm::init_terms), and the basis' workspace (basis.hpp), the caller's.
  void begin_step(const Basis& basis, const ErrorSystem<Arm>& system,
                  const QuadraticCostT<kDof>& cost, const Error& x, const Desired& desired,
                  typename Arm::Terms& terms, BasisWorkspace<Basis>& workspace) {
    if (!needs_begin_step()) return;
    if (settings_.mode == ExtrapolationMode::local) {
      shifted_ = x + centre_;  // no allocation: sized at construction
      draw(shifted_);
      prepared_valid_ = false;
      ++generation_;
    }
    if (constant_desired_ && !prepared_valid_) {
      // dynamic sizes: the points also side by side (fixed or grid points, up to kMaxStacked)
      [[maybe_unused]] const bool stacks = settings_.mode != ExtrapolationMode::local &&
                                           basis.size() * desired.q.size() * size() <= kMaxStacked;
      [[maybe_unused]] bool pairs = false;
      if constexpr (kDof == Dynamic && HasPairs<Basis>::value) {
        pairs = stacks && !basis.pairs().empty();
        if (pairs) size_pairs(desired.q.size(), basis.size());
      }
      for (long i = 0; i < size(); ++i) {
        prepare_hjb_point(basis, system, cost, points_[i], desired, terms, prepared_[i], workspace);
        if constexpr (kDof == Dynamic)
          if (pairs) keep_pair_point(i, prepared_[i], terms.mass_inverse);
      }
      prepared_valid_ = true;
      if constexpr (kDof == Dynamic) {  // [B_1 ... B_N], once (allocates: first preparation only)
        const Eigen::Index n = desired.q.size(), k = basis.size();
        if (stacks) {
          stacked_input_gradients_.resize(k, n * size());
          stacked_drift_rates_.resize(k, size());
          stacked_state_costs_.resize(size());
          for (long i = 0; i < size(); ++i) {
            stacked_input_gradients_.middleCols(i * n, n) = prepared_[i].input_gradient;
            stacked_drift_rates_.col(i) = prepared_[i].drift_rate;
            stacked_state_costs_[i] = prepared_[i].state_cost;
          }
          transpose_stack(k, n * size());
          // the rows of [B_1 ... B_N] in [first, last] with a nonzero entry: the functions before
          // and after them have J_e2 = 0 at every point (e.g. a structured basis' e1 block)
          Eigen::Index first = k, last = -1;
          for (Eigen::Index r = 0; r < k; ++r)  // row r of B: the transpose's column r
            if ((stacked_transposed_column(r).array() != 0.0).any()) {
              first = std::min(first, r);
              last = r;
            }
          stacked_first_row_ = last < 0 ? 0 : first;
          stacked_row_count_ = last < 0 ? k : last - first + 1;
        }
      }
    }
  }

  // Dynamic sizes: whether the prepared points' B are also side by side in
  // stacked_input_gradients() (fixed or grid points of a constant desired state, up to
  // kMaxStacked coefficients), for ClosedLoop's stacked products.
  bool stacked() const { return prepared_valid_ && stacked_input_gradients_.size() > 0; }
  const Eigen::MatrixXd& stacked_input_gradients() const { return stacked_input_gradients_; }
  // The same points' [B_1 ... B_N]^T (nN x K, column-major: its column r at
  // stacked_transposed_data() + r * stacked_transposed_stride()), [F_1 ... F_N] (K x N: each
  // drift_rate) and [x_i^T Q x_i] (N), for ClosedLoop's batched products with the dense kernels.
  // The transpose's columns start on 64-byte boundaries (the stride a multiple of 8 doubles, the
  // first column aligned): its product's loads never straddle two cache lines (measured: the
  // product over 300 x 72 entries 2.8 -> 2.0 us). A copy of this object reads the same entries
  // (the offset is into its own copy of the buffer), aligned again from its next preparation.
  const double* stacked_transposed_data() const {
    return stacked_transposed_buffer_.data() + stacked_transposed_offset_;
  }
  Eigen::Index stacked_transposed_stride() const { return stacked_transposed_stride_; }
  const Eigen::MatrixXd& stacked_drift_rates() const { return stacked_drift_rates_; }
  // Rows [stacked_first_row(), + stacked_row_count()) of [B_1 ... B_N] hold every nonzero entry
  // (exact zeros outside, checked when the points are prepared): the batched products skip the
  // others.
  Eigen::Index stacked_first_row() const { return stacked_first_row_; }
  Eigen::Index stacked_row_count() const { return stacked_row_count_; }
  const Eigen::VectorXd& stacked_state_costs() const { return stacked_state_costs_; }
  const Point& prepared(long i) const { return prepared_[i]; }
  // A basis of pairs (basis.hpp, HasPairs) with stacked points: their x_i (2n), M_i^-1 (n^2, entry
  // r + c n), F_i (K) and x_i^T Q x_i, each entry's values over the points side by side (entry v
  // of point i at [v * pair_stride() + i]; the stride a multiple of 8, zeros after the last point)
  // for the dense kernels' pair_points (dense_kernels.hpp: PairPoints).
  bool pairs_stacked() const { return stacked() && pair_stride_ > 0; }
  // The stride of N points: N + 1 rounded up to a multiple of 8 (AVX-512's width), a lane left
  // for the trajectory's sample (ClosedLoop::learn_from_pairs).
  static Eigen::Index pair_stride_for(long points) { return (points + 8) / 8 * 8; }
  Eigen::Index pair_stride() const { return pair_stride_; }
  const Eigen::MatrixXd& pair_states() const { return pair_states_; }
  const Eigen::MatrixXd& pair_mass_inverses() const { return pair_mass_inverses_; }
  const Eigen::MatrixXd& pair_drift_rates() const { return pair_drift_rates_; }
  const Eigen::VectorXd& pair_state_costs() const { return pair_state_costs_; }
  static constexpr Eigen::Index kMaxStacked = Eigen::Index(1) << 22;  // 32 MB

  // Calls f(point, evaluation, 1/N) for each point, with the weights Wc, Wa and desired state
  // (`terms`, `workspace` as for begin_step); points not prepared for the step (a moving desired
  // state, local points) come from `moving`, prepared there when it does not hold them.
  template <class F>
  void for_each(const Basis& basis, const ErrorSystem<Arm>& system,
                const QuadraticCostT<kDof>& cost, const Desired& desired,
                const typename Basis::Vector& critic_weights,
                const typename Basis::Vector& actor_weights, typename Arm::Terms& terms,
                BasisWorkspace<Basis>& workspace,
                [[maybe_unused]] MovingPoints<Basis, kDof>* moving, F&& f) const {
    if (!enabled()) return;
    const double weight = 1.0 / static_cast<double>(size());
    if constexpr (kDof == Dynamic) {  // the fixed-size loops keep preparing at each evaluation
      const Point* prepared =
          prepared_valid_ ? prepared_.data()
                          : moving_points(basis, system, cost, desired, terms, workspace, *moving);
      Evaluation evaluation;
      for (long i = 0; i < size(); ++i) {
        evaluate_hjb(prepared[i], cost, critic_weights, actor_weights, evaluation);
        f(prepared[i], evaluation, weight);
      }
    } else {
      Point fresh;
      Evaluation evaluation;
      for (long i = 0; i < size(); ++i) {
        const Point* point = &prepared_[i];
        if (!prepared_valid_) {
          prepare_hjb_point(basis, system, cost, points_[i], desired, terms, fresh, workspace);
          point = &fresh;
        }
        evaluate_hjb(*point, cost, critic_weights, actor_weights, evaluation);
        f(*point, evaluation, weight);
      }
    }
  }

 private:
  // The points of `moving`, prepared at `desired` unless it holds them.
  const Point* moving_points(const Basis& basis, const ErrorSystem<Arm>& system,
                             const QuadraticCostT<kDof>& cost, const Desired& desired,
                             typename Arm::Terms& terms, BasisWorkspace<Basis>& workspace,
                             MovingPoints<Basis, kDof>& moving) const {
    if (!moving.holds(desired, generation_)) {
      moving.points.resize(static_cast<std::size_t>(size()));
      for (long i = 0; i < size(); ++i)
        prepare_hjb_point(basis, system, cost, points_[i], desired, terms, moving.points[i],
                          workspace);
      moving.desired = desired;
      moving.generation = static_cast<std::int64_t>(generation_);
    }
    return moving.points.data();
  }

  void draw(const Error& centre) {
    for (Error& point : points_)
      for (Eigen::Index axis = 0; axis < point.size(); ++axis)
        point[axis] = centre[axis] + box_[axis] * (2.0 * draws_() - 1.0);
  }

  ExtrapolationSettings settings_{};
  Error box_;
  Error centre_;
  Error shifted_;  // x(t_k) + centre (local mode)
  UniformDraws draws_;
  bool constant_desired_ = true;
  bool prepared_valid_ = false;
  std::uint32_t generation_ = 0;  // model_changed() and local draws (in the bools' padding)
  Points points_;
  std::vector<Point, Eigen::aligned_allocator<Point>> prepared_;
  Eigen::MatrixXd stacked_input_gradients_;    // K x nN, [B_1 ... B_N] (stacked())
  Eigen::VectorXd stacked_transposed_buffer_;  // nN x K, its transpose,
  Eigen::Index stacked_transposed_offset_ = 0, stacked_transposed_stride_ = 0;  // aligned

  // The transpose of the stacked [B_1 ... B_N] (rows x columns) into its aligned buffer.
  void transpose_stack(Eigen::Index rows, Eigen::Index columns) {
    const Eigen::Index stride = (columns + 7) / 8 * 8;
    if (stacked_transposed_buffer_.size() != stride * rows + 8)  // sized once (no allocation after)
      stacked_transposed_buffer_.setZero(stride * rows + 8);
    const auto address = reinterpret_cast<std::uintptr_t>(stacked_transposed_buffer_.data());
    stacked_transposed_offset_ = static_cast<Eigen::Index>((64 - address % 64) % 64 / 8);
    stacked_transposed_stride_ = stride;
    Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>> transposed(
        stacked_transposed_buffer_.data() + stacked_transposed_offset_, columns, rows,
        Eigen::OuterStride<>(stride));
    transposed = stacked_input_gradients_.transpose();
  }
  auto stacked_transposed_column(Eigen::Index r) const {
    return Eigen::Map<const Eigen::VectorXd>(
        stacked_transposed_data() + r * stacked_transposed_stride_,
        stacked_input_gradients_.cols());
  }
  // pairs_stacked()'s arrays: stride x 2n, stride x n^2, stride x K, stride (column-major, so
  // that entry v over the points is column v); sized once (no allocation after).
  void size_pairs(Eigen::Index n, Eigen::Index k) {
    pair_stride_ = pair_stride_for(size());
    if (pair_states_.rows() != pair_stride_) {
      pair_states_.setZero(pair_stride_, 2 * n);
      pair_mass_inverses_.setZero(pair_stride_, n * n);
      pair_drift_rates_.setZero(pair_stride_, k);
      pair_state_costs_.setZero(pair_stride_);
    }
  }
  template <class MassInverse>
  void keep_pair_point(long i, const Point& point, const MassInverse& mass_inverse) {
    const Eigen::Index n = mass_inverse.rows();
    pair_states_.row(i) = points_[i].transpose();
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index r = 0; r < n; ++r) pair_mass_inverses_(i, r + c * n) = mass_inverse(r, c);
    pair_drift_rates_.row(i) = point.drift_rate.transpose();
    pair_state_costs_[i] = point.state_cost;
  }
  Eigen::Index pair_stride_ = 0;
  Eigen::MatrixXd pair_states_, pair_mass_inverses_, pair_drift_rates_;
  Eigen::VectorXd pair_state_costs_;
  Eigen::MatrixXd stacked_drift_rates_;                         // K x N, [F_1 ... F_N]
  Eigen::VectorXd stacked_state_costs_;                         // N, x_i^T Q x_i
  Eigen::Index stacked_first_row_ = 0, stacked_row_count_ = 0;  // the rows with nonzero entries
};

}  // namespace adparm
