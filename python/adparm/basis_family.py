"""The basis' seam in Python: one class per family of critic/actor bases, and basis_for(config),
the one place that picks the family of a config (its arm and controller.basis).

A family says what the rest of the package asks of a basis: its functions' names and number,
the default initial weights, the exact weights W* where they are known, its value and exact
Jacobian at error states, and the core's BasisKind that runs it. A new basis is a new class and
one entry of :data:`BASIS_FAMILIES` (and, for the core, its C++ basis: docs/design.md).
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

import adparm._core as _core

from ._arm_sections import plain_value, urdf_structured_size
from ._schema import ConfigSchema
from ._sections import BASIS_SIZES
from .desired import desired_state
from .dynamics import arm_terms, exact_family, lqr_value
from .urdf import config_arm

__all__ = [
    "BASIS_FAMILIES",
    "BASIS_NAMES",
    "STRUCTURED_BASIS_NAMES",
    "BasisFamily",
    "ExpressionFamily",
    "PaperBasis",
    "TwoLinkStructuredBasis",
    "UrdfStructuredBasis",
    "basis_for",
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


class BasisFamily(Protocol):
    """What the package asks of a basis on a config's arm (``config`` is checked by the caller)."""

    #: The name of the core's adparm._core.BasisKind that runs it.
    core_kind: str
    #: Whether every function and its d phi / dx are finite at every state (a built-in basis);
    #: else :meth:`nonfinite` finds the first that is not.
    finite_everywhere: bool
    #: Whether the core runs it on the dynamic-size (n-joint) loop rather than the two-link
    #: arm's fixed-size one (cpp/include/adparm/any_simulation.hpp, visit_loop).
    dynamic_sizes: bool

    def names(self, config: ConfigSchema) -> tuple[str, ...]:
        """The functions' names, in the order of the weights."""

    def size(self, config: ConfigSchema) -> int:
        """The number of functions K (the length of the weights)."""

    def initial_weights(self, config: ConfigSchema, key: str) -> np.ndarray:
        """The default init.critic_weights or init.actor_weights (``key``)."""

    def optimal_weights(self, config: ConfigSchema, rtol: float) -> np.ndarray:
        """W*, or a ValueError naming why it is not known."""

    def evaluate(
        self, config: ConfigSchema, states: np.ndarray, desired: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """phi (..., K) and d phi / dx (..., K, 2n) at error states (..., 2n) and desired
        positions (..., n)."""

    def value_features(self, config: ConfigSchema, state: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The functions whose product with W* is V*(x) at one state (optimal_value)."""

    def nonfinite(self, config: ConfigSchema, states: Any, qd: Any) -> str | None:
        """The first function (or its d phi / dx) not finite at one of ``states`` (m, 2n) with
        desired position ``qd``, named with the state; None if all are."""

    def core_program(self, config: ConfigSchema) -> _core.ExpressionProgram | None:
        """What the core needs besides core_kind to run the basis (an expression basis' compiled
        terms), or None."""


class _CoreBasis:
    """A basis of the two-link arm built into the core, evaluated row by row."""

    core_kind = "augmented"
    finite_everywhere = True
    dynamic_sizes = False
    function_names: tuple[str, ...] = BASIS_NAMES

    def nonfinite(self, config: ConfigSchema, states: Any, qd: Any) -> str | None:
        return None

    def core_program(self, config: ConfigSchema) -> _core.ExpressionProgram | None:
        return None

    def names(self, config: ConfigSchema) -> tuple[str, ...]:
        return self.function_names

    def size(self, config: ConfigSchema) -> int:
        return BASIS_SIZES[self.core_kind]

    def evaluate(
        self, config: ConfigSchema, states: np.ndarray, desired: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        n = config.dof
        kind = getattr(_core.BasisKind, self.core_kind)
        rows = states.reshape(-1, 2 * n)
        desired_rows = desired.reshape(-1, n)
        size = len(self.names(config))
        phi = np.empty((rows.shape[0], size))
        jacobian = np.empty((rows.shape[0], size, 2 * n))
        for i, (row, qd_row) in enumerate(zip(rows, desired_rows, strict=True)):
            p, j, _ = _core.basis(kind, row, qd_row, np.zeros(n))
            phi[i], jacobian[i] = p, j
        return (
            phi.reshape(states.shape[:-1] + (size,)),
            jacobian.reshape(states.shape[:-1] + (size, 2 * n)),
        )

    def value_features(self, config: ConfigSchema, state: np.ndarray, qd: np.ndarray) -> np.ndarray:
        # V* = W*^T phi(x, qd) in the augmented basis, exactly (the paper's W* is the same)
        kind = "structured" if self.core_kind == "structured" else "augmented"
        phi, _, _ = _core.basis(getattr(_core.BasisKind, kind), state, qd, np.zeros(2))
        return np.asarray(phi)


class PaperBasis(_CoreBasis):
    """The paper's 8 functions of the two-link arm: ``paper`` (phi(x), cos x2) or ``augmented``
    (phi(x, qd), cos q2: exact for any qd). Their e2 block is [[W4 + c W5, (W7 + c W8)/2],
    [., W6]] (positive_block.hpp)."""

    def __init__(self, kind: str) -> None:
        self.core_kind = kind

    def initial_weights(self, config: ConfigSchema, key: str) -> np.ndarray:
        return np.ones(BASIS_SIZES[self.core_kind])

    def optimal_weights(self, config: ConfigSchema, rtol: float) -> np.ndarray:
        K, scale = exact_family(config, rtol)
        if self.core_kind == "paper" and not (
            config.task.is_set_point and config.task.qd[1] == 0.0
        ):
            raise ValueError(
                "task.qd: the paper basis represents V* only for a set-point with qd2 = 0 "
                "(controller.basis = 'augmented' represents it for any qd)"
            )
        p = config.model.resolve(config.plant)
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


class TwoLinkStructuredBasis(_CoreBasis):
    """The structured basis of the two-link arm: the products of e1 and e2^T M_k(q) e2."""

    core_kind = "structured"
    function_names = STRUCTURED_BASIS_NAMES

    def initial_weights(self, config: ConfigSchema, key: str) -> np.ndarray:
        p = config.model.resolve(config.plant)
        return np.array([1.0, 0.0, 1.0, p["p1"], p["p2"], p["p3"]])

    def optimal_weights(self, config: ConfigSchema, rtol: float) -> np.ndarray:
        K, _ = exact_family(config, rtol)
        p = config.model.resolve(config.plant)
        return np.array([K[0, 0], 2.0 * K[0, 1], K[1, 1], p["p1"], p["p2"], p["p3"]])


class UrdfStructuredBasis:
    """The structured basis of a URDF arm (the believed model's): the products of e1 and one
    e2^T M_b(q) e2 per base inertial parameter (UrdfArm.structured_basis)."""

    core_kind = "structured"
    finite_everywhere = True
    dynamic_sizes = True

    def names(self, config: ConfigSchema) -> tuple[str, ...]:
        return tuple(config_arm(config, model=True).structured_names())

    def nonfinite(self, config: ConfigSchema, states: Any, qd: Any) -> str | None:
        return None

    def core_program(self, config: ConfigSchema) -> _core.ExpressionProgram | None:
        return None

    def size(self, config: ConfigSchema) -> int:
        believed = config.model.resolve_urdf(config.plant)
        return urdf_structured_size(
            believed["urdf"],
            "model.urdf" if config.model.urdf else "plant.urdf",
            believed["locked_joints"],
        )

    def initial_weights(self, config: ConfigSchema, key: str) -> np.ndarray:
        # K = I and the believed model's base parameters: u_hat = -R^-1 e2 at first
        return config_arm(config, model=True).structured_weights(np.eye(config.dof))

    def optimal_weights(self, config: ConfigSchema, rtol: float) -> np.ndarray:
        # [K entries; s beta] of the believed model's base parameters
        K, scale = exact_family(config, rtol)
        n = config.dof
        weights = config_arm(config, model=True).structured_weights(0.5 * (K + K.T))
        weights[n * (n + 1) // 2 :] *= scale
        return weights

    def evaluate(
        self, config: ConfigSchema, states: np.ndarray, desired: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        phi, jacobian, _ = config_arm(config, model=True).structured_basis(states, desired)
        return phi, jacobian

    def value_features(self, config: ConfigSchema, state: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return self.evaluate(config, state, qd)[0]


class ExpressionFamily:
    """An expression basis (terms and families of controller.basis, adparm.bases), compiled once
    and run by the core's dynamic-size loop."""

    core_kind = "expression"
    finite_everywhere = False  # sqrt or log of a negative value, 1/0, ...
    dynamic_sizes = True

    def nonfinite(self, config: ConfigSchema, states: Any, qd: Any) -> str | None:
        return config.controller.expression_basis(config.dof).nonfinite(states, qd)

    def core_program(self, config: ConfigSchema) -> _core.ExpressionProgram:
        # the compiled terms, run on the dynamic-size loop
        expression = config.controller.expression_basis(config.dof)
        program = _core.ExpressionProgram()
        program.opcodes = expression.opcodes.tolist()
        program.arguments = expression.arguments.tolist()
        return program

    def names(self, config: ConfigSchema) -> tuple[str, ...]:
        # the terms' text, after expansion of the families
        return config.controller.expression_basis(config.dof).terms

    def size(self, config: ConfigSchema) -> int:
        return config.controller.basis_size(config.dof)

    def initial_weights(self, config: ConfigSchema, key: str) -> np.ndarray:
        """The weights of x^T blockdiag(I, M(qd(0))) x (the believed model's inertia at the
        desired position): the actor then starts at u_hat = -R^-1 e2, which stabilises."""
        n = config.dof
        qd = desired_state(config, 0.0)[0]
        M = arm_terms(config, qd, np.zeros(n), model=True)["M"]
        P = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
        try:
            return config.controller.expression_basis(n).quadratic_form_weights(P)
        except ValueError as error:
            raise ValueError(
                f"init.{key}: controller.basis = {plain_value(config.controller.basis)!r} cannot "
                "represent the default initial value x^T blockdiag(I, M(qd)) x "
                f"({error}); set init.critic_weights and init.actor_weights"
            ) from None

    def optimal_weights(self, config: ConfigSchema, rtol: float) -> np.ndarray:
        """W* of an expression basis: on a linear believed arm (p3 = 0, no gravity, no friction)
        V* = x^T P x with P of the Riccati equation (adparm.lqr_value), in the basis' weights when
        it can represent it (e.g. "quadratic")."""
        if config.plant.urdf is not None:
            raise ValueError(
                "controller.basis: no known W* for an expression basis on a URDF arm "
                "(plant.urdf): its M(q) and G(q) vary with q, so V* is not a quadratic form in x"
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

    def evaluate(
        self, config: ConfigSchema, states: np.ndarray, desired: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        phi, jacobian, _ = config.controller.expression_basis(config.dof).evaluate(states, desired)
        return phi, jacobian

    def value_features(self, config: ConfigSchema, state: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return self.evaluate(config, state, qd)[0]


#: The family of each (arm, controller.basis): the arm "two-link" (the built-in arm) or "urdf";
#: every expression basis (terms and families) is the "expression" entry.
BASIS_FAMILIES: dict[tuple[str, str], BasisFamily] = {
    ("two-link", "augmented"): PaperBasis("augmented"),
    ("two-link", "paper"): PaperBasis("paper"),
    ("two-link", "structured"): TwoLinkStructuredBasis(),
    ("urdf", "structured"): UrdfStructuredBasis(),
    ("two-link", "expression"): ExpressionFamily(),
    ("urdf", "expression"): ExpressionFamily(),
}


def basis_for(config: ConfigSchema) -> BasisFamily:
    """The basis family of ``config``: its arm and controller.basis (BASIS_FAMILIES)."""
    arm = "two-link" if config.plant.urdf is None else "urdf"
    kind = "expression" if config.controller.is_expression else config.controller.basis
    try:
        return BASIS_FAMILIES[arm, kind]
    except KeyError:  # pragma: no cover - the schema refuses the others (URDF_REFUSED_BASES)
        raise ValueError(
            f"controller.basis: {plain_value(config.controller.basis)!r} has no basis on this arm"
        ) from None
