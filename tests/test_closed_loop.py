"""The C++ right-hand side of the closed loop equals the independent NumPy implementation."""

from __future__ import annotations

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.simulation import core_settings

from numpy_reference import basis as reference_basis
from numpy_reference import initial_state as reference_initial_state
from numpy_reference import rhs as reference_rhs
from numpy_reference import simulate as reference_simulate


def random_state(rng: np.random.Generator, config: adparm.Config) -> np.ndarray:
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
        ]
    )


def random_config(rng: np.random.Generator) -> adparm.Config:
    p2 = rng.uniform(0.5, 2.0)
    p3 = rng.uniform(0.1, 1.0)
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
                "qd": rng.uniform(-1, 1, 2),
            },
            "control": {
                "alpha1": rng.uniform(0.5, 5, (2, 2)),
                "ks": rng.uniform(0, 20),
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
        }
    )


def assert_close(actual, expected, name: str) -> None:
    actual, expected = np.asarray(actual), np.asarray(expected)
    scale = max(1.0, np.abs(expected).max())
    assert np.abs(actual - expected).max() <= 1e-12 * scale, (name, actual, expected)


@pytest.mark.parametrize("seed", range(20))
def test_right_hand_side_matches_numpy(seed) -> None:
    rng = np.random.default_rng(seed)
    config = random_config(rng) if seed else adparm.paper_config()
    settings = core_settings(config)
    for _ in range(25):
        state = random_state(rng, config)
        t = rng.uniform(0, 10)
        rate, outputs = _core.closed_loop_derivative(settings, t, state)
        expected_rate, expected_outputs = reference_rhs(config, t, state)
        assert_close(rate, expected_rate, "rate")
        for name, value in expected_outputs.items():
            assert_close(outputs[name], value, name)


def test_projection_is_active_in_the_comparison() -> None:
    # weights outside the bound with an outward rate: the projected rate is tangent
    rng = np.random.default_rng(1)
    config = random_config(rng).updated({"actor": {"weight_bound": 1.0}})
    for _ in range(20):
        state = random_state(rng, config)
        rate, _ = _core.closed_loop_derivative(core_settings(config), 0.3, state)
        Wa, dWa = state[12:20], rate[12:20]
        assert Wa @ dWa <= 1e-12 * np.linalg.norm(Wa) * np.linalg.norm(dWa)
        assert_close(rate, reference_rhs(config, 0.3, state)[0], "rate")


def test_basis_matches_numpy_and_finite_differences() -> None:
    rng = np.random.default_rng(5)
    for x in rng.uniform(-2, 2, (50, 4)):
        phi, jacobian = _core.basis(x)
        expected_phi, expected_jacobian = reference_basis(x)
        assert_close(phi, expected_phi, "phi")
        assert_close(jacobian, expected_jacobian, "jacobian")
        h = 1e-6
        numeric = np.column_stack(
            [(_core.basis(x + h * e)[0] - _core.basis(x - h * e)[0]) / (2 * h) for e in np.eye(4)]
        )
        np.testing.assert_allclose(jacobian, numeric, atol=1e-8)


def test_initial_state_layout() -> None:
    config = random_config(np.random.default_rng(3))
    np.testing.assert_array_equal(
        _core.initial_state(core_settings(config)), reference_initial_state(config)
    )
    assert _core.STATE_SIZE == 86


def test_short_simulation_matches_numpy_rk4() -> None:
    # smooth enough to compare trajectories: resets happen in both (epsilon_T large)
    config = random_config(np.random.default_rng(7)).updated(
        {
            "sim": {"T": 0.2, "dt": 1e-3, "record_every": 1},
            "critic": {"epsilon_T": 50.0, "eta_c": 400.0},
        }
    )
    result = adparm.simulate(config)
    expected = reference_simulate(config, 200)
    np.testing.assert_allclose(result.q, expected[:, 0:2], rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.dq, expected[:, 2:4], rtol=0, atol=1e-8)
    np.testing.assert_allclose(result.critic_weights, expected[:, 4:12], rtol=0, atol=1e-8)
    np.testing.assert_allclose(result.actor_weights, expected[:, 12:20], rtol=0, atol=1e-8)
    assert result.covariance_resets > 0


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
        (lambda s: setattr(s.plant, "p2", 0.0), "plant.p2: must be > 0"),
        (lambda s: setattr(s.model, "p1", 0.5), "model.p1, p2, p3"),
        (lambda s: setattr(s.probe, "phases", np.zeros((2, 1))), "probe.phases: expected shape"),
    ],
)
def test_core_checks_its_own_preconditions(change, message) -> None:
    # settings built directly, bypassing the Python validation: the core still refuses them
    settings = core_settings(adparm.paper_config())
    change(settings)
    with pytest.raises(ValueError, match=message):
        _core.Simulation(settings)
