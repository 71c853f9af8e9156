"""The analytic optimum V*, W* (docs: "The paper and its corrections"), the basis at given states,
the arm's terms, and the Riccati value of the linearised error system (lqr_value). The HJB
residual (21), which needs the core's settings of a run, is adparm.residual."""

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
    "BASIS_NAMES",
    "STRUCTURED_BASIS_NAMES",
    "arm_terms",
    "basis",
    "basis_names",
    "linearisation",
    "lqr_value",
    "initial_error_state",
    "optimal_value",
    "optimal_weights",
    "policy",
    "solvable_cost",
    "value_scale",
]

#: The paper's basis phi(x), x = [e1; e2] (the order of W*).
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

#: The structured basis of the two-link arm, x = [e1; e2], q = qd - e1, M(q) = p1 M1 + p2 M2 +
#: p3 M3 with M1 = [[1, 0], [0, 0]], M2 = [[0, 1], [1, 1]], M3 = [[2 cos q2, cos q2], [cos q2, 0]].
STRUCTURED_BASIS_NAMES = (
    "x1^2",
    "x1 x2",
    "x2^2",
    "e2^T M1 e2",
    "e2^T M2 e2",
    "e2^T M3(q) e2",
)


def check_config(config: Any) -> None:
    if not isinstance(config, ConfigSchema):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")


def basis_names(config: ConfigSchema) -> tuple[str, ...]:
    """The names of the functions of ``config.controller.basis``, in the order of the weights."""
    check_config(config)
    if config.controller.is_expression:  # the terms' text, after expansion of the families
        return config.controller.expression_basis(config.dof).terms
    if _urdf_structured(config):
        return tuple(config_arm(config, model=True).structured_names())
    return STRUCTURED_BASIS_NAMES if config.controller.basis == "structured" else BASIS_NAMES


def _urdf_structured(config: ConfigSchema) -> bool:
    """Whether the config runs the structured basis of a URDF arm (the believed model's)."""
    return config.plant.urdf is not None and config.controller.basis == "structured"


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


def basis(config: ConfigSchema, x: Any, qd: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """The basis of ``config.controller.basis`` and its exact Jacobian at error states x of shape
    (..., 2n) (n joints): phi (..., K) and d phi / dx (..., K, 2n), computed by the C++ core.
    ``qd`` is the desired position (n,) or (..., n) the basis may depend on (augmented and
    structured bases: through q = qd - e1); default the config's qd at t = 0. The structured
    basis of a URDF arm is the believed model's (``UrdfArm.structured_basis``)."""
    check_config(config)
    n = config.dof
    states = error_states(x, 2 * n)
    desired = desired_state(config, 0.0)[0] if qd is None else error_states(qd, n, "qd")
    desired = np.broadcast_to(desired, states.shape[:-1] + (n,))
    if config.controller.is_expression:
        phi, jacobian, _ = config.controller.expression_basis(n).evaluate(states, desired)
        return phi, jacobian
    if _urdf_structured(config):
        phi, jacobian, _ = config_arm(config, model=True).structured_basis(states, desired)
        return phi, jacobian
    kind = getattr(_core.BasisKind, config.controller.basis)
    rows = states.reshape(-1, 2 * n)
    desired_rows = desired.reshape(-1, n)
    size = len(basis_names(config))
    phi = np.empty((rows.shape[0], size))
    jacobian = np.empty((rows.shape[0], size, 2 * n))
    for i, (row, qd_row) in enumerate(zip(rows, desired_rows, strict=True)):
        p, j, _ = _core.basis(kind, row, qd_row, np.zeros(n))
        phi[i], jacobian[i] = p, j
    return (
        phi.reshape(states.shape[:-1] + (size,)),
        jacobian.reshape(states.shape[:-1] + (size, 2 * n)),
    )


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


def inertia_matrices(config: ConfigSchema, positions: Any, *, model: bool = False) -> np.ndarray:
    """M(q) (m, n, n) of the plant (``model=True``: the believed model) at each row of
    ``positions`` (m, n); a URDF arm is read once for all of them."""
    n = config.dof
    rows = np.atleast_2d(np.asarray(positions, dtype=float))
    if config.plant.urdf is not None:
        arm = config_arm(config, model=model)
        return np.array([arm.terms(q, np.zeros(n))["M"] for q in rows])
    return np.array([arm_terms(config, q, np.zeros(n), model=model)["M"] for q in rows])


def policy(config: ConfigSchema, x: Any, t: Any, weights: Any) -> np.ndarray:
    """The actor's input u = -1/2 R^-1 g(x)^T (d phi / dx)^T W (eq. 20) at error states x (m, 2n)
    and times t (m,) (qd(t) enters the basis and q = qd - e1 the inertia of g = [0; M^-1]), with
    weights W (K,) or one row per state (m, K); the believed model's M. With W = W* it is the
    optimal input u* = -R^-1 e2 of the exact family. Returns (m, n)."""
    check_config(config)
    n = config.dof
    states = np.atleast_2d(error_states(x, 2 * n))
    times = np.broadcast_to(real_array(t, "t"), (len(states),))
    desired = desired_state(config, times)[:, 0, :]
    _, jacobian = basis(config, states, desired)
    W = np.broadcast_to(real_array(weights, "weights"), (len(states), jacobian.shape[1]))
    gradient_e2 = np.einsum("mkx,mk->mx", jacobian, W)[:, n:]
    masses = inertia_matrices(config, desired - states[:, :n], model=True)
    R_inverse = np.linalg.inv(np.array(config.cost.R))
    return -0.5 * np.einsum(
        "ij,mj->mi", R_inverse, np.linalg.solve(masses, gradient_e2[..., None])[..., 0]
    )


def optimal_weights(config: ConfigSchema, *, rtol: float = 1e-9) -> np.ndarray:
    """The exact weights W* of V*(x) = x^T blockdiag(K, M(q)) x in the config's basis.

    They exist when K = -Q12 is symmetric positive definite, Q11 = K alpha1 + alpha1^T K and
    Q22 = s^2 R^-1 for some s > 0 (to relative tolerance rtol), for any desired trajectory with
    the augmented and structured bases and for a set-point with qd2 = 0 with the paper's basis
    (cos x2 = cos q2 there). Then V* = e1^T K e1 + s e2^T M(q) e2 and u* = -s R^-1 e2; s = 1 is
    the case of the paper's corrected example.

    Parameters
    ----------
    config : Config
        Cost, alpha1, basis, task and the arm the controller believes ([model], by default the
        plant).
    rtol : float, optional
        Relative tolerance of the conditions on Q.

    Returns
    -------
    ndarray, shape (8,), (6,) or (config.basis_size,)
        In the order of ``adparm.basis_names(config)``: W* = [K11, K22, 2 K12, s p1, 2 s p3,
        s p2, 2 s p2, 2 s p3] for the paper and augmented bases (the paper's example:
        [4, 6, -8, 5, 2, 1, 2, 2]), [K11, 2 K12, K22, s p1, s p2, s p3] for the structured basis;
        for the structured basis of a URDF arm [K_ii on squares, 2 K_ij on cross terms; s beta]
        with beta the believed model's base inertial parameters (``UrdfArm.base_parameters``).

    Raises
    ------
    ValueError
        Naming the condition that fails, when the analytic solution does not apply.

    Examples
    --------
    >>> import adparm
    >>> adparm.optimal_weights(adparm.paper_config())
    array([ 4.,  6., -8.,  5.,  2.,  1.,  2.,  2.])
    """
    if not isinstance(config, ConfigSchema):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    if config.controller.is_expression:
        return _expression_optimal_weights(config)
    n = config.dof
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
        raise ValueError(
            f"cost.Q: Q22 must equal s^2 R^-1 for some s > 0 (got Q22 = {Q22.tolist()}, "
            f"R^-1 = {np.linalg.inv(R).tolist()})"
        )
    if config.controller.basis == "paper" and not (
        config.task.is_set_point and config.task.qd[1] == 0.0
    ):
        raise ValueError(
            "task.qd: the paper basis represents V* only for a set-point with qd2 = 0 "
            "(controller.basis = 'augmented' represents it for any qd)"
        )
    if _urdf_structured(config):  # [K entries; s beta] of the believed model's base parameters
        weights = config_arm(config, model=True).structured_weights(0.5 * (K + K.T))
        weights[n * (n + 1) // 2 :] *= scale
        return weights
    p = config.model.resolve(config.plant)
    if config.controller.basis == "structured":
        return np.array([K[0, 0], 2.0 * K[0, 1], K[1, 1], p["p1"], p["p2"], p["p3"]])
    return np.array(
        [
            K[0, 0],
            K[1, 1],
            2.0 * K[0, 1],
            scale * p["p1"],
            2.0 * scale * p["p3"],
            scale * p["p2"],
            2.0 * scale * p["p2"],
            2.0 * scale * p["p3"],
        ]
    )


def _expression_optimal_weights(config: ConfigSchema) -> np.ndarray:
    """W* of an expression basis: on a linear believed arm (p3 = 0, no gravity, no friction) V* =
    x^T P x with P of the Riccati equation (adparm.lqr_value), in the basis' weights when it can
    represent it (e.g. "quadratic")."""
    if config.plant.urdf is not None:
        raise ValueError(
            "controller.basis: no known W* for an expression basis on a URDF arm (plant.urdf): "
            "its M(q) and G(q) vary with q, so V* is not a quadratic form in x"
        )
    p = config.model.resolve(config.plant)
    nonlinear = [key for key in ("p3", "g1", "g2", "coulomb", "viscous") if p[key] != 0.0]
    if nonlinear:
        raise ValueError(
            f"controller.basis: no known W* for an expression basis on a nonlinear arm (model "
            f"{', '.join(nonlinear)} != 0); it is known on a linear arm (p3 = g1 = g2 = 0, no "
            "friction), where V* = x^T P x (adparm.lqr_value)"
        )
    P = lqr_value(config)
    try:
        return config.controller.expression_basis(config.dof).quadratic_form_weights(P)
    except ValueError as error:
        raise ValueError(f"controller.basis: cannot represent V* = x^T P x ({error})") from None


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


def optimal_value(config: ConfigSchema, x: Any = None, *, t: float = 0.0) -> float:
    """The optimal value V*(x) = e1^T K e1 + e2^T M(q) e2, with q = qd(t) - e1.

    The optimal cost-to-go of eq. (10) from x for the disturbance-free error system, on the
    believed arm, when the conditions of :func:`optimal_weights` hold.

    Parameters
    ----------
    config : Config
        The instance.
    x : array_like, shape (4,), optional
        The error state; default the initial error state of ``config``.
    t : float, optional
        Time at which qd is taken.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If the analytic solution does not apply (see :func:`optimal_weights`).
    """
    weights = optimal_weights(config)
    x = initial_error_state(config) if x is None else x
    n = config.dof
    states = real_array(x, "x")
    if states.shape != (2 * n,) or not np.all(np.isfinite(states)):
        raise ValueError(f"x: expected {2 * n} finite numbers, got {x!r}")
    qd = desired_state(config, t)[0]
    if config.controller.is_expression or _urdf_structured(config):
        phi = basis(config, states, qd)[0]
    else:  # V* = W*^T phi(x, qd) in the augmented basis, exactly
        kind = "structured" if config.controller.basis == "structured" else "augmented"
        phi, _, _ = _core.basis(getattr(_core.BasisKind, kind), states, qd, np.zeros(2))
    return float(weights @ np.asarray(phi))


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
