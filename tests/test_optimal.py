"""The analytic solution of ERRATA.md: the HJB residual (eq. 21) at W* is at round-off level."""

from __future__ import annotations

import numpy as np
import pytest

import adparm

from conftest import random_optimal_config
from numpy_reference import hjb_residual as reference_residual


def states(rng: np.random.Generator, n: int) -> np.ndarray:
    return rng.uniform(-2.0, 2.0, size=(n, 4))


def test_paper_optimal_weights_are_the_errata_values() -> None:
    W = adparm.optimal_weights(adparm.paper_config())
    np.testing.assert_array_equal(W, [4, 6, -8, 5, 2, 1, 2, 2])


def test_hjb_residual_vanishes_at_optimal_weights_on_paper(rng) -> None:
    config = adparm.paper_config()
    W = adparm.optimal_weights(config)
    residual = adparm.hjb_residual(config, states(rng, 5000), W, W)
    assert residual.shape == (5000,)
    assert np.abs(residual).max() < 1e-9


def test_hjb_residual_at_printed_paper_weights_is_not_zero(rng) -> None:
    printed = np.array([2, -4, 3, 2.5, 1, 1, 1, 0.5])
    residual = adparm.hjb_residual(adparm.paper_config(), states(rng, 1000), printed, printed)
    assert np.abs(residual).max() > 1.0


@pytest.mark.parametrize("seed", range(12))
def test_hjb_residual_vanishes_on_other_valid_instances(seed) -> None:
    rng = np.random.default_rng(seed)
    config = random_optimal_config(rng)
    W = adparm.optimal_weights(config)
    X = states(rng, 2000)
    residual = adparm.hjb_residual(config, X, W, W)
    scale = 1.0 + np.einsum("ni,ij,nj->n", X, np.array(config.cost.Q), X)
    assert np.abs(residual / scale).max() < 1e-9
    # and clearly not zero for perturbed weights (critic or actor)
    for which in range(2):
        W_perturbed = [W.copy(), W.copy()]
        W_perturbed[which] += 0.05 * rng.normal(size=8)
        perturbed = adparm.hjb_residual(config, X, *W_perturbed)
        assert np.abs(perturbed / scale).max() > 1e-4


def test_hjb_residual_matches_numpy_reference(rng) -> None:
    config = random_optimal_config(rng).updated({"model": {"p1": 9.0, "p3": 0.3}})
    for x in states(rng, 50):
        Wc, Wa = rng.normal(size=8), rng.normal(size=8)
        ours = adparm.hjb_residual(config, x, Wc, Wa)
        assert isinstance(ours, float)
        expected = reference_residual(config, x, Wc, Wa)
        assert abs(ours - expected) <= 1e-12 * max(1.0, abs(expected))


def test_hjb_residual_keeps_batch_shape(rng) -> None:
    config = adparm.paper_config()
    W = np.ones(8)
    X = states(rng, 12).reshape(3, 4, 4)
    batch = adparm.hjb_residual(config, X, W, W)
    assert batch.shape == (3, 4)
    assert batch[1, 2] == adparm.hjb_residual(config, X[1, 2], W, W)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"cost": {"R": [[0.5, 0.0], [0.0, 0.25]]}}, r"Q22 must equal s\^2 R\^-1"),
        ({"control": {"alpha1": [[15.0, 10.6], [10.6, 10.4]]}}, "Q11 must equal"),
        ({"task": {"qd": [0.0, 0.3]}, "controller": {"basis": "paper"}}, "qd2 = 0"),
    ],
)
def test_optimal_weights_refuses_instances_without_known_solution(change, message) -> None:
    with pytest.raises(ValueError, match=message):
        adparm.optimal_weights(adparm.paper_config().updated(change))


def test_optimal_weights_needs_symmetric_positive_K() -> None:
    Q = np.array(adparm.paper_config().cost.Q)
    Q[:2, 2:] *= -1.0
    Q[2:, :2] *= -1.0
    config = adparm.paper_config().updated({"cost": {"Q": Q}})
    with pytest.raises(ValueError, match="positive definite"):
        adparm.optimal_weights(config)


def test_optimal_weights_follow_the_believed_model() -> None:
    config = adparm.paper_config().updated({"model": {"p1": 6.0, "p2": 1.5, "p3": 0.5}})
    np.testing.assert_array_equal(adparm.optimal_weights(config), [4, 6, -8, 6, 1, 1.5, 3, 1])


@pytest.mark.parametrize(
    ("x", "error", "message"),
    [
        (np.zeros(3), ValueError, "x: expected shape"),
        (np.array([0.0, np.nan, 0.0, 0.0]), ValueError, "x: must be finite"),
        ("abcd", TypeError, "x: expected an array"),
    ],
)
def test_hjb_residual_refuses_bad_states(x, error, message) -> None:
    with pytest.raises(error, match=message):
        adparm.hjb_residual(adparm.paper_config(), x, np.ones(8), np.ones(8))


def test_hjb_residual_refuses_bad_weights() -> None:
    with pytest.raises(ValueError, match="critic_weights: expected shape"):
        adparm.hjb_residual(adparm.paper_config(), np.zeros(4), np.ones(7), np.ones(8))
    with pytest.raises(ValueError, match="actor_weights: must be finite"):
        adparm.hjb_residual(adparm.paper_config(), np.zeros(4), np.ones(8), np.full(8, np.inf))


@pytest.mark.parametrize("seed", range(6))
def test_exact_family_q22_is_s2_r_inverse(seed) -> None:
    # Q22 = s^2 R^-1: V* = e1^T K e1 + s e2^T M e2, u* = -s R^-1 e2 (HJB residual at round-off)
    rng = np.random.default_rng(100 + seed)
    base = random_optimal_config(rng)
    s = float(rng.uniform(0.2, 5.0))
    Q, R = np.array(base.cost.Q), np.array(base.cost.R)
    K, alpha1 = -Q[:2, 2:], np.array(base.control.alpha1)
    family = adparm.solvable_cost(K, alpha1, R, s=s)
    np.testing.assert_allclose(family[2:, 2:], s**2 * np.linalg.inv(R), rtol=1e-12)
    try:
        config = base.updated({"cost": {"Q": family}})
    except ValueError:  # Q not positive definite for this s (solvable_cost would have said so)
        pytest.skip("Q not positive definite")
    assert adparm.value_scale(config) == pytest.approx(s, rel=1e-12)
    W = adparm.optimal_weights(config)
    W1 = adparm.optimal_weights(base)
    np.testing.assert_allclose(W[:3], W1[:3], rtol=1e-12)
    np.testing.assert_allclose(W[3:], s * W1[3:], rtol=1e-12)
    X = states(rng, 2000)
    residual = adparm.hjb_residual(config, X, W, W)
    scale = 1.0 + np.einsum("ni,ij,nj->n", X, family, X)
    assert np.abs(residual / scale).max() < 1e-9
    # the s = 1 weights are no solution of this cost
    assert np.abs(adparm.hjb_residual(config, X, W1, W1) / scale).max() > 1e-3


def test_solvable_cost_refuses_a_bad_scale() -> None:
    with pytest.raises(ValueError, match="s: expected a finite number > 0"):
        adparm.solvable_cost(np.eye(2), np.eye(2), np.eye(2), s=0.0)
    with pytest.raises(TypeError, match="s: expected a number"):
        adparm.solvable_cost(np.eye(2), np.eye(2), np.eye(2), s="1")
