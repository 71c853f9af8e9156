// adparm._core: the thin pybind11 binding of the C++ core. It only declares: one bind_<concept>(m)
// per concept, one Settings struct passed whole, sizes in docstrings. Argument checks live in the
// core (std::invalid_argument -> ValueError); the GIL is released around the simulation loop.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <type_traits>
#include <utility>
#include <variant>

#include "adparm/any_simulation.hpp"
#include "adparm/basis.hpp"
#include "adparm/batch.hpp"
#include "adparm/expression_basis.hpp"
#include "adparm/hjb.hpp"
#include "adparm/open_loop.hpp"
#include "adparm/pinocchio_arm.hpp"
#include "adparm/pinocchio_structured_basis.hpp"

namespace py = pybind11;
using namespace adparm;

namespace {

using RowsXX = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The module's URDF arms: every loop the module builds (Simulation, Batch, hjb_residual, ...)
// reads its URDF through this one cache, so a file is parsed once per version for a simulate,
// its diagnosis and the batches after it (urdf_loop_arm.hpp).
const std::shared_ptr<UrdfArmCache>& module_urdfs() {
  static const std::shared_ptr<UrdfArmCache> urdfs = std::make_shared<UrdfArmCache>();
  return urdfs;
}

// Settings::arm (a std::variant of the two-link arm's parameters and a URDF arm's settings) as
// the four attributes plant, model (two-link) and plant_urdf, model_urdf (URDF). A getter returns a
// copy (of the other alternative, a default one): a reference into the variant would dangle once
// plant_urdf changes the alternative, so an arm is changed by assigning it whole.
template <class Member, class Alternative>
py::object arm_member(py::handle self, Member Alternative::* member) {
  const Settings& settings = self.cast<const Settings&>();
  if (const Alternative* arms = std::get_if<Alternative>(&settings.arm))
    return py::cast(arms->*member);
  return py::cast(Member());
}

template <TwoLinkArmParameters TwoLinkArms::* member>
py::object two_link_arm(py::handle self) {
  return arm_member(self, member);
}

template <TwoLinkArmParameters TwoLinkArms::* member>
void set_two_link_arm(Settings& settings, const TwoLinkArmParameters& parameters) {
  TwoLinkArms* arms = std::get_if<TwoLinkArms>(&settings.arm);
  if (arms == nullptr)
    throw std::invalid_argument(
        std::string(member == &TwoLinkArms::plant ? "plant" : "model") +
        ": the settings' arm is a URDF arm (plant_urdf), which has no two-link parameters");
  arms->*member = parameters;
}

template <UrdfArmSettings UrdfArms::* member>
py::object urdf_arm(py::handle self) {
  return arm_member(self, member);
}

// A path makes the arm a URDF arm (keeping a URDF model given before); an empty one, the two-link
// arm (keeping its parameters, if it was one).
void set_urdf_plant(Settings& settings, const UrdfArmSettings& plant) {
  if (plant.urdf.empty()) {
    if (!std::holds_alternative<TwoLinkArms>(settings.arm)) settings.arm = TwoLinkArms{};
    return;
  }
  if (UrdfArms* arms = std::get_if<UrdfArms>(&settings.arm))
    arms->plant = plant;
  else
    settings.arm = UrdfArms{plant, UrdfArmSettings()};
}

void set_urdf_model(Settings& settings, const UrdfArmSettings& model) {
  if (UrdfArms* arms = std::get_if<UrdfArms>(&settings.arm))
    arms->model = model;
  else if (!model.urdf.empty())
    throw std::invalid_argument("model.urdf: a URDF model needs a URDF plant (plant_urdf)");
}

void bind_settings(py::module_& m) {
  py::class_<TwoLinkArmParameters>(m, "ArmParameters",
                                   "Two-link arm constants p1 p2 p3 g1 g2 coulomb viscous.")
      .def(py::init<>())
      .def_readwrite("p1", &TwoLinkArmParameters::p1)
      .def_readwrite("p2", &TwoLinkArmParameters::p2)
      .def_readwrite("p3", &TwoLinkArmParameters::p3)
      .def_readwrite("g1", &TwoLinkArmParameters::g1)
      .def_readwrite("g2", &TwoLinkArmParameters::g2)
      .def_readwrite("coulomb", &TwoLinkArmParameters::coulomb)
      .def_readwrite("viscous", &TwoLinkArmParameters::viscous);
  py::class_<RiseGains>(m, "RiseGains", "RISE gains ks, alpha2, beta1 (eqs. 27-28).")
      .def(py::init<>())
      .def_readwrite("ks", &RiseGains::ks)
      .def_readwrite("alpha2", &RiseGains::alpha2)
      .def_readwrite("beta1", &RiseGains::beta1);
  py::class_<CriticSettings>(m, "CriticSettings", "eta_c, nu, gamma0, epsilon_T (eqs. 23-24).")
      .def(py::init<>())
      .def_readwrite("eta_c", &CriticSettings::eta_c)
      .def_readwrite("nu", &CriticSettings::nu)
      .def_readwrite("gamma0", &CriticSettings::gamma0)
      .def_readwrite("epsilon_T", &CriticSettings::epsilon_T);
  py::class_<ActorSettings>(m, "ActorSettings",
                            "eta_a1, eta_a2, weight_bound (eq. 26), positive_e2, e2_margin.")
      .def(py::init<>())
      .def_readwrite("eta_a1", &ActorSettings::eta_a1)
      .def_readwrite("eta_a2", &ActorSettings::eta_a2)
      .def_readwrite("weight_bound", &ActorSettings::weight_bound)
      .def_readwrite("positive_e2", &ActorSettings::positive_e2)
      .def_readwrite("e2_margin", &ActorSettings::e2_margin)
      .def_readwrite("e2_check_positions", &ActorSettings::e2_check_positions);
  py::class_<ProbeSettings>(m, "ProbeSettings",
                            "amplitude (n, k), until, ramp, frequencies (k,), phases (n, k) for n "
                            "joints and k sinusoids.")
      .def(py::init<>())
      .def_readwrite("amplitude", &ProbeSettings::amplitude)
      .def_readwrite("until", &ProbeSettings::until)
      .def_readwrite("ramp", &ProbeSettings::ramp)
      .def_readwrite("frequencies", &ProbeSettings::frequencies)
      .def_readwrite("phases", &ProbeSettings::phases);
  py::enum_<TrajectoryKind>(m, "TrajectoryKind")
      .value("constant", TrajectoryKind::constant)
      .value("sinusoid", TrajectoryKind::sinusoid)
      .value("spline", TrajectoryKind::spline);
  py::class_<TrajectorySettings>(m, "TrajectorySettings",
                                 "kind, offset (n,); sinusoid: amplitude, frequency, phase (n, k); "
                                 "spline: breaks (m + 1,), coefficients (m, 4 n).")
      .def(py::init<>())
      .def_readwrite("kind", &TrajectorySettings::kind)
      .def_readwrite("offset", &TrajectorySettings::offset)
      .def_readwrite("amplitude", &TrajectorySettings::amplitude)
      .def_readwrite("frequency", &TrajectorySettings::frequency)
      .def_readwrite("phase", &TrajectorySettings::phase)
      .def_readwrite("breaks", &TrajectorySettings::breaks)
      .def_readwrite("coefficients", &TrajectorySettings::coefficients);
  py::class_<TaskSettings>(m, "TaskSettings", "q0 (n,), dq0 (n,), qd (TrajectorySettings).")
      .def(py::init<>())
      .def_readwrite("q0", &TaskSettings::q0)
      .def_readwrite("dq0", &TaskSettings::dq0)
      .def_readwrite("qd", &TaskSettings::qd);
  py::class_<ControlSettings>(m, "ControlSettings",
                              "alpha1 (n, n), the RISE gains and anti_windup.")
      .def(py::init<>())
      .def_readwrite("alpha1", &ControlSettings::alpha1)
      .def_readwrite("rise", &ControlSettings::rise)
      .def_readwrite("anti_windup", &ControlSettings::anti_windup);
  py::enum_<ControllerKind>(m, "ControllerKind")
      .value("adp", ControllerKind::adp)
      .value("rise", ControllerKind::rise)
      .value("pd", ControllerKind::pd)
      .value("optimal", ControllerKind::optimal);
  py::class_<ControllerSettings>(m, "ControllerSettings", "kind, rise, kp (n, n), kd (n, n).")
      .def(py::init<>())
      .def_readwrite("kind", &ControllerSettings::kind)
      .def_readwrite("rise", &ControllerSettings::rise)
      .def_readwrite("kp", &ControllerSettings::kp)
      .def_readwrite("kd", &ControllerSettings::kd);
  py::enum_<E2Cost>(m, "E2Cost")
      .value("quadratic", E2Cost::quadratic)
      .value("logcosh", E2Cost::logcosh);
  py::enum_<BasisKind>(m, "BasisKind")
      .value("paper", BasisKind::paper)
      .value("augmented", BasisKind::augmented)
      .value("structured", BasisKind::structured)
      .value("expression", BasisKind::expression);
  py::class_<ExpressionProgram>(m, "ExpressionProgram",
                                "The compiled terms of an expression basis: opcodes and one "
                                "argument per opcode (adparm.bases.compile_terms).")
      .def(py::init<>())
      .def_readwrite("opcodes", &ExpressionProgram::opcodes)
      .def_readwrite("arguments", &ExpressionProgram::arguments);
  py::enum_<ExtrapolationMode>(m, "ExtrapolationMode")
      .value("fixed", ExtrapolationMode::fixed)
      .value("grid", ExtrapolationMode::grid)
      .value("local", ExtrapolationMode::local);
  py::class_<ExtrapolationSettings>(m, "ExtrapolationSettings",
                                    "points, box (2 n,), centre (2 n,; empty: 0), mode, seed.")
      .def(py::init<>())
      .def_readwrite("points", &ExtrapolationSettings::points)
      .def_readwrite("box", &ExtrapolationSettings::box)
      .def_readwrite("centre", &ExtrapolationSettings::centre)
      .def_readwrite("mode", &ExtrapolationSettings::mode)
      .def_readwrite("seed", &ExtrapolationSettings::seed);
  py::class_<IdentifierSettings>(
      m, "IdentifierSettings",
      "The online identifier of beta (identifier.hpp): enabled, gain, gradient_term, "
      "concurrent_gain, history_size, window, singular_value_threshold, max_uncertainty, "
      "inertia, gravity, friction, stop_probe, tolerance.")
      .def(py::init<>())
      .def_readwrite("enabled", &IdentifierSettings::enabled)
      .def_readwrite("gain", &IdentifierSettings::gain)
      .def_readwrite("gradient_term", &IdentifierSettings::gradient_term)
      .def_readwrite("concurrent_gain", &IdentifierSettings::concurrent_gain)
      .def_readwrite("history_size", &IdentifierSettings::history_size)
      .def_readwrite("window", &IdentifierSettings::window)
      .def_readwrite("singular_value_threshold", &IdentifierSettings::singular_value_threshold)
      .def_readwrite("max_uncertainty", &IdentifierSettings::max_uncertainty)
      .def_readwrite("inertia", &IdentifierSettings::inertia)
      .def_readwrite("gravity", &IdentifierSettings::gravity)
      .def_readwrite("friction", &IdentifierSettings::friction)
      .def_readwrite("stop_probe", &IdentifierSettings::stop_probe)
      .def_readwrite("tolerance", &IdentifierSettings::tolerance);
  py::class_<SimSettings>(m, "SimSettings", "T, dt, record_every, divergence_bound.")
      .def(py::init<>())
      .def_readwrite("T", &SimSettings::T)
      .def_readwrite("dt", &SimSettings::dt)
      .def_readwrite("record_every", &SimSettings::record_every)
      .def_readwrite("divergence_bound", &SimSettings::divergence_bound);
  py::class_<UrdfArmSettings>(m, "UrdfArmSettings",
                              "A URDF arm of the loop: urdf (path; empty: the two-link arm), "
                              "gravity (3,), coulomb and viscous (n, 1 or 0 values), locked_joints "
                              "([(name, position), ...]), inertia_scale (every link's mass and "
                              "inertia times it: M, C and G times it; 1: as the URDF).")
      .def(py::init<>())
      .def_readwrite("urdf", &UrdfArmSettings::urdf)
      .def_readwrite("gravity", &UrdfArmSettings::gravity)
      .def_readwrite("coulomb", &UrdfArmSettings::coulomb)
      .def_readwrite("viscous", &UrdfArmSettings::viscous)
      .def_readwrite("locked_joints", &UrdfArmSettings::locked_joints)
      .def_readwrite("inertia_scale", &UrdfArmSettings::inertia_scale);
  py::class_<Settings>(m, "Settings",
                       "All settings of one run. Eigen members and the arms (plant, model, "
                       "plant_urdf, model_urdf) are copied on access: assign them whole. Q (2 n, "
                       "2 n), R (n, n), disturbance (n,), torque_limits (n, or empty: none), "
                       "critic_weights and actor_weights (K,); n "
                       "= 2 joints for the two-link arm, K the basis size. "
                       "dynamic_sizes runs the two-link arm through the n-joint (dynamic-size) "
                       "loop.")
      .def(py::init<>())
      .def_property("plant", &two_link_arm<&TwoLinkArms::plant>,
                    &set_two_link_arm<&TwoLinkArms::plant>,
                    "The two-link arm's parameters (the default arm; assigning plant_urdf makes "
                    "the arm a URDF arm, whose plant and model are default ArmParameters here).")
      .def_property("model", &two_link_arm<&TwoLinkArms::model>,
                    &set_two_link_arm<&TwoLinkArms::model>,
                    "The parameters of the two-link arm the controller believes.")
      .def_property("plant_urdf", &urdf_arm<&UrdfArms::plant>, &set_urdf_plant,
                    "A URDF plant: assigning one with a path makes the arm a URDF arm (one with "
                    "an empty path, the two-link arm); urdf empty when the arm is the two-link "
                    "arm.")
      .def_property("model_urdf", &urdf_arm<&UrdfArms::model>, &set_urdf_model,
                    "The URDF arm's believed model (urdf empty: the plant, an exact model); "
                    "assign plant_urdf first.")
      .def_property_readonly(
          "is_urdf", [](const Settings& s) { return std::holds_alternative<UrdfArms>(s.arm); },
          "Whether the arm is a URDF arm (plant_urdf) rather than the two-link arm.")
      .def_readwrite("disturbance", &Settings::disturbance)
      .def_readwrite("torque_limits", &Settings::torque_limits)
      .def_readwrite("task", &Settings::task)
      .def_readwrite("Q", &Settings::Q)
      .def_readwrite("R", &Settings::R)
      .def_readwrite("input_bound", &Settings::input_bound)
      .def_readwrite("e2_cost", &Settings::e2_cost)
      .def_readwrite("control", &Settings::control)
      .def_readwrite("critic", &Settings::critic)
      .def_readwrite("actor", &Settings::actor)
      .def_readwrite("controller", &Settings::controller)
      .def_readwrite("basis", &Settings::basis)
      .def_readwrite("basis_program", &Settings::basis_program)
      .def_readwrite("dynamic_sizes", &Settings::dynamic_sizes)
      .def_readwrite("extrapolation", &Settings::extrapolation)
      .def_readwrite("identifier", &Settings::identifier)
      .def_readwrite("critic_weights", &Settings::critic_weights)
      .def_readwrite("actor_weights", &Settings::actor_weights)
      .def_readwrite("probe", &Settings::probe)
      .def_readwrite("sim", &Settings::sim);
  m.def("paper_settings", &paper_settings, "The C++ core's copy of the paper preset.");
}

void bind_arm(py::module_& m) {
  m.def(
      "arm_terms",
      [](const TwoLinkArmParameters& parameters, const Vec2& q, const Vec2& dq) {
        TwoLinkArm::Terms terms;
        TwoLinkArm(parameters).compute(q, dq, terms);
        py::dict out;
        out["M"] = terms.mass;
        out["M_inv"] = terms.mass_inverse;
        out["C"] = terms.coriolis;
        out["G"] = terms.gravity;
        out["F"] = terms.friction;
        return out;
      },
      py::arg("parameters"), py::arg("q"), py::arg("dq"),
      "Model terms at q (2,), dq (2,): dict of M, M_inv, C (2, 2) and G, F (2,).");
  m.def(
      "two_link_regressors",
      [](const Vec2& q, const Vec2& dq, const Vec2& ddq, const Vec2& dq_r, const Vec2& ddq_r) {
        using R = TwoLinkRegressor;
        py::dict out;
        out["Y"] = R::Matrix(R::regressor(q, dq, ddq));
        out["Y_r"] = R::Matrix(R::reference_regressor(q, dq, dq_r, ddq_r));
        out["Y_M"] = R::Matrix(R::momentum_regressor(q, dq));
        out["Y_N"] = R::Matrix(R::momentum_rate_regressor(q, dq));
        return out;
      },
      py::arg("q"), py::arg("dq"), py::arg("ddq"), py::arg("dq_r"), py::arg("ddq_r"),
      "The two-link arm's regressors (2, 7) in beta = (p1, p2, p3, g1, g2, coulomb, viscous) "
      "(identifier.hpp): Y (M ddq + C dq + G + F), Y_r (M ddq_r + C(q, dq) dq_r + G + F), Y_M "
      "(M dq) and Y_N (G + F - C^T dq).");
  m.def(
      "simulate_open_loop",
      [](const TwoLinkArmParameters& parameters, const Vec2& disturbance, const Vec4& initial_state,
         double dt, long steps, bool compensate_gravity) {
        const OpenLoopArm<TwoLinkArm> system(
            TwoLinkArm(parameters), SinusoidalDisturbance{disturbance}, compensate_gravity);
        py::gil_scoped_release release;
        return simulate_open_loop(system, initial_state, dt, steps);
      },
      py::arg("parameters"), py::arg("disturbance"), py::arg("initial_state"), py::arg("dt"),
      py::arg("steps"), py::arg("compensate_gravity"),
      "RK4 of the arm alone under tau = G(q) (or 0) from [q; dq] (4,); rows (steps + 1, 4).");
}

// One value for all joints or one per joint (the core checks the count against the URDF).
Eigen::VectorXd per_joint(const std::variant<double, Eigen::VectorXd>& value) {
  if (const double* x = std::get_if<double>(&value)) return Eigen::VectorXd::Constant(1, *x);
  return std::get<Eigen::VectorXd>(value);
}

void bind_urdf_arm(py::module_& m) {
  using Vector = Eigen::VectorXd;
  m.def("urdf_parse_count", &urdf_parse_count,
        "How many URDF texts the core has parsed so far, in every thread.");
  py::class_<PinocchioArm>(m, "UrdfArm",
                           "A fixed-base serial arm from a URDF file, through Pinocchio. "
                           "gravity (3,), coulomb and viscous: one number or one per joint.")
      .def(py::init([](const std::string& urdf_path, const Eigen::Vector3d& gravity,
                       const std::variant<double, Vector>& coulomb,
                       const std::variant<double, Vector>& viscous, const LockedJoints& locked) {
             return PinocchioArm(urdf_path, gravity, per_joint(coulomb), per_joint(viscous),
                                 locked);
           }),
           py::arg("urdf_path"), py::arg("gravity") = Eigen::Vector3d(0.0, 0.0, -9.81),
           py::arg("coulomb") = 0.0, py::arg("viscous") = 0.0,
           py::arg("locked_joints") = LockedJoints())
      .def_static(
          "from_xml",
          [](const std::string& xml, const Eigen::Vector3d& gravity,
             const std::variant<double, Vector>& coulomb,
             const std::variant<double, Vector>& viscous, const std::string& name,
             const LockedJoints& locked) {
            return PinocchioArm::from_xml(xml, gravity, per_joint(coulomb), per_joint(viscous),
                                          name, locked);
          },
          py::arg("xml"), py::arg("gravity") = Eigen::Vector3d(0.0, 0.0, -9.81),
          py::arg("coulomb") = 0.0, py::arg("viscous") = 0.0, py::arg("name") = "<URDF string>",
          py::arg("locked_joints") = LockedJoints(),
          "The same from the URDF's XML text; name stands for the file in error messages.")
      .def(
          "with_gravity_and_friction",
          [](const PinocchioArm& arm, const Eigen::Vector3d& gravity,
             const std::variant<double, Vector>& coulomb,
             const std::variant<double, Vector>& viscous) {
            return arm.with_gravity_and_friction(gravity, per_joint(coulomb), per_joint(viscous));
          },
          py::arg("gravity") = Eigen::Vector3d(0.0, 0.0, -9.81), py::arg("coulomb") = 0.0,
          py::arg("viscous") = 0.0,
          "The arm the constructor would read with this gravity and friction, without reading "
          "the URDF again (the parsed model is shared or copied).")
      .def("with_inertia_scaled", &PinocchioArm::with_inertia_scaled, py::arg("scale"),
           "This arm with every link's mass and inertia times scale > 0: M, C and G times "
           "scale, friction and kinematics unchanged (1: this arm).")
      .def_property_readonly("dof", &PinocchioArm::dof)
      .def_property_readonly("source", &PinocchioArm::source)
      .def_property_readonly("joint_names", &PinocchioArm::joint_names)
      .def_property_readonly("locked_joints", &PinocchioArm::locked_joints)
      .def_property_readonly("joint_types", &PinocchioArm::joint_types)
      .def_property_readonly("gravity", &PinocchioArm::gravity_vector)
      .def_property_readonly("coulomb", &PinocchioArm::coulomb)
      .def_property_readonly("viscous", &PinocchioArm::viscous)
      .def_property_readonly("limits",
                             [](const PinocchioArm& arm) {
                               py::dict out;
                               out["lower"] = arm.limits().lower;
                               out["upper"] = arm.limits().upper;
                               out["velocity"] = arm.limits().velocity;
                               out["effort"] = arm.limits().effort;
                               return out;
                             })
      .def_property_readonly("inertial_parameters", &PinocchioArm::inertial_parameters)
      .def(
          "terms",
          [](const PinocchioArm& arm, const Vector& q, const Vector& dq) {
            PinocchioArm::Terms terms = arm.make_terms();
            {
              py::gil_scoped_release release;
              arm.compute(q, dq, terms);
            }
            py::dict out;
            out["M"] = terms.mass;
            out["M_inv"] = terms.mass_inverse;
            out["C"] = terms.coriolis;
            out["G"] = terms.gravity;
            out["F"] = terms.friction;
            return out;
          },
          py::arg("q"), py::arg("dq"),
          "Model terms at q (n,), dq (n,): dict of M, M_inv, C (n, n) and G, F (n,).")
      .def(
          "mass_regressor",
          [](const PinocchioArm& arm, const Vector& q) {
            Eigen::MatrixXd out(arm.dof(),
                                static_cast<Eigen::Index>(arm.dof()) * arm.parameter_count());
            {
              py::gil_scoped_release release;
              arm.mass_regressor(q, out);
            }
            return out;
          },
          py::arg("q"),
          "M_k(q) for the inertial parameters, side by side: (n, n * 10 n), M_k in columns "
          "[k n, (k + 1) n).")
      .def_property_readonly("inertial_parameter_names", &inertial_parameter_names)
      .def(
          "base_parameters",
          [](const PinocchioArm& arm, int samples, std::uint64_t seed, double tolerance) {
            BaseParameters base;
            {
              py::gil_scoped_release release;
              base = adparm::base_parameters(arm, samples, seed, tolerance);
            }
            return py::make_tuple(base.values, base.columns, base.combination);
          },
          py::arg("samples") = 100, py::arg("seed") = 0, py::arg("tolerance") = 1e-9,
          "(values (r,), columns (r,), combination (r, 10 n)): the base inertial parameters "
          "(pinocchio_structured_basis.hpp).")
      .def(
          "identifier_parameters",
          [](const PinocchioArm& arm) {
            const PinocchioRegressor regressor(arm);
            std::vector<std::string> groups;
            for (int i = 0; i < regressor.parameters(); ++i) {
              const ParameterGroup g = regressor.group(i);
              groups.push_back(g == ParameterGroup::inertia   ? "inertia"
                               : g == ParameterGroup::gravity ? "gravity"
                                                              : "friction");
            }
            return py::make_tuple(regressor.beta_of(arm), regressor.names(), groups);
          },
          "(values (P,), names, groups): the online identifier's base parameters beta = "
          "[kinetic (the structured basis'); gravity's beyond them; coulomb; viscous] "
          "(urdf_regressor.hpp), each group 'inertia', 'gravity' or 'friction'.")
      .def(
          "identifier_regressors",
          [](const PinocchioArm& arm, const Vector& q, const Vector& dq, const Vector& ddq,
             const Vector& dq_r, const Vector& ddq_r) {
            const Eigen::Index n = arm.dof();
            check_size(q, n, 1, "q");
            check_size(dq, n, 1, "dq");
            check_size(ddq, n, 1, "ddq");
            check_size(dq_r, n, 1, "dq_r");
            check_size(ddq_r, n, 1, "ddq_r");
            const PinocchioRegressor regressor(arm);
            using R = PinocchioRegressor;
            R::Workspace workspace = regressor.make_workspace(regressor.beta(UrdfLoopArm(arm)));
            const R::Joint qj = q, dqj = dq, ddqj = ddq, vj = dq_r, aj = ddq_r;
            R::Matrix Y, Y_r, Y_M, Y_N;
            regressor.regressor(qj, dqj, ddqj, Y, workspace);
            regressor.reference_regressor(qj, dqj, vj, aj, Y_r, workspace);
            regressor.momentum_regressor(qj, dqj, Y_M, workspace);
            regressor.momentum_rate_regressor(qj, dqj, Y_N, workspace);
            py::dict out;
            out["Y"] = Eigen::MatrixXd(Y);
            out["Y_r"] = Eigen::MatrixXd(Y_r);
            out["Y_M"] = Eigen::MatrixXd(Y_M);
            out["Y_N"] = Eigen::MatrixXd(Y_N);
            return out;
          },
          py::arg("q"), py::arg("dq"), py::arg("ddq"), py::arg("dq_r"), py::arg("ddq_r"),
          "The online identifier's regressors (n, P) in identifier_parameters()' beta "
          "(urdf_regressor.hpp): Y (M ddq + C dq + G + F), Y_r (M ddq_r + C(q, dq) dq_r + G + "
          "F), Y_M (M dq) and Y_N (G + F - C^T dq).");
}

void bind_urdf_structured_basis(py::module_& m) {
  using RowsX = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  py::class_<PinocchioStructuredBasis>(
      m, "UrdfStructuredBasis",
      "The structured basis of a URDF arm: [e1_i e1_j (i <= j); e2^T M_b(q) e2 per base "
      "inertial parameter b] (pinocchio_structured_basis.hpp).")
      .def(py::init<const PinocchioArm&>(), py::arg("arm"))
      .def_property_readonly("size", &PinocchioStructuredBasis::size)
      .def_property_readonly("joints", &PinocchioStructuredBasis::joints)
      .def_property_readonly("names", &PinocchioStructuredBasis::names)
      .def_property_readonly("base_parameters",
                             [](const PinocchioStructuredBasis& basis) {
                               const BaseParameters& base = basis.base_parameters();
                               return py::make_tuple(base.values, base.columns, base.combination);
                             })
      .def(
          "optimal_weights",
          [](const PinocchioStructuredBasis& basis, const Eigen::MatrixXd& K,
             const std::optional<Eigen::VectorXd>& inertial_parameters) {
            return inertial_parameters ? basis.optimal_weights(K, *inertial_parameters)
                                       : basis.optimal_weights(K);
          },
          py::arg("K"), py::arg("inertial_parameters") = py::none(),
          "W* = [K_ii on squares, K_ij + K_ji on cross terms; base parameters] for K (n, n); "
          "the base parameters of inertial_parameters (10 n) of an arm of the same kinematics "
          "if given.")
      .def(
          "evaluate_rows",
          [](const PinocchioStructuredBasis& basis, const RowsX& x, const RowsX& qd,
             const RowsX& dqd) {
            const Eigen::Index rows = x.rows(), N = basis.size(), n = basis.joints();
            check_size(x, rows, 2 * n, "x");
            check_size(qd, rows, n, "qd");
            check_size(dqd, rows, n, "dqd");
            py::array_t<double> phi({rows, N}), jacobian({rows, N, 2 * n}), rate({rows, N});
            double* phi_out = phi.mutable_data();
            double* jacobian_out = jacobian.mutable_data();
            double* rate_out = rate.mutable_data();
            {
              py::gil_scoped_release release;
              Eigen::VectorXd p(N), r(N), row_x(2 * n), row_qd(n), row_dqd(n);
              Eigen::MatrixXd j(N, 2 * n);
              PinocchioStructuredBasis::Workspace workspace = basis.workspace();
              for (Eigen::Index i = 0; i < rows; ++i) {
                row_x = x.row(i).transpose();
                row_qd = qd.row(i).transpose();
                row_dqd = dqd.row(i).transpose();
                basis.evaluate_at(row_x, row_qd, row_dqd, p, j, r, workspace);
                Eigen::Map<Eigen::VectorXd>(phi_out + i * N, N) = p;
                Eigen::Map<Eigen::VectorXd>(rate_out + i * N, N) = r;
                Eigen::Map<RowsX>(jacobian_out + i * N * 2 * n, N, 2 * n) = j;
              }
            }
            return py::make_tuple(phi, jacobian, rate);
          },
          py::arg("x"), py::arg("qd"), py::arg("dqd"),
          "At rows x (m, 2n), qd (m, n), dqd (m, n): phi (m, N), d phi / dx (m, N, 2n) and "
          "(d phi / d qd) dqd (m, N).");
}

void bind_trajectory(py::module_& m) {
  m.def(
      "desired_state",
      [](const TrajectorySettings& settings, const Eigen::VectorXd& times) {
        check_finite(times, "t");
        const TrajectoryT<Dynamic> trajectory(settings, settings.offset.size());
        const Eigen::Index n = trajectory.dof();
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out(times.size(),
                                                                                   3 * n);
        for (Eigen::Index i = 0; i < times.size(); ++i) {
          const auto d = trajectory(times[i]);
          out.row(i) << d.q.transpose(), d.dq.transpose(), d.ddq.transpose();
        }
        return out;
      },
      py::arg("trajectory"), py::arg("t"),
      "The desired state of n joints at times t (m,): rows [qd (n), dqd (n), ddqd (n)] "
      "(m, 3 n).");
}

void bind_basis(py::module_& m) {
  m.def(
      "basis",
      [](BasisKind kind, const Vec4& x, const Vec2& qd, const Vec2& dqd) {
        DesiredState desired;
        desired.q = qd;
        desired.dq = dqd;
        return with_basis(kind, [&](auto basis) {
          using Basis = decltype(basis);
          typename Basis::Vector phi, desired_rate;
          typename Basis::Jacobian jacobian;
          Basis::evaluate(x, desired, phi, jacobian, desired_rate);
          return py::make_tuple(Eigen::VectorXd(phi), Eigen::MatrixXd(jacobian),
                                Eigen::VectorXd(desired_rate));
        });
      },
      py::arg("kind"), py::arg("x"), py::arg("qd"), py::arg("dqd"),
      "A basis of K functions at x (4,) and desired qd, dqd (2,): phi (K,), d phi / dx (K, 4) and "
      "(d phi / d qd) dqd (K,).");
}

void bind_expression_basis(py::module_& m) {
  using RowsX = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  py::enum_<ExpressionOp>(m, "ExpressionOp")
      .value("constant", ExpressionOp::constant)
      .value("variable", ExpressionOp::variable)
      .value("add", ExpressionOp::add)
      .value("subtract", ExpressionOp::subtract)
      .value("multiply", ExpressionOp::multiply)
      .value("negate", ExpressionOp::negate)
      .value("power", ExpressionOp::power)
      .value("sin", ExpressionOp::sin)
      .value("cos", ExpressionOp::cos)
      .value("tan", ExpressionOp::tan)
      .value("exp", ExpressionOp::exp)
      .value("log", ExpressionOp::log)
      .value("sqrt", ExpressionOp::sqrt)
      .value("tanh", ExpressionOp::tanh)
      .value("store", ExpressionOp::store);
  py::class_<ExpressionBasis>(m, "ExpressionBasis",
                              "A basis compiled from a postfix program over z = [x (2n); qd (n)] "
                              "(cpp/include/adparm/expression_basis.hpp).")
      .def(py::init([](int joints, const std::vector<int>& opcodes,
                       const std::vector<double>& arguments) {
             if (opcodes.size() != arguments.size())
               throw std::invalid_argument("arguments: expected one per opcode (" +
                                           std::to_string(opcodes.size()) + "), got " +
                                           std::to_string(arguments.size()));
             std::vector<ExpressionInstruction> program(opcodes.size());
             for (std::size_t i = 0; i < opcodes.size(); ++i)
               program[i] = {static_cast<ExpressionOp>(opcodes[i]), arguments[i]};
             return ExpressionBasis(joints, program);
           }),
           py::arg("joints"), py::arg("opcodes"), py::arg("arguments"))
      .def("__len__", &ExpressionBasis::size)
      .def_property_readonly("size", &ExpressionBasis::size)
      .def_property_readonly("joints", &ExpressionBasis::joints)
      .def_property_readonly("state_dim", &ExpressionBasis::state_dim)
      .def_property_readonly("stack_depth", &ExpressionBasis::stack_depth)
      .def(
          "evaluate",
          [](const ExpressionBasis& basis, const Eigen::VectorXd& x, const Eigen::VectorXd& qd,
             const Eigen::VectorXd& dqd) {
            const Eigen::Index N = basis.size();
            Eigen::VectorXd phi(N), rate(N);
            Eigen::MatrixXd jacobian(N, basis.state_dim()), desired_jacobian(N, basis.joints());
            ExpressionBasis::Workspace workspace = basis.workspace();
            {
              py::gil_scoped_release release;
              basis.evaluate(x, qd, dqd, phi, jacobian, rate, &desired_jacobian, workspace);
            }
            return py::make_tuple(phi, jacobian, rate, desired_jacobian);
          },
          py::arg("x"), py::arg("qd"), py::arg("dqd"),
          "At x (2n,), qd (n,), dqd (n,): phi (N,), d phi / dx (N, 2n), (d phi / d qd) dqd (N,) "
          "and d phi / d qd (N, n).")
      .def(
          "evaluate_rows",
          [](const ExpressionBasis& basis, const RowsX& x, const RowsX& qd, const RowsX& dqd) {
            const Eigen::Index rows = x.rows(), N = basis.size(), n_x = basis.state_dim();
            check_size(qd, rows, basis.joints(), "qd");
            check_size(dqd, rows, basis.joints(), "dqd");
            if (x.cols() != n_x) check_size(x, rows, n_x, "x");
            py::array_t<double> phi({rows, N}), jacobian({rows, N, n_x}), rate({rows, N});
            double* phi_out = phi.mutable_data();
            double* jacobian_out = jacobian.mutable_data();
            double* rate_out = rate.mutable_data();
            {
              py::gil_scoped_release release;
              ExpressionBasis::Workspace workspace = basis.workspace();
              Eigen::VectorXd p(N), r(N), row_x(n_x), row_qd(qd.cols()), row_dqd(dqd.cols());
              Eigen::MatrixXd j(N, n_x);
              for (Eigen::Index i = 0; i < rows; ++i) {
                row_x = x.row(i).transpose();
                row_qd = qd.row(i).transpose();
                row_dqd = dqd.row(i).transpose();
                basis.evaluate(row_x, row_qd, row_dqd, p, j, r, nullptr, workspace);
                Eigen::Map<Eigen::VectorXd>(phi_out + i * N, N) = p;
                Eigen::Map<Eigen::VectorXd>(rate_out + i * N, N) = r;
                Eigen::Map<RowsX>(jacobian_out + i * N * n_x, N, n_x) = j;
              }
            }
            return py::make_tuple(phi, jacobian, rate);
          },
          py::arg("x"), py::arg("qd"), py::arg("dqd"),
          "Row by row, x (m, 2n), qd and dqd (m, n): phi (m, N), d phi / dx (m, N, 2n) and "
          "(d phi / d qd) dqd (m, N).");
}

// eqs. (20)-(21) at each row of `states` (m, 2n) with the desired state at time t; each row's
// eps_hjb into residual[i] and, given `omega` (m x K), its omega into omega.row(i).
void evaluate_hjb_rows(const Settings& settings, const RowsXX& states,
                       const Eigen::VectorXd& critic_weights, const Eigen::VectorXd& actor_weights,
                       double t, Eigen::VectorXd& residual, RowsXX* omega) {
  check_finite(critic_weights, "critic_weights");
  check_finite(actor_weights, "actor_weights");
  check_finite(states, "x");
  check_finite(t, "t");
  visit_loop(settings, [&](auto loop_type) {
    using Loop = typename decltype(loop_type)::type;
    const Loop loop = make_loop<Loop>(settings, *module_urdfs());
    check_size(critic_weights, loop.basis_size(), 1, "critic_weights");
    check_size(actor_weights, loop.basis_size(), 1, "actor_weights");
    check_size(states, states.rows(), 2 * loop.dof(), "x");
    const typename Loop::Weights wc = critic_weights, wa = actor_weights;
    const typename Loop::Desired desired = loop.trajectory()(t);
    residual.resize(states.rows());
    if (omega != nullptr) omega->resize(states.rows(), loop.basis_size());
    py::gil_scoped_release release;
    for (Eigen::Index i = 0; i < states.rows(); ++i) {
      const auto evaluation =
          hjb_evaluation(loop.basis(), loop.error_system(), loop.cost(),
                         typename Loop::Error(states.row(i).transpose()), desired, wc, wa);
      residual[i] = evaluation.error;
      if (omega != nullptr) omega->row(i) = evaluation.omega.transpose();
    }
  });
}

void bind_hjb(py::module_& m) {
  m.def(
      "hjb_residual",
      [](const Settings& settings, const RowsXX& states, const Eigen::VectorXd& critic_weights,
         const Eigen::VectorXd& actor_weights, double t) {
        Eigen::VectorXd residual;
        evaluate_hjb_rows(settings, states, critic_weights, actor_weights, t, residual, nullptr);
        return residual;
      },
      py::arg("settings"), py::arg("x"), py::arg("critic_weights"), py::arg("actor_weights"),
      py::arg("t"),
      "HJB error of eq. (21) at each row of x (m, 2 n) for weights (K,) of settings.basis, with "
      "the "
      "desired state at time t; returns (n,).");
  m.def(
      "hjb_evaluation",
      [](const Settings& settings, const RowsXX& states, const Eigen::VectorXd& critic_weights,
         const Eigen::VectorXd& actor_weights, double t) {
        Eigen::VectorXd residual;
        RowsXX omega;
        evaluate_hjb_rows(settings, states, critic_weights, actor_weights, t, residual, &omega);
        return std::make_pair(std::move(residual), std::move(omega));
      },
      py::arg("settings"), py::arg("x"), py::arg("critic_weights"), py::arg("actor_weights"),
      py::arg("t"),
      "hjb_residual's HJB error (m,) and each row's omega = (dphi/dx) (f + g u_hat) + (dphi/dqd) "
      "dqd (m, K), the regressor of eqs. (21)-(26): d eps / d Wc, and d eps / d W at Wc = Wa = W "
      "(u_hat minimises U(u) + W^T B u).");
}

void bind_closed_loop(py::module_& m) {
  m.attr("STATE_SIZE") = PaperClosedLoop::kStateSize;
  m.def(
      "closed_loop_derivative",
      [](const Settings& settings, double t, const Eigen::VectorXd& state) {
        check_finite(state, "state");
        check_finite(t, "t");
        return visit_loop(settings, [&](auto loop_type) {
          using Loop = typename decltype(loop_type)::type;
          Loop loop = make_loop<Loop>(settings, *module_urdfs());
          check_size(state, loop.state_size(), 1, "state");
          typename Loop::TimeSignals signals;
          typename Loop::State x = state, rate = Loop::State::Zero(loop.state_size());
          typename Loop::Outputs outputs;
          typename Loop::Data data = loop.make_data();
          loop.begin_step(t, x, data);
          loop.time_signals(t, signals);
          loop.derivative(signals, x, rate, &outputs, data);
          py::dict out;
          out["qd"] = outputs.qd;
          out["e1"] = outputs.errors.e1;
          out["e2"] = outputs.errors.e2;
          out["tau"] = outputs.tau;
          out["tau_commanded"] = outputs.tau_commanded;
          out["u"] = outputs.u;
          out["u_hat"] = outputs.u_hat;
          out["mu"] = outputs.mu;
          out["probe"] = outputs.probe;
          out["hjb_error"] = outputs.hjb_error;
          return py::make_tuple(Eigen::VectorXd(rate), out);
        });
      },
      py::arg("settings"), py::arg("t"), py::arg("state"),
      "Right-hand side at t of state (S,) = [q, dq, Wc (K), Wa (K), Gamma (K^2, column-major), "
      "nu (2), J] (S = 87 for the 8-function bases, 55 for the structured basis, 2 K + K^2 + 7 "
      "for an expression basis of K functions); local "
      "extrapolation points are drawn around this state first. Returns (rate (S,), outputs "
      "dict).");
  m.def(
      "initial_state",
      [](const Settings& settings) {
        return visit_loop(settings, [&](auto loop_type) {
          using Loop = typename decltype(loop_type)::type;
          return Eigen::VectorXd(make_loop<Loop>(settings, *module_urdfs()).initial_state());
        });
      },
      py::arg("settings"), "The closed loop's initial state (S,).");
  m.def(
      "extrapolation_points",
      [](const Settings& settings) {
        return visit_loop(settings, [&](auto loop_type) {
          using Loop = typename decltype(loop_type)::type;
          const Loop loop = make_loop<Loop>(settings, *module_urdfs());
          const auto& points = loop.extrapolation().points();
          RowsXX out(static_cast<Eigen::Index>(points.size()), 2 * loop.dof());
          for (std::size_t i = 0; i < points.size(); ++i) out.row(i) = points[i].transpose();
          return out;
        });
      },
      py::arg("settings"),
      "The fixed or grid extrapolation points (N, 2 n) in x (zeros for mode local, whose points "
      "are drawn around the state at each step).");
}

void bind_simulation(py::module_& m) {
  // (name, width) of each recorded series, in order; width "one", "joints", "basis", "parameters"
  // (beta_hat: one column per model parameter, none without identification) or "identifier" (one
  // column with identification, none without)
  py::tuple series(kRecordedSeries.size());
  for (std::size_t i = 0; i < kRecordedSeries.size(); ++i) {
    const SeriesWidth width = kRecordedSeries[i].width;
    const char* name = width == SeriesWidth::one          ? "one"
                       : width == SeriesWidth::joints     ? "joints"
                       : width == SeriesWidth::basis      ? "basis"
                       : width == SeriesWidth::parameters ? "parameters"
                                                          : "identifier";
    series[i] = py::make_tuple(kRecordedSeries[i].name, name);
  }
  m.attr("RECORDED_SERIES") = series;
  py::class_<AnySimulation>(m, "Simulation",
                            "The closed-loop run (basis from settings.basis); advance(n) takes up "
                            "to n RK4 steps.")
      .def(py::init([](const Settings& settings) {
             return std::make_unique<AnySimulation>(settings, *module_urdfs());
           }),
           py::arg("settings"))
      .def(
          "advance", [](AnySimulation& s, long max_steps) { return s.advance(max_steps); },
          py::arg("max_steps"), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("status",
                             [](const AnySimulation& s) {
                               switch (s.status()) {
                                 case RunStatus::running:
                                   return "running";
                                 case RunStatus::finished:
                                   return "finished";
                                 default:
                                   return "diverged";
                               }
                             })
      .def_property_readonly("steps", &AnySimulation::steps)
      .def_property_readonly("step", &AnySimulation::step)
      .def_property_readonly("divergence_time", &AnySimulation::divergence_time)
      .def_property_readonly("reset_times", &AnySimulation::reset_times)
      .def_property_readonly("saturated_time", &AnySimulation::saturated_time,
                             "Per joint, the time (s) its commanded torque lay beyond its limit "
                             "(plant.torque_limits), counted per step from the step's start.")
      .def_property_readonly("state", &AnySimulation::state)
      .def(
          "recording",
          [](const AnySimulation& s) {
            // Each series is freed as soon as NumPy has its copy: at most one series is held
            // twice besides the run's own recording.
            Recording r = s.recording();
            py::dict out;
            for (const RecordedSeries& series : kRecordedSeries) {
              Recording::Rows& rows = r.*series.member;
              if (series.width == SeriesWidth::one ||
                  (series.width == SeriesWidth::identifier && rows.cols() == 1))  // a 1-D array
                out[series.name] =
                    py::cast(Eigen::Map<const Eigen::VectorXd>(rows.data(), rows.rows()),
                             py::return_value_policy::copy);
              else
                out[series.name] = rows;
              rows.resize(0, 0);
            }
            return out;
          },
          "Recorded rows so far: dict of arrays t, hjb_error, cost (n,), q ... (n, 2), "
          "weights (n, 8).");
}

void bind_batch(py::module_& m) {
  using AnyBatch = Batch<AnySimulation>;
  py::class_<AnyBatch>(m, "Batch",
                       "Independent runs on a pool of C++ threads that take runs from a shared "
                       "queue and run each to the end; the caller polls with wait().")
      .def(py::init([](std::vector<Settings> settings, std::size_t window) {
             return std::make_unique<AnyBatch>(std::move(settings), window, module_urdfs());
           }),
           py::arg("settings"), py::arg("window") = std::numeric_limits<std::size_t>::max(),
           "Builds (checks) every run; at most `window` runs are built and not yet taken.")
      .def("__len__", &AnyBatch::size)
      .def("start", &AnyBatch::start, py::arg("threads"), "Starts the workers.")
      .def("wait", &AnyBatch::wait, py::arg("seconds"), py::call_guard<py::gil_scoped_release>(),
           "Waits up to `seconds` for a run to end; returns the indices of the runs that ended "
           "since the last call.")
      .def_property_readonly("done", &AnyBatch::done)
      .def("stop", &AnyBatch::stop, py::call_guard<py::gil_scoped_release>(),
           "Stops every worker within one step and joins them.")
      .def_property_readonly("steps_done", &AnyBatch::steps_done)
      .def_property_readonly("total_steps", &AnyBatch::total_steps)
      .def("take", &AnyBatch::take, py::arg("index"),
           "Hands run `index` over (ended, stopped part-way, or built now if never started).")
      .def("seconds", &AnyBatch::seconds, py::arg("index"),
           "Wall time spent building and advancing run `index`, s.");
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "adparm's C++ core (private; use the adparm package).";
  bind_settings(m);
  bind_arm(m);
  bind_urdf_arm(m);
  bind_urdf_structured_basis(m);
  bind_trajectory(m);
  bind_basis(m);
  bind_expression_basis(m);
  bind_hjb(m);
  bind_closed_loop(m);
  bind_simulation(m);
  bind_batch(m);
  py::list names;  // __all__: every public name bound above, in order
  for (const auto& item : m.attr("__dict__").cast<py::dict>()) {
    const std::string name = py::str(item.first);
    if (name.rfind("_", 0) != 0) names.append(name);
  }
  m.attr("__all__") = names;
}
