// adparm._core: the thin pybind11 binding of the C++ core. It only declares: one bind_<concept>(m)
// per concept, one Settings struct passed whole, sizes in docstrings. Argument checks live in the
// core (std::invalid_argument -> ValueError); the GIL is released around the simulation loop.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "adparm/basis.hpp"
#include "adparm/hjb.hpp"
#include "adparm/open_loop.hpp"
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
  py::class_<TaskSettings>(m, "TaskSettings", "q0 (2,), dq0 (2,), qd (2,).")
      .def(py::init<>())
      .def_readwrite("q0", &TaskSettings::q0)
      .def_readwrite("dq0", &TaskSettings::dq0)
      .def_readwrite("qd", &TaskSettings::qd);
  py::class_<ControlSettings>(m, "ControlSettings", "alpha1 (2, 2) and the RISE gains.")
      .def(py::init<>())
      .def_readwrite("alpha1", &ControlSettings::alpha1)
      .def_readwrite("rise", &ControlSettings::rise);
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

void bind_basis(py::module_& m) {
  m.def(
      "basis",
      [](const Vec4& x) {
        PaperBasis::Vector phi;
        PaperBasis::Jacobian jacobian;
        PaperBasis::evaluate(x, phi, jacobian);
        return py::make_tuple(phi, jacobian);
      },
      py::arg("x"), "The paper basis at x (4,): phi (8,) and its Jacobian (8, 4).");
}

void bind_hjb(py::module_& m) {
  m.def(
      "hjb_residual",
      [](const Settings& settings, const RowsX4& states, const Eigen::VectorXd& critic_weights,
         const Eigen::VectorXd& actor_weights) {
        check_size(critic_weights, PaperBasis::kSize, 1, "critic_weights");
        check_size(actor_weights, PaperBasis::kSize, 1, "actor_weights");
        check_finite(critic_weights, "critic_weights");
        check_finite(actor_weights, "actor_weights");
        check_finite(states, "x");
        const PaperClosedLoop loop(settings);
        const PaperBasis::Vector wc = critic_weights, wa = actor_weights;
        Eigen::VectorXd residual(states.rows());
        py::gil_scoped_release release;
        for (Eigen::Index i = 0; i < states.rows(); ++i)
          residual[i] = hjb_error<PaperBasis>(loop.error_system(), loop.cost(),
                                              states.row(i).transpose(), wc, wa);
        return residual;
      },
      py::arg("settings"), py::arg("x"), py::arg("critic_weights"), py::arg("actor_weights"),
      "HJB error of eq. (21) at each row of x (n, 4) for weights (8,); returns (n,).");
}

void bind_closed_loop(py::module_& m) {
  m.attr("STATE_SIZE") = PaperClosedLoop::kStateSize;
  m.def(
      "closed_loop_derivative",
      [](const Settings& settings, double t, const Eigen::VectorXd& state) {
        check_size(state, PaperClosedLoop::kStateSize, 1, "state");
        check_finite(state, "state");
        const PaperClosedLoop loop(settings);
        PaperClosedLoop::TimeSignals signals;
        PaperClosedLoop::State x = state, rate;
        PaperClosedLoop::Outputs outputs;
        loop.time_signals(t, signals);
        loop.derivative(signals, x, rate, &outputs);
        py::dict out;
        out["e1"] = outputs.errors.e1;
        out["e2"] = outputs.errors.e2;
        out["tau"] = outputs.tau;
        out["u_hat"] = outputs.u_hat;
        out["mu"] = outputs.mu;
        out["probe"] = outputs.probe;
        out["hjb_error"] = outputs.hjb_error;
        return py::make_tuple(Eigen::VectorXd(rate), out);
      },
      py::arg("settings"), py::arg("t"), py::arg("state"),
      "Right-hand side at t of state (86,) = [q, dq, Wc (8), Wa (8), Gamma (64, column-major), "
      "nu (2)]; returns (rate (86,), outputs dict).");
  m.def(
      "initial_state",
      [](const Settings& settings) {
        return Eigen::VectorXd(PaperClosedLoop(settings).initial_state());
      },
      py::arg("settings"), "The closed loop's initial state (86,).");
}

void bind_simulation(py::module_& m) {
  py::class_<PaperSimulation>(m, "Simulation",
                              "The closed-loop run; advance(n) takes up to n RK4 steps.")
      .def(py::init<const Settings&>(), py::arg("settings"))
      .def("advance", &PaperSimulation::advance, py::arg("max_steps"),
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("status",
                             [](const PaperSimulation& s) {
                               switch (s.status()) {
                                 case RunStatus::running:
                                   return "running";
                                 case RunStatus::finished:
                                   return "finished";
                                 default:
                                   return "diverged";
                               }
                             })
      .def_property_readonly("steps", &PaperSimulation::steps)
      .def_property_readonly("step", &PaperSimulation::step)
      .def_property_readonly("divergence_time", &PaperSimulation::divergence_time)
      .def_property_readonly("reset_times", &PaperSimulation::reset_times)
      .def_property_readonly("state",
                             [](const PaperSimulation& s) { return Eigen::VectorXd(s.state()); })
      .def(
          "recording",
          [](const PaperSimulation& s) {
            const Recording r = s.recording();
            py::dict out;
            out["t"] = r.t;
            out["q"] = r.q;
            out["dq"] = r.dq;
            out["e1"] = r.e1;
            out["e2"] = r.e2;
            out["tau"] = r.tau;
            out["u_hat"] = r.u_hat;
            out["mu"] = r.mu;
            out["probe"] = r.probe;
            out["critic_weights"] = r.critic_weights;
            out["actor_weights"] = r.actor_weights;
            out["hjb_error"] = r.hjb_error;
            return out;
          },
          "Recorded rows so far: dict of arrays t (n,), q ... (n, 2), weights (n, 8).");
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "adparm's C++ core (private; use the adparm package).";
  bind_settings(m);
  bind_arm(m);
  bind_basis(m);
  bind_hjb(m);
  bind_closed_loop(m);
  bind_simulation(m);
}
