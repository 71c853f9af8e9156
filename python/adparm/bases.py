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

import ast
import difflib
import itertools
import math
import operator
import re
import reprlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

import adparm._core as _core

if TYPE_CHECKING:
    import sympy

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
#: The functions a term may call.
FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "sqrt", "tanh")

#: The most functions a basis may have: the C++ core's kMaxBasisSize.
MAX_FUNCTIONS = 128
#: The most terms :func:`basis_terms` and :func:`polynomial_terms` list (a basis for a run has at
#: most MAX_FUNCTIONS).
MAX_TERMS = 1024
#: The largest degree of the ``"polynomial"`` family (one joint reaches 128 functions at 22).
MAX_DEGREE = 20
#: Bounds on a term, checked on its text before sympy does any work: its length, the nesting of
#: functions, powers, signs and brackets, the size of an exponent and of an integer, and the
#: number of terms its expansion (with q = qd - e1 substituted) may have.
MAX_TERM_LENGTH = 1000
MAX_NESTING = 32
MAX_EXPONENT = 64
MAX_INTEGER_DIGITS = 30
MAX_EXPANSION = 1000
#: The most terms the expansions of all of a basis' terms may have together.
MAX_TOTAL_EXPANSION = 10_000

_ALLOWED = re.compile(r"^[A-Za-z0-9_\s.+\-*/^()]*$")
_ATTRIBUTE = re.compile(r"\.\s*[A-Za-z_]")


def variable_names(joints: int) -> list[str]:
    """The variable names of a term for n joints: x1 to x2n, q1 to qn, qd1 to qdn."""
    _check_joints(joints)
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
    _check_joints(joints)
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)):
        raise ValueError(f"degree: must be an even integer >= 2, got {degree!r}")
    if degree < 2 or degree % 2:
        raise ValueError(
            f"degree: must be an even integer >= 2 (a value function has even degree), got {degree}"
        )
    if degree > MAX_DEGREE:
        raise ValueError(f"degree: must be <= {MAX_DEGREE}, got {_int_text(int(degree))}")
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
    _check_joints(joints)
    items = [basis] if isinstance(basis, str) else list(basis)
    if not items:
        raise ValueError("basis: needs at least one term or family")
    for item in items:
        if not isinstance(item, str):
            raise ValueError(f"basis: each entry must be a string, got {_repr(item)}")
    names = {item.strip() for item in items}
    count = sum(item.strip() not in FAMILIES for item in items)
    count += sum(len(PAPER_TERMS) for name in ("paper", "augmented") if name in names)
    if "polynomial" in names and degree is not None:
        if isinstance(degree, (int, np.integer)) and not isinstance(degree, bool):
            if degree > MAX_DEGREE:
                raise ValueError(f"degree: must be <= {MAX_DEGREE}, got {_int_text(int(degree))}")
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
        work += _check_text(term, joints)
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
    _check_text(term, joints)
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
        raise ValueError(f"basis term {term!r}: cannot parse it ({_short(str(error))})") from None
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
            + _did_you_mean(name, FUNCTIONS)
        )
    for symbol in sorted(expression.free_symbols, key=str):
        if symbol.name not in names:
            raise ValueError(
                f"basis term {term!r}: unknown variable {symbol.name!r} "
                f"({joints} joints: {_range_text(joints)})" + _did_you_mean(symbol.name, names)
            )
    if not expression.free_symbols:
        raise ValueError(
            f"basis term {term!r}: is the constant {_expression_text(expression)}; a basis "
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
            label = term if isinstance(term, str) else _expression_text(term)
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
            f"basis term {_short(repr(self.terms[column]))}: {what} at x = "
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


def _repr(value: Any) -> str:
    """repr(value) for a message: a string cut to 80 characters, anything else with bounded
    nesting (never a RecursionError)."""
    if isinstance(value, str):
        return _short(repr(value))
    short = reprlib.Repr()
    short.maxlevel, short.maxlist, short.maxstring, short.maxother = 3, 6, 60, 60
    try:
        return _short(short.repr(value))
    except Exception:  # noqa: BLE001 - a repr that fails
        return f"<{type(value).__name__}>"


def _expression_text(expression: Any) -> str:
    """A sympy expression as text for a message, cut to 60 characters (never raises: sympy
    cannot print some numbers beyond a double's range)."""
    try:
        return _short(str(expression), 60)
    except Exception:  # noqa: BLE001
        return "a number beyond the range of a double"


def _short(text: str, size: int = 80) -> str:
    """``text`` cut to ``size`` characters (a hostile term is never printed whole)."""
    return text if len(text) <= size else text[: size - 20] + f"... ({len(text):_} characters)"


def _int_text(value: int) -> str:
    digits = (
        len(str(abs(value))) if value.bit_length() < 4000 else int(value.bit_length() * 0.30103)
    )
    return str(value) if digits <= 20 else f"a {digits:_}-digit number"


_BINARY = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_OPERATIONS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}
_SUMS = (ast.Add, ast.Sub)
_PRODUCTS = (ast.Mult, ast.Div)


def _check_text(term: str, joints: int) -> int:
    """The checks of a term's text (type, length, characters, then :func:`_check_bounds`);
    returns the work of expanding it."""
    if not isinstance(term, str):
        raise ValueError(f"basis term {_repr(term)}: must be a string")
    if not term.strip():
        raise ValueError("basis term '': empty")
    if len(term) > MAX_TERM_LENGTH:
        raise ValueError(
            f"basis term {_repr(term)}: {len(term):_} characters; at most {MAX_TERM_LENGTH}"
        )
    if not _ALLOWED.match(term) or _ATTRIBUTE.search(term) or "__" in term:
        raise ValueError(
            f"basis term {_repr(term)}: may contain only variables "
            f"({_range_text(joints)}), numbers, + - * / ^ ** ( ) and the functions "
            f"{', '.join(FUNCTIONS)}"
        )
    return _check_bounds(term, joints)


def _check_bounds(term: str, joints: int) -> int:
    """Refuses, from the text alone and before sympy sees it, a term that is not an arithmetic
    expression of names, numbers and calls (``and``, ``if``, comparisons, ``//``, complex
    numbers), that nests deeper than MAX_NESTING, whose exponents are not numbers of at most
    MAX_EXPONENT, whose integers have more than MAX_INTEGER_DIGITS digits or whose floats
    overflow, or whose expansion (q = qd - e1 substituted) has more than MAX_EXPANSION terms.
    Iterative: no recursion, whatever the text. Returns the work of expanding it (in terms)."""
    where = f"basis term {_repr(term)}"
    try:
        tree = ast.parse(term.replace("^", "**").strip(), mode="eval")
    except SyntaxError as error:
        raise ValueError(f"{where}: cannot parse it ({_short(error.msg)})") from None
    except (RecursionError, MemoryError, ValueError, OverflowError) as error:
        raise ValueError(f"{where}: too deeply nested ({type(error).__name__})") from None
    q_names = {f"q{i}" for i in range(1, joints + 1)}
    # first pass, top-down: node kinds and nesting depth (a chain of + - or of * / is one level)
    stack: list[tuple[ast.AST, int, type | None]] = [(tree.body, 0, None)]
    order: list[ast.AST] = []
    while stack:
        node, depth, parent = stack.pop()
        if depth > MAX_NESTING:
            raise ValueError(f"{where}: nested more than {MAX_NESTING} deep")
        order.append(node)
        if isinstance(node, ast.BinOp):
            kind = type(node.op)
            if kind not in _BINARY:
                raise ValueError(f"{where}: operator {_op_text(node.op)} is not allowed")
            group = _SUMS if kind in _SUMS else _PRODUCTS if kind in _PRODUCTS else None
            deeper = (
                depth if group is not None and parent is not None and parent in group else depth + 1
            )
            stack.append((node.left, deeper, kind))
            stack.append((node.right, deeper, kind))
        elif isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, (ast.USub, ast.UAdd)):
                raise ValueError(f"{where}: operator {_op_text(node.op)} is not allowed")
            stack.append((node.operand, depth + 1, None))
        elif isinstance(node, ast.Call):
            if (
                not isinstance(node.func, ast.Name)
                or node.keywords
                or len(node.args) != 1
                or isinstance(node.args[0], ast.Starred)
            ):
                raise ValueError(f"{where}: a function takes one argument, as in sin(x1)")
            stack.append((node.args[0], depth + 1, None))
        elif isinstance(node, ast.Constant):
            value = node.value
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"{where}: {_short(repr(value), 30)} is not a real number")
            if isinstance(value, int) and value.bit_length() > MAX_INTEGER_DIGITS * 3.33:
                raise ValueError(
                    f"{where}: an integer of {len(str(value)):_} digits; at most "
                    f"{MAX_INTEGER_DIGITS}"
                )
            if isinstance(value, float) and not math.isfinite(value):
                text = ast.get_source_segment(term.replace("^", "**").strip(), node) or "?"
                raise ValueError(
                    f"{where}: the number {_short(text, 30)} is beyond the range of a double "
                    "(about 1.8e308)"
                )
        elif not isinstance(node, ast.Name):
            raise ValueError(
                f"{where}: {type(node).__name__.lower()} ({_node_text(node)}) is not allowed; a "
                f"term is arithmetic (+ - * / ^) of variables, numbers and "
                f"{', '.join(FUNCTIONS)}"
            )
    # second pass, bottom-up: the number of terms of each node's expansion (an upper bound), and
    # the work of expanding: the terms of the whole term, of each function's argument, of each
    # denominator and of each base of a negative or fractional power (each is expanded)
    size: dict[int, int] = {}
    values: dict[int, float] = {}  # the constant parts, as doubles: each must be finite and real
    work = 0
    cap = MAX_EXPANSION + 1
    source = term.replace("^", "**").strip()
    for node in reversed(order):
        expanded = 0
        value = _fold(node, values, where, source)
        if value is not None:
            values[id(node)] = value
        if isinstance(node, ast.Name):
            terms = 2 if node.id in q_names else 1
        elif isinstance(node, ast.Constant):
            terms = 1
        elif isinstance(node, ast.UnaryOp):
            terms = size[id(node.operand)]
        elif isinstance(node, ast.Call):
            terms, expanded = 1, size[id(node.args[0])]
        else:  # BinOp
            left, right = size[id(node.left)], size[id(node.right)]
            if isinstance(node.op, _SUMS):
                terms = left + right
            elif isinstance(node.op, ast.Mult):
                terms = left * right
            elif isinstance(node.op, ast.Div):
                terms, expanded = left, right
            else:
                if id(node.right) not in values:
                    raise ValueError(
                        f"{where}: an exponent must be a number (write exp(b*log(a)) for a "
                        "variable power)"
                    )
                exponent = values[id(node.right)]
                if abs(exponent) > MAX_EXPONENT:
                    raise ValueError(
                        f"{where}: the exponent {_number_text(exponent)} is larger than "
                        f"{MAX_EXPONENT} in size"
                    )
                k = int(abs(exponent))
                # the distinct monomials of degree k in `left` summands (the multinomial)
                power = math.comb(left + k - 1, k) if exponent == k else left
                if exponent == k and exponent >= 0:
                    terms = power
                else:  # 1 / (...)^k or (...)^(1/2): one factor, expanded inside
                    terms, expanded = 1, power
        terms = min(terms, cap)
        work += min(expanded, cap)
        if terms >= cap or expanded >= cap or work >= 4 * cap:
            raise ValueError(
                f"{where}: its expansion has more than {MAX_EXPANSION} terms; write it "
                "as several terms"
            )
        size[id(node)] = terms
    work += size[id(tree.body)]
    if work >= 4 * cap:
        raise ValueError(
            f"{where}: its expansion has more than {MAX_EXPANSION} terms; write it as several terms"
        )
    return work


def _op_text(op: ast.AST) -> str:
    return {
        ast.FloorDiv: "//",
        ast.Mod: "%",
        ast.Not: "not",
        ast.Invert: "~",
        ast.BitXor: "^",
        ast.MatMult: "@",
    }.get(type(op), type(op).__name__)


def _node_text(node: ast.AST) -> str:
    names = {
        ast.BoolOp: "and/or",
        ast.IfExp: "if ... else",
        ast.Compare: "a comparison",
        ast.Lambda: "lambda",
        ast.NamedExpr: ":=",
    }
    return names.get(type(node), type(node).__name__)


def _number_text(value: float) -> str:
    return f"{value:.6g}"


def _fold(node: ast.AST, values: dict[int, float], where: str, source: str) -> float | None:
    """The value of ``node`` as a double if it is constant (numbers, pi, + - * / ** and the
    functions of constants; its children already folded into ``values``), else None. A constant
    that overflows a double, divides by zero or is not real is a ValueError: sympy would carry
    it exactly and may take forever on it (exp(1e300^27))."""
    functions = {name: getattr(math, name) for name in FUNCTIONS}
    try:
        if isinstance(node, ast.Constant):
            result = float(node.value)
        elif isinstance(node, ast.Name):
            if node.id != "pi":
                return None
            result = math.pi
        elif isinstance(node, ast.UnaryOp):
            if id(node.operand) not in values:
                return None
            operand = values[id(node.operand)]
            result = -operand if isinstance(node.op, ast.USub) else operand
        elif isinstance(node, ast.Call):
            name = node.func.id  # type: ignore[attr-defined]
            if id(node.args[0]) not in values or name not in functions:
                return None
            result = functions[name](values[id(node.args[0])])
        elif isinstance(node, ast.BinOp):
            if id(node.left) not in values or id(node.right) not in values:
                return None
            a, b = values[id(node.left)], values[id(node.right)]
            if isinstance(node.op, ast.Pow) and abs(b) > MAX_EXPONENT:
                raise ValueError(
                    f"{where}: the exponent {_number_text(b)} is larger than {MAX_EXPONENT} in size"
                )
            result = _OPERATIONS[type(node.op)](a, b)
        else:
            return None
    except ZeroDivisionError:
        raise ValueError(f"{where}: {_segment(source, node)} divides by zero") from None
    except OverflowError:
        raise ValueError(
            f"{where}: the constant {_segment(source, node)} is beyond the range of a double"
        ) from None
    except (ValueError, TypeError) as error:
        if str(error).startswith("basis term"):
            raise
        raise ValueError(f"{where}: the constant {_segment(source, node)} is not real") from None
    if isinstance(result, complex):
        raise ValueError(f"{where}: the constant {_segment(source, node)} is not real")
    if not math.isfinite(result):
        raise ValueError(
            f"{where}: the constant {_segment(source, node)} is beyond the range of a double"
        )
    return float(result)


def _segment(source: str, node: ast.AST) -> str:
    return _short(ast.get_source_segment(source, node) or "?", 40)


def _check_joints(joints: int) -> None:
    if isinstance(joints, bool) or not isinstance(joints, (int, np.integer)) or joints < 1:
        raise ValueError(f"joints: must be an integer >= 1, got {joints!r}")


def _range_text(joints: int) -> str:
    return f"x1..x{2 * joints}, q1..q{joints}, qd1..qd{joints}"


def _did_you_mean(name: str, choices: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.5)
    return f"; did you mean {close[0]!r}?" if close else ""


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
                f"basis term {_repr(term)}: the constant {_expression_text(expression)} is not "
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
                f"basis term {_repr(term)}: the exponent of {_expression_text(expression)} must "
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
            f"basis term {_repr(term)}: cannot compile {_expression_text(expression)} "
            f"({type(expression).__name__})"
        )
