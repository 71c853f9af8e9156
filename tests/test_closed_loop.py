"""The C++ right-hand side of the closed loop equals the independent NumPy implementation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.simulation import core_settings

import numpy_reference as reference

KINDS = ("adp", "rise", "pd", "optimal")
BASES = ("augmented", "paper")
TRAJECTORIES = ("set-point", "sinusoid", "samples")
MODES = ("off", "fixed", "grid", "local")


def random_state(rng: np.random.Generator) -> np.ndarray:
    A = rng.normal(size=(8, 8))
    Gamma = A @ A.T + 0.1 * np.eye(8)
    return np.concatenate(
        [
            rng.uniform(-1.5, 1.5, 2),
            rng.uniform(-3, 3, 2),
            rng.normal(scale=3, size=8),
            rng.normal(scale=3, size=8),
            Gamma.reshape(-1, order="F"),
            rng.normal(size=2),
            rng.uniform(0, 10, 1),
        ]
    )


def random_trajectory(rng: np.random.Generator, kind: str):
    if kind == "set-point":
        return rng.uniform(-1, 1, 2)
    if kind == "sinusoid":
        n = int(rng.integers(1, 4))
        return {
            "kind": "sinusoid",
            "amplitude": rng.uniform(-1, 1, (2, n)),
            "frequency": rng.uniform(0, 5, (2, n)),
            "phase": rng.uniform(0, 6.3, (2, n)),
            "offset": rng.uniform(-1, 1, 2),
        }
    # samples from t <= 0 to t = 8 (sim.T), uneven spacing: the comparison times, up to 10 s,
    # also reach past the last sample, where the desired state is clamped
    t = np.concatenate([[-rng.uniform(0, 1)], np.sort(rng.uniform(0.1, 7.5, 8)), [8.0]])
    return {
        "kind": "samples",
        "t": t,
        "q": rng.uniform(-1, 1, (t.size, 2)),
        "boundary": str(rng.choice(["not-a-knot", "clamped", "natural"])),
    }


def random_extrapolation(rng: np.random.Generator, mode: str) -> dict:
    if mode == "off":
        return {"points": 0}
    points = 16 if mode == "grid" else int(rng.integers(1, 5))
    box = rng.uniform(0.1, 2.0, 4) if rng.uniform() < 0.5 else rng.uniform(0.1, 2.0)
    seed = int(rng.integers(0, 2**32))
    # the box's centre from its own stream (the other cases' draws stay as they were)
    centre = np.random.default_rng(seed).uniform(-0.5, 0.5, 4)
    return {"points": points, "mode": mode, "box": box, "centre": centre, "seed": seed}


def random_config(
    rng: np.random.Generator,
    kind: str = "adp",
    rise: bool = True,
    basis: str = "augmented",
    trajectory: str = "set-point",
    mode: str = "off",
) -> adparm.Config:
    p2 = rng.uniform(0.5, 2.0)
    p3 = rng.uniform(0.1, 1.0)
    qd = random_trajectory(rng, trajectory)
    return adparm.paper_config().updated(
        {
            "plant": {
                "p1": p2 + p3**2 / p2 + rng.uniform(0.5, 4),
                "p2": p2,
                "p3": p3,
                "viscous": rng.uniform(0, 1),
                "coulomb": rng.uniform(-0.5, 0.5),
                "disturbance": rng.uniform(0, 1, 2),
            },
            "model": {"p1": 6.0, "g1": 10.0, "coulomb": 0.0},
            "task": {
                "q0": rng.uniform(-1, 1, 2),
                "dq0": rng.uniform(-1, 1, 2),
                "qd": qd,
            },
            "control": {
                # diagonal above the off-diagonal entries: -alpha1 Hurwitz (config refuses others)
                "alpha1": rng.uniform(0.5, 5, (2, 2)) + 5.0 * np.eye(2),
                "ks": rng.uniform(0, 20),
                "alpha2": rng.uniform(0, 3),
                "beta1": rng.uniform(0, 2),
            },
            "critic": {"eta_c": rng.uniform(1, 1000), "nu": rng.uniform(0, 2)},
            "actor": {
                "eta_a1": rng.uniform(0, 1),
                "eta_a2": rng.uniform(0, 2),
                "weight_bound": 5.0,
            },
            "probe": {
                "amplitude": rng.uniform(-3, 3, (2, 3)),
                "frequencies": rng.uniform(0, 10, 3),
                "phases": rng.uniform(0, 6.3, (2, 3)),
                "until": 5.0,
                "ramp": rng.uniform(0, 10),
            },
            "controller": {
                "kind": kind,
                "rise": rise,
                "basis": basis,
                "kp": rng.uniform(0, 100, (2, 2)) if rng.uniform() < 0.5 else rng.uniform(0, 100),
                "kd": rng.uniform(0, 20),
            },
            "extrapolation": random_extrapolation(rng, mode),
            "sim": {"T": qd["t"][-1] if trajectory == "samples" else 10.0},
        }
    )


# every controller kind with RISE on and off (kind rise needs it on), both bases, all three
# trajectories and every extrapolation mode; adp, which learns, gets all combinations
CASES = [
    ("adp", rise, basis, trajectory, mode)
    for (basis, trajectory, mode), rise in zip(
        itertools.product(BASES, TRAJECTORIES, MODES),
        itertools.cycle((True, False, True)),
        strict=False,
    )
] + [
    (kind, rise, BASES[i % 2], TRAJECTORIES[i % 3], MODES[i % 4])
    for i, (kind, rise) in enumerate(itertools.product(("rise", "pd", "optimal"), (True, False)))
    if kind != "rise" or rise
]


def assert_close(actual, expected, name: str, rtol: float = 1e-12) -> None:
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, (name, actual.shape, expected.shape)
    scale = max(1.0, np.abs(expected).max())
    assert np.abs(actual - expected).max() <= rtol * scale, (name, actual, expected)


def compare_right_hand_sides(config: adparm.Config, rng: np.random.Generator, n: int) -> None:
    settings = core_settings(config)
    for _ in range(n):
        state = random_state(rng)
        t = rng.uniform(0, 10)
        rate, outputs = _core.closed_loop_derivative(settings, t, state)
        expected_rate, expected_outputs = reference.rhs(config, t, state)
        assert_close(rate, expected_rate, "rate")
        assert set(outputs) == set(expected_outputs)
        for name, value in expected_outputs.items():
            assert_close(outputs[name], value, name)


def test_cases_cover_every_option() -> None:
    assert {c[0] for c in CASES} == set(KINDS)
    assert {(c[0], c[1]) for c in CASES} >= {(k, r) for k in KINDS for r in (True, False)} - {
        ("rise", False)
    }
    for index, options in enumerate((BASES, TRAJECTORIES, MODES), start=2):
        assert {c[index] for c in CASES} == set(options)
    assert len({c[2:] for c in CASES if c[0] == "adp"}) == len(BASES) * len(TRAJECTORIES) * 4


@pytest.mark.parametrize(("kind", "rise", "basis", "trajectory", "mode"), CASES)
def test_right_hand_side_matches_numpy(kind, rise, basis, trajectory, mode) -> None:
    rng = np.random.default_rng(CASES.index((kind, rise, basis, trajectory, mode)))
    config = random_config(rng, kind, rise, basis, trajectory, mode)
    assert len(reference.rhs(config, 0.0, random_state(rng))[0]) == _core.STATE_SIZE
    compare_right_hand_sides(config, rng, 12)


def test_right_hand_side_matches_numpy_for_the_paper() -> None:
    compare_right_hand_sides(adparm.paper_config(), np.random.default_rng(0), 25)


@pytest.mark.parametrize("mode", ["fixed", "grid", "local"])
def test_extrapolation_changes_the_learning_rates(mode) -> None:
    # the comparison above would miss a core that ignored the points: they do matter
    rng = np.random.default_rng(11)
    config = random_config(rng, mode=mode, trajectory="sinusoid")
    without = config.updated({"extrapolation": {"points": 0}})
    state = random_state(rng)
    rate = _core.closed_loop_derivative(core_settings(config), 0.7, state)[0]
    rate_without = _core.closed_loop_derivative(core_settings(without), 0.7, state)[0]
    learning = slice(4, 84)
    assert np.abs(rate[learning] - rate_without[learning]).max() > 1e-3
    np.testing.assert_array_equal(rate[:4], rate_without[:4])
    # and another seed (fixed, local) gives other points
    if mode != "grid":
        reseeded = config.updated({"extrapolation": {"seed": config.extrapolation.seed + 1}})
        rate_reseeded = _core.closed_loop_derivative(core_settings(reseeded), 0.7, state)[0]
        assert np.abs(rate[learning] - rate_reseeded[learning]).max() > 1e-3


def test_local_points_are_drawn_around_the_given_state() -> None:
    rng = np.random.default_rng(12)
    config = random_config(rng, mode="local", trajectory="samples").updated(
        {"extrapolation": {"points": 3, "box": 1e-3}}
    )
    state = random_state(rng)
    t = 1.3
    x = reference.tracking_error(config, t, state)
    draw = np.random.RandomState(config.extrapolation.seed).random_sample((3, 4))
    points = (x + config.extrapolation.centre_vector()) + 1e-3 * (2 * draw - 1)
    rate = _core.closed_loop_derivative(core_settings(config), t, state)[0]
    assert_close(rate, reference.rhs(config, t, state, points)[0], "rate")
    # points around x = 0 instead (what the fixed mode would use) do not match
    wrong = reference.rhs(config, t, state, points - x)[0]
    assert np.abs(rate[4:84] - wrong[4:84]).max() > 1e-6 * np.abs(rate[4:84]).max()


@pytest.mark.parametrize("kind", ["rise", "pd", "optimal"])
def test_only_adp_learns_and_probes(kind) -> None:
    rng = np.random.default_rng(13)
    config = random_config(rng, kind=kind, mode="fixed", trajectory="sinusoid")
    state = random_state(rng)
    rate, outputs = _core.closed_loop_derivative(core_settings(config), 0.5, state)
    np.testing.assert_array_equal(rate[4:84], 0.0)
    np.testing.assert_array_equal(outputs["probe"], 0.0)
    adp_rate, adp_outputs = _core.closed_loop_derivative(
        core_settings(config.updated({"controller": {"kind": "adp"}})), 0.5, state
    )
    assert np.abs(adp_rate[4:84]).max() > 0.0
    assert np.abs(adp_outputs["probe"]).max() > 0.0


def test_cost_rate_is_the_running_cost_of_the_applied_input() -> None:
    rng = np.random.default_rng(14)
    for kind in KINDS:
        config = random_config(rng, kind=kind, trajectory="sinusoid")
        state = random_state(rng)
        rate, outputs = _core.closed_loop_derivative(core_settings(config), 0.4, state)
        x = np.concatenate([outputs["e1"], outputs["e2"]])
        u = np.asarray(outputs["u"])
        expected = x @ np.array(config.cost.Q) @ x + u @ np.array(config.cost.R) @ u
        assert rate[86] == pytest.approx(expected, rel=1e-12)
        if kind == "rise":
            np.testing.assert_array_equal(u, 0.0)


def test_projection_is_active_in_the_comparison() -> None:
    # weights outside the bound with an outward rate (for every other state, Wc beyond Wa pulls Wa
    # outward through eta_a2): the projected rate is tangent, and differs from the free one
    rng = np.random.default_rng(1)
    config = random_config(rng, mode="fixed").updated(
        {"actor": {"weight_bound": 1.0, "eta_a1": 1e-4, "positive_e2": False}}
    )
    free = config.updated({"actor": {"weight_bound": 1e9}})
    active = 0
    for i in range(20):
        state = random_state(rng)
        if i % 2:
            state[4:12] = 3.0 * state[12:20] + rng.normal(size=8)
        rate, _ = _core.closed_loop_derivative(core_settings(config), 0.3, state)
        free_rate, _ = _core.closed_loop_derivative(core_settings(free), 0.3, state)
        Wa, dWa, dWa_free = state[12:20], rate[12:20], free_rate[12:20]
        assert Wa @ dWa <= 1e-12 * np.linalg.norm(Wa) * np.linalg.norm(dWa)
        if Wa @ dWa_free > 0:
            active += 1
            assert abs(Wa @ dWa) <= 1e-12 * np.linalg.norm(Wa) * np.linalg.norm(dWa_free)
            assert np.linalg.norm(dWa - dWa_free) > 1e-3 * np.linalg.norm(dWa_free)
        else:
            np.testing.assert_array_equal(dWa, dWa_free)
        assert_close(rate, reference.rhs(config, 0.3, state)[0], "rate")
        assert_close(free_rate, reference.rhs(free, 0.3, state)[0], "free rate")
    assert 5 <= active <= 15


@pytest.mark.parametrize("basis", BASES)
def test_hjb_residual_with_a_moving_target_matches_numpy(basis) -> None:
    rng = np.random.default_rng(15)
    config = random_config(rng, basis=basis, trajectory="sinusoid")
    X = rng.uniform(-2, 2, (20, 4))
    Wc, Wa = rng.normal(size=8), rng.normal(size=8)
    for t in (0.0, 0.9, 4.2):
        actual = _core.hjb_residual(core_settings(config), X, Wc, Wa, t)
        expected = [reference.hjb_residual(config, x, Wc, Wa, t) for x in X]
        assert_close(actual, expected, "hjb_residual")


def central_difference(function, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    return np.column_stack(
        [(function(x + h * e) - function(x - h * e)) / (2 * h) for e in np.eye(x.size)]
    )


@pytest.mark.parametrize("kind", BASES)
def test_basis_matches_numpy_and_finite_differences(kind) -> None:
    rng = np.random.default_rng(5)
    core_kind = getattr(_core.BasisKind, kind)
    for x in rng.uniform(-2, 2, (40, 4)):
        qd, dqd = rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)
        phi, jacobian, rate = _core.basis(core_kind, x, qd, dqd)
        expected = reference.basis(kind, x, qd, dqd)
        for name, actual, value in zip(
            ("phi", "jacobian", "rate"), (phi, jacobian, rate), expected, strict=True
        ):
            assert_close(actual, value, name)

        def phi_at(y, qd=qd, dqd=dqd):
            return _core.basis(core_kind, y, qd, dqd)[0]

        numeric = central_difference(phi_at, x)
        np.testing.assert_allclose(jacobian, numeric, rtol=0, atol=1e-8)
        # desired_rate = (d phi / d qd) dqd: the derivative of phi along qd + s dqd
        along = central_difference(
            lambda s, x=x, qd=qd, dqd=dqd: phi_at(x, qd + s[0] * dqd), np.zeros(1)
        )[:, 0]
        np.testing.assert_allclose(rate, along, rtol=0, atol=1e-8)
        if kind == "augmented":
            assert set(np.flatnonzero(rate)) <= {4, 7}
            assert np.abs(rate[[4, 7]]).max() > 0.0
        else:
            np.testing.assert_array_equal(rate, 0.0)


def test_augmented_basis_is_the_paper_basis_when_qd2_is_zero() -> None:
    rng = np.random.default_rng(6)
    for x in rng.uniform(-2, 2, (20, 4)):
        qd = np.array([rng.uniform(-2, 2), 0.0])
        dqd = np.array([rng.uniform(-3, 3), 0.0])
        augmented = _core.basis(_core.BasisKind.augmented, x, qd, dqd)
        paper = _core.basis(_core.BasisKind.paper, x, qd, dqd)
        for a, p in zip(augmented, paper, strict=True):
            assert_close(a, p, "basis")
        # but not when qd2 moves (rate) or is not zero (phi, jacobian)
        moving = _core.basis(_core.BasisKind.augmented, x, qd, dqd + [0.0, 1.0])[2]
        assert np.abs(moving).max() > 1e-6 * x[2] ** 2
        shifted = _core.basis(_core.BasisKind.augmented, x, qd + [0.0, 0.5], dqd)
        assert np.abs(shifted[0] - paper[0]).max() > 1e-3 * (x[2] ** 2 + abs(x[2] * x[3]))


def test_initial_state_layout() -> None:
    config = random_config(np.random.default_rng(3), trajectory="sinusoid")
    np.testing.assert_array_equal(
        _core.initial_state(core_settings(config)), reference.initial_state(config)
    )
    assert _core.STATE_SIZE == reference.STATE_SIZE == 87


@pytest.mark.parametrize(
    ("mode", "points", "box"),
    [
        ("fixed", 7, [0.1, 0.2, 0.3, 0.4]),
        ("fixed", 1, 2.5),
        ("grid", 1, 1.0),
        ("grid", 16, [0.1, 0.2, 0.3, 0.4]),
        ("grid", 81, 0.5),
        ("local", 5, 1.0),
    ],
)
def test_extrapolation_points(mode, points, box) -> None:
    config = adparm.paper_config().updated(
        {"extrapolation": {"mode": mode, "points": points, "box": box, "seed": 1234}}
    )
    actual = adparm.extrapolation_points(config)
    assert actual.shape == (points, 4)
    half = np.broadcast_to(np.asarray(box, dtype=float), (4,))
    if mode == "fixed":
        draw = np.random.RandomState(1234).random_sample((points, 4))
        np.testing.assert_array_equal(actual, half * (2 * draw - 1))
    elif mode == "grid":
        m = round(points**0.25)
        axes = [np.linspace(-h, h, m) if m > 1 else [0.0] for h in half]
        np.testing.assert_allclose(actual, list(itertools.product(*axes)), rtol=0, atol=1e-15)
        np.testing.assert_allclose(actual[0], -half if m > 1 else 0.0, rtol=0, atol=1e-15)
        if m > 1:  # last axis fastest
            np.testing.assert_allclose(
                actual[1], [-half[0], -half[1], -half[2], -half[3] + 2 * half[3] / (m - 1)]
            )
    else:
        np.testing.assert_array_equal(actual, 0.0)
    np.testing.assert_allclose(actual, reference.extrapolation_points(config), rtol=0, atol=1e-15)


def compare_simulation(config: adparm.Config, steps: int) -> tuple[dict, np.ndarray, np.ndarray]:
    run = _core.Simulation(core_settings(config))
    assert run.advance(steps) == steps
    recording = run.recording()
    expected, resets = reference.simulate(config, steps)
    assert recording["t"].shape == (steps + 1,)
    np.testing.assert_allclose(recording["t"], config.sim.dt * np.arange(steps + 1), atol=1e-12)
    columns = {
        "q": slice(0, 2),
        "dq": slice(2, 4),
        "critic_weights": slice(4, 12),
        "actor_weights": slice(12, 20),
        "cost": 86,
    }
    for name, column in columns.items():
        scale = max(1.0, np.abs(expected[:, column]).max())
        np.testing.assert_allclose(
            recording[name], expected[:, column], rtol=0, atol=1e-10 * scale, err_msg=name
        )
    assert_close(run.state, expected[-1], "final state", rtol=1e-10)
    np.testing.assert_allclose(run.reset_times, resets, rtol=0, atol=1e-12)
    # the recorded outputs are those of the right-hand side at the recorded states
    for k in range(0, steps + 1, 7):
        _, outputs = reference.rhs(config, recording["t"][k], expected[k])
        for name, value in outputs.items():
            assert_close(recording[name][k], value, name, rtol=1e-10)
    return recording, expected, resets


SINUSOID = {
    "kind": "sinusoid",
    "amplitude": [[0.5, 0.2], [0.3, 0.1]],
    "frequency": [[1.0, 2.0], [1.5, 0.5]],
    "phase": [[0.1, 0.2], [0.3, 0.4]],
    "offset": [0.1, -0.2],
}


def test_short_simulation_matches_numpy_rk4_local_sinusoid_adp() -> None:
    config = adparm.paper_config().updated(
        {
            "sim": {"T": 0.2, "dt": 1e-3, "record_every": 1},
            "task": {"q0": [0.3, -0.2], "qd": SINUSOID},
            "extrapolation": {"points": 4, "mode": "local", "box": 0.3, "seed": 11},
            # a few resets of Gamma, which evolves in between
            "critic": {"eta_c": 400.0, "epsilon_T": 1e-3},
        }
    )
    recording, expected, resets = compare_simulation(config, 200)
    assert 2 < len(resets) < 50  # Gamma is reset a few times and evolves in between
    assert np.abs(recording["critic_weights"][-1] - 1.0).max() > 0.1
    # the comparison tells the local draws apart: drawing once at x(0), or another seed, gives
    # runs far outside its tolerance
    drawn_once, _ = reference.simulate(config, 200, redraw=False)
    assert np.abs(drawn_once[-1, 4:20] - expected[-1, 4:20]).max() > 1e-4
    reseeded = _core.Simulation(core_settings(config.updated({"extrapolation": {"seed": 12}})))
    reseeded.advance(200)
    assert np.abs(reseeded.state[4:20] - expected[-1, 4:20]).max() > 1e-4


def test_points_of_a_moving_desired_state_are_those_prepared_at_every_evaluation() -> None:
    """A URDF arm tracking a sinusoid with fixed extrapolation points: the core prepares the points
    once per desired state (RK4's second and third stages share it, the fourth the next step's
    first); its run equals RK4 over the core's derivative, a fresh loop at every evaluation that
    prepares them there."""
    config = adparm.Config.from_dict(
        {
            "plant": {"urdf": "examples/arms/planar_3link.urdf"},
            "task": {
                "qd": {
                    "kind": "sinusoid",
                    "amplitude": [0.4, 0.3, 0.2],
                    "frequency": [1.0, 1.5, 2.0],
                    "offset": [0.0, 0.2, -0.1],
                }
            },
            "extrapolation": {"points": 6},
            "critic": {"epsilon_T": 0.0},  # no resets: a plain RK4 run
            "sim": {"dt": 1e-3, "T": 0.03},
        }
    )
    settings = core_settings(config)
    simulation = _core.Simulation(settings)
    state = np.array(simulation.state, dtype=float)
    steps, dt = 30, config.sim.dt

    def rate(t: float, y: np.ndarray) -> np.ndarray:
        return np.asarray(_core.closed_loop_derivative(settings, t, y)[0])

    t = 0.0
    for _ in range(steps):
        k1 = rate(t, state)
        k2 = rate(t + 0.5 * dt, state + 0.5 * dt * k1)
        k3 = rate(t + 0.5 * dt, state + 0.5 * dt * k2)
        k4 = rate(t + dt, state + dt * k3)
        state = state + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        t += dt
    simulation.advance(steps)
    np.testing.assert_allclose(simulation.state, state, rtol=1e-11, atol=1e-13)
    # the points matter here
    alone = _core.Simulation(core_settings(config.updated({"extrapolation": {"points": 0}})))
    alone.advance(steps)
    assert np.abs(np.asarray(alone.state) - state).max() > 1e-9


def test_short_simulation_matches_numpy_rk4_samples_pd() -> None:
    t = [-0.1, 0.05, 0.1, 0.15, 0.25]
    config = adparm.paper_config().updated(
        {
            "sim": {"T": 0.2, "dt": 1e-3, "record_every": 1},
            "task": {
                "q0": [0.2, 0.1],
                "qd": {
                    "kind": "samples",
                    "t": t,
                    "q": [[0.0, 0.0], [0.3, 0.1], [0.5, -0.2], [0.2, 0.4], [0.0, 0.0]],
                },
            },
            "controller": {"kind": "pd", "kp": [[60.0, 5.0], [5.0, 40.0]], "kd": 8.0},
        }
    )
    recording, expected, _ = compare_simulation(config, 200)
    assert np.all(expected[:, 4:84] == expected[0, 4:84])  # pd does not learn
    assert np.abs(recording["qd"]).max() > 0.1


def _set_arm(settings, which: str, **values: float) -> None:
    # the settings' arms are copies on access (a std::variant in the core): assign them whole
    arm = getattr(settings, which)
    for key, value in values.items():
        setattr(arm, key, value)
    setattr(settings, which, arm)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda s: setattr(s, "critic_weights", np.ones(7)), "init.critic_weights: expected shape"),
        (lambda s: setattr(s, "actor_weights", np.full(8, np.nan)), "init.actor_weights: must be"),
        (lambda s: setattr(s, "R", -np.eye(2)), "cost.R: must be positive definite"),
        (lambda s: setattr(s, "Q", np.triu(np.ones((4, 4)))), "cost.Q: must be symmetric"),
        (lambda s: setattr(s.sim, "dt", 0.0), "sim.dt: must be a finite number > 0"),
        (lambda s: setattr(s.sim, "record_every", 0), "sim.record_every: must be >= 1"),
        (lambda s: setattr(s.critic, "gamma0", -1.0), "critic.gamma0"),
        (lambda s: _set_arm(s, "plant", p2=0.0), "plant.p2: must be > 0"),
        (lambda s: _set_arm(s, "model", p1=0.5), "model.p1, p2, p3"),
        (lambda s: setattr(s.probe, "phases", np.zeros((2, 1))), "probe.phases: expected shape"),
        (lambda s: setattr(s.extrapolation, "box", -np.ones(4)), "extrapolation.box: half-widths"),
        (lambda s: setattr(s.controller, "kp", np.full((2, 2), np.nan)), "controller.kp: must be"),
    ],
)
def test_core_checks_its_own_preconditions(change, message) -> None:
    # settings built directly, bypassing the Python validation: the core still refuses them
    settings = core_settings(adparm.paper_config())
    change(settings)
    with pytest.raises(ValueError, match=message):
        _core.Simulation(settings)


def test_core_refuses_a_grid_that_is_not_m_to_the_fourth() -> None:
    settings = core_settings(adparm.paper_config())
    extrapolation = settings.extrapolation
    extrapolation.mode = _core.ExtrapolationMode.grid
    extrapolation.points = 5
    settings.extrapolation = extrapolation
    with pytest.raises(ValueError, match="grid mode needs N = m\\^4 points"):
        _core.Simulation(settings)


def test_positive_e2_projection_is_exercised_and_keeps_the_block_from_falling() -> None:
    # the random states of the comparisons above put W on both sides of the boundary; here: the
    # projection changes the rates in some of them, never lowers lambda_min of an active e2 block,
    # and matches the NumPy reference (eigh + brute-force active sets) with and without it
    rng = np.random.default_rng(7)
    config = adparm.paper_config().updated({"actor": {"e2_margin": 0.5}})
    free = config.updated({"actor": {"positive_e2": False}})
    changed = 0
    for _ in range(60):
        state = random_state(rng)
        rate = _core.closed_loop_derivative(core_settings(config), 0.3, state)[0]
        free_rate = _core.closed_loop_derivative(core_settings(free), 0.3, state)[0]
        assert_close(rate, reference.rhs(config, 0.3, state)[0], "rate")
        changed += not np.allclose(rate, free_rate, rtol=0, atol=0)
        for slice_ in (reference.WC_SLICE, reference.WA_SLICE):
            W, dW = state[slice_], rate[slice_]
            for c in (1.0, -1.0):
                values, vectors = np.linalg.eigh(reference.e2_block(W, c))
                if values[0] <= 0.5:  # d lambda_min / dt = v^T dP v >= 0
                    v = vectors[:, 0]
                    assert v @ reference.e2_block(dW, c) @ v >= -1e-9 * np.abs(dW).max()
    assert changed >= 20
