"""adparm.two_link_parameters against an independent Lagrangian derivation (sympy) of a planar
two-link arm, through the M, C, G of the NumPy reference (itself checked against the core)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import adparm

from numpy_reference import arm_terms


def _lagrangian_arm():
    """M(q), C(q, dq) dq and G(q) of a planar two-link arm from its kinetic and potential energy,
    with q1 from the horizontal, q2 relative to link 1 and gravity along -y."""
    q1, q2, dq1, dq2 = sp.symbols("q1 q2 dq1 dq2", real=True)
    m1, m2, l1, lc1, lc2, I1, I2, g = sp.symbols("m1 m2 l1 lc1 lc2 I1 I2 g", positive=True)
    q, dq = sp.Matrix([q1, q2]), sp.Matrix([dq1, dq2])
    centre1 = sp.Matrix([lc1 * sp.cos(q1), lc1 * sp.sin(q1)])
    centre2 = sp.Matrix(
        [l1 * sp.cos(q1) + lc2 * sp.cos(q1 + q2), l1 * sp.sin(q1) + lc2 * sp.sin(q1 + q2)]
    )
    v1, v2 = centre1.jacobian(q) * dq, centre2.jacobian(q) * dq
    kinetic = (
        m1 * v1.dot(v1) / 2 + m2 * v2.dot(v2) / 2 + I1 * dq1**2 / 2 + I2 * (dq1 + dq2) ** 2 / 2
    )
    potential = m1 * g * centre1[1] + m2 * g * centre2[1]
    mass = sp.hessian(kinetic, dq).applyfunc(sp.simplify)
    # Euler-Lagrange: d/dt dT/ddq - dT/dq = M ddq + (dM/dt) dq - dT/dq, so C dq = dM/dt dq - dT/dq
    dmass = sum((mass.diff(qi) * dqi for qi, dqi in zip(q, dq, strict=True)), sp.zeros(2, 2))
    coriolis = dmass * dq - sp.Matrix([kinetic.diff(qi) for qi in q])
    gravity = sp.Matrix([potential.diff(qi) for qi in q])
    symbols = (m1, m2, l1, lc1, lc2, I1, I2, g, q1, q2, dq1, dq2)
    return (sp.lambdify(symbols, expr, "numpy") for expr in (mass, coriolis, gravity))


def test_two_link_parameters_match_the_lagrangian_of_the_physical_arm() -> None:
    mass, coriolis, gravity = _lagrangian_arm()
    rng = np.random.default_rng(3)
    for _ in range(20):
        m1, m2, l1, lc1, lc2, I1, I2 = rng.uniform(0.1, 3.0, size=7)  # noqa: N806
        g = rng.uniform(1.0, 10.0)
        params = adparm.two_link_parameters(m1, m2, l1, lc1, lc2, I1, I2, g=g)
        arm = params | {"coulomb": 0.0, "viscous": 0.0}
        for _ in range(5):
            q, dq = rng.uniform(-3, 3, size=2), rng.uniform(-3, 3, size=2)
            args = (m1, m2, l1, lc1, lc2, I1, I2, g, *q, *dq)
            M, C, G, _ = arm_terms(arm, q, dq)
            np.testing.assert_allclose(M, mass(*args), rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(C @ dq, np.ravel(coriolis(*args)), rtol=1e-11, atol=1e-11)
            np.testing.assert_allclose(G, np.ravel(gravity(*args)), rtol=1e-12, atol=1e-12)
        # the lumped parameters are a valid plant
        config = adparm.paper_config().updated({"plant": params})
        assert config.plant.p3 == params["p3"]


def test_two_link_parameters_formulas_and_default_gravity() -> None:
    params = adparm.two_link_parameters(m1=2.0, m2=1.0, l1=1.0, lc1=0.5, lc2=0.4, I1=0.1, I2=0.05)
    assert params == pytest.approx(
        {
            "p1": 2 * 0.25 + 1 * (1 + 0.16) + 0.1 + 0.05,
            "p2": 0.16 + 0.05,
            "p3": 0.4,
            "g1": (1.0 + 1.0) * 9.81,
            "g2": 0.4 * 9.81,
        },
        rel=1e-15,
    )


@pytest.mark.parametrize(
    ("field", "value", "error", "message"),
    [
        ("m1", 0.0, ValueError, "m1: must be > 0"),
        ("m2", -1.0, ValueError, "m2: must be > 0"),
        ("l1", float("nan"), ValueError, "l1: must be finite"),
        ("lc2", -0.1, ValueError, "lc2: must be >= 0"),
        ("I1", "1", TypeError, "I1: must be a real number"),
        ("I2", True, TypeError, "I2: must be a real number"),
        ("g", float("inf"), ValueError, "g: must be finite"),
    ],
)
def test_two_link_parameters_refuse_bad_input(field, value, error, message) -> None:
    arguments = {"m1": 1.0, "m2": 1.0, "l1": 1.0, "lc1": 0.5, "lc2": 0.5, "I1": 0.1, "I2": 0.1}
    arguments[field] = value
    with pytest.raises(error, match=message):
        adparm.two_link_parameters(**arguments)


def test_two_link_parameters_refuse_a_singular_mass_matrix() -> None:
    # point masses at the joints' far ends with link 1 massless about its joint: det M = 0 at q2=0
    with pytest.raises(ValueError, match="positive definite"):
        adparm.two_link_parameters(m1=1.0, m2=1.0, l1=1.0, lc1=0.0, lc2=1.0, I1=0.0, I2=0.0)
