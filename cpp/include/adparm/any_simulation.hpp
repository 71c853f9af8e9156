// The one table of the loops a run can take (arm x basis), and the building of a loop from its
// Settings. Every choice of loop goes through visit_loop: AnySimulation (hence Batch) and the
// binding's functions of a loop (adparm._core). A new arm or basis is its own header, one line in
// Loops and one branch in visit_loop (and, if it is built from settings, in make_loop's helpers).
//
//   arm (settings)   basis (settings.basis)         loop: ClosedLoop<Arm, Basis> with Arm, Basis
//   arm: TwoLinkArms paper, augmented, structured   TwoLinkArm, the basis (fixed sizes)
//                    the same, dynamic_sizes        DynamicArm<TwoLinkArm>, DynamicBasis<the basis>
//                    expression                     DynamicArm<TwoLinkArm>, ExpressionLoopBasis
//   arm: UrdfArms    expression                     UrdfLoopArm, ExpressionLoopBasis
//                    structured                     UrdfLoopArm, PinocchioStructuredBasis
//                    paper, augmented               refused (kUrdfBasisRefusal)
#pragma once

#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "adparm/arm_model.hpp"
#include "adparm/basis.hpp"
#include "adparm/closed_loop.hpp"
#include "adparm/dynamic_size.hpp"
#include "adparm/expression_basis.hpp"
#include "adparm/pinocchio_structured_basis.hpp"
#include "adparm/settings.hpp"
#include "adparm/simulation.hpp"
#include "adparm/urdf_loop_arm.hpp"

namespace adparm {

// A loop type as a value: visit_loop calls its f with LoopType<Loop>{}; f reads the type as
// typename decltype(loop_type)::type.
template <class Loop>
struct LoopType {
  using type = Loop;
};

template <class... Loop>
struct LoopList {
  template <class L>
  static constexpr bool contains = (std::is_same_v<L, Loop> || ...);
  using Simulations = std::variant<Simulation<typename Loop::ArmType, typename Loop::BasisType>...>;
};

// Every loop a run can take.
using Loops = LoopList<ClosedLoop<TwoLinkArm, PaperBasis>, ClosedLoop<TwoLinkArm, AugmentedBasis>,
                       ClosedLoop<TwoLinkArm, StructuredBasis>,
                       ClosedLoop<DynamicArm<TwoLinkArm>, DynamicBasis<PaperBasis>>,
                       ClosedLoop<DynamicArm<TwoLinkArm>, DynamicBasis<AugmentedBasis>>,
                       ClosedLoop<DynamicArm<TwoLinkArm>, DynamicBasis<StructuredBasis>>,
                       ClosedLoop<DynamicArm<TwoLinkArm>, ExpressionLoopBasis>,
                       ClosedLoop<UrdfLoopArm, ExpressionLoopBasis>,
                       ClosedLoop<UrdfLoopArm, PinocchioStructuredBasis>>;

inline constexpr const char* kUrdfBasisRefusal =
    "controller.basis: the paper and augmented bases are the two-link arm's; a URDF arm "
    "(plant.urdf) takes the structured basis or an expression basis (quadratic, polynomial, "
    "terms)";

// Calls f(LoopType<Loop>{}) for the loop of the settings and returns what f returns (the same
// type for every loop).
template <class F>
decltype(auto) visit_loop(const Settings& settings, F&& f) {
  const auto call = [&f](auto loop_type) -> decltype(auto) {
    static_assert(Loops::contains<typename decltype(loop_type)::type>, "a loop not in Loops");
    return f(loop_type);
  };
  if (std::holds_alternative<UrdfArms>(settings.arm)) {
    if (settings.basis == BasisKind::structured)
      return call(LoopType<ClosedLoop<UrdfLoopArm, PinocchioStructuredBasis>>{});
    if (settings.basis != BasisKind::expression) throw std::invalid_argument(kUrdfBasisRefusal);
    return call(LoopType<ClosedLoop<UrdfLoopArm, ExpressionLoopBasis>>{});
  }
  if (settings.basis == BasisKind::expression)  // dynamic sizes only
    return call(LoopType<ClosedLoop<DynamicArm<TwoLinkArm>, ExpressionLoopBasis>>{});
  return with_basis(settings.basis, [&](auto basis) -> decltype(auto) {
    using Basis = decltype(basis);
    if (settings.dynamic_sizes)
      return call(LoopType<ClosedLoop<DynamicArm<TwoLinkArm>, DynamicBasis<Basis>>>{});
    return call(LoopType<ClosedLoop<TwoLinkArm, Basis>>{});
  });
}

// Building a loop from Settings ----------------------------------------------------------------

// The plant and the model a loop believes, built from the settings; model_is_plant: the same arm
// (the loop then computes its terms once per evaluation).
template <class Arm>
struct LoopArms {
  Arm plant;
  Arm model;
  bool model_is_plant;
};

// The arms of the settings' alternative (visit_loop picks a loop of that arm).
template <class Alternative>
const Alternative& arm_settings(const Settings& settings) {
  const Alternative* arms = std::get_if<Alternative>(&settings.arm);
  if (arms == nullptr)
    throw std::invalid_argument("plant: the loop's arm is not the arm of the settings");
  return *arms;
}

// A two-link arm (TwoLinkArm, or DynamicArm of it) from the two-link parameters.
template <class Arm>
LoopArms<Arm> loop_arms(const Settings& settings, UrdfArmCache& /*urdfs: unused*/) {
  const TwoLinkArms& arms = arm_settings<TwoLinkArms>(settings);
  return {Arm(arms.plant, "plant"), Arm(arms.model, "model"), arms.plant == arms.model};
}

// A URDF arm: the plant of its plant settings; the model of its model settings, or the plant when
// the model's path is empty (or the model is the plant). Read through `urdfs`: a model of the
// plant's file shares the plant's parsed model.
template <>
inline LoopArms<UrdfLoopArm> loop_arms<UrdfLoopArm>(const Settings& settings, UrdfArmCache& urdfs) {
  const UrdfArms& arms = arm_settings<UrdfArms>(settings);
  UrdfLoopArm plant = urdfs.arm(arms.plant, "plant.urdf");
  if (arms.model.urdf.empty() || arms.model == arms.plant) return {plant, plant, true};
  UrdfLoopArm model = urdfs.arm(arms.model, "model.urdf");
  if (model.dof() != plant.dof())
    throw std::invalid_argument("model.urdf: the model has " + std::to_string(model.dof()) +
                                " joints, the plant (plant.urdf) " + std::to_string(plant.dof()));
  return {std::move(plant), std::move(model), false};
}

// The basis a loop builds from its settings for the believed model: a fixed basis has nothing to
// build; the expression basis compiles settings.basis_program for the arm's n joints; the
// structured basis of a URDF run is the believed model's (its base parameters are those the
// controller can know).
template <class Basis, class Arm>
Basis loop_basis(const Settings& settings, const Arm& model) {
  if constexpr (std::is_same_v<Basis, ExpressionLoopBasis>) {
    return ExpressionLoopBasis(model.dof(), settings.basis_program);
  } else if constexpr (std::is_same_v<Basis, PinocchioStructuredBasis>) {
    PinocchioStructuredBasis basis(model.arm());
    if (settings.actor.positive_e2)  // not in the paper: pinocchio_structured_basis.hpp
      basis.set_check_positions(model.arm(), settings.actor.e2_check_positions);
    return basis;
  } else {
    return Basis();
  }
}

// The loop of the settings (Loop: one of Loops), its URDF arms read through `urdfs` (a Batch's,
// shared by its runs).
template <class Loop>
Loop make_loop(const Settings& settings, UrdfArmCache& urdfs) {
  const LoopArms<typename Loop::ArmType> arms = loop_arms<typename Loop::ArmType>(settings, urdfs);
  return Loop(settings, arms.plant, arms.model, arms.model_is_plant,
              loop_basis<typename Loop::BasisType>(settings, arms.model));
}

// The same, reading its URDF files for itself (once each).
template <class Loop>
Loop make_loop(const Settings& settings) {
  UrdfArmCache urdfs;
  return make_loop<Loop>(settings, urdfs);
}

// A simulation of the loop of the settings, picked at run time.
class AnySimulation {
 public:
  explicit AnySimulation(const Settings& settings) : impl_(make(settings)) {}
  // The URDF arms read through `urdfs` (a Batch's, shared by its runs).
  AnySimulation(const Settings& settings, UrdfArmCache& urdfs) : impl_(make(settings, urdfs)) {}

  long advance(long max_steps, const RunControl& control = {}) {
    return std::visit([&](auto& s) { return s.advance(max_steps, control); }, impl_);
  }
  RunStatus status() const {
    return std::visit([](const auto& s) { return s.status(); }, impl_);
  }
  long steps() const {
    return std::visit([](const auto& s) { return s.steps(); }, impl_);
  }
  long step() const {
    return std::visit([](const auto& s) { return s.step(); }, impl_);
  }
  double divergence_time() const {
    return std::visit([](const auto& s) { return s.divergence_time(); }, impl_);
  }
  const std::vector<double>& reset_times() const {
    return std::visit([](const auto& s) -> const std::vector<double>& { return s.reset_times(); },
                      impl_);
  }
  Eigen::VectorXd saturated_time() const {
    return std::visit([](const auto& s) { return s.saturated_time(); }, impl_);
  }
  Eigen::VectorXd state() const {
    return std::visit([](const auto& s) { return Eigen::VectorXd(s.state()); }, impl_);
  }
  Recording recording() const {
    return std::visit([](const auto& s) { return s.recording(); }, impl_);
  }

 private:
  using Variant = Loops::Simulations;
  static Variant make(const Settings& settings) {
    UrdfArmCache urdfs;
    return make(settings, urdfs);
  }
  static Variant make(const Settings& settings, UrdfArmCache& urdfs) {
    return visit_loop(settings, [&](auto loop_type) {
      using Loop = typename decltype(loop_type)::type;
      using Sim = Simulation<typename Loop::ArmType, typename Loop::BasisType>;
      return Variant(std::in_place_type<Sim>, make_loop<Loop>(settings, urdfs), settings.sim);
    });
  }
  Variant impl_;
};

}  // namespace adparm
