"""The analytic optimal solution of ERRATA.md and the HJB residual of eq. (21)."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _core
from .config import Config
from .simulation import core_settings

__all__ = ["BASIS_NAMES", "hjb_residual", "optimal_weights"]

#: The paper's basis phi(x), x = [e1; e2] (ERRATA ordering).
BASIS_NAMES = (
    "x1^2",
    "x2^2",
    "x1 x2",
    "x3^2",
    "x3^2 cos x2",
    "x4^2",
    "x3 x4",
    "x3 x4 cos x2",
)


def optimal_weights(config: Config, *, rtol: float = 1e-9) -> np.ndarray:
    """The exact weights W* of V*(x) = x^T blockdiag(K, M(q)) x in the paper's basis.

    They exist when K = -Q12 is symmetric positive definite, Q11 = K alpha1 + alpha1^T K and
    Q22 = R^-1 (to relative tolerance rtol), and qd2 = 0 (the basis uses cos x2 = cos q2). Then
    u* = -R^-1 e2 and W* = [K11, K22, 2 K12, p1, 2 p3, p2, 2 p2, 2 p3] with p of the arm the
    controller believes ([model], default the plant). Otherwise raises ValueError naming the
    condition that fails."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    Q = np.array(config.cost.Q)
    R = np.array(config.cost.R)
    alpha1 = np.array(config.control.alpha1)
    Q11, Q12, Q22 = Q[:2, :2], Q[:2, 2:], Q[2:, 2:]
    K = -Q12

    def close(a: np.ndarray, b: np.ndarray) -> bool:
        scale = max(np.abs(a).max(), np.abs(b).max(), 1.0)
        return bool(np.abs(a - b).max() <= rtol * scale)

    if not close(K, K.T):
        raise ValueError(f"cost.Q: K = -Q12 must be symmetric, got {K.tolist()}")
    if np.linalg.eigvalsh(0.5 * (K + K.T)).min() <= 0.0:
        raise ValueError(f"cost.Q: K = -Q12 must be positive definite, got {K.tolist()}")
    lyapunov = K @ alpha1 + alpha1.T @ K
    if not close(Q11, lyapunov):
        raise ValueError(
            "cost.Q: Q11 must equal K alpha1 + alpha1^T K with K = -Q12 "
            f"(got Q11 = {Q11.tolist()}, K alpha1 + alpha1^T K = {lyapunov.tolist()})"
        )
    if not close(Q22, np.linalg.inv(R)):
        raise ValueError(
            f"cost.Q: Q22 must equal R^-1 (got Q22 = {Q22.tolist()}, "
            f"R^-1 = {np.linalg.inv(R).tolist()})"
        )
    if config.task.qd[1] != 0.0:
        raise ValueError(
            "task.qd: the paper basis represents V* only for qd2 = 0, "
            f"got qd = {list(config.task.qd)}"
        )
    p = config.model.resolve(config.plant)
    return np.array(
        [
            K[0, 0],
            K[1, 1],
            2.0 * K[0, 1],
            p["p1"],
            2.0 * p["p3"],
            p["p2"],
            2.0 * p["p2"],
            2.0 * p["p3"],
        ]
    )


def _weights(value: Any, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name}: expected an array of 8 numbers, got {value!r}") from error
    if array.shape != (8,):
        raise ValueError(f"{name}: expected shape (8,), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: must be finite")
    return array


def hjb_residual(
    config: Config, x: Any, critic_weights: Any, actor_weights: Any
) -> np.ndarray | float:
    """The HJB error of eq. (21) at x = [e1; e2], computed by the C++ core with the cost, alpha1,
    set-point and believed arm of ``config``. ``x`` is one state (4,) or a batch (..., 4); the
    result has x's leading shape (a float for one state)."""
    try:
        states = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as error:
        raise TypeError(f"x: expected an array of shape (..., 4), got {x!r}") from error
    if states.ndim == 0 or states.shape[-1] != 4:
        raise ValueError(f"x: expected shape (..., 4), got {states.shape}")
    if not np.all(np.isfinite(states)):
        raise ValueError("x: must be finite")
    residual = _core.hjb_residual(
        core_settings(config),
        np.ascontiguousarray(states.reshape(-1, 4)),
        _weights(critic_weights, "critic_weights"),
        _weights(actor_weights, "actor_weights"),
    )
    if states.ndim == 1:
        return float(residual[0])
    return residual.reshape(states.shape[:-1])
