"""What torque an arm needs through the start of its run: the commanded torque of the same run
without torque limits over its first second (transient_torque), and plant.torque_limits raised
to let it and the task's torque through (advised_torque_limits), the limits the verdict and a
diverged run's message advise."""

from __future__ import annotations

import math
import os

import numpy as np

import adparm._core as _core

from .config import Config
from .dynamics import task_torque
from .result import SimulationResult
from .translate import core_settings

__all__ = [
    "ADVISED_LIMITS_RULE",
    "TRANSIENT_HORIZON",
    "advised_torque_limits",
    "clipped",
    "limits_text",
    "transient_torque",
]

#: The first seconds of a run whose commanded torque advised torque limits let through (the
#: transient from q0 and the probe's start): the SO-101's peaks all fall within its first 0.2 s.
TRANSIENT_HORIZON = 1.0

#: How advised_torque_limits raises plant.torque_limits, in the advice's words.
ADVISED_LIMITS_RULE = (
    "twice what the arm needs: the task's torque and the commanded torque over the first "
    f"{TRANSIENT_HORIZON:g} s of the same run without limits; the others as given"
)


def clipped(result: SimulationResult) -> np.ndarray:
    """Where a run's applied torque was clipped at plant.torque_limits: tau != tau_commanded per
    recorded row and joint (a SimulationResult's arrays; all False without limits)."""
    return np.asarray(result.tau, dtype=float) != np.asarray(result.tau_commanded, dtype=float)


def transient_torque(config: Config) -> np.ndarray | None:
    """Per joint, max |tau_commanded| over the first TRANSIENT_HORIZON seconds of the same run
    without torque limits (every step recorded): what limits must let through besides the task's
    torque, or the arm is not held through its transient. None when that run diverges. Kept
    for the last configs (by their TOML text and their URDF files' versions): a diverged run's
    message, its CLI text and its diagnosis each ask."""
    free = config.updated(
        {
            "plant": {"torque_limits": "none"},
            "sim": {"T": min(config.sim.T, TRANSIENT_HORIZON), "record_every": 1},
        }
    )
    key = (free.to_toml(), tuple(_stamp(path) for path in (config.plant.urdf, config.model.urdf)))
    if key not in _PEAKS:
        run = _core.Simulation(core_settings(free))
        run.advance(run.steps)
        tau = np.asarray(run.recording()["tau_commanded"], dtype=float)
        _PEAKS[key] = np.max(np.abs(tau), axis=0) if run.status == "finished" else None
        while len(_PEAKS) > _KEPT:
            _PEAKS.pop(next(iter(_PEAKS)))
    peak = _PEAKS[key]
    return None if peak is None else peak.copy()


#: transient_torque's last results (oldest first), and how many it keeps.
_PEAKS: dict[tuple[str, tuple[tuple[int, int] | None, ...]], np.ndarray | None] = {}
_KEPT = 16


def _stamp(path: str | None) -> tuple[int, int] | None:
    """A file's version (modification time, size), None without one."""
    if path is None:
        return None
    stat = os.stat(path)
    return stat.st_mtime_ns, stat.st_size


def advised_torque_limits(config: Config) -> list[float]:
    """plant.torque_limits (per joint; inf: none) raised where they are below twice what the arm
    needs (ADVISED_LIMITS_RULE): the task's torque with the disturbance (dynamics.task_torque)
    and the transient's (transient_torque), rounded up to three digits. The UR5 with 5 N m on
    every joint and qd = 0 is given [17.6, 134, 35.4, 5, 5, 5], the SO-101 with 0.05 N m on its
    wrist roll and gripper 0.202 and 0.209 N m there: with them both runs end "ok" (tests)."""
    n = config.dof
    limits = config.plant.limit_vector(n)
    if limits.size == 0:
        return [math.inf] * n
    need = task_torque(config) + np.abs(np.asarray(config.plant.disturbance, dtype=float))
    transient = transient_torque(config)
    wanted = 2.0 * (need if transient is None else np.maximum(need, transient))
    return [
        _ceil3(float(wanted[i]))
        if math.isfinite(limits[i]) and wanted[i] > limits[i]
        else float(limits[i])
        for i in range(n)
    ]


def limits_text(limits: list[float]) -> str:
    """[a, b, ...] as the advice writes it (inf: no limit)."""
    return "[" + ", ".join("inf" if math.isinf(v) else f"{v:g}" for v in limits) + "]"


def _ceil3(value: float) -> float:
    """value rounded up to three significant digits."""
    step = 10.0 ** (math.floor(math.log10(value)) - 2)
    return float(f"{math.ceil(value / step - 1e-9) * step:.3g}")
