"""bench/numpy_loop.py, the plain NumPy loop that bench/bench_python.py times against the core,
computes the same closed loop as adparm.simulate (no timing here)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.simulation import core_settings

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import numpy_loop  # noqa: E402

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

STEPS = 300


def assert_matches_core(config: adparm.Config, steps: int = STEPS) -> None:
    states = numpy_loop.NumpyPaperLoop(config).run(steps)
    index, pairs = numpy_loop.recorded_pairs(config, states)
    assert index[-1] == steps
    np.testing.assert_array_equal(index[:-1] % config.sim.record_every, 0)
    for name, (ours, core) in pairs.items():
        assert np.allclose(ours, core, rtol=1e-10, atol=1e-9), (
            f"{name}: max |difference| {np.abs(ours - core).max():.3e}"
        )


def test_paper_config_matches_core() -> None:
    config = adparm.paper_config()
    assert config.sim.record_every == 10
    assert_matches_core(config)


@pytest.mark.parametrize(
    "changes",
    [
        {"task": {"qd": [0.3, -0.2]}},
        {"critic": {"eta_c": 200.0}, "controller": {"rise": False}},
        {
            "controller": {"basis": "paper"},
            "model": {"p1": 4.5, "viscous": 0.2},
            "probe": {"ramp": 0.1},
            "sim": {"record_every": 7},
        },
    ],
    ids=["set-point", "eta_c-no-rise", "paper-basis-model-error"],
)
def test_variations_match_core(changes: dict) -> None:
    assert_matches_core(adparm.paper_config().updated(changes))


def test_covariance_reset_happens_within_the_compared_steps() -> None:
    config = adparm.paper_config().updated({"sim": {"T": STEPS * 1e-3}})
    assert adparm.simulate(config).covariance_resets > 0


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"controller": {"kind": "pd"}}, "controller.kind"),
        ({"extrapolation": {"points": 4}}, "extrapolation.points"),
        ({"task": {"qd": {"kind": "sinusoid"}}}, "task.qd"),
        ({"cost": {"input_bound": 5.0}}, "cost.input_bound"),
    ],
)
def test_out_of_scope_config_is_refused(changes: dict, field: str) -> None:
    with pytest.raises(ValueError, match=re.escape(field)):
        numpy_loop.NumpyPaperLoop(adparm.paper_config().updated(changes))


# --- bench/numpy_pinocchio_loop.py: NumPy + Pinocchio's Python bindings, any URDF arm -------------

import numpy_pinocchio_loop  # noqa: E402

TWO_LINK_URDF = Path(__file__).resolve().parents[1] / "examples" / "arms" / "two_link.urdf"
#: state entries of the two-link loop with the quadratic basis (10 functions): q, dq, Wc, Wa, J
PINOCCHIO_FIELDS = {
    "q": slice(0, 2),
    "dq": slice(2, 4),
    "critic_weights": slice(4, 14),
    "actor_weights": slice(14, 24),
    "cost": -1,
}


def loop_settings(config: adparm.Config) -> numpy_pinocchio_loop.LoopSettings:
    """The NumPy + Pinocchio loop's settings of ``config`` (n joints; sized settings broadcast)."""
    p, c, a, e = config.plant, config.critic, config.actor, config.extrapolation
    n = config.dof

    def sized(value: object, size: int) -> np.ndarray:
        return np.broadcast_to(np.asarray(value, dtype=float), (size,)).copy()

    return numpy_pinocchio_loop.LoopSettings(
        q0=sized(config.task.q0, n),
        dq0=sized(config.task.dq0, n),
        qd=sized(config.task.qd, n),
        critic_weights=config.initial_weights("critic_weights"),
        actor_weights=config.initial_weights("actor_weights"),
        Q=np.array(config.cost.Q, dtype=float),
        R=np.array(config.cost.R, dtype=float),
        alpha1=np.array(config.control.alpha1, dtype=float),
        disturbance=sized(p.disturbance, n),
        eta_c=c.eta_c,
        nu=c.nu,
        gamma0=c.gamma0,
        epsilon_T=config.resolved_epsilon_T,
        eta_a1=a.eta_a1,
        eta_a2=a.eta_a2,
        weight_bound=a.weight_bound,
        points=e.points,
        box=sized(e.box, 2 * n),
        seed=e.seed,
        dt=config.sim.dt,
    )


def pinocchio_loop_of(config: adparm.Config) -> numpy_pinocchio_loop.NumpyPinocchioLoop:
    """The NumPy + Pinocchio loop of the built-in two-link arm of ``config``: the same arm from
    examples/arms/two_link.urdf with gravity [0, 0, -9.8] and the config's friction."""
    p = config.plant
    arm = numpy_pinocchio_loop.PinocchioArm(
        TWO_LINK_URDF, [0.0, 0.0, -9.8], coulomb=p.coulomb, viscous=p.viscous
    )
    basis = numpy_pinocchio_loop.QuadraticBasis(arm.dof)
    return numpy_pinocchio_loop.NumpyPinocchioLoop(arm, basis, loop_settings(config))


def pinocchio_config(**changes) -> adparm.Config:
    """The paper's run with the quadratic basis (the dynamic path), no RISE, no probing signal."""
    base = {"controller": {"basis": "quadratic", "rise": False}, "probe": {"until": 0.0}}
    for key, value in changes.items():
        base.setdefault(key, {}).update(value)
    return adparm.paper_config().updated(base)


@pytest.mark.parametrize(
    "points, critic", [(0, {}), (10, {}), (0, {"epsilon_T": 1.0})], ids=["N0", "N10", "N0-resets"]
)
def test_numpy_pinocchio_loop_matches_core_on_the_paper_arm(points: int, critic: dict) -> None:
    steps = 600
    config = pinocchio_config(
        extrapolation={"points": points}, critic=critic, sim={"T": steps * 1e-3}
    )
    states = pinocchio_loop_of(config).run(steps)
    result = adparm.simulate(config)
    index = np.rint(np.asarray(result.t) / config.sim.dt).astype(int)
    assert index[-1] == steps
    for name, entries in PINOCCHIO_FIELDS.items():
        ours, core = states[index][..., entries], np.asarray(getattr(result, name))
        scale = max(1.0, float(np.abs(core).max()))
        difference = float(np.abs(ours - core).max())
        assert difference <= 1e-8 * scale, f"{name}: max |difference| {difference:.3e}"
    # the run learns (the weights move); with points (epsilon_T = 1e-3) or a raised epsilon_T the
    # covariance is reset within the compared steps
    assert np.abs(states[-1, 4:14] - states[0, 4:14]).max() > 0.1
    assert (result.covariance_resets > 0) == (points > 0 or bool(critic))


def test_numpy_pinocchio_loop_differs_from_the_core_on_another_arm() -> None:
    # the comparison above can fail: a 10 % heavier link 2 changes the states far above 1e-8
    steps = 200
    config = pinocchio_config(extrapolation={"points": 10}, sim={"T": steps * 1e-3})
    states = pinocchio_loop_of(config).run(steps)
    heavier = config.updated({"plant": {"p2": 1.1 * config.plant.p2}})
    result = adparm.simulate(heavier)
    assert np.abs(states[-1, 0:2] - np.asarray(result.q)[-1]).max() > 1e-6


def test_quadratic_basis_matches_the_core_expression_basis(rng) -> None:
    # the same functions in the same order (adparm's "quadratic" family) and the same Jacobian
    basis = numpy_pinocchio_loop.QuadraticBasis(3)
    core = adparm.ExpressionBasis("quadratic", joints=3)
    assert basis.size == core.size == 21
    for x in rng.uniform(-1.0, 1.0, (5, 6)):
        phi, jacobian, _ = core.evaluate(x)
        np.testing.assert_array_equal(basis.phi(x), phi)
        np.testing.assert_array_equal(basis.jacobian(x), jacobian)


@pytest.mark.parametrize("name", ["two_link", "planar_3link", "spatial_3dof", "ur5"])
def test_numpy_pinocchio_arm_matches_the_core_urdf_arm(name: str, rng) -> None:
    # the arm of urdf_speed.py's NumPy loop is the core's (continuous joints as angles, friction)
    if name == "ur5":
        path = adparm.example_robot_urdf("ur5")
    else:
        path = TWO_LINK_URDF.parent / f"{name}.urdf"
    gravity, coulomb, viscous = [0.1, -0.2, -9.81], -0.1, 0.3
    ours = numpy_pinocchio_loop.PinocchioArm(path, gravity, coulomb=coulomb, viscous=viscous)
    core = adparm.UrdfArm(path, gravity=gravity, coulomb=coulomb, viscous=viscous)
    assert ours.dof == core.dof
    for _ in range(5):
        q, dq = rng.uniform(-2.0, 2.0, (2, core.dof))
        terms = core.terms(q, dq)
        for key, value in zip("MCGF", ours.terms(q, dq), strict=True):
            np.testing.assert_allclose(value, terms[key], rtol=1e-12, atol=1e-12, err_msg=key)


# --- the structured basis in the NumPy + Pinocchio loop ---------------------------------------

PLANAR_EXAMPLE = TWO_LINK_URDF.parents[1] / "planar_3link.toml"


@pytest.mark.parametrize("name", ["planar_3link", "spatial_3dof", "ur5"])
def test_numpy_structured_basis_matches_the_core(name: str, rng) -> None:
    # phi from Pinocchio's kinetic-energy regressor, the Jacobian from its kinematics derivatives
    # (Python bindings) against the core's structured basis, with the core's base parameters
    path = (
        adparm.example_robot_urdf("ur5") if name == "ur5" else TWO_LINK_URDF.parent / f"{name}.urdf"
    )
    core = adparm.UrdfArm(path)
    values, columns, _ = core.base_parameters()
    arm = numpy_pinocchio_loop.PinocchioArm(path, [0.0, 0.0, -9.81])
    qd = rng.uniform(-1.0, 1.0, arm.dof)
    ours = numpy_pinocchio_loop.StructuredBasis(arm, values, columns, qd)
    assert ours.size == len(core.structured_names())
    np.testing.assert_array_equal(
        ours.optimal_weights(np.eye(arm.dof)), core.structured_weights(np.eye(arm.dof))
    )
    for x in rng.uniform(-1.0, 1.0, (5, 2 * arm.dof)):
        phi, jacobian, _ = core.structured_basis(x, qd)
        np.testing.assert_allclose(ours.phi(x), phi, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ours.jacobian(x), jacobian, rtol=1e-12, atol=1e-12)


def structured_loop_of(config: adparm.Config) -> numpy_pinocchio_loop.NumpyPinocchioLoop:
    """The NumPy + Pinocchio loop of a URDF ``config`` (constant set-point, no RISE, no probing)
    with the structured basis of the core's base parameters."""
    p = config.plant
    arm = numpy_pinocchio_loop.PinocchioArm(
        p.urdf, p.resolved_gravity, coulomb=p.coulomb, viscous=p.viscous
    )
    values, columns, _ = adparm.UrdfArm(p.urdf).base_parameters()
    settings = loop_settings(config)
    basis = numpy_pinocchio_loop.StructuredBasis(arm, values, columns, settings.qd)
    return numpy_pinocchio_loop.NumpyPinocchioLoop(arm, basis, settings)


def assert_loop_states_match(states, result, n: int, K: int) -> None:
    """The NumPy loop's states [q, dq, Wc, Wa, ...] at the core's recorded rows match its q, dq,
    critic and actor weights and cost to 1e-8 of each array's scale."""
    index = np.rint(np.asarray(result.t) / result.config.sim.dt).astype(int)
    fields = {
        "q": slice(0, n),
        "dq": slice(n, 2 * n),
        "critic_weights": slice(2 * n, 2 * n + K),
        "actor_weights": slice(2 * n + K, 2 * n + 2 * K),
        "cost": -1,
    }
    for name, entries in fields.items():
        ours, core = states[index][..., entries], np.asarray(getattr(result, name))
        scale = max(1.0, float(np.abs(core).max()))
        difference = float(np.abs(ours - core).max())
        assert difference <= 1e-8 * scale, f"{name}: max |difference| {difference:.3e}"


@pytest.mark.parametrize("points", [0, 10])
def test_numpy_pinocchio_loop_matches_core_with_the_structured_basis(points: int) -> None:
    # examples/planar_3link.toml (structured basis, default weights K = I and the arm's base
    # parameters; W* has K = diag(2, 1, 0.5)) without RISE, through the NumPy loop and the core;
    # the NumPy loop has the paper's laws, without the positive_e2 projection (which acts in
    # this run at t = 0.23 s; tests/test_urdf_learning.py tests it)
    steps = 400
    config = adparm.load_config(PLANAR_EXAMPLE).updated(
        {
            "actor": {"positive_e2": False},
            "controller": {"basis": "structured", "rise": False},
            "extrapolation": {"points": points},
            "sim": {"T": steps * 1e-3},
        }
    )
    n = config.dof
    states = structured_loop_of(config).run(steps)
    result = adparm.simulate(config)
    index = np.rint(np.asarray(result.t) / config.sim.dt).astype(int)
    assert index[-1] == steps
    K = len(adparm.basis_names(config))
    assert K == 13
    assert_loop_states_match(states, result, n, K)
    # the critic learns (its e1 block moves towards K = diag(2, 1, 0.5))
    assert np.abs(states[-1, 2 * n : 2 * n + 6] - states[0, 2 * n : 2 * n + 6]).max() > 0.01


def test_numpy_pinocchio_loop_matches_core_through_low_rank_steps() -> None:
    # examples/ur5.toml's structured basis has 55 functions: without points the core takes
    # low-rank RK4 steps (ClosedLoop::step, more than 24 functions: each stage's rank-one dGamma
    # kept as a vector, Gamma formed once per step); the NumPy loop forms every stage's Gamma
    ur5 = TWO_LINK_URDF.parents[1] / "ur5.toml"
    steps = 150
    config = adparm.load_config(ur5).updated(
        {
            "actor": {"positive_e2": False},
            "controller": {"rise": False},
            "extrapolation": {"points": 0},
            "sim": {"T": steps * 1e-3},
        }
    )
    n = config.dof
    K = len(adparm.basis_names(config))
    assert K == 55
    states = structured_loop_of(config).run(steps)
    result = adparm.simulate(config)
    index = np.rint(np.asarray(result.t) / config.sim.dt).astype(int)
    assert index[-1] == steps
    assert_loop_states_match(states, result, n, K)
    # Gamma at the end: the same state layout [q, dq, Wc, Wa, Gamma, nu, J] in both loops
    simulation = _core.Simulation(core_settings(config))
    simulation.advance(steps)
    gamma = slice(2 * n + 2 * K, 2 * n + 2 * K + K * K)
    core_gamma = np.asarray(simulation.state)[gamma]
    difference = float(np.abs(states[-1, gamma] - core_gamma).max())
    assert difference <= 1e-8 * max(1.0, float(np.abs(core_gamma).max()))
    # the critic learns
    assert np.abs(states[-1, 2 * n : 2 * n + 21] - states[0, 2 * n : 2 * n + 21]).max() > 1e-3
