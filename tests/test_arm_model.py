"""The two-link arm of the C++ core: terms against NumPy, dM/dt - 2C skew, energy balance."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from adparm import _core

from numpy_reference import arm_terms as reference_terms

angles = st.floats(-np.pi, np.pi)
speeds = st.floats(-5.0, 5.0)
joint = st.tuples(angles, angles).map(np.array)
velocity = st.tuples(speeds, speeds).map(np.array)


def parameters(**values: float) -> _core.ArmParameters:
    p = _core.ArmParameters()
    for key, value in values.items():
        setattr(p, key, value)
    return p


PAPER = {
    "p1": 5.0,
    "p2": 1.0,
    "p3": 1.0,
    "g1": 9.8 * 1.2,
    "g2": 9.8,
    "coulomb": -0.1,
    "viscous": 0.0,
}


@given(q=joint, dq=velocity)
def test_terms_match_numpy(q, dq) -> None:
    values = dict(PAPER, viscous=0.3)
    terms = _core.arm_terms(parameters(**values), q, dq)
    M, C, G, F = reference_terms(values, q, dq)
    np.testing.assert_allclose(terms["M"], M, rtol=0, atol=1e-12)
    np.testing.assert_allclose(terms["C"], C, rtol=0, atol=1e-12)
    np.testing.assert_allclose(terms["G"], G, rtol=0, atol=1e-12)
    np.testing.assert_allclose(terms["F"], F, rtol=0, atol=1e-12)
    np.testing.assert_allclose(terms["M_inv"] @ M, np.eye(2), rtol=0, atol=1e-12)


@given(q=joint, dq=velocity, p3=st.floats(0.1, 1.9))
def test_dM_dt_minus_2C_is_skew_symmetric(q, dq, p3) -> None:
    arm = parameters(**dict(PAPER, p3=p3))
    h = 1e-6
    dM = (_core.arm_terms(arm, q + h * dq, dq)["M"] - _core.arm_terms(arm, q - h * dq, dq)["M"]) / (
        2 * h
    )
    N = dM - 2 * _core.arm_terms(arm, q, dq)["C"]
    assert np.abs(N + N.T).max() < 1e-8
    # and the test can fail: with the wrong sign of C the matrix is not skew while q2 moves
    wrong = dM + 2 * _core.arm_terms(arm, q, dq)["C"]
    if abs(np.sin(q[1]) * dq[1]) > 1e-2:
        assert np.abs(wrong + wrong.T).max() > 1e-3


def kinetic_energy(values: dict, states: np.ndarray) -> np.ndarray:
    out = []
    for s in states:
        M = reference_terms(values, s[:2], s[2:])[0]
        out.append(0.5 * s[2:] @ M @ s[2:])
    return np.array(out)


def potential_energy(values: dict, states: np.ndarray) -> np.ndarray:
    # G = dP/dq for P = g1 sin q1 + g2 sin(q1 + q2)
    return values["g1"] * np.sin(states[:, 0]) + values["g2"] * np.sin(states[:, 0] + states[:, 1])


@pytest.mark.parametrize("seed", range(3))
def test_gravity_compensated_arm_keeps_kinetic_energy(seed) -> None:
    rng = np.random.default_rng(seed)
    values = dict(PAPER, coulomb=0.0)
    x0 = np.concatenate([rng.uniform(-1, 1, 2), rng.uniform(-2, 2, 2)])
    states = _core.simulate_open_loop(parameters(**values), np.zeros(2), x0, 1e-3, 5000, True)
    assert states.shape == (5001, 4)
    energy = kinetic_energy(values, states)
    assert np.ptp(energy) < 1e-9 * energy[0]
    assert np.ptp(states[:, 0]) > 0.1  # the arm really moved


def test_uncompensated_arm_conserves_total_energy_not_kinetic() -> None:
    values = dict(PAPER, coulomb=0.0)
    x0 = np.array([0.3, -0.2, 0.5, -1.0])
    states = _core.simulate_open_loop(parameters(**values), np.zeros(2), x0, 1e-3, 3000, False)
    kinetic = kinetic_energy(values, states)
    total = kinetic + potential_energy(values, states)
    assert np.ptp(total) < 1e-8 * np.abs(total).max()
    assert np.ptp(kinetic) > 1.0


def test_friction_and_disturbance_change_the_energy() -> None:
    values = dict(PAPER, coulomb=0.0, viscous=0.5)
    x0 = np.array([0.3, -0.2, 0.5, -1.0])
    states = _core.simulate_open_loop(parameters(**values), np.zeros(2), x0, 1e-3, 2000, True)
    energy = kinetic_energy(values, states)
    assert np.all(np.diff(energy) < 0)  # viscous friction dissipates


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"p2": 0.0}, "plant.p2: must be > 0"),
        ({"p1": 1.5}, "positive definite"),
        ({"g1": np.nan}, "must be finite"),
    ],
)
def test_core_refuses_invalid_arm(values, message) -> None:
    with pytest.raises(ValueError, match=message):
        _core.arm_terms(parameters(**dict(PAPER, **values)), np.zeros(2), np.zeros(2))
