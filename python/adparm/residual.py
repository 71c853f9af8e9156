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

__all__ = ["hjb_residual", "residual_settings"]


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
