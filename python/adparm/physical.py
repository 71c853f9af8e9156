"""From the physical parameters of a two-link arm to the lumped form of eq. (1).

The two-link arm of the paper is written with five lumped constants,

.. math::

    M(q) = \\begin{bmatrix} p_1 + 2 p_3 \\cos q_2 & p_2 + p_3 \\cos q_2 \\\\
                            p_2 + p_3 \\cos q_2 & p_2 \\end{bmatrix}, \\qquad
    G(q) = \\begin{bmatrix} g_1 \\cos q_1 + g_2 \\cos(q_1 + q_2) \\\\
                            g_2 \\cos(q_1 + q_2) \\end{bmatrix},

and C(q, dq) follows from M. :func:`two_link_parameters` computes them from masses, lengths,
centre-of-mass distances and inertias, for the ``[plant]`` and ``[model]`` sections of a
configuration.
"""

from __future__ import annotations

import math
import numbers

__all__ = ["two_link_parameters"]


def _positive(value: object, name: str, *, allow_zero: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: must be a real number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name}: must be finite, got {number!r}")
    if number < 0.0 or (number == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name}: must be {bound}, got {number!r}")
    return number


def two_link_parameters(
    m1: float,
    m2: float,
    l1: float,
    lc1: float,
    lc2: float,
    I1: float,  # noqa: N803 (the usual symbol)
    I2: float,  # noqa: N803
    g: float = 9.81,
) -> dict[str, float]:
    """Lumped parameters p1, p2, p3, g1, g2 of a planar two-link arm from its physical ones.

    Joint angles are measured as in the paper: q1 from the horizontal, q2 relative to link 1, and
    gravity acts along -y, so that the potential energy is
    ``m1 g lc1 sin q1 + m2 g (l1 sin q1 + lc2 sin(q1 + q2))``.

    Parameters
    ----------
    m1, m2 : float
        Masses of link 1 and link 2 (kg), > 0.
    l1 : float
        Length of link 1 (m), the distance between the two joints, > 0.
    lc1, lc2 : float
        Distance of each link's centre of mass from its own joint (m), >= 0.
    I1, I2 : float
        Moment of inertia of each link about its centre of mass, around the joint axis
        (kg m^2), >= 0.
    g : float, optional
        Gravitational acceleration (m/s^2), >= 0; default 9.81.

    Returns
    -------
    dict
        ``{"p1", "p2", "p3", "g1", "g2"}`` with

        - ``p1 = m1 lc1^2 + m2 (l1^2 + lc2^2) + I1 + I2``
        - ``p2 = m2 lc2^2 + I2``
        - ``p3 = m2 l1 lc2``
        - ``g1 = (m1 lc1 + m2 l1) g``
        - ``g2 = m2 lc2 g``

        ready to be the ``[plant]`` (or ``[model]``) section of a configuration.

    Raises
    ------
    TypeError
        If an argument is not a real number.
    ValueError
        If an argument is not finite or out of range (named in the message), or if the
        resulting mass matrix is not positive definite for every q2 (a link with no mass and no
        inertia).

    Examples
    --------
    >>> import adparm
    >>> arm = adparm.two_link_parameters(m1=1.0, m2=1.0, l1=1.0, lc1=0.5, lc2=0.5,
    ...                                  I1=1 / 12, I2=1 / 12)
    >>> {key: round(value, 4) for key, value in arm.items()}
    {'p1': 1.6667, 'p2': 0.3333, 'p3': 0.5, 'g1': 14.715, 'g2': 4.905}
    """
    m1 = _positive(m1, "m1")
    m2 = _positive(m2, "m2")
    l1 = _positive(l1, "l1")
    lc1 = _positive(lc1, "lc1", allow_zero=True)
    lc2 = _positive(lc2, "lc2", allow_zero=True)
    I1 = _positive(I1, "I1", allow_zero=True)  # noqa: N806
    I2 = _positive(I2, "I2", allow_zero=True)  # noqa: N806
    g = _positive(g, "g", allow_zero=True)
    p1 = m1 * lc1**2 + m2 * (l1**2 + lc2**2) + I1 + I2
    p2 = m2 * lc2**2 + I2
    p3 = m2 * l1 * lc2
    # min over q2 of det M(q) = p1 p2 - p2^2 - p3^2 = m2 l1^2 I2 + (m1 lc1^2 + I1) p2: zero only
    # when I2 = 0 and link 1 has no inertia about its joint (or link 2 none about its own).
    if not (p2 > 0.0 and p1 * p2 - p2**2 - p3**2 > 0.0):
        raise ValueError(
            "m1, m2, l1, lc1, lc2, I1, I2: M(q) must be positive definite for every q2 "
            f"(need p2 > 0 and p1 p2 - p2^2 - p3^2 > 0; got p1={p1!r}, p2={p2!r}, p3={p3!r}); "
            "give link 2 an inertia I2 > 0, or link 1 an inertia about its joint"
        )
    return {"p1": p1, "p2": p2, "p3": p3, "g1": (m1 * lc1 + m2 * l1) * g, "g2": m2 * lc2 * g}
