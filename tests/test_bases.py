"""User-defined bases (python/adparm/bases.py, cpp/include/adparm/expression_basis.hpp): the C++
engine against sympy's own derivatives, the paper's bases reproduced bit for bit, the families,
and the errors that name the term."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

from adparm import _core, bases
from adparm.bases import ExpressionBasis

# --- an independent reference: sympy differentiates, lambdify evaluates -------------------------


def reference(terms: list[str], joints: int, x, qd, dqd):
    """phi, d phi / dx, (d phi / d qd) dqd and d phi / d qd from sympy's symbolic derivatives of
    the terms (sympified here, q_i replaced by qd_i - x_i), evaluated by NumPy."""
    xs = sympy.symbols(f"x1:{2 * joints + 1}")
    qs = sympy.symbols(f"q1:{joints + 1}")
    qds = sympy.symbols(f"qd1:{joints + 1}")
    names = {s.name: s for s in (*xs, *qs, *qds)}
    names.update(
        {f: getattr(sympy, f) for f in ("sin", "cos", "tan", "exp", "log", "sqrt", "tanh")}
    )
    expressions = [
        sympy.sympify(term.replace("^", "**"), locals=names).subs(
            {q: qd_ - x_ for q, qd_, x_ in zip(qs, qds, xs[:joints], strict=True)}
        )
        for term in terms
    ]
    variables = (*xs, *qds)
    phi = sympy.Matrix(expressions)
    jacobian = phi.jacobian(xs)
    desired = phi.jacobian(qds)
    values = [*np.asarray(x, float), *np.asarray(qd, float)]
    evaluate = sympy.lambdify(variables, [phi, jacobian, desired], modules="numpy")
    p, j, d = (np.array(a, dtype=float) for a in evaluate(*values))
    return p.ravel(), j, d @ np.asarray(dqd, float), d


def assert_matches(actual, expected, name, rtol=1e-12):
    actual, expected = np.asarray(actual), np.asarray(expected)
    assert actual.shape == expected.shape, name
    scale = max(1.0, float(np.abs(expected).max(initial=0.0)))
    np.testing.assert_allclose(actual, expected, rtol=rtol, atol=rtol * scale, err_msg=name)


def check_against_reference(terms, joints, points):
    basis = ExpressionBasis(terms, joints)
    assert basis.size == len(terms)
    for x, qd, dqd in points:
        phi, jacobian, rate, desired = basis.core.evaluate(x, qd, dqd)
        expected = reference(list(basis.terms), joints, x, qd, dqd)
        for name, a, e in zip(
            ("phi", "jacobian", "rate", "desired_jacobian"),
            (phi, jacobian, rate, desired),
            expected,
            strict=True,
        ):
            assert_matches(a, e, f"{name} of {terms} at x={x}, qd={qd}")


def random_points(rng, joints, count=4, scale=1.5):
    return [
        (
            rng.uniform(-scale, scale, 2 * joints),
            rng.uniform(-scale, scale, joints),
            rng.uniform(-2, 2, joints),
        )
        for _ in range(count)
    ]


# --- random expressions -----------------------------------------------------------------------


def expressions(joints: int):
    names = bases.variable_names(joints)
    leaves = st.sampled_from(names) | st.sampled_from(["0.5", "2", "3", "1.25"])

    def extend(children):
        pair = st.tuples(children, children)
        return st.one_of(
            pair.map(lambda p: f"({p[0]} + {p[1]})"),
            pair.map(lambda p: f"({p[0]} - {p[1]})"),
            pair.map(lambda p: f"({p[0]})*({p[1]})"),
            st.tuples(children, st.integers(1, 4)).map(lambda p: f"({p[0]})^{p[1]}"),
            children.map(lambda a: f"sin({a})"),
            children.map(lambda a: f"cos({a})"),
            children.map(lambda a: f"tanh({a})"),
            children.map(lambda a: f"exp(({a})/4)"),
            children.map(lambda a: f"sqrt(1 + ({a})^2)"),
            children.map(lambda a: f"log(2 + cos({a}))"),
            children.map(lambda a: f"-({a})"),
        )

    return st.recursive(leaves, extend, max_leaves=8)


@settings(max_examples=25)
@given(data=st.data(), joints=st.integers(1, 3), seed=st.integers(0, 2**32 - 1))
def test_engine_matches_sympy_derivatives_of_random_expressions(data, joints, seed) -> None:
    terms = data.draw(st.lists(expressions(joints), min_size=1, max_size=4))
    keep = []
    for term in terms:  # constants and qd-only terms are refused, repeats dropped, by design
        try:
            bases.parse_term(term, joints)
        except ValueError as error:
            assert "constant" in str(error) or "desired state only" in str(error)
            continue
        keep.append(term)
    if not keep:
        return
    unique = bases.basis_terms(keep, joints)
    rng = np.random.default_rng(seed)
    check_against_reference(unique, joints, random_points(rng, joints, count=3))


@pytest.mark.parametrize(
    "terms",
    [
        ["x1^-2", "x2^-1*x3", "x1^(3/2)", "sqrt(x2)", "x1^0.3"],
        ["tan(x1)", "log(x2)", "exp(x1*x2)", "tanh(q1)", "sin(qd1)*x3"],
        ["3*x1 - 2*x2*x3 + x4/5", "-x1*x2", "pi*x1^2 - cos(q1 + q2)*x2"],
        ["x5*x6*cos(q2 + q3)", "x4^2*sin(q1)^2", "qd3*x1^2"],
        # repeated functions of the same argument are computed once per evaluation
        [
            "x3^2*cos(q2)",
            "x3*x4*cos(q2)",
            "x1*cos(q2)",
            "x1*cos(q1)",
            "x2*sin(q2)",
            "x4*cos(2*q2)",
            "x4*cos(q2)^2 + cos(q2)",
            "x5*cos(x2 - qd2)",
        ],
    ],
)
def test_engine_matches_sympy_on_every_operation(terms) -> None:
    rng = np.random.default_rng(1)
    points = [
        (rng.uniform(0.2, 1.0, 6), rng.uniform(-1, 1, 3), rng.uniform(-2, 2, 3)) for _ in range(10)
    ]
    check_against_reference(terms, 3, points)


def test_desired_rate_is_the_desired_jacobian_times_dqd_and_q_is_qd_minus_e1() -> None:
    basis = ExpressionBasis(["x3^2*cos(q2)", "x1*x2"], joints=2)
    written_out = ExpressionBasis(["x3^2*cos(qd2 - x2)"], joints=2)
    # the same function twice is one term
    assert ExpressionBasis(["x3^2*cos(q2)", "x3^2*cos(qd2 - x2)"], joints=2).size == 1
    rng = np.random.default_rng(2)
    for x, qd, dqd in random_points(rng, 2, count=20):
        phi, jacobian, rate, desired = basis.core.evaluate(x, qd, dqd)
        phi2, jacobian2, rate2, desired2 = written_out.core.evaluate(x, qd, dqd)
        np.testing.assert_allclose(phi[0], phi2[0], rtol=1e-15)
        np.testing.assert_allclose(jacobian[0], jacobian2[0], rtol=1e-15)
        np.testing.assert_allclose(desired[0], desired2[0], rtol=1e-15)
        np.testing.assert_allclose(rate, desired @ dqd, rtol=1e-15, atol=1e-15)
        assert desired[0, 1] != 0.0 and desired[0, 0] == 0.0
        np.testing.assert_array_equal(desired[1], 0.0)  # x1 x2 does not depend on qd
        np.testing.assert_allclose(desired[0, 1], -jacobian[0, 1], rtol=1e-15)


# --- the paper's bases written as terms -------------------------------------------------------


@pytest.mark.parametrize(
    ("terms", "kind"),
    [
        (bases.PAPER_TERMS, _core.BasisKind.paper),
        (bases.AUGMENTED_TERMS, _core.BasisKind.augmented),
    ],
)
def test_paper_terms_reproduce_the_hand_written_bases_bit_for_bit(terms, kind) -> None:
    basis = ExpressionBasis(list(terms))
    family = ExpressionBasis("paper" if kind == _core.BasisKind.paper else "augmented")
    assert basis.terms == family.terms == terms
    rng = np.random.default_rng(3)
    for x, qd, dqd in random_points(rng, 2, count=300, scale=3.0):
        ours = basis.core.evaluate(x, qd, dqd)[:3]
        theirs = _core.basis(kind, x, qd, dqd)
        for name, a, b in zip(("phi", "jacobian", "rate"), ours, theirs, strict=True):
            np.testing.assert_array_equal(a, b, err_msg=name)


def test_evaluate_broadcasts_over_leading_axes() -> None:
    basis = ExpressionBasis(["x1^2", "x3*x4*cos(q2)", "x2*qd1"])
    rng = np.random.default_rng(4)
    x = rng.uniform(-1, 1, (3, 5, 4))
    qd = rng.uniform(-1, 1, (5, 2))
    dqd = rng.uniform(-1, 1, 2)
    phi, jacobian, rate = basis.evaluate(x, qd, dqd)
    assert phi.shape == (3, 5, 3) and jacobian.shape == (3, 5, 3, 4) and rate.shape == (3, 5, 3)
    for i, j in itertools.product(range(3), range(5)):
        p, jac, r, _ = basis.core.evaluate(x[i, j], qd[j], dqd)
        np.testing.assert_array_equal(phi[i, j], p)
        np.testing.assert_array_equal(jacobian[i, j], jac)
        np.testing.assert_array_equal(rate[i, j], r)
    phi0, _, rate0 = basis.evaluate(x[0, 0])  # qd = dqd = 0 by default
    np.testing.assert_array_equal(rate0, 0.0)
    assert phi0[1] == pytest.approx(x[0, 0, 2] * x[0, 0, 3] * math.cos(-x[0, 0, 1]), rel=1e-15)


# --- families -----------------------------------------------------------------------------------


def monomials_by_sympy(joints: int, degree: int) -> set:
    xs = sympy.symbols(f"x1:{2 * joints + 1}")
    return {
        m
        for m in sympy.polys.monomials.itermonomials(xs, degree)
        if sympy.Poly(m, *xs).total_degree() in range(2, degree + 1, 2)
    }


@pytest.mark.parametrize("joints", [1, 2, 3, 6])
def test_quadratic_family_is_every_xi_xj(joints) -> None:
    n_x = 2 * joints
    terms = bases.quadratic_terms(joints)
    assert len(terms) == n_x * (n_x + 1) // 2
    assert {bases.parse_term(t, joints) for t in terms} == monomials_by_sympy(joints, 2)
    assert bases.basis_terms("quadratic", joints) == terms


@pytest.mark.parametrize(("joints", "degree"), [(1, 2), (1, 6), (2, 4), (3, 4), (2, 6)])
def test_polynomial_family_is_every_even_degree_monomial(joints, degree) -> None:
    n_x = 2 * joints
    terms = bases.polynomial_terms(joints, degree)
    expected_count = sum(math.comb(n_x + k - 1, k) for k in range(2, degree + 1, 2))
    assert len(terms) == expected_count
    parsed = [bases.parse_term(t, joints) for t in terms]
    assert len(set(parsed)) == len(parsed)
    assert set(parsed) == monomials_by_sympy(joints, degree)
    assert bases.basis_terms("polynomial", joints, degree=degree) == terms


def test_quadratic_basis_represents_any_quadratic_form_exactly() -> None:
    rng = np.random.default_rng(5)
    joints = 3
    basis = ExpressionBasis("quadratic", joints)
    A = rng.normal(size=(6, 6))
    P = A @ A.T
    # W for V = x^T P x: P_ii on x_i^2, 2 P_ij on x_i x_j
    weights = np.array([P[i, j] * (1 if i == j else 2) for i in range(6) for j in range(i, 6)])
    x = rng.uniform(-1, 1, (50, 6))
    phi, jacobian, _ = basis.evaluate(x)
    np.testing.assert_allclose(phi @ weights, np.einsum("ni,ij,nj->n", x, P, x), rtol=1e-12)
    np.testing.assert_allclose(np.einsum("k,nki->ni", weights, jacobian), 2 * x @ P, rtol=1e-12)


def test_combined_lists_drop_repeated_terms() -> None:
    terms = bases.basis_terms(["quadratic", "paper", "x2*x1", "x3*x4*cos(q2)"], 2)
    assert terms[:10] == bases.quadratic_terms(2)
    assert terms[10:] == ["x3^2*cos(x2)", "x3*x4*cos(x2)", "x3*x4*cos(q2)"]
    # x3 x4 cos(q2) = x3 x4 cos(qd2 - x2) is a repeat of nothing above but repeats itself
    assert bases.basis_terms(["x3*x4*cos(q2)", "x4*x3*cos(qd2 - x2)"], 2) == ["x3*x4*cos(q2)"]
    basis = ExpressionBasis(["polynomial", "quadratic"], 2, degree=4)
    assert basis.size == 10 + 35


# --- errors -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("terms", "joints", "fragments"),
    [
        (["x1^2", "x5^2"], 2, ["'x5^2'", "unknown variable 'x5'", "did you mean 'x4'"]),
        (["qdd1*x1"], 2, ["'qdd1*x1'", "unknown variable 'qdd1'", "did you mean 'qd1'"]),
        (["x1*cosh(q1)"], 2, ["'x1*cosh(q1)'", "unknown function 'cosh'", "did you mean 'cos'"]),
        (["x1 +"], 2, ["'x1 +'", "cannot parse"]),
        (["3"], 2, ["'3'", "constant"]),
        (["x1 - x1"], 2, ["'x1 - x1'", "constant"]),
        (["x1^2", "qd1*cos(qd2)"], 2, ["'qd1*cos(qd2)'", "desired state only"]),
        (["x1.__class__"], 2, ["'x1.__class__'", "may contain only"]),
        (["x1; import os"], 2, ["may contain only"]),
        (["x1**x2"], 2, ["'x1**x2'", "exponent"]),
        ([""], 2, ["empty"]),
        (["x1^2"], 0, ["joints"]),
        ("paper", 3, ["'paper'", "two-link"]),
        ("polynomial", 2, ["degree"]),
        ([], 2, ["at least one"]),
    ],
)
def test_errors_name_the_term(terms, joints, fragments) -> None:
    with pytest.raises(ValueError) as error:
        ExpressionBasis(terms, joints)
    for fragment in fragments:
        assert fragment in str(error.value)


@pytest.mark.parametrize("degree", [3, 0, 2.0, True])
def test_polynomial_degree_must_be_even(degree) -> None:
    with pytest.raises(ValueError, match="degree"):
        bases.polynomial_terms(2, degree)


@pytest.mark.parametrize(
    ("opcodes", "arguments", "message"),
    [
        ([42], [0.0], "unknown opcode 42"),
        ([1, 14], [4.0], "one per opcode"),
        ([1, 14], [7.0, 0.0], "unknown variable index 7"),
        ([1, 14], [0.5, 0.0], "unknown variable index 0.5"),
        ([1, 4, 14], [0.0, 0.0, 0.0], "stack underflow"),
        ([1, 1, 14], [0.0, 1.0, 0.0], "exactly one value"),
        ([1, 14, 1], [0.0, 0.0, 1.0], "after its last store"),
        ([], [], "no function"),
        ([0, 14], [float("nan"), 0.0], "finite"),
    ],
)
def test_core_refuses_bad_programs(opcodes, arguments, message) -> None:
    with pytest.raises(ValueError, match=message):
        _core.ExpressionBasis(2, opcodes, arguments)


def test_core_checks_sizes() -> None:
    basis = ExpressionBasis(["x1^2", "x3*qd2"]).core
    with pytest.raises(ValueError, match=r"x: expected shape \(4, 1\)"):
        basis.evaluate(np.zeros(3), np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="dqd"):
        basis.evaluate(np.zeros(4), np.zeros(2), np.zeros(3))
    with pytest.raises(ValueError, match="qd"):
        basis.evaluate_rows(np.zeros((5, 4)), np.zeros((4, 2)), np.zeros((5, 2)))
    with pytest.raises(ValueError, match=r"expected shape \(\.\.\., 4\)"):
        ExpressionBasis(["x1^2"]).evaluate(np.zeros((2, 3)))


def test_quadratic_form_weights() -> None:
    rng = np.random.default_rng(6)
    A = rng.normal(size=(4, 4))
    P = A @ A.T
    weights = ExpressionBasis("quadratic").quadratic_form_weights(P)
    expected = [P[i, j] * (1 if i == j else 2) for i in range(4) for j in range(i, 4)]
    np.testing.assert_allclose(weights, expected, rtol=1e-10, atol=1e-12)
    # the paper's basis holds blockdiag(diag, [[a, b], [b, c]]) forms, in its own order
    D = np.diag([1.0, 2.0, 3.0, 4.0])
    D[2, 3] = D[3, 2] = 0.25
    paper = ExpressionBasis("paper").quadratic_form_weights(D)
    np.testing.assert_allclose(paper, [1, 2, 0, 3, 0, 4, 0.5, 0], atol=1e-12)
    with pytest.raises(ValueError, match=r"lacks x1\*x3, x1\*x4, x2\*x3, x2\*x4;"):
        ExpressionBasis("paper").quadratic_form_weights(P)
    with pytest.raises(ValueError, match=r"P: expected a finite \(4, 4\)"):
        ExpressionBasis("paper").quadratic_form_weights(np.eye(3))


def test_monomials_with_coefficients_and_desired_variables_match_sympy() -> None:
    # monomials take the engine's stackless path; these check it against sympy too
    terms = bases.polynomial_terms(2, 4) + ["3*x1*x2^2*qd2", "-2.5*x3^3*x4", "-x1*qd1^2", "qd2*x4"]
    rng = np.random.default_rng(7)
    check_against_reference(terms, 2, random_points(rng, 2, count=10))
    # and give the same numbers as the stack path: the same program with "+ 0" appended (which
    # makes it no monomial) runs on the stack
    opcodes, arguments = bases.compile_terms(["3*x1*x2^2*qd2"], 2)
    plain = _core.ExpressionBasis(2, opcodes.tolist(), arguments.tolist())
    op = _core.ExpressionOp
    stacked = _core.ExpressionBasis(
        2,
        [*opcodes[:-1].tolist(), int(op.constant), int(op.add), int(op.store)],
        [*arguments[:-1].tolist(), 0.0, 0.0, 0.0],
    )
    for x, qd, dqd in random_points(rng, 2, count=10):
        for a, b in zip(plain.evaluate(x, qd, dqd), stacked.evaluate(x, qd, dqd), strict=True):
            np.testing.assert_array_equal(a, b)
