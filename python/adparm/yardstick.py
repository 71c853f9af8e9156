"""J*, the yardstick of any cost: :func:`optimal_cost`, the numerically optimal cost from x0 for
the believed model (or the plant) without disturbance, by direct transcription (CasADi + IPOPT),
refined until it settles to a stated tolerance (:class:`OptimalCost`), and its default horizon.
adparm.truth re-exports them."""

from __future__ import annotations

import math
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

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
        (N, J(N)) of each solve at the final horizon, the coarsest first.
    torque_limits : tuple of float or None
        The bounds ``|tau_i| <= limit_i`` on the applied torque (None: no limits).
    input_bound : tuple of float or None
        lambda of the bounded input cost U(u) (None: the quadratic u^T R u).
    e2_cost : str
        "quadratic" or "logcosh" (the state cost's e2 block).
    active_until : float
        The last node time (s) at which a torque limit is active (0 when none is).
    terminal_share : float
        x(T)^T P x(T) / J: the share of the terminal cost, which is the cost-to-go of the
        small-signal problem and so trusted only where it is small and no limit is active.
    """

    error: float
    rtol: float
    converged: bool
    intervals: int
    horizon: float
    terminal: bool
    history: tuple[tuple[int, float], ...]
    torque_limits: tuple[float, ...] | None = None
    input_bound: tuple[float, ...] | None = None
    e2_cost: str = "quadratic"
    active_until: float = 0.0
    terminal_share: float = 0.0

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
        limits = (
            f"; torque limits active until t = {self.active_until:.3g} s"
            if self.active_until > 0.0
            else ""
        )
        if math.isnan(self.error):
            return f"no error estimate (one solve, {self.intervals} intervals){limits}"
        if self.converged:
            return (
                f"relative error <= {self.rtol:.0e} (estimated {self.error:.1e}, "
                f"{self.intervals} intervals){limits}"
            )
        return (
            f"not converged to {self.rtol:.0e}: relative change {self.error:.1e} at "
            f"{self.intervals} intervals{limits}"
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
    """``config`` with the model the plant itself (an exact model; the settings derived from the
    believed model kept: Config.believing_the_plant)."""
    return config.believing_the_plant()


def _count(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer >= 10, got {value!r}")
    if value < 10:
        raise ValueError(f"{name}: expected an integer >= 10, got {value!r}")
    return int(value)


def _per_joint(value: Any, n: int, name: str, *, infinite: bool) -> tuple[float, ...] | None:
    """None, or n numbers > 0 from one number or n of them (inf allowed when ``infinite``)."""
    if value is None:
        return None
    kind = "numbers > 0" + (" (inf: no limit)" if infinite else ", finite")
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected one number or {n} {kind}, got {value!r}") from None
    if array.shape not in ((), (n,)):
        raise ValueError(f"{name}: expected one number or {n} {kind}, got {value!r}")
    array = np.broadcast_to(array, (n,)).copy()
    if np.isnan(array).any() or (array <= 0.0).any() or (not infinite and np.isinf(array).any()):
        raise ValueError(f"{name}: expected one number or {n} {kind}, got {value!r}")
    return tuple(float(v) for v in array)


def _diagonal(matrix: np.ndarray, name: str, why: str) -> np.ndarray:
    if np.abs(matrix - np.diag(np.diag(matrix))).max() > 0.0:
        raise ValueError(f"{name}: {why} needs it diagonal, got {matrix.tolist()}")
    return np.diag(matrix).copy()


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
    torque_limits: Any = None,
    input_bound: Any = None,
    e2_cost: str | None = None,
) -> OptimalCost:
    """The optimal cost int_0^inf Q(x) + U(u) dt from x0 (default: the initial error state of
    ``config``) for the error system without disturbance, de1 = -alpha1 e1 + e2,
    M(q) de2 = -C(q, dq) e2 + u, q = qd - e1, dq = alpha1 e1 - e2 (a set-point qd), by direct
    multiple shooting (CasADi, IPOPT), on the two-link arm or a URDF arm. Any cost Q, R;
    optionally with the applied torque tau = h(q, dq) - u bounded (``torque_limits``), the
    bounded input cost (``input_bound``) and the logcosh state cost (``e2_cost``). On the exact
    instances (optimal_weights) it equals V*(x0) = e1^T K e1 + s e2^T M e2.

    The transcription has N RK4 intervals over the horizon with u linear within each, plus the
    terminal cost x(T)^T P x(T) of :func:`lqr_value`. It starts at N = ``intervals`` and doubles
    N, each solve starting from the last, until the relative change is at most ``rtol`` or N
    would pass ``max_intervals``; the result says which (``converged``) and the estimate.

    Limits. With ``torque_limits``, ``|tau_i| <= limit_i`` holds at every node (both ends of each
    interval, u being linear in it), tau = h - u with h the feedforward of eq. (5) at the
    set-point (M alpha1 de1 + C alpha1 e1 + G + F, friction included). With ``input_bound``
    (lambda), the input cost is U(u) = sum_i R_i [2 lambda_i u_i atanh(u_i / lambda_i) +
    lambda_i^2 ln(1 - u_i^2 / lambda_i^2)] (R diagonal) with ``|u_i| <= lambda_i (1 - 1e-6)``;
    ``e2_cost = "logcosh"`` replaces the state cost's e2 block by sum_i 2 lambda_i^2 R_i^2
    q22_i ln cosh(e2_i / (R_i lambda_i)) (q22 the diagonal of Q's e2 block). Near x = 0 both
    costs are the quadratic ones and no torque limit is active (the gravity torque at the
    set-point must be inside them), so the terminal cost x^T P x is the cost-to-go of that
    small-signal problem: with the default horizon and any of these options, the horizon is
    lengthened (up to 4 times) until it leaves 12 LQR time constants after the last active torque
    limit and x(T)^T P x(T) is below 1e-9 of J (``active_until``, ``terminal_share``).

    Parameters
    ----------
    config : Config
        Cost, alpha1, set-point and the arm (the two-link arm, or a URDF arm whose M, C, G are
        built by adam-robotics; locked joints are refused).
    x0 : array_like, shape (2n,), optional
        The initial error state.
    horizon : float, optional
        Transcribed time (s); default :func:`default_horizon`, 12 time constants of the slowest
        LQR closed-loop mode (lengthened with limits, see above).
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
    torque_limits : float or array_like, optional
        ``|tau_i| <= limit_i`` (N m; one number or one per joint, inf: none). Default: the config's
        ``plant.torque_limits`` where it has one, else none.
    input_bound : float or array_like, optional
        lambda_i > 0 of the bounded input cost U(u). Default: the config's ``cost.input_bound``
        where it has one, else the quadratic u^T R u.
    e2_cost : {"quadratic", "logcosh"}, optional
        Default: the config's ``cost.e2_cost`` where it has one, else "quadratic". "logcosh"
        needs ``input_bound`` and a diagonal e2 block of Q.

    Returns
    -------
    OptimalCost
        A float with ``error``, ``rtol``, ``converged``, ``intervals``, ``horizon``,
        ``terminal``, ``history``, ``torque_limits``, ``input_bound``, ``e2_cost``,
        ``active_until``, ``terminal_share`` and a one-line ``note``.

    Raises
    ------
    ValueError
        For a moving qd, a URDF arm with locked joints or without adam-robotics, limits that
        cannot hold the set-point, or a bad argument.
    RuntimeError
        If IPOPT does not converge.
    KeyboardInterrupt
        On Ctrl-C (or SIGTERM, where its handler raises it) during a solve.
    """
    check_config(config)
    if not config.task.is_set_point:
        raise ValueError("task.qd: optimal_cost needs a set-point (a constant qd)")
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
    n = config.dof
    names = ("torque_limits", "input_bound", "e2_cost")
    if torque_limits is None:
        names = ("plant.torque_limits", *names[1:])
        torque_limits = config.plant.limit_vector(n)
        if torque_limits.size == 0:
            torque_limits = None
    if input_bound is None:
        names = (names[0], "cost.input_bound", names[2])
        input_bound = config.cost.input_bound
    if e2_cost is None:
        names = (*names[:2], "cost.e2_cost")
        e2_cost = config.cost.e2_cost
    limits = _per_joint(torque_limits, n, names[0], infinite=True)
    bound = _per_joint(input_bound, n, names[1], infinite=False)
    if e2_cost not in ("quadratic", "logcosh"):
        raise ValueError(f"{names[2]}: expected 'quadratic' or 'logcosh', got {e2_cost!r}")
    if e2_cost == "logcosh" and bound is None:
        raise ValueError(f"{names[2]}: 'logcosh' needs an input bound ({names[1]})")
    if not model:
        config = plant_config(config)
    x0 = initial_error_state(config) if x0 is None else np.asarray(x0, dtype=float)
    if x0.shape != (2 * n,) or not np.all(np.isfinite(x0)):
        raise ValueError(f"x0: expected {2 * n} finite numbers, got {x0!r}")
    lengthen = horizon is None and terminal and (limits, bound) != (None, None)
    tail = default_horizon(config) if horizon is None else horizon
    horizon = tail
    if not (math.isfinite(horizon) and horizon > 0.0):
        raise ValueError(f"horizon: expected a finite number > 0, got {horizon!r}")
    options = {"limits": limits, "bound": bound, "e2_cost": e2_cost, "limits_name": names[0]}
    transcription = _Transcription(config, x0, float(horizon), bool(terminal), **options)
    history: list[tuple[int, float]] = []
    change, guess, count, lengthened = math.nan, None, intervals, 0
    while True:
        value, guess = transcription.solve(count, guess)
        active, share = transcription.active_until(guess), transcription.terminal_share(guess)
        if lengthen and not history and lengthened < 4:
            wanted = max(active + tail, 2.0 * horizon if share > 1e-9 else 0.0)
            if wanted > horizon * (1.0 + 1e-9):  # too short: start again over a longer one
                horizon, lengthened = wanted, lengthened + 1
                transcription = _Transcription(config, x0, horizon, bool(terminal), **options)
                continue
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
        torque_limits=limits,
        input_bound=bound,
        e2_cost=e2_cost,
        active_until=active,
        terminal_share=share,
    )


def _log_cosh(y: Any) -> Any:
    """ln cosh y without overflow (its asymptote |y| - ln 2 + ln(1 + e^-2|y|) past |y| = 20)."""
    import casadi

    a = casadi.fabs(y)
    return casadi.if_else(
        a < 20.0, casadi.log(casadi.cosh(y)), a - math.log(2.0) + casadi.log1p(casadi.exp(-2 * a))
    )


class _Transcription:
    """Direct multiple shooting of the error system of ``config``'s believed arm from x0 over
    the horizon: one CasADi RK4 step, mapped over the N intervals of each solve, and the
    applied torque at the nodes where it is bounded."""

    #: |u_i| <= lambda_i (1 - BOUND_MARGIN): U(u) is finite at lambda, its slope is not.
    BOUND_MARGIN = 1e-6

    def __init__(
        self,
        config: Config,
        x0: np.ndarray,
        horizon: float,
        terminal: bool,
        *,
        limits: tuple[float, ...] | None = None,
        bound: tuple[float, ...] | None = None,
        e2_cost: str = "quadratic",
        limits_name: str = "torque_limits",
    ) -> None:
        import casadi

        from .symbolic_arm import arm_expressions, set_point_feedforward

        n = config.dof
        self.n, self.x0, self.horizon = n, x0, horizon
        self.P = lqr_value(config) if terminal else np.zeros((2 * n, 2 * n))
        Q, R = np.array(config.cost.Q), np.array(config.cost.R)
        alpha1 = np.array(config.control.alpha1)
        qd = desired_state(config, 0.0)[0]

        x = casadi.SX.sym("x", 2 * n)
        u = casadi.SX.sym("u", n)
        e1, e2 = x[:n], x[n:]
        q = casadi.DM(qd) - e1
        dq = casadi.mtimes(casadi.DM(alpha1), e1) - e2
        a = casadi.SX.sym("a", n)  # de2 at a stage, a decision variable
        terms = arm_expressions(config, q, dq)
        de1 = -casadi.mtimes(casadi.DM(alpha1), e1) + e2
        rhs = -casadi.mtimes(terms["C"], e2) + u
        if e2_cost == "logcosh":
            q22 = _diagonal(Q[n:, n:], "cost.Q", "e2_cost = 'logcosh' (its e2 block)")
            r = _diagonal(R, "cost.R", "an input bound")
            scale = np.asarray(bound) * r
            Q0 = Q.copy()
            Q0[n:, n:] = 0.0
            state = casadi.bilin(casadi.DM(Q0), x, x) + casadi.sum1(
                casadi.DM(2.0 * scale**2 * q22) * _log_cosh(e2 / casadi.DM(scale))
            )
        else:
            state = casadi.bilin(casadi.DM(Q), x, x)
        if bound is not None:
            r = _diagonal(R, "cost.R", "an input bound")
            lam = casadi.DM(bound)
            z = u / lam
            effort = casadi.sum1(
                casadi.DM(r) * (2 * lam * u * casadi.atanh(z) + lam**2 * casadi.log1p(-(z**2)))
            )
        else:
            effort = casadi.bilin(casadi.DM(R), u, u)
        # M(q) de2 = -C e2 + u as the equality M a - rhs = 0 (no symbolic inverse of M)
        self.f = casadi.Function(
            "f",
            [x, u, a],
            [casadi.vertcat(de1, a, state + effort), casadi.mtimes(terms["M"], a) - rhs],
        )
        self.mass = casadi.Function("mass", [x, u], [casadi.vec(terms["M"]), rhs])
        self.bound = None if bound is None else np.asarray(bound) * (1.0 - self.BOUND_MARGIN)
        self.limits = None if limits is None else np.asarray(limits)
        self.tau = None
        if limits is not None:
            # Coulomb friction's jump at dq = 0 would make the constraint discontinuous: it is
            # relaxed, |h - u - coulomb sign(dq)| <= limit implying |h - u| <= limit + |coulomb|
            # (h with viscous friction alone), so J* stays a lower bound of the true optimum
            smooth = dict(terms, F=casadi.DM(terms["viscous"]) * dq)
            h = set_point_feedforward(smooth, alpha1, e1, e2)
            self.tau = casadi.Function("tau", [x, u], [h - u])
            gravity = np.array(self.tau(np.zeros(2 * n), np.zeros(n))).ravel()  # h(0) = G(qd)
            self.limits = self.limits + np.abs(terms["coulomb"])
            if np.any(np.abs(gravity) >= np.asarray(limits)):
                raise ValueError(
                    f"{limits_name}: {list(limits)} cannot hold the set-point, whose gravity "
                    f"torque is G(qd) = {gravity.tolist()} N m"
                )

    def solve(self, intervals: int, guess: Any) -> tuple[float, Any]:
        """J of N = ``intervals``, and (t, X, U) of the solution, the next solve's start
        (``guess``: the last one's, interpolated; None: the LQR-like decay of x0)."""
        import casadi

        f, step, n = self.f, self.horizon / intervals, self.n
        xa = casadi.SX.sym("xa", 2 * n)
        ua, ub = casadi.SX.sym("ua", n), casadi.SX.sym("ub", n)
        stages = casadi.SX.sym("stages", n, 4)  # de2 at the four RK4 stages
        k1, r1 = f(xa, ua, stages[:, 0])
        k2, r2 = f(xa + step / 2 * k1[: 2 * n], (ua + ub) / 2, stages[:, 1])
        k3, r3 = f(xa + step / 2 * k2[: 2 * n], (ua + ub) / 2, stages[:, 2])
        k4, r4 = f(xa + step * k3[: 2 * n], ub, stages[:, 3])
        end = casadi.vertcat(xa, 0) + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        residuals = casadi.vertcat(r1, r2, r3, r4)
        rk4 = casadi.Function("rk4", [xa, ua, ub, stages], [end, residuals])
        rk4 = rk4.map(intervals)

        opti = casadi.Opti()
        X = opti.variable(2 * n, intervals + 1)
        U = opti.variable(n, intervals + 1)
        A = opti.variable(n, 4 * intervals)  # interval i's stages in columns 4i to 4i + 3
        ends, residuals = rk4(X[:, :-1], U[:, :-1], U[:, 1:], A)  # every interval at once
        opti.subject_to(X[:, 0] == self.x0)
        opti.subject_to(X[:, 1:] == ends[: 2 * n, :])
        opti.subject_to(casadi.vec(residuals) == 0)
        if self.bound is not None:
            limit = np.repeat(self.bound[:, None], intervals + 1, axis=1)
            opti.subject_to(opti.bounded(-limit, U, limit))
        if self.tau is not None:
            finite = np.isfinite(self.limits)
            torque = self.tau.map(intervals + 1)(X, U)
            limit = np.repeat(self.limits[finite][:, None], intervals + 1, axis=1)
            rows = [i for i in range(n) if finite[i]]
            opti.subject_to(opti.bounded(-limit, torque[rows, :], limit))
        total = casadi.sum2(ends[2 * n, :]) + casadi.bilin(casadi.DM(self.P), X[:, -1], X[:, -1])
        opti.minimize(total)
        t = np.linspace(0.0, self.horizon, intervals + 1)
        if guess is None:  # the LQR policy's decay as the initial guess
            X_start, U_start = np.outer(self.x0, np.exp(-t)), np.zeros((n, intervals + 1))
        else:
            t_old, X_old, U_old = guess
            X_start = np.array([np.interp(t, t_old, row) for row in X_old])
            U_start = np.array([np.interp(t, t_old, row) for row in U_old])
        opti.set_initial(X, X_start)
        opti.set_initial(U, U_start)
        opti.set_initial(A, self._stage_guess(X_start, U_start))
        opti.solver(
            "ipopt",
            {"print_time": False, "detect_simple_bounds": True},
            {"print_level": 0, "sb": "yes", "tol": 1e-10},
        )
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
        self.value = float(solution.value(total))
        return self.value, (t, states, inputs)

    def _stage_guess(self, X: np.ndarray, U: np.ndarray) -> np.ndarray:
        """de2 = M^-1 (-C e2 + u) at the nodes and the interval midpoints of a guess (X, U),
        as the four stages of each interval (start, middle, middle, end)."""
        n = self.n
        X_mid, U_mid = (X[:, :-1] + X[:, 1:]) / 2, (U[:, :-1] + U[:, 1:]) / 2
        columns = X.shape[1] + X_mid.shape[1]
        mass, rhs = self.mass.map(columns)(np.hstack([X, X_mid]), np.hstack([U, U_mid]))
        mass = np.array(mass).T.reshape(columns, n, n).transpose(0, 2, 1)  # vec is column-major
        de2 = np.linalg.solve(mass, np.array(rhs).T[:, :, None])[:, :, 0].T
        nodes, middles = de2[:, : X.shape[1]], de2[:, X.shape[1] :]
        return np.stack([nodes[:, :-1], middles, middles, nodes[:, 1:]], axis=2).reshape(n, -1)

    def active_until(self, solution: Any) -> float:
        """The last node time at which a torque limit is active (to 1e-6 relative), else 0."""
        if self.tau is None:
            return 0.0
        t, X, U = solution
        torque = np.array(self.tau.map(len(t))(X, U))
        active = np.any(np.abs(torque) >= self.limits[:, None] * (1.0 - 1e-6), axis=0)
        return float(t[np.nonzero(active)[0][-1]]) if active.any() else 0.0

    def terminal_share(self, solution: Any) -> float:
        """x(T)^T P x(T) / J of the last solve."""
        end = solution[1][:, -1]
        return float(end @ self.P @ end / self.value) if self.value > 0.0 else 0.0


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
