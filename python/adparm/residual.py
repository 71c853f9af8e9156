"""The HJB error of eq. (21) at given states and weights, evaluated by the C++ core with the
settings of a run (adparm.translate)."""

from __future__ import annotations

from typing import Any

import numpy as np

import adparm._core as _core

from .config import Config
from .dynamics import check_config, error_states, weight_vector
from .optimal import basis_names
from .translate import core_settings

__all__ = ["best_residual", "hjb_residual", "relative_residual", "residual_settings"]


def residual_settings(config: Config) -> _core.Settings:
    """The core settings of ``config`` for evaluating the HJB error at given states: without
    extrapolation points, which that evaluation does not use (N of them would be drawn and
    prepared at every call)."""
    settings = core_settings(config)
    settings.extrapolation.points = 0
    return settings


def hjb_residual(
    config: Config, x: Any, critic_weights: Any, actor_weights: Any, *, t: float = 0.0
) -> np.ndarray | float:
    """The HJB error of eq. (21) at states x = [e1; e2], computed by the C++ core.

    Parameters
    ----------
    config : Config
        Cost, alpha1, basis and the arm the controller believes.
    x : array_like, shape (2n,) or (..., 2n)
        One state or a batch (n joints; 4 for the two-link arm).
    critic_weights, actor_weights : array_like, shape (K,)
        Wc and Wa, in the order of ``adparm.basis_names(config)``.
    t : float, optional
        Time at which the desired state (qd, dqd) is taken.

    Returns
    -------
    float or ndarray
        A float for one state, else an array of x's leading shape. At Wc = Wa = W* it vanishes
        to round-off at every state.
    """
    check_config(config)
    n_x = 2 * config.dof
    states = error_states(x, n_x)
    size = len(basis_names(config))
    residual = _core.hjb_residual(
        residual_settings(config),
        np.ascontiguousarray(states.reshape(-1, n_x)),
        weight_vector(critic_weights, "critic_weights", size),
        weight_vector(actor_weights, "actor_weights", size),
        float(t),
    )
    if states.ndim == 1:
        return float(residual[0])
    return residual.reshape(states.shape[:-1])


def _time_groups(config: Config, X: np.ndarray, t_end: float) -> list[tuple[float, np.ndarray]]:
    """X split over the times its HJB error is taken at: all at 0 for a set-point, else over 8
    times in [0, t_end] (the desired state enters the HJB error), in order."""
    times = [0.0] if config.task.is_set_point else np.linspace(0.0, t_end, 8)
    groups = np.array_split(X, len(times))
    return [(float(t), np.ascontiguousarray(g)) for t, g in zip(times, groups, strict=True)]


def _cost_scale(config: Config, X: np.ndarray) -> float:
    """rms(x^T Q x) over X: the scale of the relative residuals."""
    cost = np.einsum("ni,ij,nj->n", X, np.array(config.cost.Q), X)
    return max(float(np.sqrt(np.mean(cost**2))), 1e-300)


def relative_residual(
    config: Config, X: np.ndarray, Wc: np.ndarray, Wa: np.ndarray, t_end: float = 0.0
) -> float:
    """rms(eps) / rms(x^T Q x) over the states X (split over times as in best_residual)."""
    eps = np.concatenate(
        [
            np.atleast_1d(hjb_residual(config, g, Wc, Wa, t=t))
            for t, g in _time_groups(config, X, t_end)
        ]
    )
    return float(np.sqrt(np.mean(eps**2))) / _cost_scale(config, X)


def best_residual(config: Config, X: np.ndarray, start: np.ndarray, t_end: float) -> float:
    """min over W of the relative HJB residual, rms(eps) / rms(x^T Q x), with Wc = Wa = W over
    the states X (least squares from ``start``; a moving qd: X split over 8 times in [0, t_end]):
    how well the basis can represent V* there (adparm.truth's hjb_residual_best). The Jacobian
    is exact: d eps / d W at Wc = Wa = W is omega (eq. 21's regressor, the core's
    hjb_evaluation), since u_hat minimises U(u) + W^T B u, so the actor's share vanishes; one
    evaluation per iteration instead of K + 1 finite differences (a 7-joint arm's 69 weights:
    20 s -> 0.5 s)."""
    from scipy.optimize import least_squares

    scale = _cost_scale(config, X)
    settings = residual_settings(config)  # converted once
    groups = _time_groups(config, X, t_end)
    last: dict[str, Any] = {}

    def evaluate(W: np.ndarray) -> dict[str, Any]:  # residuals and Jacobian, once per W
        key = W.tobytes()
        if last.get("key") != key:
            parts = [_core.hjb_evaluation(settings, g, W, W, t) for t, g in groups]
            last["key"] = key
            last["fun"] = np.concatenate([eps for eps, _ in parts]) / scale
            last["jac"] = np.vstack([omega for _, omega in parts]) / scale
        return last

    best = least_squares(
        lambda W: evaluate(W)["fun"],
        start,
        jac=lambda W: evaluate(W)["jac"],
        method="lm",
        max_nfev=200,
    )
    return float(np.sqrt(np.mean(best.fun**2)))
