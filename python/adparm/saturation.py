"""What the actuator limits did to a run (saturation_text) and whether they can hold its task at
all (limits_below_task): the torque the arm needs along the desired trajectory against
``plant.torque_limits``; and where a URDF arm's joints left their position limits
(position_limits_text)."""

from __future__ import annotations

import numpy as np

from .config import Config
from .dynamics import task_torque
from .result import SimulationResult
from .transient import ADVISED_LIMITS_RULE, advised_torque_limits, clipped, limits_text
from .units import effort_units, position_units
from .urdf import config_arm

__all__ = ["limits_below_task", "position_limits_text", "saturation_text"]


def saturation_text(result: SimulationResult) -> str | None:
    """What the actuator limits did to a run (None when no joint's torque was clipped): which
    joints were clipped at ``plant.torque_limits`` and for how long, and that the theory's
    assumption of unlimited torque was broken while the controller's own input was unbounded (or
    inside its bound, ``cost.input_bound``): clipping is not a failure of the learning."""
    config = result.config
    seconds = np.asarray(result.saturated_time, dtype=float)
    if config.plant.limit_vector(config.dof).size == 0 or not np.any(seconds > 0.0):
        return None
    duration = float(result.t[-1] - result.t[0]) if result.t.size > 1 else config.sim.T
    duration = max(duration, float(seconds.max()))
    joints = ", ".join(
        f"joint {i + 1} for {value:.3g} s ({100.0 * value / duration:.3g} %)"
        for i, value in enumerate(seconds)
        if value > 0.0
    )
    text = f"the applied torque was clipped at plant.torque_limits: {joints} of {duration:.3g} s"
    limit = config.cost.bound_vector(config.dof)
    if limit.size == 0:
        return (
            text + "; the controller's input is unbounded, so the theory's assumption (the "
            "commanded torque is applied) was broken, not the learning"
        )
    # a constrained-input controller: was its input inside its bound while clipped?
    inside = np.any(clipped(result) & (np.abs(result.u) <= limit), axis=1)
    if not np.any(inside):
        return text
    rows = result.t[1] - result.t[0] if result.t.size > 1 else config.sim.dt
    return (
        text + f"; for about {np.count_nonzero(inside) * rows:.3g} s of it the controller's input "
        "was inside its bound (cost.input_bound), so the theory's assumption (the commanded "
        "torque is applied) was broken, not the learning"
    )


def limits_below_task(config: Config) -> tuple[str, str] | None:
    """(what the verdict adds, the advice) when some joint's limit (plant.torque_limits) is below
    the torque the plant needs on the task: max over the desired trajectory of |M ddqd + C dqd +
    G + F| (dynamics.task_torque) plus the disturbance's amplitude; None otherwise. No change of
    the learning helps such a run. The advice names limits twice what the arm needs
    (transient.advised_torque_limits: the task's torque, and the commanded torque of the same run
    without limits over its first second): the UR5 with 5 N m on every joint needs 59.2 N m on
    its shoulder to hold qd = 0 against gravity, the SO-101 with 0.05 N m on every joint 0.54 N m
    on its shoulder, and 0.1-0.13 N m on its base, wrist roll and gripper through the transient
    (limits raised on the task's joints alone let those spin): with the limits the advice names
    each run ends "ok"."""
    n = config.dof
    limits = config.plant.limit_vector(n)
    if limits.size == 0:
        return None
    need = task_torque(config) + np.abs(np.asarray(config.plant.disturbance, dtype=float))
    short = np.flatnonzero(np.isfinite(limits) & (need > limits))
    if short.size == 0:
        return None
    units = effort_units(config)
    joints = ", ".join(
        f"joint {i + 1} needs {need[i]:.3g} {units[i]} (limit {limits[i]:.3g} {units[i]})"
        for i in short
    )
    return (
        "the torque limits cannot hold the task (max |M ddqd + C dqd + G + F| over the desired "
        f"trajectory, with the disturbance): {joints}; no controller can follow this task within "
        "them, and no change of the learning helps",
        f"raise plant.torque_limits to {limits_text(advised_torque_limits(config))} "
        f"({ADVISED_LIMITS_RULE}), or choose a task.qd that needs less torque",
    )


def torque_limit_values(config: Config) -> list[float | None] | None:
    """plant.torque_limits per joint (None: no limit on that joint), or None without limits."""
    limits = config.plant.limit_vector(config.dof)
    if limits.size == 0:
        return None
    return [float(v) if np.isfinite(v) else None for v in limits]


def torque_limits_text(limits: list[float | None], units: list[str] | None) -> str:
    """plant.torque_limits per joint with their units ("60, 15 N m"; "none" for no limit; each
    with its own unit where they differ: "80 N m, 200 N"); units None (a summary written
    before they were stored): N m."""
    units = units or ["N m"] * len(limits)
    values = ["none" if v is None else f"{v:g}" for v in limits]
    if len(set(units)) == 1:
        return ", ".join(values) + f" {units[0]}"
    return ", ".join(v if v == "none" else f"{v} {u}" for v, u in zip(values, units, strict=True))


#: How far (rad, or m for a prismatic joint) past a URDF's position limit a joint may go before
#: the verdict says so: round-off of a task at the limit, not a motion.
POSITION_LIMIT_SLACK = 1e-6


def position_limits_text(result: SimulationResult) -> str | None:
    """Where the plant's joints went past the URDF's position limits (``<limit lower upper>``;
    None when none did, for the two-link arm, and for continuous joints): per joint, the farthest
    position and for how long, and whether the task itself (qd over the run, or q0) lies outside.
    The simulation has no joint stops: such a run is not one the real arm can make."""
    config = result.config
    if config.plant.urdf is None or result.t.size == 0:
        return None
    arm = config_arm(config)
    low = np.asarray(arm.limits["lower"], dtype=float)
    high = np.asarray(arm.limits["upper"], dtype=float)

    def past_limits(values: object) -> np.ndarray:
        """How far each position lies past its limits (> 0 outside)."""
        values = np.asarray(values, dtype=float)
        return np.maximum(low - values, values - high)

    def outside(values: object) -> bool:
        return bool(np.any(past_limits(values) > POSITION_LIMIT_SLACK))

    q = np.asarray(result.q, dtype=float)
    past = past_limits(q)
    went_past = np.flatnonzero(np.nanmax(past, axis=0) > POSITION_LIMIT_SLACK)
    if went_past.size == 0:
        return None
    rows = float(result.t[1] - result.t[0]) if result.t.size > 1 else config.sim.dt
    units = position_units(config)
    names = arm.joint_names
    joints = []
    for i in went_past:
        far = int(np.nanargmax(past[:, i]))
        joints.append(
            f"joint {i + 1} ('{names[i]}') reached {q[far, i]:.3g} {units[i]}, "
            f"{past[far, i]:.2g} {units[i]} past its limits [{low[i]:.3g}, {high[i]:.3g}], for "
            "about "
            f"{np.count_nonzero(past[:, i] > POSITION_LIMIT_SLACK) * rows:.3g} s"
        )

    causes = []
    if outside(result.qd):
        causes.append(
            "task.qd lies outside the limits (left out, it is derived within them)"
            if isinstance(config.task.qd, tuple)
            else "task.qd leaves the limits (choose its offset and amplitude within them)"
        )
    if outside(config.task.q0):
        causes.append("task.q0 lies outside the limits (left out, it is derived within them)")
    probe = np.asarray(result.probe, dtype=float)
    outside_rows = np.any(past[:, went_past] > POSITION_LIMIT_SLACK, axis=1)
    if not causes and np.any(probe[outside_rows] != 0.0):
        # a strong probe moves the arm widely: a qd farther from the limits did not keep the
        # Panda within them (measured; docs: URDF arms, joint limits)
        causes.append(
            "the task lies within them and the probe was on while they went past: it drove them "
            "(a probe the real arm can take is smaller on those joints, and excites less)"
        )
    last_outside = int(np.flatnonzero(outside_rows)[-1])
    if not causes and np.any(clipped(result)[: last_outside + 1]):
        # an arm its torque limits cannot hold falls or swings past them wherever qd lies (the
        # SO-101 with 0.05 N m on every joint, Talos' arm with 0.5 N m)
        causes.append(
            "the task lies within them and the applied torque was clipped at "
            "plant.torque_limits before they went past: the limits let the arm go (a task.qd "
            "farther from the position limits does not help)"
        )
    cause = (
        "; ".join(causes)
        if causes
        else "the task lies within them and the transient went past them: choose a task.qd "
        "at least that much farther from those limits"
    )
    return (
        f"the joints went past the URDF's position limits, which the simulation does not enforce "
        f"(no joint stops): {'; '.join(joints)}; {cause}"
    )
