"""The region of Bellman-error extrapolation points a URDF arm derives (docs: URDF arms, the
derived values): the joint's range within its limits (:func:`extrapolation_range`, the default)
or a box symmetric about qd (:func:`extrapolation_box`, when a centre is given). Re-exported by
:mod:`adparm.rates`, which derives the rest of a URDF arm's settings."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["BOX_REACH_CAP", "RANGE_WIDTH_FLOOR", "extrapolation_box", "extrapolation_range"]

#: The derived box's e1 half-width cap (rad): M(q) of a revolute joint repeats every 2 pi.
BOX_REACH_CAP = math.pi
#: extrapolation_range's least width of a joint's e1 range (rad).
RANGE_WIDTH_FLOOR = 1.0


def _limit_distances(
    qd: np.ndarray, low: np.ndarray, high: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """qd's distances to each joint's lower and upper limit, qd - low and high - qd, at most
    BOX_REACH_CAP (a missing limit, nan or infinite, is no limit: fmin drops the nan)."""
    return np.fmin(qd - low, BOX_REACH_CAP), np.fmin(high - qd, BOX_REACH_CAP)


def extrapolation_box(
    qd: np.ndarray, q0: np.ndarray, low: np.ndarray, high: np.ndarray, alpha1: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The derived extrapolation.box of a URDF arm that gives extrapolation.centre but not the box
    (b1 on e1, b2 on e2, per joint, symmetric about the centre; docs: URDF arms):
    b1_i = max(1, 2 max|e1(0)|, min(pi, qd_i - low_i, high_i - qd_i)), the largest box around qd
    whose joint positions stay within the limits, so the points inform the inertia block of the
    weights over the joint range (a 1 rad box left 5- and 7-joint chains 106 % and 4.3 % off W*
    after 10 s) without points at positions the arm cannot take (the former box, the larger of
    the two distances, reached past the limits of the Z1's three joints whose qd sits on a limit
    and left it 5.2 % off W* with one random cost; over 36 random costs on six arms each rule
    left one run outside 1 %, and this one reaches 1 % later on the SO-100, Kinova, xArm7 and
    Panda: docs, URDF arms, "Other random costs"). The box is symmetric ([-box, box]): a
    joint with qd on or near a limit gets the floor, 1 rad, half of it outside the limits; an
    unlimited joint reaches pi (M(q) repeats every 2 pi). b2 = |alpha1|_max b1 (e2 ~ alpha1 e1)."""
    below, above = _limit_distances(qd, low, high)
    reach = np.minimum(below, above)
    floor = max(1.0, 2.0 * float(np.abs(qd - q0).max()))
    b1 = np.maximum(floor, np.minimum(BOX_REACH_CAP, reach))
    b2 = float(np.abs(np.linalg.eigvals(alpha1)).max()) * b1
    return b1, b2


def extrapolation_range(
    qd: np.ndarray, q0: np.ndarray, low: np.ndarray, high: np.ndarray, alpha1: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """An asymmetric extrapolation box, (centre, box) in x = [e1; e2], each (2n,), to give as
    ``extrapolation.centre`` and ``extrapolation.box``, the derived default of a URDF arm that
    gives neither (36 of 36 random costs within 1 % of W* on six arms, where a box symmetric
    about qd left one outside: docs, URDF arms). With e1 = qd - q, the joint positions q = qd - e1
    span the joint's range within its limits, at most pi each way from qd: e1_i in [lo_i, hi_i] with
    lo_i = max(qd_i - high_i, -pi), hi_i = min(qd_i - low_i, pi) (a missing limit: pi), widened to
    hold 0 and e1_i(0), and then about its middle to a width of at least 1 rad (a joint whose
    range is narrower reaches past its limits). e2 stays symmetric about 0, with half-width
    |alpha1|_max max(|lo_i|, |hi_i|) (e2 ~ alpha1 e1 over the e1 range)."""
    e1_start = qd - q0
    below, above = _limit_distances(qd, low, high)
    lower, upper = -above, below
    lower = np.minimum(lower, np.minimum(0.0, e1_start))
    upper = np.maximum(upper, np.maximum(0.0, e1_start))
    grow = np.maximum(0.0, RANGE_WIDTH_FLOOR - (upper - lower)) / 2.0
    lower, upper = lower - grow, upper + grow
    reach = np.maximum(np.abs(lower), np.abs(upper))
    rate = float(np.abs(np.linalg.eigvals(alpha1)).max())
    centre = np.concatenate([(lower + upper) / 2.0, np.zeros_like(lower)])
    box = np.concatenate([(upper - lower) / 2.0, rate * reach])
    return centre, box
