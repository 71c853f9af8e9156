// adparm._core: the thin pybind11 binding of the C++ core. It only declares: one bind_<concept>(m)
// per concept, one Settings struct passed whole, sizes in docstrings. Argument checks live in the
// core (std::invalid_argument -> ValueError); the GIL is released around the simulation loop.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <variant>

#include "adparm/basis.hpp"
#include "adparm/batch.hpp"
#include "adparm/hjb.hpp"
#include "adparm/open_loop.hpp"
#include "adparm/pinocchio_arm.hpp"
#include "adparm/simulation.hpp"

namespace py = pybind11;
using namespace adparm;

namespace {

using RowsX4 = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;

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
  py::class_<ActorSettings>(m, "ActorSettings", "eta_a1, eta_a2, weight_bound (eq. 26).")
      .def(py::init<>())
      .def_readwrite("eta_a1", &ActorSettings::eta_a1)
      .def_readwrite("eta_a2", &ActorSettings::eta_a2)
      .def_readwrite("weight_bound", &ActorSettings::weight_bound);
  py::class_<ProbeSettings>(m, "ProbeSettings",
                            "amplitude (2, n), until, ramp, frequencies (n,), phases (2, n).")
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
                                 "kind, offset (2,); sinusoid: amplitude, frequency, phase (2, n); "
                                 "spline: breaks (n + 1,), coefficients (n, 8).")
      .def(py::init<>())
      .def_readwrite("kind", &TrajectorySettings::kind)
      .def_readwrite("offset", &TrajectorySettings::offset)
      .def_readwrite("amplitude", &TrajectorySettings::amplitude)
      .def_readwrite("frequency", &TrajectorySettings::frequency)
      .def_readwrite("phase", &TrajectorySettings::phase)
      .def_readwrite("breaks", &TrajectorySettings::breaks)
      .def_readwrite("coefficients", &TrajectorySettings::coefficients);
  py::class_<TaskSettings>(m, "TaskSettings", "q0 (2,), dq0 (2,), qd (TrajectorySettings).")
      .def(py::init<>())
      .def_readwrite("q0", &TaskSettings::q0)
      .def_readwrite("dq0", &TaskSettings::dq0)
      .def_readwrite("qd", &TaskSettings::qd);
  py::class_<ControlSettings>(m, "ControlSettings", "alpha1 (2, 2) and the RISE gains.")
      .def(py::init<>())
      .def_readwrite("alpha1", &ControlSettings::alpha1)
      .def_readwrite("rise", &ControlSettings::rise);
  py::enum_<ControllerKind>(m, "ControllerKind")
      .value("adp", ControllerKind::adp)
      .value("rise", ControllerKind::rise)
      .value("pd", ControllerKind::pd)
      .value("optimal", ControllerKind::optimal);
  py::class_<ControllerSettings>(m, "ControllerSettings", "kind, rise, kp (2, 2), kd (2, 2).")
      .def(py::init<>())
      .def_readwrite("kind", &ControllerSettings::kind)
      .def_readwrite("rise", &ControllerSettings::rise)
      .def_readwrite("kp", &ControllerSettings::kp)
      .def_readwrite("kd", &ControllerSettings::kd);
  py::enum_<BasisKind>(m, "BasisKind")
      .value("paper", BasisKind::paper)
      .value("augmented", BasisKind::augmented);
  py::enum_<ExtrapolationMode>(m, "ExtrapolationMode")
      .value("fixed", ExtrapolationMode::fixed)
      .value("grid", ExtrapolationMode::grid)
      .value("local", ExtrapolationMode::local);
  py::class_<ExtrapolationSettings>(m, "ExtrapolationSettings", "points, box (4,), mode, seed.")
      .def(py::init<>())
      .def_readwrite("points", &ExtrapolationSettings::points)
      .def_readwrite("box", &ExtrapolationSettings::box)
      .def_readwrite("mode", &ExtrapolationSettings::mode)
      .def_readwrite("seed", &ExtrapolationSettings::seed);
  py::class_<SimSettings>(m, "SimSettings", "T, dt, record_every, divergence_bound.")
      .def(py::init<>())
      .def_readwrite("T", &SimSettings::T)
      .def_readwrite("dt", &SimSettings::dt)
      .def_readwrite("record_every", &SimSettings::record_every)
      .def_readwrite("divergence_bound", &SimSettings::divergence_bound);
  py::class_<Settings>(m, "Settings",
                       "All settings of one run. Eigen members are copied on access: assign them "
                       "whole. Q (4, 4), R (2, 2), disturbance (2,), critic_weights and "
                       "actor_weights (8,).")
      .def(py::init<>())
      .def_readwrite("plant", &Settings::plant)
      .def_readwrite("model", &Settings::model)
      .def_readwrite("disturbance", &Settings::disturbance)
      .def_readwrite("task", &Settings::task)
      .def_readwrite("Q", &Settings::Q)
      .def_readwrite("R", &Settings::R)
      .def_readwrite("control", &Settings::control)
      .def_readwrite("critic", &Settings::critic)
      .def_readwrite("actor", &Settings::actor)
      .def_readwrite("controller", &Settings::controller)
      .def_readwrite("basis", &Settings::basis)
      .def_readwrite("extrapolation", &Settings::extrapolation)
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
  py::class_<PinocchioArm>(m, "UrdfArm",
                           "A fixed-base serial arm from a URDF file, through Pinocchio. "
                           "gravity (3,), coulomb and viscous: one number or one per joint.")
      .def(py::init([](const std::string& urdf_path, const Eigen::Vector3d& gravity,
                       const std::variant<double, Vector>& coulomb,
                       const std::variant<double, Vector>& viscous) {
             return PinocchioArm(urdf_path, gravity, per_joint(coulomb), per_joint(viscous));
           }),
           py::arg("urdf_path"), py::arg("gravity") = Eigen::Vector3d(0.0, 0.0, -9.81),
           py::arg("coulomb") = 0.0, py::arg("viscous") = 0.0)
      .def_static(
          "from_xml",
          [](const std::string& xml, const Eigen::Vector3d& gravity,
             const std::variant<double, Vector>& coulomb,
             const std::variant<double, Vector>& viscous, const std::string& name) {
            return PinocchioArm::from_xml(xml, gravity, per_joint(coulomb), per_joint(viscous),
                                          name);
          },
          py::arg("xml"), py::arg("gravity") = Eigen::Vector3d(0.0, 0.0, -9.81),
          py::arg("coulomb") = 0.0, py::arg("viscous") = 0.0, py::arg("name") = "<URDF string>",
          "The same from the URDF's XML text; name stands for the file in error messages.")
      .def_property_readonly("dof", &PinocchioArm::dof)
      .def_property_readonly("source", &PinocchioArm::source)
      .def_property_readonly("joint_names", &PinocchioArm::joint_names)
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
          "[k n, (k + 1) n).");
}

void bind_trajectory(py::module_& m) {
  m.def(
      "desired_state",
      [](const TrajectorySettings& settings, const Eigen::VectorXd& times) {
        check_finite(times, "t");
        const Trajectory trajectory(settings);
        Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> out(times.size(), 6);
        for (Eigen::Index i = 0; i < times.size(); ++i) {
          const DesiredState d = trajectory(times[i]);
          out.row(i) << d.q.transpose(), d.dq.transpose(), d.ddq.transpose();
        }
        return out;
      },
      py::arg("trajectory"), py::arg("t"),
      "The desired state at times t (n,): rows [qd1, qd2, dqd1, dqd2, ddqd1, ddqd2] (n, 6).");
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
      "A basis at x (4,) and desired qd, dqd (2,): phi (8,), d phi / dx (8, 4) and "
      "(d phi / d qd) dqd (8,).");
}

void bind_hjb(py::module_& m) {
  m.def(
      "hjb_residual",
      [](const Settings& settings, const RowsX4& states, const Eigen::VectorXd& critic_weights,
         const Eigen::VectorXd& actor_weights, double t) {
        check_size(critic_weights, 8, 1, "critic_weights");
        check_size(actor_weights, 8, 1, "actor_weights");
        check_finite(critic_weights, "critic_weights");
        check_finite(actor_weights, "actor_weights");
        check_finite(states, "x");
        check_finite(t, "t");
        return with_basis(settings.basis, [&](auto basis) {
          using Basis = decltype(basis);
          const ClosedLoop<TwoLinkArm, Basis> loop(settings);
          const typename Basis::Vector wc = critic_weights, wa = actor_weights;
          const DesiredState desired = loop.trajectory()(t);
          Eigen::VectorXd residual(states.rows());
          py::gil_scoped_release release;
          for (Eigen::Index i = 0; i < states.rows(); ++i)
            residual[i] = hjb_error<Basis>(loop.error_system(), loop.cost(),
                                           states.row(i).transpose(), desired, wc, wa);
          return residual;
        });
      },
      py::arg("settings"), py::arg("x"), py::arg("critic_weights"), py::arg("actor_weights"),
      py::arg("t"),
      "HJB error of eq. (21) at each row of x (n, 4) for weights (8,), with the desired state at "
      "time t; returns (n,).");
}

void bind_closed_loop(py::module_& m) {
  m.attr("STATE_SIZE") = PaperClosedLoop::kStateSize;
  m.def(
      "closed_loop_derivative",
      [](const Settings& settings, double t, const Eigen::VectorXd& state) {
        check_size(state, PaperClosedLoop::kStateSize, 1, "state");
        check_finite(state, "state");
        check_finite(t, "t");
        return with_basis(settings.basis, [&](auto basis) {
          using Loop = ClosedLoop<TwoLinkArm, decltype(basis)>;
          Loop loop(settings);
          typename Loop::TimeSignals signals;
          typename Loop::State x = state, rate;
          typename Loop::Outputs outputs;
          loop.begin_step(t, x);
          loop.time_signals(t, signals);
          loop.derivative(signals, x, rate, &outputs);
          py::dict out;
          out["qd"] = outputs.qd;
          out["e1"] = outputs.errors.e1;
          out["e2"] = outputs.errors.e2;
          out["tau"] = outputs.tau;
          out["u"] = outputs.u;
          out["u_hat"] = outputs.u_hat;
          out["mu"] = outputs.mu;
          out["probe"] = outputs.probe;
          out["hjb_error"] = outputs.hjb_error;
          return py::make_tuple(Eigen::VectorXd(rate), out);
        });
      },
      py::arg("settings"), py::arg("t"), py::arg("state"),
      "Right-hand side at t of state (87,) = [q, dq, Wc (8), Wa (8), Gamma (64, column-major), "
      "nu (2), J]; local extrapolation points are drawn around this state first. Returns "
      "(rate (87,), outputs dict).");
  m.def(
      "initial_state",
      [](const Settings& settings) {
        return with_basis(settings.basis, [&](auto basis) {
          return Eigen::VectorXd(ClosedLoop<TwoLinkArm, decltype(basis)>(settings).initial_state());
        });
      },
      py::arg("settings"), "The closed loop's initial state (87,).");
  m.def(
      "extrapolation_points",
      [](const Settings& settings) {
        const PaperClosedLoop loop(settings);
        const auto& points = loop.extrapolation().points();
        RowsX4 out(static_cast<Eigen::Index>(points.size()), 4);
        for (std::size_t i = 0; i < points.size(); ++i) out.row(i) = points[i].transpose();
        return out;
      },
      py::arg("settings"),
      "The fixed or grid extrapolation points (N, 4) in x (zeros for mode local, whose points are "
      "drawn around the state at each step).");
}

void bind_simulation(py::module_& m) {
  py::class_<AnySimulation>(m, "Simulation",
                            "The closed-loop run (basis from settings.basis); advance(n) takes up "
                            "to n RK4 steps.")
      .def(py::init<const Settings&>(), py::arg("settings"))
      .def("advance", &AnySimulation::advance, py::arg("max_steps"),
           py::call_guard<py::gil_scoped_release>())
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
      .def_property_readonly("state", &AnySimulation::state)
      .def(
          "recording",
          [](const AnySimulation& s) {
            const Recording r = s.recording();
            py::dict out;
            out["t"] = r.t;
            out["q"] = r.q;
            out["dq"] = r.dq;
            out["qd"] = r.qd;
            out["e1"] = r.e1;
            out["e2"] = r.e2;
            out["tau"] = r.tau;
            out["u"] = r.u;
            out["u_hat"] = r.u_hat;
            out["mu"] = r.mu;
            out["probe"] = r.probe;
            out["critic_weights"] = r.critic_weights;
            out["actor_weights"] = r.actor_weights;
            out["hjb_error"] = r.hjb_error;
            out["cost"] = r.cost;
            return out;
          },
          "Recorded rows so far: dict of arrays t, hjb_error, cost (n,), q ... (n, 2), "
          "weights (n, 8).");
}

void bind_batch(py::module_& m) {
  using AnyBatch = Batch<AnySimulation>;
  py::class_<AnyBatch>(m, "Batch",
                       "Independent runs advanced in parallel C++ threads; run i is a Simulation.")
      .def(py::init<const std::vector<Settings>&>(), py::arg("settings"))
      .def("__len__", &AnyBatch::size)
      .def("advance", &AnyBatch::advance, py::arg("max_steps"), py::arg("threads"),
           py::call_guard<py::gil_scoped_release>(),
           "Advances every running run by up to max_steps steps on `threads` threads; returns "
           "whether any is still running.")
      .def_property_readonly("running", &AnyBatch::running)
      .def(
          "simulation", [](AnyBatch& b, std::size_t i) -> AnySimulation& { return b[i]; },
          py::arg("index"), py::return_value_policy::reference_internal)
      .def("seconds", &AnyBatch::seconds, py::arg("index"),
           "Wall time spent advancing run `index`, s.");
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "adparm's C++ core (private; use the adparm package).";
  bind_settings(m);
  bind_arm(m);
  bind_urdf_arm(m);
  bind_trajectory(m);
  bind_basis(m);
  bind_hjb(m);
  bind_closed_loop(m);
  bind_simulation(m);
  bind_batch(m);
}
