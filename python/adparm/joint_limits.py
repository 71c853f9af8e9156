"""A URDF arm's joint position limits as the defaults read them: the box the derived settings
sample (limits_box) and the default set-point inside the limits (rest_position)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["HOME_MARGIN", "limits_box", "rest_position"]


def limits_box(arm: Any) -> tuple[np.ndarray, np.ndarray]:
    """The joint-limit box clipped to [-pi, pi] (a continuous joint: [-pi, pi])."""
    limits = arm.limits
    low = np.clip(np.nan_to_num(limits["lower"], nan=-np.pi), -np.pi, np.pi)
    high = np.clip(np.nan_to_num(limits["upper"], nan=np.pi), -np.pi, np.pi)
    return low, np.maximum(high, low)


#: A URDF arm's default set-point (rest_position) keeps 0 on a joint where 0 lies at least this
#: far (rad, or m; at most a quarter of the joint's range) inside the URDF's position limits.
HOME_MARGIN = 0.4


def rest_position(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """task.qd's default on a URDF arm with position limits [low, high] per joint: 0 moved to at
    least HOME_MARGIN (at most a quarter of the range) inside them (the Panda's joint 4,
    [-3.07, -0.07]: -0.47). A set-point on a limit let the transient run past it (the SO-100's
    shoulder 0.05 rad below its lower limit for 6.6 s, the simulation having no joint stops)."""
    margin = np.minimum(HOME_MARGIN, (high - low) / 4.0)
    return np.clip(np.zeros_like(low), low + margin, high - margin)
