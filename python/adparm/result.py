"""The result of a run: SimulationResult (its arrays, status and config), the exceptions that
carry a partial one (SimulationDiverged, SimulationInterrupted), ApproximationWarning, and the
one-line text of a step that failed after a run.

The result type imports none of the modules that present it. Its methods that belong to the
layers above (``diagnostics``: adparm.truth; ``plot``: adparm.plotting; ``save``,
``to_dataframe``: adparm.storage; ``summary``: adparm.summary) call the function that module
registers here with :func:`register` when it is imported (``import adparm`` imports them all),
as does adparm.plotting for ``Comparison.plot`` ("plot_comparison"); each registered function
looks its implementation up when called, so replacing that module's function replaces the
method's (docs/design.md, "The Python package's layers")."""

from __future__ import annotations

import dataclasses
import functools
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

import adparm._core as _core

from .config import Config

if TYPE_CHECKING:  # pragma: no cover
    import pandas
    from matplotlib.figure import Figure

__all__ = [
    "ApproximationWarning",
    "SimulationDiverged",
    "SimulationInterrupted",
    "SimulationResult",
    "register",
]

#: The functions a result's methods call in the layers above, by method ("diagnose", "plot",
#: "save", "to_dataframe", "summary"), each registered by its module (register).
PRESENTERS: dict[str, Callable[..., Any]] = {}


def register(method: str, function: Callable[..., Any]) -> None:
    """Let SimulationResult's ``method`` call ``function(result, ...)`` (a module of the analysis
    or output layer registers its function when it is imported)."""
    PRESENTERS[method] = function


def presenter(method: str) -> Callable[..., Any]:
    try:
        return PRESENTERS[method]
    except KeyError:  # pragma: no cover - import adparm registers every one
        raise RuntimeError(f"SimulationResult.{method}: import adparm first") from None


#: A result's status: the run reached sim.T, diverged (SimulationDiverged), was stopped by Ctrl-C
#: (SimulationInterrupted) or is still running (a result read from a run in progress).
STATUSES = ("finished", "diverged", "interrupted", "running")

#: The series a run records, (name, width) in the core's order (adparm._core.RECORDED_SERIES, the
#: C++ table kRecordedSeries): width "one" (a value per row), "joints" (a column per joint) or
#: "basis" (a column per basis function), "parameters" (a column per model parameter) or
#: "identifier" (one value per row); the last two only with identification (``identifier``),
#: else None. Each is an array attribute of SimulationResult.
RECORDED_SERIES: tuple[tuple[str, str], ...] = tuple(
    (str(name), str(width)) for name, width in _core.RECORDED_SERIES
)
ARRAYS_1 = tuple(name for name, width in RECORDED_SERIES if width == "one")
ARRAYS_2 = tuple(name for name, width in RECORDED_SERIES if width == "joints")
ARRAYS_N = tuple(name for name, width in RECORDED_SERIES if width == "basis")
#: The series of the online identifier (None without identification).
ARRAYS_IDENTIFIER = tuple(
    name for name, width in RECORDED_SERIES if width in ("parameters", "identifier")
)


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """One closed-loop run, one row per recorded step (all arrays read-only).

    Returned by :func:`adparm.simulate`; ``.plot()``, ``.save()``, ``.summary()`` and
    ``.to_dataframe()`` present it.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time (s).
    q, dq : ndarray, shape (n, 2)
        Joint angles (rad; m on a prismatic joint) and velocities (rad/s; m/s).
    qd : ndarray, shape (n, 2)
        Desired joint angles (rad; m on a prismatic joint).
    e1, e2 : ndarray, shape (n, 2)
        Tracking error e1 = qd - q (rad) and filtered error e2 = de1 + alpha1 e1 (rad/s).
    tau : ndarray, shape (n, 2)
        Applied torque (N m; a force in N on a prismatic joint): the commanded torque clipped
        to ``plant.torque_limits``.
    tau_commanded : ndarray, shape (n, 2)
        The controller's torque h_hat + mu - u before the clip (N m; equal to ``tau`` without
        limits).
    u : ndarray, shape (n, 2)
        The controller's input (adp: u_hat + probe).
    u_hat : ndarray, shape (n, 2)
        The actor's input (eq. 20).
    mu : ndarray, shape (n, 2)
        The RISE term (eq. 27).
    probe : ndarray, shape (n, 2)
        The probing signal.
    critic_weights, actor_weights : ndarray, shape (n, K)
        Wc and Wa, in the order of ``adparm.basis_names(config)`` (K = 8, or 6 for the
        structured basis).
    hjb_error : ndarray, shape (n,)
        The HJB error of eq. (21).
    cost : ndarray, shape (n,)
        Accumulated cost of eq. (10), the integral of x^T Q x + u^T R u, integrated by RK4 with
        the state.
    covariance_reset_times : ndarray, shape (k,)
        Times (s) at which Gamma was reset.
    config : Config
        The configuration of the run.
    status : str
        ``"finished"``, ``"diverged"``, ``"interrupted"`` or ``"running"``.
    wall_time : float
        Seconds spent in the core.
    saturated_time : ndarray, shape (joints,)
        Seconds each joint's commanded torque lay beyond its limit (``plant.torque_limits``),
        counted per RK4 step by the core (zeros without limits).
    model_parameters : ndarray, shape (n, P), or None
        With ``identifier.enabled``: the estimate beta_hat the controller used from each row's
        time, in the order of ``adparm.base_parameter_names(config)``; None without.
    stack_singular_value : ndarray, shape (n,), or None
        With ``identifier.enabled``: the history stack's minimum singular value (over the
        identified parameters); None without.
    stack_uncertainty : ndarray, shape (n,), or None
        With ``identifier.enabled``: the predicted relative error of the stack's least-squares
        estimate (``identifier.max_uncertainty``; inf while undetermined); None without.
    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    qd: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    tau: np.ndarray
    tau_commanded: np.ndarray
    u: np.ndarray
    u_hat: np.ndarray
    mu: np.ndarray
    probe: np.ndarray
    critic_weights: np.ndarray
    actor_weights: np.ndarray
    hjb_error: np.ndarray
    cost: np.ndarray
    covariance_reset_times: np.ndarray
    config: Config
    status: str = "finished"
    wall_time: float = field(default=float("nan"))
    saturated_time: np.ndarray | None = None
    model_parameters: np.ndarray | None = None
    stack_singular_value: np.ndarray | None = None
    stack_uncertainty: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = np.shape(self.t)[0] if np.ndim(self.t) == 1 else -1
        if n < 0:
            raise ValueError(f"t: expected a 1-d array, got shape {np.shape(self.t)}")
        shapes = {name: (n,) for name in ARRAYS_1}
        joints = self.config.dof if isinstance(self.config, Config) else 2
        shapes.update({name: (n, joints) for name in ARRAYS_2})
        size = self.config.basis_size if isinstance(self.config, Config) else 8
        shapes.update({name: (n, size) for name in ARRAYS_N})
        for name, shape in shapes.items():
            array = read_only_float(getattr(self, name))
            if array.shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {array.shape}")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        resets = np.array(self.covariance_reset_times, dtype=float).reshape(-1)
        resets.flags.writeable = False
        object.__setattr__(self, "covariance_reset_times", resets)
        saturated = (
            np.zeros(joints)
            if self.saturated_time is None
            else np.array(self.saturated_time, dtype=float).reshape(-1)
        )
        if saturated.shape != (joints,):
            raise ValueError(f"saturated_time: expected shape {(joints,)}, got {saturated.shape}")
        saturated.flags.writeable = False
        object.__setattr__(self, "saturated_time", saturated)
        for name in ARRAYS_IDENTIFIER:
            value = getattr(self, name)
            if value is None or np.size(value) == 0:  # the core's empty columns: no identifier
                object.__setattr__(self, name, None)
                continue
            array = read_only_float(value)
            if array.shape[0] != n:
                raise ValueError(f"{name}: expected {n} rows, got shape {array.shape}")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        if self.status not in STATUSES:
            raise ValueError(f"status: expected one of {', '.join(STATUSES)}, got {self.status!r}")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        # pickle and copy.deepcopy rebuild through __init__, so the arrays are checked and
        # read-only again (the default would restore them writable)
        return (
            SimulationResult,
            tuple(getattr(self, f.name) for f in dataclasses.fields(self)),
        )

    @property
    def covariance_resets(self) -> int:
        """Number of resets of Gamma (eq. 24's reset rule)."""
        return int(self.covariance_reset_times.size)

    def to_dict(self) -> dict[str, Any]:
        """The arrays by name (copies), with status and wall_time (model_parameters and
        stack_singular_value only with identification)."""
        names = (*ARRAYS_1, *ARRAYS_2, *ARRAYS_N, "covariance_reset_times", "saturated_time")
        out: dict[str, Any] = {name: np.array(getattr(self, name)) for name in names}
        for name in ARRAYS_IDENTIFIER:  # only with identification
            value = getattr(self, name)
            if value is not None:
                out[name] = np.array(value)
        out["status"] = self.status
        out["wall_time"] = self.wall_time
        return out

    def plot(
        self,
        which: str | Iterable[str] | None = None,
        *,
        ax: Any = None,
        fig: Figure | None = None,
    ) -> dict[str, Figure] | Figure:
        """Figures 2-4 of the paper, the torques, and the identified model's parameters
        (:func:`adparm.plotting.plot_result`).

        Parameters
        ----------
        which : str or iterable of str, optional
            Names from ``adparm.plotting.FIGURES`` (``fig2_critic_weights``,
            ``fig3_actor_weights``, ``fig4_errors``, ``torques``, and ``model_parameters``
            for an identifying run: beta_hat against the plant's beta). None (default) gives
            all of this run's as a dict name -> Figure; a single name gives that Figure.
        ax : Axes or sequence of Axes, optional
            With a single name: draw into these axes (see :mod:`adparm.plotting`).
        fig : Figure, optional
            With a single name: add the panels to this figure.

        Returns
        -------
        dict of str to Figure, or Figure
        """
        return presenter("plot")(self, which, ax=ax, fig=fig)

    def save(self, path: str | Path) -> Path:
        """Write to ``path``: ``.npz`` (everything, for adparm.load_result) or ``.csv``."""
        return presenter("save")(self, path)

    def to_dataframe(self) -> pandas.DataFrame:
        """The time series as a pandas DataFrame (columns of adparm.storage.columns()).
        Needs pandas (``pip install pandas``)."""
        return presenter("to_dataframe")(self)

    @functools.cached_property
    def diagnostics(self) -> dict[str, Any]:
        """The truth about this run (adparm.truth.diagnose): the verdict ("ok" or the problems
        found: a non-positive-definite e2 block, away from a known W*, a basis that cannot
        represent V*, learning not converged), the HJB residual of the final weights over the
        explored region relative to x^T Q x, and the learned V against the best yardstick."""
        return presenter("diagnose")(self)

    def summary(self, tolerance: float | None = None, optimal_cost: Any = None) -> dict[str, Any]:
        """The metrics of summary.json (adparm.summary.summarize; ``optimal_cost``: True or
        adparm.optimal_cost's options adds J / J* - 1, at the cost of an IPOPT solve)."""
        return presenter("summary")(self, tolerance=tolerance, optimal_cost=optimal_cost)

    def __repr__(self) -> str:
        return (
            f"SimulationResult(status={self.status!r}, rows={self.t.size}, "
            f"t_end={self.t[-1] if self.t.size else float('nan'):g}, "
            f"covariance_resets={self.covariance_resets}, wall_time={self.wall_time:.3g})"
        )


class SimulationDiverged(RuntimeError):
    """A run whose state became non-finite or left sim.divergence_bound.

    ``result`` holds what was recorded up to the last finite step; ``time`` is when it diverged.
    From simulate_batch: ``index`` is the run's position in the batch and ``results`` holds every
    run's result (None from simulate)."""

    def __init__(
        self,
        message: str,
        result: SimulationResult,
        time: float,
        *,
        index: int | None = None,
        results: list[SimulationResult] | None = None,
    ) -> None:
        super().__init__(message)
        self.result = result
        self.time = time
        self.index = index
        self.results = results


class SimulationInterrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT, or anything raising KeyboardInterrupt) stopped a call between two chunks.

    It is a KeyboardInterrupt, so a script that does not catch it stops as usual. ``result``
    holds what the call would have returned, up to where it stopped: from simulate, the
    SimulationResult of the rows recorded so far (status "interrupted"); from simulate_batch, the
    list of results (runs not done have status "interrupted"); from sweep, the SweepResult of the
    points done; from compare, the Comparison of the controllers run so far. ``time`` is the
    simulated time reached (simulate; None otherwise)."""

    def __init__(self, message: str, result: Any, time: float | None = None) -> None:
        super().__init__(message)
        self.result = result
        self.time = time


def read_only_float(value: Any) -> np.ndarray:
    """``value`` as a float array that nobody else can write: a read-only float64 array that is
    not a view of another NumPy array is kept as it is (no copy: the core's recordings), anything
    else is copied."""
    if (
        isinstance(value, np.ndarray)
        and value.dtype == np.float64
        and not value.flags.writeable
        and not isinstance(value.base, np.ndarray)
        and type(value) is np.ndarray
    ):
        return value
    return np.array(value, dtype=float)


def make_result(run: _core.Simulation, config: Config, wall_time: float) -> SimulationResult:
    recording = run.recording()
    for array in recording.values():
        array.flags.writeable = False  # handed over: SimulationResult keeps them without a copy
    return SimulationResult(
        **recording,
        covariance_reset_times=np.array(run.reset_times),
        config=config,
        status="interrupted" if run.status == "running" else run.status,
        wall_time=wall_time,
        saturated_time=np.array(run.saturated_time),
    )


class ApproximationWarning(UserWarning):
    """A learning run whose critic is not a good approximation of V*: the basis cannot represent
    V* (the HJB residual of the final weights is large off the trajectory while small along it),
    or learning has not converged. The message says which and what to try.

    Where warnings are made errors (``warnings.simplefilter("error")``, pytest's
    ``filterwarnings = error``), :func:`adparm.simulate` raises it, and its ``result`` attribute
    holds the finished run."""


def warn_if_approximate(result: SimulationResult, stacklevel: int = 3) -> None:
    """Emits ApproximationWarning when :func:`diagnose` finds that the basis cannot represent V*
    or that learning has not converged (only for finished runs)."""
    if result.status != "finished":
        return
    diagnostics = result.diagnostics
    kind = diagnostics.get("approximation")
    if kind is None and not diagnostics.get("problems"):
        return
    message = f"adparm: {diagnostics['verdict']}. Try: {'; '.join(diagnostics['advice']) or '-'}"
    warnings.warn(message, ApproximationWarning, stacklevel=stacklevel)


def post_run_failure(step: str, error: BaseException) -> str:
    """One line for a post-run step that failed: the step, the error's type and its message
    (its first line, at most 300 characters)."""
    text = (str(error).strip().splitlines() or [""])[0]
    if len(text) > 300:
        text = text[:297] + "..."
    return f"{step} failed after the run: {type(error).__name__}" + (f": {text}" if text else "")


def stop_time(result: SimulationResult) -> float | None:
    """When a run that did not finish stopped: a diverged run at the end of the step after its
    last finite row (0 if it recorded none; the time SimulationDiverged reports when the state
    left the bound within a step), an interrupted or running one at its last row. None for a
    finished run."""
    if result.status == "finished":
        return None
    t = result.t
    if result.status == "diverged":
        return min(float(t[-1]) + result.config.sim.dt, result.config.sim.T) if t.size else 0.0
    return float(t[-1]) if t.size else 0.0
