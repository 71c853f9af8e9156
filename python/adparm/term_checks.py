"""The bounds and checks of a basis term's text before sympy reads it (length, characters,
nesting, exponents, the size of its expansion), and the short texts that name a term in a
message. adparm.bases uses them; its MAX_* bounds are defined here."""

from __future__ import annotations

import ast
import difflib
import math
import operator
import re
import reprlib
from collections.abc import Sequence
from typing import Any

import numpy as np

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


def term_repr(value: Any) -> str:
    """repr(value) for a message: a string cut to 80 characters, anything else with bounded
    nesting (never a RecursionError)."""
    if isinstance(value, str):
        return term_short(repr(value))
    short = reprlib.Repr()
    short.maxlevel, short.maxlist, short.maxstring, short.maxother = 3, 6, 60, 60
    try:
        return term_short(short.repr(value))
    except Exception:  # noqa: BLE001 - a repr that fails
        return f"<{type(value).__name__}>"


def expression_text(expression: Any) -> str:
    """A sympy expression as text for a message, cut to 60 characters (never raises: sympy
    cannot print some numbers beyond a double's range)."""
    try:
        return term_short(str(expression), 60)
    except Exception:  # noqa: BLE001
        return "a number beyond the range of a double"


def term_short(text: str, size: int = 80) -> str:
    """``text`` cut to ``size`` characters (a hostile term is never printed whole)."""
    return text if len(text) <= size else text[: size - 20] + f"... ({len(text):_} characters)"


def int_text(value: int) -> str:
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


def check_text(term: str, joints: int) -> int:
    """The checks of a term's text (type, length, characters, then :func:`_check_bounds`);
    returns the work of expanding it."""
    if not isinstance(term, str):
        raise ValueError(f"basis term {term_repr(term)}: must be a string")
    if not term.strip():
        raise ValueError("basis term '': empty")
    if len(term) > MAX_TERM_LENGTH:
        raise ValueError(
            f"basis term {term_repr(term)}: {len(term):_} characters; at most {MAX_TERM_LENGTH}"
        )
    if not _ALLOWED.match(term) or _ATTRIBUTE.search(term) or "__" in term:
        raise ValueError(
            f"basis term {term_repr(term)}: may contain only variables "
            f"({range_text(joints)}), numbers, + - * / ^ ** ( ) and the functions "
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
    where = f"basis term {term_repr(term)}"
    try:
        tree = ast.parse(term.replace("^", "**").strip(), mode="eval")
    except SyntaxError as error:
        raise ValueError(f"{where}: cannot parse it ({term_short(error.msg)})") from None
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
                raise ValueError(f"{where}: {term_short(repr(value), 30)} is not a real number")
            if isinstance(value, int) and value.bit_length() > MAX_INTEGER_DIGITS * 3.33:
                raise ValueError(
                    f"{where}: an integer of {len(str(value)):_} digits; at most "
                    f"{MAX_INTEGER_DIGITS}"
                )
            if isinstance(value, float) and not math.isfinite(value):
                text = ast.get_source_segment(term.replace("^", "**").strip(), node) or "?"
                raise ValueError(
                    f"{where}: the number {term_short(text, 30)} is beyond the range of a double "
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
    return term_short(ast.get_source_segment(source, node) or "?", 40)


def check_joints(joints: int) -> None:
    if isinstance(joints, bool) or not isinstance(joints, (int, np.integer)) or joints < 1:
        raise ValueError(f"joints: must be an integer >= 1, got {joints!r}")


def range_text(joints: int) -> str:
    return f"x1..x{2 * joints}, q1..q{joints}, qd1..qd{joints}"


def did_you_mean(name: str, choices: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.5)
    return f"; did you mean {close[0]!r}?" if close else ""
