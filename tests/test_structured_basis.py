"""The structured basis of the two-link arm ([controller] basis = "structured"): 6 functions
[e1_i e1_j (i <= j); e2^T M_k(q) e2] whose exact weights are W* = [K11, 2 K12, K22, p1, p2, p3]."""

from __future__ import annotations

import numpy as np
import pytest

import adparm
from adparm import _core

from conftest import random_optimal_config
from numpy_reference import arm_terms as reference_arm_terms
from numpy_reference import hjb_residual as reference_residual
from numpy_reference import model_parameters, plant_parameters, structured_basis

# Short learning runs here have not converged and say so; that warning is not what is tested.
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


def structured(config: adparm.Config) -> adparm.Config:
    return config.updated({"controller": {"basis": "structured"}})


def states(rng: np.random.Generator, n: int) -> np.ndarray:
    return rng.uniform(-2.0, 2.0, size=(n, 4))


def test_paper_optimal_weights_are_K_and_the_inertia_parameters() -> None:
    config = structured(adparm.paper_config())
    # K = -Q12 = [[4, -4], [-4, 6]], p = (5, 1, 1)
    np.testing.assert_array_equal(adparm.optimal_weights(config), [4, -8, 6, 5, 1, 1])
    assert adparm.basis_names(config) == adparm.optimal.STRUCTURED_BASIS_NAMES
    assert len(adparm.basis_names(adparm.paper_config())) == 8


@pytest.mark.parametrize("seed", range(10))
def test_hjb_residual_vanishes_at_optimal_weights(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    config = structured(random_optimal_config(rng))
    W = adparm.optimal_weights(config)
    X = states(rng, 2000)
    residual = adparm.hjb_residual(config, X, W, W)
    scale = np.einsum("ni,ij,nj->n", X, np.array(config.cost.Q), X)
    assert np.abs(residual / scale).max() < 1e-12
    # a perturbed critic or actor is clearly not optimal (the actor's effect is second order: the
    # HJB error is stationary in u at u*)
    for which, bound in ((0, 1e-4), (1, 1e-8)):
        perturbed = [W.copy(), W.copy()]
        perturbed[which] += 0.05 * rng.normal(size=6)
        assert np.abs(adparm.hjb_residual(config, X, *perturbed) / scale).max() > bound


def test_hjb_residual_vanishes_along_a_trajectory(rng) -> None:
    # dqd != 0: the (d phi / d qd) dqd term of the regressor must be exact too
    base = structured(random_optimal_config(rng))
    config = base.updated(
        {"task": {"qd": {"kind": "sinusoid", "amplitude": [0.5, 0.8], "frequency": [1.3, 2.1]}}}
    )
    W = adparm.optimal_weights(config)
    X = states(rng, 500)
    scale = np.einsum("ni,ij,nj->n", X, np.array(config.cost.Q), X)
    for t in (0.0, 0.4, 1.7):
        assert np.abs(adparm.hjb_residual(config, X, W, W, t=t) / scale).max() < 1e-12


def test_optimal_weights_give_the_value_function(rng) -> None:
    config = structured(random_optimal_config(rng)).updated({"model": {"p1": 7.0, "p3": 0.5}})
    W = adparm.optimal_weights(config)
    K = -np.array(config.cost.Q)[:2, 2:]
    for x in states(rng, 50):
        qd = rng.uniform(-1, 1, size=2)
        M, _, _, _ = reference_arm_terms(model_parameters(config), qd - x[:2], np.zeros(2))
        phi, _ = adparm.basis(config, x, qd=qd)
        value = x[:2] @ K @ x[:2] + x[2:] @ M @ x[2:]
        assert W @ phi == pytest.approx(value, rel=1e-13, abs=1e-13)
    x = states(rng, 1)[0]
    qd = adparm.desired_state(config, 0.0)[0]
    M = reference_arm_terms(model_parameters(config), qd - x[:2], np.zeros(2))[0]
    expected = x[:2] @ K @ x[:2] + x[2:] @ M @ x[2:]
    assert adparm.optimal_value(config, x) == pytest.approx(expected, rel=1e-13)


def test_basis_and_jacobian_match_the_numpy_reference(rng) -> None:
    config = structured(adparm.paper_config())
    X = states(rng, 40)
    qd = rng.uniform(-1.5, 1.5, size=(40, 2))
    phi, jacobian = adparm.basis(config, X, qd=qd)
    assert phi.shape == (40, 6) and jacobian.shape == (40, 6, 4)
    for i in range(40):
        ref_phi, ref_jacobian, _ = structured_basis(X[i], qd[i])
        np.testing.assert_allclose(phi[i], ref_phi, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(jacobian[i], ref_jacobian, rtol=1e-14, atol=1e-14)
        # and the Jacobian is the derivative (central differences, a check of the reference)
        h = 1e-6
        for k in range(4):
            step = np.zeros(4)
            step[k] = h
            upper, _, _ = structured_basis(X[i] + step, qd[i])
            lower, _, _ = structured_basis(X[i] - step, qd[i])
            np.testing.assert_allclose(
                (upper - lower) / (2 * h), ref_jacobian[:, k], rtol=1e-6, atol=1e-7
            )
    # the desired rate (d phi / d qd) dqd
    dqd = np.array([0.3, -1.1])
    _, _, rate = _core.basis(_core.BasisKind.structured, X[0], qd[0], dqd)
    np.testing.assert_allclose(rate, structured_basis(X[0], qd[0], dqd)[2], rtol=1e-14, atol=1e-14)


def test_hjb_residual_matches_the_numpy_reference(rng) -> None:
    config = structured(random_optimal_config(rng)).updated(
        {"model": {"p1": 6.0}, "task": {"qd": {"kind": "sinusoid"}}}
    )
    Wc, Wa = rng.normal(size=6), rng.normal(size=6)
    X = states(rng, 20)
    ours = adparm.hjb_residual(config, X, Wc, Wa, t=0.9)
    reference = [reference_residual(config, x, Wc, Wa, t=0.9) for x in X]
    np.testing.assert_allclose(ours, reference, rtol=1e-11, atol=1e-10)


def test_default_initial_weights_are_K_identity_and_the_believed_inertia() -> None:
    config = structured(adparm.paper_config()).updated({"model": {"p1": 4.5, "p3": 0.8}})
    np.testing.assert_array_equal(config.initial_weights(), [1, 0, 1, 4.5, 1, 0.8])
    np.testing.assert_array_equal(config.initial_weights("actor_weights"), [1, 0, 1, 4.5, 1, 0.8])
    np.testing.assert_array_equal(adparm.paper_config().initial_weights(), np.ones(8))
    result = adparm.simulate(structured(adparm.paper_config()).updated({"sim": {"T": 0.05}}))
    assert result.critic_weights.shape == (6, 6)
    np.testing.assert_array_equal(result.critic_weights[0], [1, 0, 1, 5, 1, 1])


def test_weights_of_the_wrong_size_are_refused() -> None:
    with pytest.raises(ValueError, match=r"init.critic_weights: expected shape \(6,\)"):
        structured(adparm.paper_config()).updated({"init": {"critic_weights": [1.0] * 8}})
    with pytest.raises(ValueError, match=r"init.actor_weights: expected shape \(8,\)"):
        adparm.paper_config().updated({"init": {"actor_weights": [1.0] * 6}})
    config = structured(adparm.paper_config())
    with pytest.raises(ValueError, match=r"critic_weights: expected shape \(6,\)"):
        adparm.hjb_residual(config, np.zeros(4), np.ones(8), np.ones(6))


def test_arm_terms_match_the_numpy_reference(rng) -> None:
    config = adparm.paper_config().updated({"plant": {"viscous": 0.3}, "model": {"p2": 1.2}})
    for _ in range(5):
        q, dq = rng.uniform(-2, 2, size=2), rng.uniform(-2, 2, size=2)
        terms = adparm.arm_terms(config, q, dq)
        reference_terms = reference_arm_terms(plant_parameters(config), q, dq)
        for key, reference in zip("MCGF", reference_terms, strict=True):
            np.testing.assert_allclose(terms[key], reference, rtol=1e-14, atol=1e-14, err_msg=key)
        believed = adparm.arm_terms(config, q, dq, model=True)
        np.testing.assert_allclose(
            believed["M"], reference_arm_terms(model_parameters(config), q, dq)[0], rtol=1e-14
        )
        # dM/dt - 2C is skew-symmetric (dM/dt along dq, by central differences)
        h = 1e-6
        dM = (
            adparm.arm_terms(config, q + h * dq, dq)["M"]
            - adparm.arm_terms(config, q - h * dq, dq)["M"]
        ) / (2 * h)
        N = dM - 2 * terms["C"]
        np.testing.assert_allclose(N + N.T, 0.0, atol=1e-8)


def test_structured_critic_learns_the_inertia_by_extrapolation() -> None:
    # Bellman-error extrapolation at fixed points, no probing: from the default weights (K = I,
    # the believed inertia) the critic reaches W* = [K, p] within 1 % by t = 10 s
    config = structured(adparm.paper_config()).updated(
        {
            "probe": {"until": 0.0},
            "extrapolation": {"points": 20, "mode": "fixed", "seed": 1},
            "sim": {"T": 10.0, "record_every": 100},
        }
    )
    result = adparm.simulate(config)
    W = adparm.optimal_weights(config)
    error = np.linalg.norm(result.critic_weights - W, axis=1) / np.linalg.norm(W)
    assert error[0] > 0.3  # K = I is far from K
    assert error[-1] < 0.01, error[-1]


def test_structured_critic_learns_from_perturbed_weights() -> None:
    # from weights within +-20 % of W* (a believed arm 20 % off): the e2 block must move too
    config = structured(adparm.paper_config())
    W = adparm.optimal_weights(config)
    start = W * np.array([1.2, 0.8, 1.15, 0.8, 1.2, 0.85])
    config = config.updated(
        {
            "init": {"critic_weights": start.tolist(), "actor_weights": start.tolist()},
            "probe": {"until": 0.0},
            "extrapolation": {"points": 20, "mode": "fixed", "seed": 2},
            "sim": {"T": 10.0, "record_every": 100},
        }
    )
    result = adparm.simulate(config)
    error = np.linalg.norm(result.critic_weights[-1] - W) / np.linalg.norm(W)
    assert error < 0.01, error


@pytest.mark.parametrize("n", [1, 2, 3, 6])
def test_solvable_cost_for_n_joints(n: int, rng) -> None:
    A = rng.normal(size=(n, n))
    K = A @ A.T + np.eye(n)
    alpha1 = np.linalg.eigvalsh(K).max() * np.eye(n)  # Q > 0 needs K < 2 alpha1 here
    R = np.eye(n)
    Q = adparm.solvable_cost(K, alpha1, R)
    assert Q.shape == (2 * n, 2 * n)
    np.testing.assert_allclose(Q[:n, n:], -K)
    np.testing.assert_allclose(Q[:n, :n], K @ alpha1 + alpha1.T @ K)
    assert np.linalg.eigvalsh(Q).min() > 0.0
    with pytest.raises(ValueError, match="alpha1: expected a finite n x n matrix"):
        adparm.solvable_cost(K, np.eye(n + 1), R)
