"""User-defined bases: terms written as text, parsed once with sympy, evaluated in the C++ core.

A basis is a list of terms, each an expression in the error state ``x1 .. x2n`` (``x = [e1; e2]``),
the joint angles ``q1 .. qn`` and the desired joint positions ``qd1 .. qdn``, for example
``["x1^2", "x3*x4*cos(q2)", "x3^2*cos(qd2 - x2)"]``; ``^`` and ``**`` are both powers. Families
expand to lists of terms: ``"quadratic"`` (every ``x_i x_j``, ``i <= j``), ``"polynomial"`` with a
``degree`` (every monomial of even degree up to it), and, for two joints, ``"paper"`` and
``"augmented"`` (the paper's 8 functions, with ``cos x2`` or ``cos q2``). A list may mix families
and terms; a term equal to an earlier one (after expansion) is dropped.

Each term is compiled, with ``q = qd - e1`` substituted, to a postfix program that the C++ core's
``ExpressionBasis`` (cpp/include/adparm/expression_basis.hpp) evaluates with its exact Jacobians by
forward-mode differentiation, with no Python call and no heap allocation per evaluation.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

import adparm._core as _core

if TYPE_CHECKING:
    import sympy
from .term_checks import (
    FUNCTIONS,
    MAX_DEGREE,
    MAX_EXPANSION,
    MAX_FUNCTIONS,
    MAX_TERMS,
    MAX_TOTAL_EXPANSION,
    check_joints,
    check_text,
    did_you_mean,
    expression_text,
    int_text,
    range_text,
    term_repr,
    term_short,
)

__all__ = [
    "AUGMENTED_TERMS",
    "FAMILIES",
    "FUNCTIONS",
    "PAPER_TERMS",
    "ExpressionBasis",
    "basis_terms",
    "compile_terms",
    "parse_term",
    "polynomial_terms",
    "quadratic_terms",
    "variable_names",
]

#: The paper's 8 functions in the order of ``adparm.BASIS_NAMES`` (two joints; cos of x2).
PAPER_TERMS = (
    "x1^2",
    "x2^2",
    "x1*x2",
    "x3^2",
    "x3^2*cos(x2)",
    "x4^2",
    "x3*x4",
    "x3*x4*cos(x2)",
)
#: The same with cos q2 (= cos(qd2 - x2)): the augmented basis, exact for any qd(t).
AUGMENTED_TERMS = tuple(term.replace("cos(x2)", "cos(q2)") for term in PAPER_TERMS)
#: Names that expand to lists of terms.
FAMILIES = ("paper", "augmented", "quadratic", "polynomial")


def variable_names(joints: int) -> list[str]:
    """The variable names of a term for n joints: x1 to x2n, q1 to qn, qd1 to qdn."""
    check_joints(joints)
    return (
        [f"x{i}" for i in range(1, 2 * joints + 1)]
        + [f"q{i}" for i in range(1, joints + 1)]
        + [f"qd{i}" for i in range(1, joints + 1)]
    )


def quadratic_terms(joints: int) -> list[str]:
    """Every monomial ``x_i x_j`` (``i <= j``) of the error state: ``2n (2n + 1) / 2`` terms.

    With them V = x^T P x for any symmetric P (the exact value function of a linear arm).
    """
    return polynomial_terms(joints, 2)


def polynomial_terms(joints: int, degree: int) -> list[str]:
    """Every monomial of the error state x (2n) of even degree 2, 4, ..., ``degree``."""
    check_joints(joints)
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)):
        raise ValueError(f"degree: must be an even integer >= 2, got {degree!r}")
    if degree < 2 or degree % 2:
        raise ValueError(
            f"degree: must be an even integer >= 2 (a value function has even degree), got {degree}"
        )
    if degree > MAX_DEGREE:
        raise ValueError(f"degree: must be <= {MAX_DEGREE}, got {int_text(int(degree))}")
    count = polynomial_size(joints, int(degree))
    if count > MAX_TERMS:
        raise ValueError(
            f"degree: {degree} gives {count:_} monomials for {joints} joints; at most "
            f"{MAX_TERMS} terms (a run takes at most {MAX_FUNCTIONS} functions)"
        )
    terms = []
    for k in range(2, int(degree) + 1, 2):
        for combination in itertools.combinations_with_replacement(range(1, 2 * joints + 1), k):
            powers = {i: combination.count(i) for i in sorted(set(combination))}
            terms.append("*".join(f"x{i}^{p}" if p > 1 else f"x{i}" for i, p in powers.items()))
    return terms


def polynomial_size(joints: int, degree: int) -> int:
    """The number of monomials of :func:`polynomial_terms` (without listing them)."""
    n_x = 2 * joints
    return sum(math.comb(n_x + k - 1, k) for k in range(2, degree + 1, 2))


def basis_terms(
    basis: str | Sequence[str], joints: int = 2, *, degree: int | None = None
) -> list[str]:
    """The terms of a basis: a family name, one term, or a list mixing both.

    ``"paper"`` and ``"augmented"`` need two joints, ``"polynomial"`` a ``degree``. Terms equal
    after expansion to an earlier one are dropped (so families combine without duplicates).
    """
    return [term for term, _ in _unique_terms(basis, joints, degree)]


def _unique_terms(
    basis: str | Sequence[str], joints: int, degree: int | None, limit: int = MAX_TERMS
) -> list[tuple[str, sympy.Expr]]:
    """basis_terms, with each term's parsed expression; at most ``limit`` terms, counted (the
    families by their size) before any is listed or parsed."""
    check_joints(joints)
    items = [basis] if isinstance(basis, str) else list(basis)
    if not items:
        raise ValueError("basis: needs at least one term or family")
    for item in items:
        if not isinstance(item, str):
            raise ValueError(f"basis: each entry must be a string, got {term_repr(item)}")
    names = {item.strip() for item in items}
    count = sum(item.strip() not in FAMILIES for item in items)
    count += sum(len(PAPER_TERMS) for name in ("paper", "augmented") if name in names)
    if "polynomial" in names and degree is not None:
        if isinstance(degree, (int, np.integer)) and not isinstance(degree, bool):
            if degree > MAX_DEGREE:
                raise ValueError(f"degree: must be <= {MAX_DEGREE}, got {int_text(int(degree))}")
            if degree >= 2:
                count += polynomial_size(joints, int(degree))
    elif "quadratic" in names:  # the polynomial family includes it
        count += polynomial_size(joints, 2)
    if count > limit:
        raise ValueError(
            f"basis: {count:_} functions; at most {limit}"
            + (" (the C++ core's limit)" if limit == MAX_FUNCTIONS else "")
        )
    terms: list[str] = []
    for item in items:
        name = item.strip()
        if name in ("paper", "augmented"):
            if joints != 2:
                raise ValueError(
                    f"basis: {name!r} is the paper's two-link basis; for {joints} joints use "
                    f"'quadratic', 'polynomial' or your own terms"
                )
            terms.extend(PAPER_TERMS if name == "paper" else AUGMENTED_TERMS)
        elif name == "quadratic":
            terms.extend(quadratic_terms(joints))
        elif name == "polynomial":
            if degree is None:
                raise ValueError("degree: the 'polynomial' basis needs a degree (e.g. degree = 4)")
            terms.extend(polynomial_terms(joints, degree))
        else:
            terms.append(item)
    work = 0
    for term in terms:  # every term bounded, and their expansion in all, before sympy parses one
        work += check_text(term, joints)
        if work > MAX_TOTAL_EXPANSION:
            raise ValueError(
                f"basis: its terms expand to more than {MAX_TOTAL_EXPANSION:_} terms in all "
                f"(each at most {MAX_EXPANSION}); use fewer or smaller terms"
            )
    expressions = [parse_term(term, joints) for term in terms]
    seen: set[Any] = set()
    unique = []
    for term, expression in zip(terms, expressions, strict=True):
        key = _expanded(expression, joints)
        if key not in seen:
            seen.add(key)
            unique.append((term, expression))
    return unique


def parse_term(term: str, joints: int = 2) -> sympy.Expr:
    """One term as a sympy expression in the symbols of :func:`variable_names`.

    A ValueError names the term for anything else: an unknown variable or function (with the
    closest known name), bad syntax, a constant.
    """
    import sympy
    from sympy.core.function import AppliedUndef
    from sympy.parsing.sympy_parser import (
        TokenError,
        convert_xor,
        parse_expr,
        standard_transformations,
    )

    names = variable_names(joints)
    check_text(term, joints)
    local: dict[str, Any] = {name: sympy.Symbol(name) for name in names}
    local.update({name: getattr(sympy, name) for name in FUNCTIONS})
    local["pi"] = sympy.pi
    global_dict: dict[str, Any] = {
        name: getattr(sympy, name) for name in ("Integer", "Float", "Rational", "Symbol")
    }
    global_dict["Function"] = sympy.Function
    try:
        expression = parse_expr(
            term,
            local_dict=local,
            global_dict=global_dict,
            transformations=standard_transformations + (convert_xor,),
        )
    except (SyntaxError, TypeError, ValueError, TokenError) as error:
        raise ValueError(
            f"basis term {term!r}: cannot parse it ({term_short(str(error))})"
        ) from None
    except (RecursionError, MemoryError, OverflowError) as error:  # bounded above: a safety net
        raise ValueError(
            f"basis term {term!r}: too large to parse ({type(error).__name__})"
        ) from None
    if not isinstance(expression, sympy.Expr):
        raise ValueError(f"basis term {term!r}: not an expression")
    for function in sorted(expression.atoms(AppliedUndef), key=str):
        name = type(function).__name__
        raise ValueError(
            f"basis term {term!r}: unknown function {name!r} (known: {', '.join(FUNCTIONS)})"
            + did_you_mean(name, FUNCTIONS)
        )
    for symbol in sorted(expression.free_symbols, key=str):
        if symbol.name not in names:
            raise ValueError(
                f"basis term {term!r}: unknown variable {symbol.name!r} "
                f"({joints} joints: {range_text(joints)})" + did_you_mean(symbol.name, names)
            )
    if not expression.free_symbols:
        raise ValueError(
            f"basis term {term!r}: is the constant {expression_text(expression)}; a basis "
            "function must depend on "
            f"the state (only its gradient enters the HJB error)"
        )
    if not any(not symbol.name.startswith("qd") for symbol in expression.free_symbols):
        raise ValueError(
            f"basis term {term!r}: depends on the desired state only; a basis function must "
            f"depend on x or q (its gradient in x enters the HJB error)"
        )
    if expression.has(sympy.zoo, sympy.oo, -sympy.oo, sympy.nan, sympy.I):
        raise ValueError(f"basis term {term!r}: is not finite and real")
    return expression


def compile_terms(
    terms: Sequence[str] | Sequence[sympy.Expr],
    joints: int = 2,
    *,
    labels: Sequence[str] | None = None,
) -> tuple[NDArray[np.int32], NDArray[np.float64]]:
    """The postfix program of the C++ ``ExpressionBasis``: (opcodes, arguments).

    Variables are numbered over z = [x; qd] (x1 to x2n, then qd1 to qdn); q_i is replaced by
    qd_i - x_i. ``labels``: the terms' texts, for messages (default: the terms themselves).
    """
    import sympy

    names = variable_names(joints)
    index = {name: i for i, name in enumerate(names[: 2 * joints])}
    index.update({f"qd{i}": 2 * joints + i - 1 for i in range(1, joints + 1)})
    substitution = {
        sympy.Symbol(f"q{i}"): sympy.Symbol(f"qd{i}") - sympy.Symbol(f"x{i}")
        for i in range(1, joints + 1)
    }
    program: list[tuple[Any, float]] = []
    for i, term in enumerate(terms):
        expression = parse_term(term, joints) if isinstance(term, str) else term
        if labels is not None:
            label = labels[i]
        else:
            label = term if isinstance(term, str) else expression_text(term)
        _emit(expression.xreplace(substitution), index, program, label)
        program.append((_core.ExpressionOp.store, 0.0))
    opcodes = np.array([int(op) for op, _ in program], dtype=np.int32)
    arguments = np.array([argument for _, argument in program], dtype=np.float64)
    return opcodes, arguments


class ExpressionBasis:
    """A basis from terms, evaluated with exact Jacobians by the C++ core.

    Parameters
    ----------
    basis
        A family name (``"quadratic"``, ``"polynomial"``, ``"paper"``, ``"augmented"``), a term,
        or a list of both (see :func:`basis_terms`).
    joints
        The arm's joint count n: x has 2n entries, q and qd n.
    degree
        The degree of the ``"polynomial"`` family.

    Examples
    --------
    >>> basis = ExpressionBasis(["x1^2", "x3*x4*cos(q2)"], joints=2)
    >>> phi, dphi_dx, rate = basis.evaluate([1.0, 0.0, 2.0, 3.0], qd=[0.0, 0.0])
    >>> phi.tolist()
    [1.0, 6.0]
    """

    def __init__(
        self, basis: str | Sequence[str], joints: int = 2, *, degree: int | None = None
    ) -> None:
        self.joints = joints
        unique = _unique_terms(basis, joints, degree, MAX_FUNCTIONS)
        self.terms: tuple[str, ...] = tuple(term for term, _ in unique)
        self.expressions = tuple(expression for _, expression in unique)
        self.opcodes, self.arguments = compile_terms(self.expressions, joints, labels=self.terms)
        self.core = _core.ExpressionBasis(joints, self.opcodes.tolist(), self.arguments.tolist())

    @property
    def size(self) -> int:
        """The number of functions N."""
        return len(self.terms)

    def __len__(self) -> int:
        return self.size

    def __repr__(self) -> str:
        return f"ExpressionBasis({list(self.terms)!r}, joints={self.joints})"

    def evaluate(
        self, x: ArrayLike, qd: ArrayLike | None = None, dqd: ArrayLike | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """phi, d phi / dx and (d phi / d qd) dqd at x of shape (..., 2n).

        qd and dqd (default zero) broadcast against x's leading shape with n entries last.
        Returns arrays of shapes (..., N), (..., N, 2n) and (..., N).
        """
        n, n_x = self.joints, 2 * self.joints
        x = real_array(x, "x")
        if x.ndim == 0 or x.shape[-1] != n_x:
            raise ValueError(f"x: expected shape (..., {n_x}), got {x.shape}")
        lead = x.shape[:-1]
        qd = np.broadcast_to(np.zeros(n) if qd is None else real_array(qd, "qd"), lead + (n,))
        dqd = np.broadcast_to(np.zeros(n) if dqd is None else real_array(dqd, "dqd"), lead + (n,))
        phi, jacobian, rate = self.core.evaluate_rows(
            x.reshape(-1, n_x), qd.reshape(-1, n), dqd.reshape(-1, n)
        )
        return (
            phi.reshape(lead + (self.size,)),
            jacobian.reshape(lead + (self.size, n_x)),
            rate.reshape(lead + (self.size,)),
        )

    def quadratic_form_weights(self, P: ArrayLike, *, seed: int = 0) -> NDArray[np.float64]:
        """Weights W with W^T phi(x, qd) = x^T P x for every x and qd, e.g. initial weights from
        a quadratic V (a Riccati solution, or blockdiag(K, M) of the believed model).

        Solved by least squares at 4 N + 20 random states (x in [-1, 1]^2n, qd in [-pi, pi]^n)
        and verified there; a ValueError says when the basis cannot represent x^T P x (which
        quadratic monomials it lacks).
        """
        n_x = 2 * self.joints
        P = real_array(P, "P")
        if P.shape != (n_x, n_x) or not np.all(np.isfinite(P)):
            raise ValueError(f"P: expected a finite ({n_x}, {n_x}) matrix, got shape {P.shape}")
        P = 0.5 * (P + P.T)
        rng = np.random.default_rng(seed)
        count = 4 * self.size + 20
        x = rng.uniform(-1.0, 1.0, (count, n_x))
        qd = rng.uniform(-np.pi, np.pi, (count, self.joints))
        problem = self.nonfinite(x, qd, jacobian=False)
        if problem is not None:  # e.g. sqrt or log of a negative value: name the term, not LAPACK's
            raise ValueError(problem)
        phi, _, _ = self.evaluate(x, qd)
        V = np.einsum("ni,ij,nj->n", x, P, x)
        weights, *_ = np.linalg.lstsq(phi, V, rcond=None)
        scale = max(float(np.linalg.norm(V)), 1e-300)
        if np.linalg.norm(phi @ weights - V) > 1e-9 * scale:
            present = {_expanded(e, self.joints) for e in self.expressions}
            xs = [_symbol(f"x{i}") for i in range(1, n_x + 1)]
            missing = [
                f"x{i + 1}^2" if i == j else f"x{i + 1}*x{j + 1}"
                for i in range(n_x)
                for j in range(i, n_x)
                if P[i, j] != 0.0 and xs[i] * xs[j] not in present
            ]
            raise ValueError(
                "P: this basis cannot represent x^T P x"
                + (f" (it lacks {', '.join(missing)}; add them or 'quadratic')" if missing else "")
            )
        weights[np.abs(weights) < 1e-12 * max(np.abs(weights).max(), 1.0)] = 0.0
        return weights

    def nonfinite(
        self, x: ArrayLike, qd: ArrayLike | None = None, *, jacobian: bool = True
    ) -> str | None:
        """None when every function (and, ``jacobian``, its d phi / dx) is finite at the states
        x (..., 2n) with desired positions qd; else a message naming the first term that is not
        and the state, e.g. ``basis term 'sqrt(x1)': not finite at x = [-0.16, ...], qd = [...]``
        (check before any linear algebra: LAPACK would only say "SVD did not converge")."""
        x = real_array(x, "x")
        with np.errstate(all="ignore"):
            phi, dphi, _ = self.evaluate(x, qd)
        bad = ~np.isfinite(phi)
        what = "not finite"
        if jacobian and bad.sum() == 0:
            bad, what = ~np.isfinite(dphi).all(axis=-1), "its derivative d phi / dx is not finite"
        if not bad.any():
            return None
        index = tuple(np.argwhere(bad)[0])
        row, column = index[:-1], index[-1]
        desired = np.broadcast_to(
            np.zeros(self.joints) if qd is None else real_array(qd, "qd"),
            x.shape[:-1] + (self.joints,),
        )
        return (
            f"basis term {term_short(repr(self.terms[column]))}: {what} at x = "
            f"{np.round(x[row], 3).tolist()}, qd = {np.round(desired[row], 3).tolist()} (sqrt "
            "and log need positive arguments, 1/f and tan finite values)"
        )

    def desired_jacobian(self, x: ArrayLike, qd: ArrayLike | None = None) -> NDArray[np.float64]:
        """d phi / d qd (N, n) at one point x (2n,), qd (n,)."""
        n = self.joints
        qd = np.zeros(n) if qd is None else real_array(qd, "qd")
        return self.core.evaluate(real_array(x, "x"), qd, np.zeros(n))[3]


# --- internals ------------------------------------------------------------------------------------


def real_array(value: Any, name: str) -> NDArray[np.float64]:
    """``value`` as a float64 array; a complex one is refused (check_real)."""
    array = np.asarray(value)
    check_real(array, name)
    return np.asarray(array, dtype=np.float64)


def check_real(array: np.ndarray, name: str) -> None:
    """TypeError for complex values: NumPy would drop the imaginary part with a warning only."""
    if np.iscomplexobj(array) or (
        array.dtype == object and any(isinstance(item, complex) for item in array.flat)
    ):
        raise TypeError(
            f"{name}: expected real numbers, got complex values (the imaginary part would be "
            "dropped)"
        )


def _symbol(name: str) -> Any:
    import sympy

    return sympy.Symbol(name)


def _expanded(expression: sympy.Expr, joints: int) -> Any:
    """A canonical form of a term for spotting duplicates: q substituted, expanded."""
    import sympy

    substitution = {
        sympy.Symbol(f"q{i}"): sympy.Symbol(f"qd{i}") - sympy.Symbol(f"x{i}")
        for i in range(1, joints + 1)
    }
    return sympy.expand(expression.xreplace(substitution))


_UNARY = {"sin", "cos", "tan", "exp", "log", "tanh"}


def _factor_key(factor: sympy.Expr, index: dict[str, int]) -> tuple:
    # variables and their powers first, by index, then everything else in sympy's order
    base = factor.base if factor.is_Pow and factor.exp.is_number else factor
    if base.is_Symbol:
        return (0, index[base.name], "")
    return (1, 0, str(factor.sort_key()))


def _emit(expression: sympy.Expr, index: dict[str, int], program: list, term: str) -> None:
    import sympy

    op = _core.ExpressionOp
    if expression.is_number:
        value = complex(expression)
        if value.imag != 0 or not np.isfinite(value.real):
            raise ValueError(
                f"basis term {term_repr(term)}: the constant {expression_text(expression)} is not "
                "finite and real"
            )
        program.append((op.constant, value.real))
    elif expression.is_Symbol:
        program.append((op.variable, float(index[expression.name])))
    elif expression.is_Add:
        first, *rest = expression.args
        _emit(first, index, program, term)
        for summand in rest:
            coefficient, _ = summand.as_coeff_Mul()
            if coefficient.is_number and coefficient < 0:
                _emit(-summand, index, program, term)
                program.append((op.subtract, 0.0))
            else:
                _emit(summand, index, program, term)
                program.append((op.add, 0.0))
    elif expression.is_Mul:
        coefficient, factors = expression.as_coeff_mul()
        ordered = sorted(factors, key=lambda f: _factor_key(f, index))
        _emit(ordered[0], index, program, term)
        for factor in ordered[1:]:
            _emit(factor, index, program, term)
            program.append((op.multiply, 0.0))
        if coefficient == -1:
            program.append((op.negate, 0.0))
        elif coefficient != 1:
            _emit(coefficient, index, program, term)
            program.append((op.multiply, 0.0))
    elif expression.is_Pow:
        if not expression.exp.is_number:
            raise ValueError(
                f"basis term {term_repr(term)}: the exponent of {expression_text(expression)} must "
                "be a number "
                f"(write exp(b*log(a)) for a variable power)"
            )
        _emit(expression.base, index, program, term)
        program.append((op.power, float(expression.exp)))
    elif isinstance(expression, sympy.Function) and type(expression).__name__ in _UNARY:
        (argument,) = expression.args
        _emit(argument, index, program, term)
        program.append((getattr(op, type(expression).__name__), 0.0))
    else:
        raise ValueError(
            f"basis term {term_repr(term)}: cannot compile {expression_text(expression)} "
            f"({type(expression).__name__})"
        )
