"""J*, the yardstick of any cost: :func:`optimal_cost`, the numerically optimal cost from x0 for
the believed model (or the plant) without disturbance, by direct transcription (CasADi + IPOPT),
refined until it settles to a stated tolerance (:class:`OptimalCost`), and its default horizon.
adparm.truth re-exports them."""

from __future__ import annotations

import dataclasses
import math
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from ._arm_sections import ModelConfig
from .config import Config
from .desired import desired_state
from .dynamics import check_config, initial_error_state, linearisation, lqr_value

__all__ = ["OptimalCost", "default_horizon", "optimal_cost", "plant_config"]


class OptimalCost(float):
    """J* of :func:`optimal_cost`: the float value of its finest transcription, which also says
    how far it is trusted.

    Attributes
    ----------
    error : float
        Estimated relative error: ``|J(N) - J(N/2)| / J(N)``, the change at the last doubling of
        the intervals N (NaN after a single solve). The transcription converges at order 4
        (RK4, inputs linear in each interval), so the error of J(N) is then about 1/15 of it;
        the change is the stated, conservative figure.
    rtol : float
        The tolerance the refinement aimed at.
    converged : bool
        Whether ``error <= rtol``.
    intervals : int
        N of the value.
    horizon : float
        The transcribed horizon (s).
    terminal : bool
        Whether the cost-to-go after the horizon is charged (x^T P x of lqr_value).
    history : tuple of (int, float)
        (N, J(N)) of each solve, the coarsest first.
    """

    error: float
    rtol: float
    converged: bool
    intervals: int
    horizon: float
    terminal: bool
    history: tuple[tuple[int, float], ...]

    def __new__(cls, value: float, **attributes: Any) -> OptimalCost:
        self = super().__new__(cls, value)
        for key, item in attributes.items():
            object.__setattr__(self, key, item)
        return self

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild_optimal_cost, (float(self), dict(self.__dict__)))

    def __repr__(self) -> str:
        return f"OptimalCost({float(self)!r}, {self.note})"

    @property
    def note(self) -> str:
        """One line: the tolerance met (or not) and the estimate, e.g. ``relative error <= 1e-04
        (estimated 1.3e-05, 800 intervals)``."""
        if math.isnan(self.error):
            return f"no error estimate (one solve, {self.intervals} intervals)"
        if self.converged:
            return (
                f"relative error <= {self.rtol:.0e} (estimated {self.error:.1e}, "
                f"{self.intervals} intervals)"
            )
        return (
            f"not converged to {self.rtol:.0e}: relative change {self.error:.1e} at "
            f"{self.intervals} intervals"
        )


def _rebuild_optimal_cost(value: float, attributes: dict[str, Any]) -> OptimalCost:
    return OptimalCost(value, **attributes)


def default_horizon(config: Config) -> float:
    """The horizon of :func:`optimal_cost`: 12 time constants of the slowest closed-loop mode of
    the LQR policy on the linearisation (its state has decayed by e^-12 there)."""
    check_config(config)
    A, B = linearisation(config)
    P = lqr_value(config)
    closed = A - B @ np.linalg.solve(np.array(config.cost.R), B.T @ P)
    return 12.0 / float(np.min(-np.linalg.eigvals(closed).real))


def plant_config(config: Config) -> Config:
    """``config`` with the model the plant itself (an exact model)."""
    return dataclasses.replace(config, model=ModelConfig())


def _count(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer >= 10, got {value!r}")
    if value < 10:
        raise ValueError(f"{name}: expected an integer >= 10, got {value!r}")
    return int(value)


def optimal_cost(
    config: Config,
    x0: Any = None,
    *,
    horizon: float | None = None,
    intervals: int = 400,
    rtol: float = 1e-4,
    max_intervals: int = 3200,
    terminal: bool = True,
    model: bool = True,
) -> OptimalCost:
    """The optimal cost int_0^inf x^T Q x + u^T R u dt from x0 (default: the initial error state
    of ``config``) for the error system without disturbance, de1 = -alpha1 e1 + e2,
    M(q) de2 = -C(q, dq) e2 + u, q = qd - e1, dq = alpha1 e1 - e2 (a set-point qd), by direct
    multiple shooting (CasADi, IPOPT). Any cost Q, R. On the exact instances (optimal_weights)
    it equals V*(x0) = e1^T K e1 + s e2^T M e2.

    The transcription has N RK4 intervals over the horizon with u linear within each, plus the
    terminal cost x(T)^T P x(T) of :func:`lqr_value`. It starts at N = ``intervals`` and doubles
    N, each solve starting from the last, until the relative change is at most ``rtol`` or N
    would pass ``max_intervals``; the result says which (``converged``) and the estimate.

    Parameters
    ----------
    config : Config
        Cost, alpha1, set-point and the arm (the two-link arm only).
    x0 : array_like, shape (4,), optional
        The initial error state.
    horizon : float, optional
        Transcribed time (s); default :func:`default_horizon`, 12 time constants of the slowest
        LQR closed-loop mode.
    intervals : int, optional
        N of the first solve (>= 10).
    rtol : float, optional
        The relative change between N and 2N at which refinement stops.
    max_intervals : int, optional
        The largest N (``max_intervals = intervals``: one solve, no error estimate).
    terminal : bool, optional
        Charge the cost after the horizon by x^T P x (default). False: the optimum of the cost
        over [0, horizon] alone, a lower bound of any input's cost over that time.
    model : bool, optional
        The arm the controller believes (default); False: the plant, whose error system a run's
        e obeys, so that J* bounds every run's cost on its applied input (adparm.compare).

    Returns
    -------
    OptimalCost
        A float with ``error``, ``rtol``, ``converged``, ``intervals``, ``horizon``,
        ``terminal``, ``history`` and a one-line ``note``.

    Raises
    ------
    ValueError
        For a URDF arm, a moving qd, an input bound (cost.input_bound), or a bad argument.
    RuntimeError
        If IPOPT does not converge.
    KeyboardInterrupt
        On Ctrl-C (or SIGTERM, where its handler raises it) during a solve.
    """
    check_config(config)
    if config.plant.urdf is not None:
        raise ValueError(
            "plant.urdf: optimal_cost transcribes the built-in two-link arm only, not a URDF arm"
        )
    if not config.task.is_set_point:
        raise ValueError("task.qd: optimal_cost needs a set-point (a constant qd)")
    if config.cost.input_bound is not None:
        raise ValueError(
            "cost.input_bound: optimal_cost transcribes the quadratic cost only, not the bounded "
            "input cost (use adparm.optimal_value on the exact family, adparm.saturated_cost)"
        )
    intervals = _count(intervals, "intervals")
    max_intervals = _count(max_intervals, "max_intervals")
    if max_intervals < intervals:
        raise ValueError(
            f"max_intervals: expected at least intervals = {intervals}, got {max_intervals}"
        )
    if isinstance(rtol, bool) or not isinstance(rtol, (int, float, np.floating, np.integer)):
        raise TypeError(f"rtol: expected a number in (0, 1), got {rtol!r}")
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"rtol: expected a number in (0, 1), got {rtol!r}")
    if not model:
        config = plant_config(config)
    x0 = initial_error_state(config) if x0 is None else np.asarray(x0, dtype=float)
    if x0.shape != (4,) or not np.all(np.isfinite(x0)):
        raise ValueError(f"x0: expected 4 finite numbers, got {x0!r}")
    if horizon is None:
        horizon = default_horizon(config)
    if not (math.isfinite(horizon) and horizon > 0.0):
        raise ValueError(f"horizon: expected a finite number > 0, got {horizon!r}")
    transcription = _Transcription(config, x0, float(horizon), bool(terminal))
    history: list[tuple[int, float]] = []
    change, guess, count = math.nan, None, intervals
    while True:
        value, guess = transcription.solve(count, guess)
        if history:
            previous = history[-1][1]
            scale = max(abs(value), abs(previous))
            change = abs(value - previous) / scale if scale > 0.0 else 0.0
        history.append((count, value))
        if change <= rtol or 2 * count > max_intervals:
            break
        count *= 2
    return OptimalCost(
        value,
        error=change,
        rtol=float(rtol),
        converged=bool(change <= rtol),
        intervals=count,
        horizon=float(horizon),
        terminal=bool(terminal),
        history=tuple(history),
    )


class _Transcription:
    """Direct multiple shooting of the error system of ``config``'s believed two-link arm from
    x0 over the horizon: one CasADi RK4 step, mapped over the N intervals of each solve."""

    def __init__(self, config: Config, x0: np.ndarray, horizon: float, terminal: bool) -> None:
        import casadi

        self.x0, self.horizon = x0, horizon
        self.P = lqr_value(config) if terminal else np.zeros((4, 4))
        Q, R = np.array(config.cost.Q), np.array(config.cost.R)
        alpha1 = np.array(config.control.alpha1)
        p = config.model.resolve(config.plant)
        qd = desired_state(config, 0.0)[0]

        x = casadi.SX.sym("x", 4)
        u = casadi.SX.sym("u", 2)
        e1, e2 = x[:2], x[2:]
        q2 = qd[1] - x[1]
        dq = casadi.mtimes(casadi.DM(alpha1), e1) - e2
        c2, s2 = casadi.cos(q2), casadi.sin(q2)
        m12 = p["p2"] + p["p3"] * c2
        M = casadi.vertcat(
            casadi.horzcat(p["p1"] + 2 * p["p3"] * c2, m12), casadi.horzcat(m12, p["p2"])
        )
        h = p["p3"] * s2
        C = casadi.vertcat(
            casadi.horzcat(-h * dq[1], -h * (dq[0] + dq[1])), casadi.horzcat(h * dq[0], 0)
        )
        de1 = -casadi.mtimes(casadi.DM(alpha1), e1) + e2
        de2 = casadi.solve(M, -casadi.mtimes(C, e2) + u)
        rate = casadi.vertcat(
            de1, de2, casadi.bilin(casadi.DM(Q), x, x) + casadi.bilin(casadi.DM(R), u, u)
        )
        self.f = casadi.Function("f", [x, u], [rate])

    def solve(self, intervals: int, guess: Any) -> tuple[float, Any]:
        """J of N = ``intervals``, and (t, X, U) of the solution, the next solve's start
        (``guess``: the last one's, interpolated; None: the LQR-like decay of x0)."""
        import casadi

        f, step = self.f, self.horizon / intervals
        xa = casadi.SX.sym("xa", 4)
        ua, ub = casadi.SX.sym("ua", 2), casadi.SX.sym("ub", 2)
        k1 = f(xa, ua)
        k2 = f(xa + step / 2 * k1[:4], (ua + ub) / 2)
        k3 = f(xa + step / 2 * k2[:4], (ua + ub) / 2)
        k4 = f(xa + step * k3[:4], ub)
        end = casadi.vertcat(xa, 0) + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        rk4 = casadi.Function("rk4", [xa, ua, ub], [end]).map(intervals)

        opti = casadi.Opti()
        X = opti.variable(4, intervals + 1)
        U = opti.variable(2, intervals + 1)
        ends = rk4(X[:, :-1], U[:, :-1], U[:, 1:])  # every interval at once
        opti.subject_to(X[:, 0] == self.x0)
        opti.subject_to(X[:, 1:] == ends[:4, :])
        total = casadi.sum2(ends[4, :]) + casadi.bilin(casadi.DM(self.P), X[:, -1], X[:, -1])
        opti.minimize(total)
        t = np.linspace(0.0, self.horizon, intervals + 1)
        if guess is None:  # the LQR policy's decay as the initial guess
            opti.set_initial(X, np.outer(self.x0, np.exp(-t)))
        else:
            t_old, X_old, U_old = guess
            opti.set_initial(X, np.array([np.interp(t, t_old, row) for row in X_old]))
            opti.set_initial(U, np.array([np.interp(t, t_old, row) for row in U_old]))
        opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-10})
        with _interrupts() as interrupted:
            try:
                solution = opti.solve()
            except RuntimeError as error:  # IPOPT failed, or was stopped by Ctrl-C
                if interrupted:
                    raise KeyboardInterrupt("optimal_cost: interrupted") from None
                raise RuntimeError(
                    f"optimal_cost: IPOPT did not converge at {intervals} intervals ({error})"
                ) from error
        states = np.atleast_2d(solution.value(X))
        inputs = np.atleast_2d(solution.value(U))
        return float(solution.value(total)), (t, states, inputs)


@contextmanager
def _interrupts() -> Iterator[list[int]]:
    """The signals whose Python handler raised KeyboardInterrupt (Ctrl-C) within: CasADi calls
    the handler while IPOPT runs and turns its KeyboardInterrupt into a failed solve, which the
    caller raises again as a KeyboardInterrupt (not as 'IPOPT did not converge')."""
    interrupted: list[int] = []
    previous: dict[int, Any] = {}

    def noting(signum: int, frame: Any) -> None:
        try:
            previous[signum](signum, frame)
        except KeyboardInterrupt:
            interrupted.append(signum)
            raise

    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            if callable(signal.getsignal(signum)):
                previous[signum] = signal.signal(signum, noting)
    try:
        yield interrupted
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
