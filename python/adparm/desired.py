"""The desired trajectory of a config as the core evaluates it: desired_state(config, t) gives
[qd, dqd, ddqd] (the model layer: Config resolution and the optimum use it)."""

from __future__ import annotations

from typing import Any

import numpy as np

import adparm._core as _core

from ._arm_sections import SampledTrajectory, SinusoidTrajectory
from ._schema import ConfigSchema

__all__ = ["desired_state", "trajectory_settings"]


def trajectory_settings(config: ConfigSchema) -> _core.TrajectorySettings:
    qd = config.task.qd
    trajectory = _core.TrajectorySettings()
    if isinstance(qd, SinusoidTrajectory):
        trajectory.kind = _core.TrajectoryKind.sinusoid
        joints = len(qd.amplitude)  # offset None: 0 (a URDF arm's is derived: rates)
        trajectory.offset = np.zeros(joints) if qd.offset is None else np.array(qd.offset)
        trajectory.amplitude = np.array(qd.amplitude)
        trajectory.frequency = np.array(qd.frequency)
        trajectory.phase = np.array(qd.phase)
    elif isinstance(qd, SampledTrajectory):
        spline = qd.spline()
        # scipy's c[m, i, j]: coefficient of (t - x_i)^(3 - m) for joint j -> rows i, 4 j + m
        trajectory.kind = _core.TrajectoryKind.spline
        trajectory.offset = np.zeros(spline.c.shape[2])  # unused; its size is the joint count
        trajectory.breaks = np.array(spline.x)
        trajectory.coefficients = np.ascontiguousarray(
            np.transpose(spline.c, (1, 2, 0)).reshape(spline.c.shape[1], 4 * spline.c.shape[2])
        )
    else:
        trajectory.offset = np.array(qd)
    return trajectory


def desired_state(config: ConfigSchema, t: Any) -> np.ndarray:
    """The desired state of ``config.task.qd`` as the core evaluates it: for one time t, a (3, n)
    array [qd, dqd, ddqd] (n joints); for times (m,), an (m, 3, n) array."""
    if not isinstance(config, ConfigSchema):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    times = np.asarray(t, dtype=float)
    if times.ndim > 1:
        raise ValueError(f"t: expected a time or a 1-d array of times, got shape {times.shape}")
    rows = np.asarray(_core.desired_state(trajectory_settings(config), times.reshape(-1)))
    rows = rows.reshape(-1, 3, config.dof)
    return rows[0] if times.ndim == 0 else rows
