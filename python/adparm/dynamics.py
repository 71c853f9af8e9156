"""The arm's dynamics as the controller believes them and what the optimum needs of them, with no
basis: M, C, G, F at given states (arm_terms, inertia_matrices), the initial error state, the
exact family's scale s (value_scale) and cost (solvable_cost), the Riccati value of the
linearised error system (lqr_value), and the base parameters beta in which the dynamics are linear
(base_parameters, base_parameter_names). adparm.optimal re-exports them."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

import adparm._core as _core

from ._schema import ConfigSchema
from .bases import check_real, real_array
from .desired import desired_state
from .urdf import config_arm

__all__ = [
    "TASK_SAMPLES",
    "arm_terms",
    "base_parameter_groups",
    "base_parameter_names",
    "base_parameters",
    "check_config",
    "error_states",
    "exact_family",
    "inertia_matrices",
    "initial_error_state",
    "linearisation",
    "lqr_value",
    "saturated_cost",
    "solvable_cost",
    "task_torque",
    "value_scale",
    "weight_vector",
]


def check_config(config: Any) -> None:
    if not isinstance(config, ConfigSchema):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")


def error_states(x: Any, size: int, name: str = "x") -> np.ndarray:
    try:
        array = np.asarray(x)
    except ValueError as error:  # ragged
        raise TypeError(f"{name}: expected an array of shape (..., {size}), got {x!r}") from error
    check_real(array, name)  # complex refused: NumPy would drop the imaginary part
    try:
        states = np.asarray(array, dtype=float)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name}: expected an array of shape (..., {size}), got {x!r}") from error
    if states.ndim == 0 or states.shape[-1] != size:
        raise ValueError(f"{name}: expected shape (..., {size}), got {states.shape}")
    if not np.all(np.isfinite(states)):
        raise ValueError(f"{name}: must be finite")
    return states


def arm_terms(
    config: ConfigSchema, q: Any, dq: Any, *, model: bool = False
) -> dict[str, np.ndarray]:
    """The terms of eq. (1) of the plant (``model=True``: the arm the controller believes) at
    joint position q and velocity dq (n,): {"M": (n, n) inertia, "C": (n, n) Coriolis matrix with
    dM/dt - 2C skew-symmetric, "G": (n,) gravity, "F": (n,) friction}."""
    check_config(config)
    n = config.dof
    q_array, dq_array = error_states(q, n, "q"), error_states(dq, n, "dq")
    if q_array.shape != (n,) or dq_array.shape != (n,):
        raise ValueError(
            f"q, dq: expected shape ({n},) each, got {q_array.shape}, {dq_array.shape}"
        )
    if config.plant.urdf is not None:  # Pinocchio, through the core's URDF arm
        terms = config_arm(config, model=model).terms(q_array, dq_array)
        return {key: np.array(terms[key]) for key in ("M", "C", "G", "F")}
    parameters = _core.ArmParameters()
    values = (
        config.model.resolve(config.plant)
        if model
        else {
            key: getattr(config.plant, key)
            for key in ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")
        }
    )
    for key, value in values.items():
        setattr(parameters, key, value)
    terms = _core.arm_terms(parameters, q_array, dq_array)
    return {key: np.array(terms[key]) for key in ("M", "C", "G", "F")}


#: The two-link arm's beta, in which M ddq + C dq + G + F is linear (the online identifier's
#: parameters, cpp/include/adparm/identifier.hpp).
TWO_LINK_BASE_PARAMETERS = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")


#: Samples of the desired trajectory over [0, sim.T] for task_torque (a set-point: one).
TASK_SAMPLES = 200


def task_torque(config: ConfigSchema, *, model: bool = False) -> np.ndarray:
    """max over the desired trajectory of |h_i| = |M ddqd + C dqd + G + F|_i, per joint: the
    torque that holds the arm on the task (the plant's, or the believed model's with ``model``),
    at TASK_SAMPLES times over [0, sim.T] (a set-point: qd alone)."""
    samples = 1 if config.task.is_set_point else TASK_SAMPLES
    times = np.linspace(0.0, config.sim.T, samples)
    states = np.unique(desired_state(config, times), axis=0)
    feedforward = np.zeros(config.dof)
    for qd, dqd, ddqd in states:
        terms = arm_terms(config, qd, dqd, model=model)
        h = terms["M"] @ ddqd + terms["C"] @ dqd + terms["G"] + terms["F"]
        feedforward = np.maximum(feedforward, np.abs(h))
    return feedforward


def base_parameters(config: ConfigSchema, which: str = "plant") -> np.ndarray:
    """The base parameters beta of the plant (``which="plant"``) or of the model the controller
    believes (``which="model"``), in the order of :func:`base_parameter_names`.

    Two-link arm: (p1, p2, p3, g1, g2, coulomb, viscous), in which M ddq + C dq + G + F =
    Y(q, dq, ddq) beta (the online identifier's parameters; ``result.model_parameters`` holds its
    estimate). URDF arm (``UrdfArm.identifier_parameters``): the base inertial parameters of the
    kinetic energy first (``UrdfArm.base_parameters``, those of the structured basis' W*), then
    the parameters gravity sees beyond them, then the Coulomb and the viscous coefficient of
    each joint.

    Examples
    --------
    >>> import adparm
    >>> adparm.base_parameters(adparm.paper_config())
    array([ 5.  ,  1.  ,  1.  , 11.76,  9.8 , -0.1 ,  0.  ])
    """
    check_config(config)
    if which not in ("plant", "model"):
        raise ValueError(f'which: expected "plant" or "model", got {which!r}')
    if config.plant.urdf is not None:
        values = config_arm(config, model=which == "model").identifier_parameters()[0]
        return np.array(values, dtype=float)
    values = (
        config.model.resolve(config.plant)
        if which == "model"
        else {key: getattr(config.plant, key) for key in TWO_LINK_BASE_PARAMETERS}
    )
    return np.array([float(values[key]) for key in TWO_LINK_BASE_PARAMETERS])


def base_parameter_names(config: ConfigSchema) -> tuple[str, ...]:
    """Names of :func:`base_parameters`: ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous") for
    the two-link arm; for a URDF arm the inertial parameter each base parameter is named by
    ("m link2", ..., as in the structured basis' names), then "coulomb <joint>" and
    "viscous <joint>"."""
    check_config(config)
    if config.plant.urdf is None:
        return TWO_LINK_BASE_PARAMETERS
    return tuple(config_arm(config).identifier_parameters()[1])


#: The group ("inertia", "gravity", "friction") of each two-link base parameter.
TWO_LINK_PARAMETER_GROUPS = ("inertia",) * 3 + ("gravity",) * 2 + ("friction",) * 2


def base_parameter_groups(config: ConfigSchema) -> tuple[str, ...]:
    """The group of each of :func:`base_parameters` ("inertia", "gravity" or "friction"): what
    identifier.inertia, .gravity and .friction select. A URDF arm's come from the core
    (``UrdfArm.identifier_parameters``)."""
    check_config(config)
    if config.plant.urdf is None:
        return TWO_LINK_PARAMETER_GROUPS
    return tuple(config_arm(config).identifier_parameters()[2])


def inertia_matrices(config: ConfigSchema, positions: Any, *, model: bool = False) -> np.ndarray:
    """M(q) (m, n, n) of the plant (``model=True``: the believed model) at each row of
    ``positions`` (m, n); a URDF arm is read once for all of them."""
    n = config.dof
    rows = np.atleast_2d(np.asarray(positions, dtype=float))
    if config.plant.urdf is not None:
        arm = config_arm(config, model=model)
        return np.array([arm.terms(q, np.zeros(n))["M"] for q in rows])
    return np.array([arm_terms(config, q, np.zeros(n), model=model)["M"] for q in rows])


def value_scale(config: ConfigSchema, *, rtol: float = 1e-9) -> float | None:
    """s > 0 with Q22 = s^2 R^-1 (to relative tolerance rtol), or None when there is none.

    In the exact family V* = e1^T K e1 + s e2^T M(q) e2 and u* = -s R^-1 e2 (s = 1: the paper's
    corrected example)."""
    n = config.dof
    Q22 = np.array(config.cost.Q)[n:, n:]
    R = np.array(config.cost.R)
    product = Q22 @ R  # = s^2 I
    s2 = np.trace(product) / n
    if not s2 > 0.0 or np.abs(product - s2 * np.eye(n)).max() > rtol * max(s2, 1.0):
        return None
    return float(np.sqrt(s2))


def solvable_cost(K: Any, alpha1: Any, R: Any, s: float = 1.0) -> np.ndarray:
    """The state weight Q for which V* = e1^T K e1 + s e2^T M(q) e2 is the exact HJB solution.

    For an n-joint arm (n = 2 for the two-link arm). Use it with ``cost.R = R`` and
    ``control.alpha1 = alpha1`` to make an instance whose W* is known.

    Parameters
    ----------
    K : array_like, shape (n, n)
        Symmetric positive definite: the e1 block of V*.
    alpha1 : array_like, shape (n, n)
        The gain in e2 = de1 + alpha1 e1.
    R : array_like, shape (n, n)
        The input weight.
    s : float, optional
        The scale of the e2 block (s = 1: the paper's corrected example).

    Returns
    -------
    ndarray, shape (2n, 2n)
        Q with Q11 = K alpha1 + alpha1^T K, Q12 = Q21 = -K, Q22 = s^2 R^-1.

    Raises
    ------
    ValueError
        If an input has the wrong shape or is not finite, K is not symmetric positive definite,
        s is not > 0, or the resulting Q is not positive definite (then cost.Q would be refused).
    """
    if isinstance(s, bool) or not isinstance(s, (int, float, np.floating, np.integer)):
        raise TypeError(f"s: expected a number > 0, got {s!r}")
    if not (np.isfinite(s) and s > 0.0):
        raise ValueError(f"s: expected a finite number > 0, got {s!r}")
    K, alpha1, R = (real_array(v, name) for v, name in ((K, "K"), (alpha1, "alpha1"), (R, "R")))
    n = K.shape[0] if K.ndim == 2 else 0
    for name, value in (("K", K), ("alpha1", alpha1), ("R", R)):
        if n < 1 or value.shape != (n, n) or not np.all(np.isfinite(value)):
            raise ValueError(
                f"{name}: expected a finite n x n matrix (n = {n or 'the size of K'}), "
                f"got {value.tolist()}"
            )
    if not np.allclose(K, K.T) or np.linalg.eigvalsh(K).min() <= 0.0:
        raise ValueError(f"K: must be symmetric positive definite, got {K.tolist()}")
    Q = np.block([[K @ alpha1 + alpha1.T @ K, -K], [-K, s**2 * np.linalg.inv(R)]])
    Q = 0.5 * (Q + Q.T)
    if np.linalg.eigvalsh(Q).min() <= 0.0:
        raise ValueError(
            "K, alpha1, R: Q = [[K alpha1 + alpha1^T K, -K], [-K, s^2 R^-1]] is not positive "
            "definite; increase alpha1 or s, or decrease R"
        )
    return Q


def saturated_cost(K: Any, alpha1: Any, R: Any, input_bound: Any) -> dict[str, Any]:
    """The ``[cost]`` section of the exact constrained-input family: with it, V* = e1^T K e1 +
    e2^T M(q) e2 solves the HJB equation of the bounded input ``|u_i| <= lambda_i`` exactly, and
    u* = -lambda tanh(R^-1 e2 / lambda) (docs: constrained-input).

    Parameters
    ----------
    K : array_like, shape (n, n)
        Symmetric positive definite: the e1 block of V*.
    alpha1 : array_like, shape (n, n)
        The gain in e2 = de1 + alpha1 e1.
    R : array_like, shape (n, n)
        The input weight, diagonal with positive entries.
    input_bound : float or array_like, shape (n,)
        lambda, > 0: one number for every joint or one per joint.

    Returns
    -------
    dict
        ``{"Q": ..., "R": ..., "input_bound": ..., "e2_cost": "logcosh"}`` (nested lists), for
        ``Config.from_dict({"cost": ...})`` or ``config.updated(cost=...)``; Q is
        :func:`solvable_cost` (K, alpha1, R), so W* is that of the unbounded exact family.

    Raises
    ------
    ValueError
        As :func:`solvable_cost`, or if R is not diagonal or a bound is not a finite number > 0.
    """
    Q = solvable_cost(K, alpha1, R)
    n = Q.shape[0] // 2
    R = real_array(R, "R")
    if np.any(R != np.diag(np.diag(R))):
        raise ValueError(f"R: must be diagonal (the bounded input cost), got {R.tolist()}")
    bound = real_array(input_bound, "input_bound")
    if bound.ndim == 0:
        bound = np.full(n, float(bound))
    if bound.shape != (n,) or not np.all(np.isfinite(bound)) or np.any(bound <= 0.0):
        raise ValueError(
            f"input_bound: expected one finite number > 0 or {n} of them, got {bound.tolist()}"
        )
    return {
        "Q": Q.tolist(),
        "R": R.tolist(),
        "input_bound": bound.tolist(),
        "e2_cost": "logcosh",
    }


def weight_vector(value: Any, name: str, size: int = 8) -> np.ndarray:
    check_real(np.asarray(value), name)
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name}: expected an array of {size} numbers, got {value!r}") from error
    if array.shape != (size,):
        raise ValueError(f"{name}: expected shape ({size},), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: must be finite")
    return array


def initial_error_state(config: ConfigSchema) -> np.ndarray:
    """x(0) = [e1(0); e2(0)] of ``config``: e1 = qd(0) - q0, e2 = dqd(0) - dq0 + alpha1 e1."""
    if not isinstance(config, ConfigSchema):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    desired = desired_state(config, 0.0)
    alpha1 = np.array(config.control.alpha1)
    e1 = desired[0] - np.array(config.task.q0)
    e2 = desired[1] - np.array(config.task.dq0) + alpha1 @ e1
    return np.concatenate([e1, e2])


def two_link_mass(config: ConfigSchema, q2: float) -> np.ndarray:
    p = config.model.resolve(config.plant)
    c = math.cos(q2)
    m12 = p["p2"] + p["p3"] * c
    return np.array([[p["p1"] + 2.0 * p["p3"] * c, m12], [m12, p["p2"]]])


def linearisation(config: ConfigSchema) -> tuple[np.ndarray, np.ndarray]:
    """A, B of dx = A x + B u at x = 0 for the set-point qd(0): de1 = -alpha1 e1 + e2,
    M(qd) de2 = u (C e2 is quadratic in x and the feedforward cancels G and F)."""
    alpha1 = np.array(config.control.alpha1)
    qd = desired_state(config, 0.0)[0]
    n = config.dof
    if config.plant.urdf is None:
        M = two_link_mass(config, qd[1])
    else:
        M = arm_terms(config, qd, np.zeros(n), model=True)["M"]
    A = np.block([[-alpha1, np.eye(n)], [np.zeros((n, n)), np.zeros((n, n))]])
    B = np.vstack([np.zeros((n, n)), np.linalg.inv(M)])
    return A, B


def lqr_value(config: ConfigSchema) -> np.ndarray:
    """P (4 x 4) of the algebraic Riccati equation A^T P + P A - P B R^-1 B^T P + Q = 0 of the
    error system linearised at the set-point qd(0) (believed model, A = [[-alpha1, I], [0, 0]],
    B = [0; M(qd)^-1]), solved by python-control (control.care). x^T P x is V* exactly for a
    linear arm (p3 = 0) and the local V* near the set-point otherwise; on the exact instances
    P = blockdiag(K, s M(qd))."""
    import control

    check_config(config)
    A, B = linearisation(config)
    Q, R = np.array(config.cost.Q), np.array(config.cost.R)
    P, _, _ = control.care(A, B, Q, R)
    P = np.asarray(P)
    return 0.5 * (P + P.T)


def exact_family(config: ConfigSchema, rtol: float = 1e-9) -> tuple[np.ndarray, float]:
    """K = -Q12 and s of the exact family V* = e1^T K e1 + s e2^T M(q) e2 (optimal_weights): a
    ValueError names the condition on Q that fails."""
    n = config.dof
    if config.cost.input_bound is not None and config.cost.e2_cost != "logcosh":
        raise ValueError(
            'cost.e2_cost: with cost.input_bound the exact family needs e2_cost = "logcosh" '
            "(adparm.saturated_cost); with the quadratic e2 cost V* is not known"
        )
    Q = np.array(config.cost.Q)
    R = np.array(config.cost.R)
    alpha1 = np.array(config.control.alpha1)
    Q11, Q12, Q22 = Q[:n, :n], Q[:n, n:], Q[n:, n:]
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
    scale = value_scale(config)
    if scale is None:
        derived = config.derived.get("cost.R")
        raise ValueError(
            f"cost.Q: Q22 must equal s^2 R^-1 for some s > 0 (got Q22 = {Q22.tolist()}, "
            f"R^-1 = {np.linalg.inv(R).tolist()})"
            + (
                # a URDF arm derives cost.R when left out, also on config.updated with Q alone
                f"; cost.R was not given but derived for this arm ({derived}): R = "
                f"{R.tolist()}; give cost.R with the R that Q was built from "
                '(config.updated({"cost": {"Q": Q, "R": R}}))'
                if derived is not None
                else ""
            )
        )
    return K, scale
