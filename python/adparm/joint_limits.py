"""A URDF arm's joint position limits as the defaults read them: the box the derived settings
sample (limits_box) and the default set-point inside the limits (rest_position), one the arm
holds within its torque limits (default_set_point)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "DISTURBANCE",
    "DISTURBANCE_RATE",
    "HOME_MARGIN",
    "default_disturbance",
    "default_set_point",
    "effort_limits",
    "limits_box",
    "rest_position",
]

#: A URDF arm's default plant.disturbance amplitude (N m) is min(DISTURBANCE, DISTURBANCE_RATE
#: M_jj(qd)) on joint j (rates.urdf_defaults): the paper's 0.1 N m, but at most 0.1 rad/s^2 on
#: the joint alone, as on the paper's second link (0.1 N m on M_22 = p2 = 1 kg m^2). 0.1 N m on
#: every joint swung the SO-101's gripper (1.6e-5 kg m^2) 0.5 rad past its set-point and biased
#: the Kinova's identified parameters. The default set-point is held against DISTURBANCE (the
#: derived disturbance's bound: the derived one depends on the set-point).
DISTURBANCE = 0.1
DISTURBANCE_RATE = 0.1


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


def default_disturbance(inertia: np.ndarray) -> tuple[tuple[float, ...], str]:
    """A URDF arm's default plant.disturbance from the plant's M_jj(qd) (``inertia``), with its
    reason: min(DISTURBANCE, DISTURBANCE_RATE M_jj) N m on joint j, to 4 digits."""
    disturbance = np.minimum(DISTURBANCE, DISTURBANCE_RATE * np.asarray(inertia, dtype=float))
    rule = f"min({DISTURBANCE:g}, {DISTURBANCE_RATE:g} M_jj(qd)) N m per joint"
    why = "the paper's 0.1 N m, at most its second link's 0.1 rad/s^2 on a joint alone"
    return tuple(float(f"{v:.4g}") for v in disturbance), f"{rule}: {why}"


def effort_limits(arm: Any) -> np.ndarray:
    """A URDF arm's ``<limit effort>`` per joint, inf where it gives none (or 0): no limit."""
    effort = np.asarray(arm.limits["effort"], dtype=float)
    return np.where(effort > 0.0, effort, np.inf)


def default_set_point(config: Any) -> tuple[np.ndarray, str]:
    """task.qd's default on a URDF arm, with its reason: :func:`rest_position` of the plant's
    joint limits; where the arm cannot hold that pose against gravity within its torque limits
    (|G_j| + the disturbance's amplitude above plant.torque_limits, or the URDF's effort, on some
    joint; G of the plant and of the believed model, the larger), the pose within the same
    margins that least loads the actuators: min sum_j (G_j(q) / limit_j)^2 (summed over both
    arms) by L-BFGS-B from the rest position, if it holds. Baxter's left arm: at 0 its shoulder
    needs 56.4 N m against its 50; the pose found needs 28 % of every limit, and the run from it
    ends "ok". With the believed model's G alone, Baxter believed 20 % light (model.scale = 0.8)
    held 0 by the model's 45 N m, and its plant could not (55.3 N m)."""
    from scipy.optimize import Bounds, minimize

    from .urdf import config_arm

    plant = config_arm(config)
    low = np.asarray(plant.limits["lower"], dtype=float)
    high = np.asarray(plant.limits["upper"], dtype=float)
    rest = rest_position(low, high)
    reason = (
        f"0, moved to at least {HOME_MARGIN:g} rad (at most a quarter of the range) inside the "
        "joint limits"
    )
    n = rest.size
    if "plant.torque_limits" in config.explicit_keys:
        limits = config.plant.limit_vector(n)
    else:
        limits = effort_limits(plant)
    if limits.size == 0 or not np.any(np.isfinite(limits)):
        return rest, reason
    disturbance = (
        np.abs(np.asarray(config.plant.disturbance, dtype=float))
        if "plant.disturbance" in config.explicit_keys
        else np.full(n, DISTURBANCE)
    )
    model = config_arm(config, model=True)
    arms = (plant,) if model is plant else (plant, model)
    zero, finite = np.zeros(n), np.isfinite(limits)

    def gravities(q: np.ndarray) -> list[np.ndarray]:
        return [np.asarray(arm.terms(q, zero)["G"], dtype=float) for arm in arms]

    def load(q: np.ndarray) -> np.ndarray:
        return np.max(np.abs(gravities(q)), axis=0) + disturbance

    if np.all(load(rest)[finite] <= limits[finite]):
        return rest, reason
    margin = np.minimum(HOME_MARGIN, (high - low) / 4.0)
    box = Bounds(  # an unlimited joint: a turn about the rest position
        np.where(np.isfinite(low), low + margin, rest - np.pi),
        np.where(np.isfinite(high), high - margin, rest + np.pi),
    )

    def objective(q: np.ndarray) -> float:
        return float(sum(np.sum((g[finite] / limits[finite]) ** 2) for g in gravities(q)))

    found = minimize(objective, rest, method="L-BFGS-B", bounds=box).x
    found = np.clip(np.round(found, 4), box.lb, box.ub) + 0.0  # 0.1 mrad, within the margins
    if not np.all(load(found)[finite] <= limits[finite]):
        return rest, reason  # no pose found the arm holds: the verdict says so (saturation)
    share = float(np.max(load(found)[finite] / limits[finite]))
    return found, (
        "the pose that least loads the actuators against gravity, min sum (G_j / limit_j)^2 "
        f"({100 * share:.0f} % of the nearest limit with the disturbance), at least "
        f"{HOME_MARGIN:g} rad inside the joint limits: the arm cannot hold 0 there within its "
        "torque limits"
    )
