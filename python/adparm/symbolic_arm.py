"""The believed arm's terms of eq. (1) as CasADi expressions, for the numerical yardstick
(adparm.optimal_cost): M(q), C(q, dq), G(q), F(dq) and the feedforward h at a set-point.

The two-link arm's terms are those of Section 4. A URDF arm's M and G come from adam-robotics
(its CasADi CRBA and RNEA, with the base fixed; adparm writes no rigid-body algorithm of its own)
and C from M by the Christoffel symbols,
C_ij = sum_k (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) dq_k / 2, by CasADi's exact derivatives:
the factorisation of Pinocchio's computeCoriolisMatrix, which the
core's URDF arms use (dM/dt - 2C skew-symmetric; tests/test_yardstick_limits.py checks all three
against Pinocchio's Python bindings to 1e-10)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._schema import ConfigSchema
from .urdf import config_arm

__all__ = ["ADAM_MISSING", "arm_expressions", "set_point_feedforward"]

#: What optimal_cost says on a URDF arm without adam-robotics.
ADAM_MISSING = (
    "plant.urdf: optimal_cost on a URDF arm builds M, C, G with adam-robotics, which is not "
    "installed (pip install 'adam-robotics[casadi]>=0.5')"
)


def arm_expressions(config: ConfigSchema, q: Any, dq: Any) -> dict[str, Any]:
    """{"M", "C", "G", "F"} of the arm ``config`` believes (config.model over config.plant) as
    CasADi SX expressions of the SX symbols q, dq (n each), F = coulomb sign(dq) + viscous dq,
    and its coefficients {"coulomb", "viscous"} (n each, NumPy). A URDF arm with locked joints is
    refused (adam-robotics has no reduced model): a ValueError naming the locked_joints field."""
    if config.plant.urdf is None:
        return _two_link(config, q, dq)
    return _urdf(config, q, dq)


def set_point_feedforward(terms: dict[str, Any], alpha1: np.ndarray, e1: Any, e2: Any) -> Any:
    """h = M (ddqd + alpha1 de1) + C (dqd + alpha1 e1) + G + F (eq. 5 in full) at a set-point
    (dqd = ddqd = 0, so de1 = -dq = -alpha1 e1 + e2): the torque tau = h - u realises the error
    system's input u (mu = 0, no disturbance)."""
    import casadi

    gain = casadi.DM(alpha1)
    de1 = -casadi.mtimes(gain, e1) + e2
    return (
        casadi.mtimes(terms["M"], casadi.mtimes(gain, de1))
        + casadi.mtimes(terms["C"], casadi.mtimes(gain, e1))
        + terms["G"]
        + terms["F"]
    )


def _friction(coulomb: Any, viscous: Any, dq: Any) -> Any:
    import casadi

    return casadi.DM(coulomb) * casadi.sign(dq) + casadi.DM(viscous) * dq


def _two_link(config: ConfigSchema, q: Any, dq: Any) -> dict[str, Any]:
    import casadi

    p = config.model.resolve(config.plant)
    c2, s2 = casadi.cos(q[1]), casadi.sin(q[1])
    m12 = p["p2"] + p["p3"] * c2
    M = casadi.vertcat(
        casadi.horzcat(p["p1"] + 2 * p["p3"] * c2, m12), casadi.horzcat(m12, p["p2"])
    )
    h = p["p3"] * s2
    C = casadi.vertcat(
        casadi.horzcat(-h * dq[1], -h * (dq[0] + dq[1])), casadi.horzcat(h * dq[0], 0)
    )
    c12 = casadi.cos(q[0] + q[1])
    G = casadi.vertcat(p["g1"] * casadi.cos(q[0]) + p["g2"] * c12, p["g2"] * c12)
    ones = np.ones(2)
    coulomb, viscous = p["coulomb"] * ones, p["viscous"] * ones
    F = _friction(coulomb, viscous, dq)
    return {"M": M, "C": C, "G": G, "F": F, "coulomb": coulomb, "viscous": viscous}


def _urdf(config: ConfigSchema, q: Any, dq: Any) -> dict[str, Any]:
    import casadi

    believed = config.model.resolve_urdf(config.plant)
    if believed["locked_joints"]:
        field = "model" if config.model.locked_joints is not None else "plant"
        raise ValueError(
            f"{field}.locked_joints: optimal_cost does not transcribe a URDF arm with locked "
            "joints (adam-robotics builds the full model); leave locked_joints out"
        )
    try:
        from adam.casadi import KinDynComputations
    except ImportError:
        raise ValueError(ADAM_MISSING) from None
    arm = config_arm(
        config, model=True
    )  # the joint names, friction and gravity as the core has them
    n = arm.dof
    gravity = np.concatenate([np.asarray(arm.gravity, dtype=float), np.zeros(3)])
    dynamics = KinDynComputations(str(believed["urdf"]), list(arm.joint_names), gravity=gravity)
    base = casadi.SX.eye(4)  # the fixed base at the URDF's root frame
    position, velocity = casadi.SX.sym("q", n), casadi.SX.sym("dq", n)
    M = dynamics.mass_matrix(base, position)[6:, 6:]
    G = dynamics.gravity_term(base, position)[6:]
    dM = casadi.jacobian(casadi.vec(M), position)  # column k: vec(dM/dq_k)
    # A_ij = sum_k dM_ik/dq_j dq_k; C = (dM/dt + A - A^T) / 2 (Christoffel symbols)
    A = casadi.horzcat(*(casadi.mtimes(casadi.reshape(dM[:, j], n, n), velocity) for j in range(n)))
    dMdt = casadi.reshape(casadi.mtimes(dM, velocity), n, n)
    C = 0.5 * (dMdt + A - A.T)
    M, C, G = casadi.Function("terms", [position, velocity], [M, C, G])(q, dq)
    if believed["scale"] is not None:  # model.scale: every link's mass and inertia times it
        M, C, G = believed["scale"] * M, believed["scale"] * C, believed["scale"] * G
    coulomb = np.broadcast_to(np.asarray(arm.coulomb, float), (n,)).copy()
    viscous = np.broadcast_to(np.asarray(arm.viscous, float), (n,)).copy()
    F = _friction(coulomb, viscous, dq)
    return {"M": M, "C": C, "G": G, "F": F, "coulomb": coulomb, "viscous": viscous}
