"""The analytic optimum V*, W* (docs: "The paper and its corrections"), the basis at given
states and the policy of given weights, each through the config's basis family
(adparm.basis_family). The arm's terms, the exact family's scale and cost and lqr_value are
adparm.dynamics (re-exported here); the HJB residual (21), which needs the core's settings of a
run, is adparm.residual."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._schema import ConfigSchema
from .bases import real_array
from .basis_family import BASIS_NAMES, STRUCTURED_BASIS_NAMES, basis_for
from .desired import desired_state
from .dynamics import (
    arm_terms,
    base_parameter_names,
    base_parameters,
    check_config,
    error_states,
    inertia_matrices,
    initial_error_state,
    linearisation,
    lqr_value,
    saturated_cost,
    solvable_cost,
    value_scale,
)

__all__ = [
    "BASIS_NAMES",
    "STRUCTURED_BASIS_NAMES",
    "arm_terms",
    "base_parameter_names",
    "base_parameters",
    "basis",
    "basis_names",
    "linearisation",
    "lqr_value",
    "inertia_matrices",
    "initial_error_state",
    "optimal_value",
    "optimal_weights",
    "policy",
    "saturated_cost",
    "solvable_cost",
    "value_scale",
]


def basis_names(config: ConfigSchema) -> tuple[str, ...]:
    """The names of the functions of ``config.controller.basis``, in the order of the weights."""
    check_config(config)
    return basis_for(config).names(config)


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
    return basis_for(config).evaluate(config, states, desired)


def policy(config: ConfigSchema, x: Any, t: Any, weights: Any) -> np.ndarray:
    """The actor's input u = -1/2 R^-1 g(x)^T (d phi / dx)^T W (eq. 20) at error states x (m, 2n)
    and times t (m,) (qd(t) enters the basis and q = qd - e1 the inertia of g = [0; M^-1]), with
    weights W (K,) or one row per state (m, K); the believed model's M. With W = W* it is the
    optimal input u* = -R^-1 e2 of the exact family. With cost.input_bound the bounded policy
    u = lambda tanh(v / lambda) of that v (docs: constrained-input). Returns (m, n)."""
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
    unbounded = -0.5 * np.einsum(
        "ij,mj->mi", R_inverse, np.linalg.solve(masses, gradient_e2[..., None])[..., 0]
    )
    if config.cost.input_bound is None:
        return unbounded
    bound = config.cost.bound_vector(n)  # u = -lambda tanh(D), D = -unbounded / lambda
    return bound * np.tanh(unbounded / bound)


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
    check_config(config)
    return basis_for(config).optimal_weights(config, rtol)


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
    phi = basis_for(config).value_features(config, states, qd)
    return float(weights @ np.asarray(phi))
