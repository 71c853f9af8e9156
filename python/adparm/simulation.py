"""Running the closed loop in the C++ core and the result it returns."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm.auto import tqdm

from . import _core
from .config import _ARM_KEYS, Config, SampledTrajectory, SinusoidTrajectory

if TYPE_CHECKING:  # pragma: no cover
    import pandas
    from matplotlib.figure import Figure

__all__ = [
    "SimulationDiverged",
    "SimulationInterrupted",
    "SimulationResult",
    "core_settings",
    "desired_state",
    "extrapolation_points",
    "default_threads",
    "simulate",
    "simulate_batch",
]

# The C++ core advances a run in chunks of steps, with the GIL released; Python regains control
# between chunks, to update the progress bar and to act on Ctrl-C. The chunk length adapts so that
# one call lasts about CALL_SECONDS, whatever a step costs (extrapolation points, batch size).
CALL_SECONDS = 0.05
FIRST_CALL_STEPS = 1_000
MIN_CALL_STEPS = 100


def core_settings(config: Config) -> _core.Settings:
    """The C++ core's Settings struct for ``config`` (passed whole to the core)."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    settings = _core.Settings()
    plant = _core.ArmParameters()
    for key in _ARM_KEYS:
        setattr(plant, key, getattr(config.plant, key))
    model = _core.ArmParameters()
    for key, value in config.model.resolve(config.plant).items():
        setattr(model, key, value)
    settings.plant = plant
    settings.model = model
    settings.disturbance = np.array(config.plant.disturbance)

    task = _core.TaskSettings()
    task.q0 = np.array(config.task.q0)
    task.dq0 = np.array(config.task.dq0)
    task.qd = _trajectory_settings(config)
    settings.task = task

    settings.Q = np.array(config.cost.Q)
    settings.R = np.array(config.cost.R)

    control = _core.ControlSettings()
    control.alpha1 = np.array(config.control.alpha1)
    rise = _core.RiseGains()
    rise.ks, rise.alpha2, rise.beta1 = (
        config.control.ks,
        config.control.alpha2,
        config.control.beta1,
    )
    control.rise = rise
    settings.control = control

    critic = _core.CriticSettings()
    for key in ("eta_c", "nu", "gamma0"):
        setattr(critic, key, getattr(config.critic, key))
    critic.epsilon_T = config.resolved_epsilon_T
    settings.critic = critic
    actor = _core.ActorSettings()
    for key in ("eta_a1", "eta_a2", "weight_bound"):
        setattr(actor, key, getattr(config.actor, key))
    settings.actor = actor

    controller = _core.ControllerSettings()
    controller.kind = getattr(_core.ControllerKind, config.controller.kind)
    controller.rise = config.controller.rise
    controller.kp = config.controller.gain_matrix("kp", config.dof)
    controller.kd = config.controller.gain_matrix("kd", config.dof)
    settings.controller = controller
    settings.basis = getattr(_core.BasisKind, config.controller.basis)
    extrapolation = _core.ExtrapolationSettings()
    extrapolation.points = config.extrapolation.points
    extrapolation.box = config.extrapolation.box_vector(config.dof)
    extrapolation.mode = getattr(_core.ExtrapolationMode, config.extrapolation.mode)
    extrapolation.seed = config.extrapolation.seed
    settings.extrapolation = extrapolation

    settings.critic_weights = config.initial_weights("critic_weights")
    settings.actor_weights = config.initial_weights("actor_weights")

    probe = _core.ProbeSettings()
    probe.amplitude = config.probe.amplitude_matrix(config.dof)
    probe.until = config.probe.until
    probe.ramp = config.probe.ramp
    probe.frequencies = np.array(config.probe.frequencies)
    probe.phases = config.probe.phase_matrix(config.dof)
    settings.probe = probe

    sim = _core.SimSettings()
    for key in ("T", "dt", "record_every", "divergence_bound"):
        setattr(sim, key, getattr(config.sim, key))
    settings.sim = sim
    return settings


def _trajectory_settings(config: Config) -> _core.TrajectorySettings:
    qd = config.task.qd
    trajectory = _core.TrajectorySettings()
    if isinstance(qd, SinusoidTrajectory):
        trajectory.kind = _core.TrajectoryKind.sinusoid
        trajectory.offset = np.array(qd.offset)
        trajectory.amplitude = np.array(qd.amplitude)
        trajectory.frequency = np.array(qd.frequency)
        trajectory.phase = np.array(qd.phase)
    elif isinstance(qd, SampledTrajectory):
        spline = qd.spline()
        # scipy's c[m, i, j]: coefficient of (t - x_i)^(3 - m) for joint j -> rows i, 4 j + m
        trajectory.kind = _core.TrajectoryKind.spline
        trajectory.breaks = np.array(spline.x)
        trajectory.coefficients = np.ascontiguousarray(
            np.transpose(spline.c, (1, 2, 0)).reshape(spline.c.shape[1], 8)
        )
    else:
        trajectory.offset = np.array(qd)
    return trajectory


def desired_state(config: Config, t: Any) -> np.ndarray:
    """The desired state of ``config.task.qd`` as the core evaluates it: for one time t, a (3, 2)
    array [qd, dqd, ddqd]; for times (n,), an (n, 3, 2) array."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    times = np.asarray(t, dtype=float)
    if times.ndim > 1:
        raise ValueError(f"t: expected a time or a 1-d array of times, got shape {times.shape}")
    rows = np.asarray(_core.desired_state(_trajectory_settings(config), times.reshape(-1)))
    rows = rows.reshape(-1, 3, 2)
    return rows[0] if times.ndim == 0 else rows


def extrapolation_points(config: Config) -> np.ndarray:
    """The extrapolation points (N, 4) in x = [e1; e2] of a fixed or grid ``config.extrapolation``
    (for mode local: the offsets are drawn anew at each step, and this returns zeros)."""
    return np.array(_core.extrapolation_points(core_settings(config)))


#: A result's status: the run reached sim.T, diverged (SimulationDiverged), was stopped by Ctrl-C
#: (SimulationInterrupted) or is still running (a result read from a run in progress).
STATUSES = ("finished", "diverged", "interrupted", "running")

_ARRAYS_2 = ("q", "dq", "qd", "e1", "e2", "tau", "u", "u_hat", "mu", "probe")
_ARRAYS_N = ("critic_weights", "actor_weights")


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """One closed-loop run, one row per recorded step (all arrays read-only).

    t (n,) s; q, dq (n, 2) rad, rad/s; qd (n, 2) desired position; e1 = qd - q,
    e2 = de1 + alpha1 e1 (n, 2); tau (n, 2) applied torque N m; u (n, 2) the controller's input
    (adp: u_hat + probe); u_hat (n, 2) actor input (eq. 20); mu (n, 2) RISE term (eq. 27);
    probe (n, 2) probing signal; critic_weights, actor_weights (n, K) in the order of
    adparm.basis_names(config) (K = 8, or 6 for the structured basis);
    hjb_error (n,) eq. (21); cost (n,) accumulated cost of eq. (10),
    int_0^t x^T Q x + u^T R u, integrated by RK4 with the state; covariance_reset_times (k,) s.
    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    qd: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    tau: np.ndarray
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

    def __post_init__(self) -> None:
        n = np.shape(self.t)[0] if np.ndim(self.t) == 1 else -1
        if n < 0:
            raise ValueError(f"t: expected a 1-d array, got shape {np.shape(self.t)}")
        shapes = {"t": (n,), "hjb_error": (n,), "cost": (n,)}
        shapes.update({name: (n, 2) for name in _ARRAYS_2})
        size = len(self.config.initial_weights()) if isinstance(self.config, Config) else 8
        shapes.update({name: (n, size) for name in _ARRAYS_N})
        for name, shape in shapes.items():
            array = np.array(getattr(self, name), dtype=float)
            if array.shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {array.shape}")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        resets = np.array(self.covariance_reset_times, dtype=float).reshape(-1)
        resets.flags.writeable = False
        object.__setattr__(self, "covariance_reset_times", resets)
        if self.status not in STATUSES:
            raise ValueError(f"status: expected one of {', '.join(STATUSES)}, got {self.status!r}")

    @property
    def covariance_resets(self) -> int:
        """Number of resets of Gamma (eq. 24's reset rule)."""
        return int(self.covariance_reset_times.size)

    def to_dict(self) -> dict[str, Any]:
        """The arrays by name (copies), with status and wall_time."""
        names = ("t", "hjb_error", "cost", *_ARRAYS_2, *_ARRAYS_N, "covariance_reset_times")
        out: dict[str, Any] = {name: np.array(getattr(self, name)) for name in names}
        out["status"] = self.status
        out["wall_time"] = self.wall_time
        return out

    def plot(self, which: Iterable[str] | None = None) -> dict[str, Figure]:
        """Figures 2-4 of the paper and the torques, as matplotlib figures by name (see
        adparm.plotting.FIGURES); ``which`` picks some of them."""
        from .plotting import plot_result

        return plot_result(self, which)

    def save(self, path: str | Path) -> Path:
        """Write to ``path``: ``.npz`` (everything, for adparm.load_result) or ``.csv``."""
        from .storage import save_result

        return save_result(self, path)

    def to_dataframe(self) -> pandas.DataFrame:
        """The time series as a pandas DataFrame (columns of adparm.storage.columns()).
        Needs pandas (``pip install pandas``)."""
        try:
            import pandas
        except ImportError as error:  # pragma: no cover - pandas is in the test extra
            raise ImportError("to_dataframe() needs pandas: pip install pandas") from error
        from .storage import columns, table

        return pandas.DataFrame(table(self), columns=columns(self.critic_weights.shape[1]))

    def summary(self, tolerance: float = 0.02) -> dict[str, Any]:
        """The metrics of summary.json (adparm.summary.summarize)."""
        from .summary import summarize

        return summarize(self, tolerance=tolerance)

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


def _result(run: _core.Simulation, config: Config, wall_time: float) -> SimulationResult:
    return SimulationResult(
        **run.recording(),
        covariance_reset_times=np.array(run.reset_times),
        config=config,
        status="interrupted" if run.status == "running" else run.status,
        wall_time=wall_time,
    )


def _divergence_message(run: _core.Simulation, config: Config) -> str:
    return (
        f"simulation diverged at t = {run.divergence_time:.6g} s (state or a recorded output "
        f"non-finite, or beyond sim.divergence_bound = {config.sim.divergence_bound:g}); the "
        "partial result is in the exception's .result"
    )


def _progress_bar(total: float, unit: str, desc: str, enabled: bool) -> tqdm:
    return tqdm(
        total=total,
        unit=unit,
        unit_scale=True,
        disable=not enabled,
        desc=desc,
        bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} " + unit + " [{elapsed}<{remaining}]",
    )


class _Pacer:
    """Calls ``advance(steps)`` with a number of steps adapted after each call so that a call
    lasts about CALL_SECONDS (at most 8 times more or fewer steps than the call before)."""

    def __init__(self) -> None:
        self.steps = max(MIN_CALL_STEPS, FIRST_CALL_STEPS)

    def advance(self, advance: Callable[[int], Any]) -> None:
        start = time.perf_counter()
        advance(self.steps)
        wanted = self.steps * CALL_SECONDS / max(time.perf_counter() - start, 1e-9)
        self.steps = int(max(MIN_CALL_STEPS, min(wanted, 8 * self.steps, 10**9)))


# Values of one recorded row besides the weights: t, hjb_error, cost and ten joint series of 2.
_ROW_VALUES = 3 + 2 * len(_ARRAYS_2)


def _check_memory(configs: list[Config]) -> None:
    """Refuse runs whose recordings would not fit in half of this machine's memory."""
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        return
    needed = 0
    for config in configs:
        steps = math.ceil(config.sim.T / config.sim.dt * (1.0 - 1e-12))
        rows = steps // config.sim.record_every + 2
        width = _ROW_VALUES + 2 * len(config.initial_weights())
        needed += 8 * rows * width
    if needed > memory // 2:
        which = "the runs' recordings" if len(configs) > 1 else "the recording"
        raise ValueError(
            f"sim.record_every: {which} would take {needed / 2**30:.3g} GiB, more than half of "
            f"this machine's {memory / 2**30:.3g} GiB; record fewer rows (a larger "
            "sim.record_every or a shorter sim.T)"
        )


def simulate(config: Config, *, progress: bool = False) -> SimulationResult:
    """Simulate the closed loop of ``config`` in the C++ core (fixed-step RK4).

    ``progress=True`` shows a tqdm progress bar in simulated seconds. Raises SimulationDiverged
    (with the partial result) if the state diverges, and SimulationInterrupted (with the rows
    recorded so far) on Ctrl-C, which is acted on between two chunks of about CALL_SECONDS."""
    settings = core_settings(config)
    _check_memory([config])
    run = _core.Simulation(settings)
    pacer = _Pacer()
    start = time.perf_counter()
    try:
        with _progress_bar(round(config.sim.T, 6), "s", "simulating", progress) as bar:
            while run.status == "running":
                pacer.advance(run.advance)
                bar.update(round(config.sim.T * run.step / run.steps, 6) - bar.n)
    except KeyboardInterrupt:
        result = _result(run, config, time.perf_counter() - start)
        reached = config.sim.T * run.step / run.steps
        raise SimulationInterrupted(
            f"simulation interrupted at t = {reached:.6g} s of sim.T = {config.sim.T:g} s; the "
            f"{result.t.size} rows recorded so far are in the exception's .result",
            result,
            reached,
        ) from None
    result = _result(run, config, time.perf_counter() - start)
    if run.status == "diverged":
        raise SimulationDiverged(_divergence_message(run, config), result, run.divergence_time)
    return result


def _simulate_keeping_divergence(
    config: Config, progress: bool = False
) -> tuple[SimulationResult, str | None]:
    """simulate(config) and None, or a diverged run's partial result and the error message."""
    try:
        return simulate(config, progress=progress), None
    except SimulationDiverged as error:
        return error.result, str(error)


def default_threads() -> int:
    """The number of CPUs this process may run on (simulate_batch's default thread count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _check_threads(threads: int | None) -> int:
    if threads is None:
        return default_threads()
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)):
        raise TypeError(f"threads: expected an integer >= 1 or None, got {threads!r}")
    if threads < 1:
        raise ValueError(f"threads: expected an integer >= 1 or None, got {threads!r}")
    return int(threads)


def simulate_batch(
    configs: Iterable[Config],
    *,
    threads: int | None = None,
    progress: bool = False,
    on_divergence: str = "raise",
) -> list[SimulationResult]:
    """Simulate many independent runs in parallel C++ threads; one result per config, in order.

    Each run gives bit-for-bit the result of ``simulate(config)``, whatever ``threads`` is (None:
    every CPU this process may use). ``wall_time`` of each result is the time spent advancing that
    run. ``progress=True`` shows a tqdm bar in steps over all runs. Every run's recording is held
    in memory (about 4.7 MB for a 150 s run at the default sim.record_every = 10); for
    thousands of runs, see :func:`adparm.sweep`, which keeps only summary rows. ``on_divergence``:
    ``"raise"`` (default) lets every run end, then raises SimulationDiverged for the first run
    that diverged, with ``.index`` and ``.results`` (all results); ``"keep"`` returns the
    results, the diverged ones with ``status == "diverged"`` and their partial rows. Ctrl-C
    raises SimulationInterrupted, whose ``.result`` lists every run's result so far."""
    if isinstance(configs, Config):
        raise TypeError("configs: expected an iterable of adparm.Config, got one Config")
    configs = list(configs)
    for i, config in enumerate(configs):
        if not isinstance(config, Config):
            raise TypeError(f"configs[{i}]: expected adparm.Config, got {type(config).__name__}")
    if on_divergence not in ("raise", "keep"):
        raise ValueError(f"on_divergence: expected 'raise' or 'keep', got {on_divergence!r}")
    workers = min(_check_threads(threads), max(1, len(configs)))  # no idle threads
    settings = [core_settings(config) for config in configs]
    _check_memory(configs)
    batch = _core.Batch(settings)
    runs = [batch.simulation(i) for i in range(len(configs))]
    total = sum(run.steps for run in runs)
    pacer = _Pacer()  # steps per run and call
    try:
        with _progress_bar(total, "steps", "simulating", progress) as bar:
            while batch.running:
                pacer.advance(lambda steps: batch.advance(steps, workers))
                bar.update(sum(run.step for run in runs) - bar.n)
    except KeyboardInterrupt:
        results = [_result(runs[i], c, batch.seconds(i)) for i, c in enumerate(configs)]
        done = sum(result.status != "interrupted" for result in results)
        raise SimulationInterrupted(
            f"batch interrupted with {done} of {len(configs)} runs done; every run's result so "
            "far is in the exception's .result",
            results,
        ) from None
    results = [_result(runs[i], config, batch.seconds(i)) for i, config in enumerate(configs)]
    diverged = [i for i, run in enumerate(runs) if run.status == "diverged"]
    if diverged and on_divergence == "raise":
        i = diverged[0]
        raise SimulationDiverged(
            f"configs[{i}]: {_divergence_message(runs[i], configs[i])}; "
            f"{len(diverged)} of {len(configs)} runs diverged, all results are in .results",
            results[i],
            runs[i].divergence_time,
            index=i,
            results=results,
        )
    return results
