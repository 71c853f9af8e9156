"""How much longer a run needs, from its own progress towards a known W*: longer_run_estimate,
and the advice adparm.truth gives with it (longer_run_advice)."""

from __future__ import annotations

import math

import numpy as np

from .rates import nice_ceil
from .result import SimulationResult

__all__ = [
    "EPSILON_T_FLOOR",
    "LONGER_RUN_LIMIT",
    "SETTLED_FALL",
    "half_time_index",
    "longer_run_advice",
    "longer_run_estimate",
    "reset_window_advice",
]

#: A measure of learning (the weights' error with W* known, the HJB residual without) that fell by
#: less than this fraction over the second half of a run has settled: a longer run will not help.
#: (The UR5 with an unknown payload and an identifier that never saw enough: 0.018 -> 0.018, and
#: the advice named sim.T = 1e13 s.)
SETTLED_FALL = 0.02


def half_time_index(t: np.ndarray) -> int:
    """The row of a run's record at half its time span (where its progress is measured from)."""
    return int(np.searchsorted(t, t[0] + 0.5 * (t[-1] - t[0])))


def longer_run_estimate(
    result: SimulationResult, target: np.ndarray | None, tolerance: float
) -> dict[str, float] | None:
    """How much longer learning needs, from the run's own progress (W* known): the larger of the
    critic's and the actor's relative weight errors, e(t), falls from e(t_mid) to e(t_end) over
    the second half of the run; at that exponential rate it reaches ``tolerance`` after
    ``needed`` = ln(e(t_end) / tolerance) / rate more seconds, and ``T`` = a round horizon of at
    least t_end + 1.5 needed (a margin: learning slows near the end). ``needed`` is inf when the
    error fell by less than SETTLED_FALL (settled). Also ``error_start`` (e(0)) and ``moved``
    (how far the weights went from their start, relative to W*). None without W* or rows."""
    if target is None or result.t.size < 4:
        return None
    norm = float(np.linalg.norm(target))
    error = np.maximum(
        np.linalg.norm(result.critic_weights - target, axis=1),
        np.linalg.norm(result.actor_weights - target, axis=1),
    ) / max(norm, 1e-300)
    t = result.t
    t_end = float(t[-1])
    middle = half_time_index(t)
    e_mid, e_end = float(error[middle]), float(error[-1])
    moved = max(
        float(np.linalg.norm(result.critic_weights[-1] - result.critic_weights[0])),
        float(np.linalg.norm(result.actor_weights[-1] - result.actor_weights[0])),
    ) / max(norm, 1e-300)
    out = {
        "moved": moved,
        "error_start": float(error[0]),
        "error_mid": e_mid,
        "error_end": e_end,
        "t_mid": float(t[middle]),
        "t_end": t_end,
    }
    if not (e_end < (1.0 - SETTLED_FALL) * e_mid) or not math.isfinite(e_end) or t_end <= t[middle]:
        return {**out, "needed": math.inf, "T": math.inf}
    rate = math.log(e_mid / e_end) / (t_end - float(t[middle]))
    needed = max(0.0, math.log(e_end / tolerance) / rate)
    return {**out, "needed": needed, "T": nice_ceil(t_end + 1.5 * needed)}


#: Below this critic.epsilon_T no lower one is advised (Gamma's condition number gamma0 /
#: epsilon_T would pass 1e9 with the default gamma0).
EPSILON_T_FLOOR = 1e-8


def reset_window_advice(result: SimulationResult, t_mid: float) -> str | None:
    """For learning that settled away from W*, or crawls towards it, while Gamma was still being
    reset (eq. 24's rule, lambda_min(Gamma) < critic.epsilon_T) over the second half of the run:
    a 10 times lower epsilon_T, which lengthens each least-squares window between resets so that
    it informs the weakly excited weights, and, with extrapolation points, twice as many (more
    samples of those weights per evaluation). Measured with random exact costs from the default
    weights (bench/every_arm.py): the Kinova of seed 42 levels off 1.15 % from W* with
    epsilon_T = 1e-5, the one of seed 95 1.6 %, and the xArm7 of seed 58, reset every 29 ms,
    crawls 1.05 -> 1.02. A lower epsilon_T alone ends seeds 42 and 58 "ok" but leaves seed 95 at
    1.68 % (with 1e-6 and 1e-7); twice the points alone end seeds 42 and 95 "ok" but seed 58 at a
    non-stabilising solution; both together end all three "ok" (and the Kinova of seed 53; docs:
    truth). None when Gamma was not reset then or epsilon_T is at its floor."""
    config = result.config
    epsilon_t = float(config.resolved_epsilon_T)
    resets = int(np.count_nonzero(np.asarray(result.covariance_reset_times) > t_mid))
    if resets == 0 or not epsilon_t / 10.0 >= EPSILON_T_FLOOR:
        return None
    points = int(config.extrapolation.points)
    more = f" and extrapolation.points to {2 * points}" if points > 0 else ""
    return (
        f"lower critic.epsilon_T to {epsilon_t / 10.0:.3g}{more}: Gamma was reset {resets} times "
        "over the second half, and longer least-squares windows between resets"
        + (", with twice the samples," if points > 0 else "")
        + " inform the weights the samples excite weakly"
    )


#: A longer run is suggested only up to this many times the run's horizon, or up to
#: LONGER_RUN_FLOOR seconds (beyond both, learning is too slow for a longer run to be the remedy).
LONGER_RUN_LIMIT = 20.0

#: The horizon a longer run may always reach: a short run's 20 times is no sign of slow learning
#: (TIAGo's arm from its defaults, run for 1 s, needs 50 s, as its 4 s and 10 s runs say; it was
#: told to change critic.epsilon_T and extrapolation.points).
LONGER_RUN_FLOOR = 120.0

#: A run whose weights moved but whose error did not fall by SETTLED_FALL from its start may have
#: ended before learning started, or in its transient: it is told this many times its horizon (up
#: to LONGER_RUN_FLOOR), not that a longer run will not help. TIAGo's arm with its hand locked:
#: 0.95 -> 0.94 over its first second (Gamma reset 21 times), "ok" at 10 s; the paper's run:
#: 0.93 -> 6.0 at 3 s, "ok" at 30 s.
UNSTARTED_SCALE = 10.0


def _no_progress_yet(estimate: dict[str, float]) -> bool:
    """Whether the weights moved (learning is on) but their error did not fall by SETTLED_FALL
    from its start: the run may have ended before learning started, or in its transient (the
    paper's run grows to 6 times W* at 3 s and is "ok" at 30 s)."""
    start = estimate["error_start"]
    return estimate["moved"] > 0.0 and estimate["error_end"] >= (1.0 - SETTLED_FALL) * start


def longer_run_advice(
    result: SimulationResult,
    target: np.ndarray | None,
    tolerance: float,
    policy_error: float | None = None,
) -> str:
    """What a longer run would do, from :func:`longer_run_estimate`; ``policy_error`` (rms |u_hat -
    u*| / rms |u*| over the last 10 %): weights within the tolerance whose policy is not were
    still settling over that window, and twice the run's horizon takes it after them."""
    estimate = longer_run_estimate(result, target, tolerance)
    if estimate is None:
        return "run longer (sim.T)"
    progress = (
        f"the weights' error went from {estimate['error_mid']:.3g} at t = "
        f"{estimate['t_mid']:.3g} s to {estimate['error_end']:.3g} at {estimate['t_end']:.3g} s"
    )
    if estimate["error_end"] < tolerance and policy_error is not None and policy_error > tolerance:
        t = result.t
        window = float(t[0] + 0.9 * (t[-1] - t[0]))
        return (
            f"run longer: {progress}, within the tolerance; the policy's error is taken over the "
            f"last 10 % of the run (from {window:.3g} s), while they were still settling: sim.T = "
            f"{nice_ceil(2.0 * estimate['t_end']):g} s takes it after they settled"
        )
    longest = max(LONGER_RUN_LIMIT * result.config.sim.T, LONGER_RUN_FLOOR)
    if math.isfinite(estimate["T"]) and estimate["T"] <= longest:
        return (
            f"run longer: {progress}; at that rate sim.T = {estimate['T']:g} s reaches the "
            "tolerance (an estimate with a margin of 1.5)"
        )
    if not math.isfinite(estimate["T"]):
        start, horizon = estimate["error_start"], nice_ceil(UNSTARTED_SCALE * estimate["t_end"])
        if _no_progress_yet(estimate) and horizon <= LONGER_RUN_FLOOR:
            return (
                f"run longer: no progress yet: the weights' error went from {start:.3g} at t = 0 "
                f"to {estimate['error_end']:.3g} at {estimate['t_end']:.3g} s (a run this short "
                "can end before learning starts, or in its transient); sim.T = "
                f"{horizon:g} s shows whether it converges"
            )
        advice = (
            f"a longer run will not help: {progress} (under {100 * SETTLED_FALL:g} % progress "
            "over the second half of the run)"
        )
    else:
        advice = (
            f"learning is slow: {progress}; at that rate the tolerance needs about "
            f"{estimate['needed']:.3g} s more (sim.T = {estimate['T']:g} s, over "
            f"{LONGER_RUN_LIMIT:g} times this run's and {LONGER_RUN_FLOOR:g} s); likely some "
            "direction of the weights is barely informed by the samples (the cost R, the "
            "extrapolation box or the basis)"
        )
    windows = reset_window_advice(result, estimate["t_mid"])
    return advice + ("; " + windows if windows else "")
