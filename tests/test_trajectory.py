"""The desired state [qd, dqd, ddqd] the core evaluates, against closed forms and scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

import adparm
from adparm import _core
from adparm.simulation import core_settings

import numpy_reference as reference

TIMES = np.array([0.0, 0.013, 0.5, 1.0, 2.345, 7.0, 9.99])


def config_with(qd, T: float = 10.0) -> adparm.Config:
    return adparm.paper_config().updated({"task": {"qd": qd}, "sim": {"T": T}})


def test_set_point() -> None:
    config = config_with([0.3, -0.7])
    one = adparm.desired_state(config, 1.5)
    assert one.shape == (3, 2)
    np.testing.assert_array_equal(one, [[0.3, -0.7], [0.0, 0.0], [0.0, 0.0]])
    many = adparm.desired_state(config, TIMES)
    assert many.shape == (TIMES.size, 3, 2)
    np.testing.assert_array_equal(many, np.broadcast_to(one, many.shape))


def test_sinusoid_against_the_closed_form() -> None:
    a = np.array([[0.5, -0.2, 0.05], [0.3, 0.1, 0.0]])
    w = np.array([[1.0, 2.5, 7.0], [1.5, 0.5, 3.0]])
    p = np.array([[0.1, -0.2, 1.0], [0.3, 0.4, 2.0]])
    offset = np.array([0.1, -0.2])
    config = config_with(
        {"kind": "sinusoid", "amplitude": a, "frequency": w, "phase": p, "offset": offset}
    )
    actual = adparm.desired_state(config, TIMES)
    assert actual.shape == (TIMES.size, 3, 2)
    for row, t in zip(actual, TIMES, strict=True):
        qd = offset + [
            sum(a[j, k] * np.sin(w[j, k] * t + p[j, k]) for k in range(3)) for j in (0, 1)
        ]
        dqd = [
            sum(a[j, k] * w[j, k] * np.cos(w[j, k] * t + p[j, k]) for k in range(3)) for j in (0, 1)
        ]
        ddqd = [
            -sum(a[j, k] * w[j, k] ** 2 * np.sin(w[j, k] * t + p[j, k]) for k in range(3))
            for j in (0, 1)
        ]
        np.testing.assert_allclose(row, [qd, dqd, ddqd], rtol=0, atol=1e-14)
        np.testing.assert_array_equal(adparm.desired_state(config, t), row)
    np.testing.assert_allclose(
        actual, [np.array(reference.desired(config, t)) for t in TIMES], rtol=0, atol=1e-14
    )


def test_sinusoid_pairs_and_default_phase() -> None:
    config = config_with({"kind": "sinusoid", "amplitude": [0.5, 0.3], "frequency": [2.0, 3.0]})
    t = 0.7
    expected = [
        [0.5 * np.sin(2.0 * t), 0.3 * np.sin(3.0 * t)],
        [1.0 * np.cos(2.0 * t), 0.9 * np.cos(3.0 * t)],
        [-2.0 * np.sin(2.0 * t), -2.7 * np.sin(3.0 * t)],
    ]
    np.testing.assert_allclose(adparm.desired_state(config, t), expected, rtol=0, atol=1e-15)


SAMPLE_T = [-0.5, 0.0, 0.8, 1.5, 3.0, 4.2, 6.0]
SAMPLE_Q = [[0.0, 0.1], [0.2, -0.3], [0.5, 0.1], [0.1, 0.6], [-0.4, 0.2], [0.3, -0.1], [0.0, 0.0]]


@pytest.mark.parametrize("boundary", ["not-a-knot", "clamped", "natural"])
def test_samples_against_scipy(boundary) -> None:
    config = config_with(
        {"kind": "samples", "t": SAMPLE_T, "q": SAMPLE_Q, "boundary": boundary}, T=6.0
    )
    spline = CubicSpline(SAMPLE_T, SAMPLE_Q, axis=0, bc_type=boundary)
    times = np.concatenate([SAMPLE_T, np.linspace(-0.5, 6.0, 53)])
    actual = adparm.desired_state(config, times)
    expected = np.stack([spline(times, nu) for nu in range(3)], axis=1)
    scale = np.abs(expected).max(axis=0)
    np.testing.assert_allclose(actual, expected, rtol=0, atol=1e-13 * scale.max())
    np.testing.assert_allclose(actual[: len(SAMPLE_T), 0], SAMPLE_Q, rtol=0, atol=1e-14)
    np.testing.assert_allclose(
        actual, [np.array(reference.desired(config, t)) for t in times], atol=1e-13 * scale.max()
    )


def test_samples_are_clamped_outside_the_sampled_times() -> None:
    config = config_with({"kind": "samples", "t": SAMPLE_T, "q": SAMPLE_Q}, T=6.0)
    spline = CubicSpline(SAMPLE_T, SAMPLE_Q, axis=0)
    before = adparm.desired_state(config, [-3.0, -0.6])
    after = adparm.desired_state(config, [6.01, 100.0])
    for rows, end in ((before, SAMPLE_T[0]), (after, SAMPLE_T[-1])):
        expected = np.stack([spline(end, nu) for nu in range(3)])
        for row in rows:
            np.testing.assert_allclose(row, expected, rtol=0, atol=1e-12)
    for t, row in zip((-3.0, -0.6, 6.01, 100.0), (*before, *after), strict=True):
        np.testing.assert_allclose(row, np.array(reference.desired(config, t)), atol=1e-12)
    # not the spline's own extrapolation
    assert np.abs(after[1, 0] - spline(100.0)).max() > 1.0


@pytest.mark.parametrize("kind", ["sinusoid", "samples"])
def test_derivatives_are_those_of_qd(kind) -> None:
    # central differences of qd and dqd: independent of any closed form
    if kind == "sinusoid":
        qd = {"kind": "sinusoid", "amplitude": [[0.5, 0.2]] * 2, "frequency": [[1.0, 4.0]] * 2}
    else:
        qd = {"kind": "samples", "t": SAMPLE_T, "q": SAMPLE_Q}
    config = config_with(qd, T=6.0)
    h = 1e-5
    times = np.array([0.3, 1.1, 2.2, 3.7, 5.1])
    rows = adparm.desired_state(config, times)
    plus, minus = adparm.desired_state(config, times + h), adparm.desired_state(config, times - h)
    np.testing.assert_allclose(rows[:, 1], (plus[:, 0] - minus[:, 0]) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(rows[:, 2], (plus[:, 1] - minus[:, 1]) / (2 * h), atol=1e-6)
    assert np.abs(rows[:, 1:]).max() > 0.1


def test_closed_loop_uses_the_desired_state() -> None:
    config = config_with({"kind": "sinusoid", "amplitude": [0.5, 0.3], "frequency": [2.0, 3.0]})
    state = _core.initial_state(core_settings(config))
    for t in (0.0, 0.4, 2.0):
        _, outputs = _core.closed_loop_derivative(core_settings(config), t, state)
        qd, dqd, _ = adparm.desired_state(config, t)
        np.testing.assert_array_equal(outputs["qd"], qd)
        np.testing.assert_allclose(outputs["e1"], qd - state[:2], rtol=0, atol=1e-15)
        alpha1 = np.array(config.control.alpha1)
        e2 = dqd - state[2:4] + alpha1 @ (qd - state[:2])
        np.testing.assert_allclose(outputs["e2"], e2, rtol=0, atol=1e-13)


def test_desired_state_refuses_a_matrix_of_times() -> None:
    with pytest.raises(ValueError, match="t: expected a time or a 1-d array"):
        adparm.desired_state(adparm.paper_config(), np.zeros((2, 2)))
