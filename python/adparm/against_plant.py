"""A run measured against the plant, whatever its controller believed: J of eq. (10) on the
input the error system received (applied_input, applied_cost), J* on the same footing
(run_optimal_cost), the critic's final weights against the plant's W* (plant_critic_error) and
the believed base parameters against the plant's (believed_parameter_error). adparm.compare's
columns and the summary's (hence a sweep's) are these.

Every J charges the input the error system receives, u = h + tau_d - tau (eq. 4, h of the
plant): with tau = h_hat + mu - u_c that is the controller's u_c less the RISE term mu, plus the
disturbance and the model's error. Along the run M de2 = -C e2 + u holds for that u, so the optimum
J* of the same cost on the plant's error system (adparm.optimal_cost) is a lower bound of every J.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from .config import Config
from .identification import plant_critic_error  # re-exported: compare's and the summary's column
from .result import SimulationResult, post_run_failure

__all__ = [
    "applied_cost",
    "applied_input",
    "believed_parameter_error",
    "plant_critic_error",
    "run_optimal_cost",
]


def applied_input(result: SimulationResult) -> np.ndarray:
    """The input u = h + tau_d - tau (eq. 4, h of the plant) the error system received at each
    recorded row, (rows, n): M de2 = -C e2 + u along the run. With tau = h_hat + mu - u_c it is
    u_c - mu + tau_d + (h - h_hat): the controller's input u_c less the RISE term mu, plus the
    disturbance tau_d = [d1 sin t, d2 cos t, d3 sin t, ...] and the error of the believed
    feedforward h_hat (zero for an exact model)."""
    t = result.t
    amplitude = np.array(result.config.plant.disturbance, dtype=float)
    waves = np.where(np.arange(amplitude.size) % 2 == 0, np.sin(t)[:, None], np.cos(t)[:, None])
    u = result.u - result.mu + amplitude * waves
    from .config import ModelConfig

    identifying = result.model_parameters is not None
    if (result.config.model != ModelConfig() or identifying) and t.size:
        # h - h_hat: the model's error (an identifying run's h_hat is of beta_hat at each row)
        u = u + _feedforward(result, model=False) - _feedforward(result, model=True)
    return u


def _feedforward(result: SimulationResult, *, model: bool) -> np.ndarray:
    """h = M (ddqd + alpha1 de1) + C (dqd + alpha1 e1) + G + F with de1 = dqd - dq (eq. 5 in
    full) of the plant (or, ``model``, the believed arm) at the recorded rows. The believed arm of
    an identifying run is its estimate beta_hat at each row: the two-link arm's terms of
    (p1, p2, p3, g1, g2, coulomb, viscous) = beta_hat; a URDF arm's h_hat as the run recorded it,
    tau_commanded - mu + u (tau = h_hat + mu - u)."""
    from .desired import desired_state
    from .optimal import arm_terms
    from .urdf import config_arm

    config = result.config
    if model and result.model_parameters is not None:
        if config.plant.urdf is not None:
            return result.tau_commanded - result.mu + result.u
        return _estimated_feedforward(result)
    alpha1 = np.array(config.control.alpha1)
    desired = desired_state(config, result.t)
    if config.plant.urdf is not None:  # read the URDF once
        terms = config_arm(config, model=model).terms
    else:

        def terms(q: np.ndarray, dq: np.ndarray) -> dict[str, np.ndarray]:
            return arm_terms(config, q, dq, model=model)

    h = np.empty_like(result.q)
    for i, (q, dq, e1, (_, dqd, ddqd)) in enumerate(
        zip(result.q, result.dq, result.e1, desired, strict=True)
    ):
        T = terms(q, dq)
        M, C = np.asarray(T["M"]), np.asarray(T["C"])
        h[i] = M @ (ddqd + alpha1 @ (dqd - dq)) + C @ (dqd + alpha1 @ e1) + T["G"] + T["F"]
    return h


def _estimated_feedforward(result: SimulationResult) -> np.ndarray:
    """h_hat of eq. (5) at the recorded rows of an identifying two-link run: the arm's terms
    (adparm._core.arm_terms, not the identifier's regressors) of the parameters beta_hat
    recorded at each row."""
    from . import _core
    from .desired import desired_state
    from .dynamics import TWO_LINK_BASE_PARAMETERS

    config = result.config
    alpha1 = np.array(config.control.alpha1)
    desired = desired_state(config, result.t)
    h = np.empty_like(result.q)
    parameters = _core.ArmParameters()
    for i, (q, dq, e1, (_, dqd, ddqd), beta) in enumerate(
        zip(result.q, result.dq, result.e1, desired, result.model_parameters, strict=True)
    ):
        for key, value in zip(TWO_LINK_BASE_PARAMETERS, beta, strict=True):
            setattr(parameters, key, float(value))
        T = _core.arm_terms(parameters, q, dq)
        M, C = np.asarray(T["M"]), np.asarray(T["C"])
        h[i] = M @ (ddqd + alpha1 @ (dqd - dq)) + C @ (dqd + alpha1 @ e1) + T["G"] + T["F"]
    return h


def _simpson(values: np.ndarray, t: np.ndarray) -> float:
    from scipy.integrate import simpson

    if t.size < 2:
        return 0.0
    return float(simpson(values, x=t))


def applied_cost(result: SimulationResult) -> tuple[float, float]:
    """J = int_0^T x^T Q x + u^T R u dt with u = :func:`applied_input`, and its estimated relative
    quadrature error.

    ``result.cost`` (RK4 with the state) charges the controller's input u_c; the difference
    u^T R u - u_c^T R u_c is integrated over the recorded rows by Simpson's rule. With
    ``cost.input_bound`` (or the ln cosh e2 cost) ``result.cost`` charges those costs, so the
    whole quadratic integrand is integrated over the recorded rows by Simpson's rule. The error
    estimate is the change of that integral from every other row to every row, relative to J
    (0 when u = u_c: no RISE, no disturbance, an exact model)."""
    t = result.t
    if t.size == 0:
        return math.nan, math.nan
    R = np.array(result.config.cost.R)
    u, u_c = applied_input(result), result.u
    cost_section = result.config.cost
    if cost_section.input_bound is not None or cost_section.e2_cost != "quadratic":
        # result.cost charges the bounded input cost U(u_c) (and the ln cosh e2 cost): J is
        # then the quadratic cost of the recorded rows alone, by Simpson's rule
        x = np.hstack([result.e1, result.e2])
        whole = np.einsum("ri,ij,rj->r", x, np.array(cost_section.Q), x)
        whole += np.einsum("ri,ij,rj->r", u, R, u)
        cost = _simpson(whole, t)
        every_other = np.unique(np.r_[np.arange(0, t.size, 2), t.size - 1])
        if every_other.size < 3:
            return cost, math.nan
        change = abs(cost - _simpson(whole[every_other], t[every_other]))
        return cost, change / abs(cost) if cost else math.nan
    extra = np.einsum("ri,ij,rj->r", u, R, u) - np.einsum("ri,ij,rj->r", u_c, R, u_c)
    cost = float(result.cost[-1] - result.cost[0]) + _simpson(extra, t)
    if not np.any(extra):
        return cost, 0.0
    every_other = np.unique(np.r_[np.arange(0, t.size, 2), t.size - 1])
    if every_other.size < 3:
        return cost, math.nan
    change = abs(_simpson(extra, t) - _simpson(extra[every_other], t[every_other]))
    return cost, change / abs(cost) if cost else math.nan


def believed_parameter_error(result: SimulationResult) -> float | None:
    """max_i |beta_hat_i(T) - beta_i| / |beta_i| over the parameters the identifier estimates
    (identifier.inertia, .gravity, .friction; beta_i = 0: the absolute error), beta the plant's
    base parameters (adparm.base_parameters): the identifying run's estimate at its last
    recorded row, or, without identification, the believed model's parameters (held
    throughout). None without rows, or when the arm's parameters are not comparable (a URDF
    model whose base parameters differ in number from the plant's)."""
    from .identification import identified_parameters
    from .optimal import base_parameters

    config = result.config
    if result.t.size == 0:
        return None
    plant = base_parameters(config, "plant")
    if result.model_parameters is not None:
        believed = np.asarray(result.model_parameters[-1], dtype=float)
    else:
        believed = base_parameters(config, "model")
    indices = identified_parameters(config)
    if believed.shape != plant.shape or not indices:
        return None
    errors = [
        abs(believed[i] - plant[i]) / abs(plant[i]) if plant[i] != 0.0 else abs(believed[i])
        for i in indices
    ]
    return float(max(errors))


def run_optimal_cost(config: Config, **options: Any) -> tuple[float | None, str | None]:
    """J* on the same footing as :func:`applied_cost`'s J of a run of ``config`` (compare's
    J / J* - 1, a sweep's with ``optimal_cost``): adparm.optimal_cost on the plant's error
    system (model=False), over sim.T without a terminal cost when sim.T is shorter than its
    default horizon (else to infinity: beyond that horizon the rest is below 1e-9 of J*), with
    the config's torque limits widened by the disturbance's amplitude and the quadratic cost J
    charges (a controller's bounded input cost is not charged); ``options`` go to
    adparm.optimal_cost (e.g. ``intervals``, ``max_intervals``, ``rtol``). Returns J*, or None
    where it does not apply (a moving qd) or fails (e.g. a URDF arm with locked joints), and the
    failure (one line) or None."""
    from .sweep import solve_once
    from .truth import optimal_cost  # the module's attribute: tests replace it
    from .yardstick import default_horizon, plant_config

    if not config.task.is_set_point:
        return None, None
    # J charges x^T Q x + u^T R u (applied_cost), so J* does too, whatever the controller's cost
    quadratic = dataclasses.replace(config.cost, input_bound=None, e2_cost="quadratic")
    config = dataclasses.replace(config, cost=quadratic)
    limits = config.plant.limit_vector(config.dof)
    options = {**options, "model": False}
    if limits.size:
        # a run's applied input u = h + tau_d - tau keeps |h - u| <= limit + |d| (tau_d_i is
        # d_i sin t or d_i cos t): J* over these relaxed limits bounds every row's J
        disturbance = np.abs(np.asarray(config.plant.disturbance, dtype=float))
        options["torque_limits"] = np.asarray(limits, dtype=float) + disturbance

    def solve() -> tuple[float | None, str | None]:
        try:
            if config.sim.T < default_horizon(plant_config(config)):
                return optimal_cost(config, horizon=config.sim.T, terminal=False, **options), None
            return optimal_cost(config, **options), None
        except Exception as error:  # noqa: BLE001 - IPOPT or a yardstick failed: no run is lost
            return None, post_run_failure("J* (adparm.optimal_cost)", error)

    return solve_once(config, options, solve)  # within a sweep: once per problem
