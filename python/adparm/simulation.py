"""Running the closed loop in the C++ core and the result it returns."""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import os
import warnings
from collections.abc import Callable, Iterable, Iterator
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
    "available_memory",
    "core_settings",
    "desired_state",
    "extrapolation_points",
    "default_threads",
    "memory_needed",
    "simulate",
    "simulate_batch",
]

# The C++ core runs every run on worker threads (adparm._core.Batch: a shared queue, each run to
# its end, no barrier between threads); Python only polls, every POLL_SECONDS, to update the
# progress bar and to act on Ctrl-C or SIGTERM, and a stop request is acted on within one step.
POLL_SECONDS = 0.05


def core_settings(config: Config) -> _core.Settings:
    """The C++ core's Settings struct for ``config`` (passed whole to the core)."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    settings = _core.Settings()
    plant = _core.ArmParameters()
    model = _core.ArmParameters()
    if config.plant.urdf is None:
        for key in _ARM_KEYS:
            setattr(plant, key, getattr(config.plant, key))
        for key, value in config.model.resolve(config.plant).items():
            setattr(model, key, value)
    settings.plant = plant
    settings.model = model
    if config.plant.urdf is not None:  # a URDF arm: the two-link parameters are not used
        settings.plant_urdf = _urdf_settings(
            config.plant.urdf,
            config.plant.resolved_gravity,
            config.plant.coulomb,
            config.plant.viscous,
            config.plant.locked_joints,
        )
        settings.model_urdf = _urdf_settings(**config.model.resolve_urdf(config.plant))
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
    for key in ("eta_a1", "eta_a2", "weight_bound", "positive_e2", "e2_margin"):
        setattr(actor, key, getattr(config.actor, key))
    if (
        config.actor.positive_e2
        and config.plant.urdf is not None
        and config.controller.basis == "structured"
        and config.controller.kind == "adp"
    ):  # where the structured basis keeps its e2 block positive (not in the paper)
        from .rates import check_positions

        actor.e2_check_positions = np.asfortranarray(check_positions(config).T)
    settings.actor = actor

    controller = _core.ControllerSettings()
    controller.kind = getattr(_core.ControllerKind, config.controller.kind)
    controller.rise = config.controller.rise
    controller.kp = config.controller.gain_matrix("kp", config.dof)
    controller.kd = config.controller.gain_matrix("kd", config.dof)
    settings.controller = controller
    if config.controller.is_expression:  # the compiled terms, run on the dynamic-size loop
        settings.basis = _core.BasisKind.expression
        expression = config.controller.expression_basis(config.dof)
        program = _core.ExpressionProgram()
        program.opcodes = expression.opcodes.tolist()
        program.arguments = expression.arguments.tolist()
        settings.basis_program = program
    else:
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


def _urdf_settings(
    urdf: str,
    gravity: Any,
    coulomb: float | tuple[float, ...],
    viscous: float | tuple[float, ...],
    locked_joints: dict[str, float] | None = None,
) -> _core.UrdfArmSettings:
    """The core's description of a URDF arm (friction: one value per joint, or one for all;
    locked joints: {name: position} or None)."""
    arm = _core.UrdfArmSettings()
    arm.urdf = urdf
    arm.gravity = np.array(gravity, dtype=float)
    arm.coulomb = np.atleast_1d(np.array(coulomb, dtype=float))
    arm.viscous = np.atleast_1d(np.array(viscous, dtype=float))
    arm.locked_joints = [(name, float(value)) for name, value in (locked_joints or {}).items()]
    return arm


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
    """The desired state of ``config.task.qd`` as the core evaluates it: for one time t, a (3, n)
    array [qd, dqd, ddqd] (n joints); for times (m,), an (m, 3, n) array."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    times = np.asarray(t, dtype=float)
    if times.ndim > 1:
        raise ValueError(f"t: expected a time or a 1-d array of times, got shape {times.shape}")
    rows = np.asarray(_core.desired_state(_trajectory_settings(config), times.reshape(-1)))
    rows = rows.reshape(-1, 3, config.dof)
    return rows[0] if times.ndim == 0 else rows


def extrapolation_points(config: Config) -> np.ndarray:
    """The extrapolation points (N, 2n) in x = [e1; e2] of a fixed or grid ``config.extrapolation``
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

    Returned by :func:`adparm.simulate`; ``.plot()``, ``.save()``, ``.summary()`` and
    ``.to_dataframe()`` present it.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time (s).
    q, dq : ndarray, shape (n, 2)
        Joint angles (rad) and velocities (rad/s).
    qd : ndarray, shape (n, 2)
        Desired joint angles (rad).
    e1, e2 : ndarray, shape (n, 2)
        Tracking error e1 = qd - q (rad) and filtered error e2 = de1 + alpha1 e1 (rad/s).
    tau : ndarray, shape (n, 2)
        Applied torque tau = h_hat + mu - u (N m).
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
        joints = self.config.dof if isinstance(self.config, Config) else 2
        shapes.update({name: (n, joints) for name in _ARRAYS_2})
        size = self.config.basis_size if isinstance(self.config, Config) else 8
        shapes.update({name: (n, size) for name in _ARRAYS_N})
        for name, shape in shapes.items():
            array = _read_only_float(getattr(self, name))
            if array.shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {array.shape}")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        resets = np.array(self.covariance_reset_times, dtype=float).reshape(-1)
        resets.flags.writeable = False
        object.__setattr__(self, "covariance_reset_times", resets)
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
        """The arrays by name (copies), with status and wall_time."""
        names = ("t", "hjb_error", "cost", *_ARRAYS_2, *_ARRAYS_N, "covariance_reset_times")
        out: dict[str, Any] = {name: np.array(getattr(self, name)) for name in names}
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
        """Figures 2-4 of the paper and the torques (:func:`adparm.plotting.plot_result`).

        Parameters
        ----------
        which : str or iterable of str, optional
            Names from ``adparm.plotting.FIGURES`` (``fig2_critic_weights``,
            ``fig3_actor_weights``, ``fig4_errors``, ``torques``). None (default) gives all of
            them as a dict name -> Figure; a single name gives that Figure.
        ax : Axes or sequence of Axes, optional
            With a single name: draw into these axes (see :mod:`adparm.plotting`).
        fig : Figure, optional
            With a single name: add the panels to this figure.

        Returns
        -------
        dict of str to Figure, or Figure
        """
        from .plotting import plot_result

        return plot_result(self, which, ax=ax, fig=fig)

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

        return pandas.DataFrame(
            table(self), columns=columns(self.critic_weights.shape[1], self.q.shape[1])
        )

    @functools.cached_property
    def diagnostics(self) -> dict[str, Any]:
        """The truth about this run (adparm.truth.diagnose): the verdict ("ok" or the problems
        found: a non-positive-definite e2 block, away from a known W*, a basis that cannot
        represent V*, learning not converged), the HJB residual of the final weights over the
        explored region relative to x^T Q x, and the learned V against the best yardstick."""
        from .truth import diagnose

        return diagnose(self)

    def summary(self, tolerance: float | None = None) -> dict[str, Any]:
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


def _read_only_float(value: Any) -> np.ndarray:
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


def _result(run: _core.Simulation, config: Config, wall_time: float) -> SimulationResult:
    recording = run.recording()
    for array in recording.values():
        array.flags.writeable = False  # handed over: SimulationResult keeps them without a copy
    return SimulationResult(
        **recording,
        covariance_reset_times=np.array(run.reset_times),
        config=config,
        status="interrupted" if run.status == "running" else run.status,
        wall_time=wall_time,
    )


def _divergence_message(run: _core.Simulation, result: SimulationResult) -> str:
    from .truth import divergence_causes

    config = result.config
    causes = divergence_causes(config, result)
    return (
        f"simulation diverged at t = {run.divergence_time:.6g} s (state or a recorded output "
        f"non-finite, or beyond sim.divergence_bound = {config.sim.divergence_bound:g})"
        + (f"; likely cause: {'; '.join(causes)}" if causes else "")
        + "; the partial result is in the exception's .result"
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


def _start_batch(batch: _core.Batch, threads: int, window: int | None) -> None:
    """batch.start; threads that cannot be created (the core's std::system_error, a
    RuntimeError) are a ValueError that says so and what to do, with no worker left running."""
    try:
        if window is None:
            batch.start(threads)
        else:
            batch.start(threads, window)
    except RuntimeError as error:
        try:
            batch.stop()
        except Exception:  # noqa: BLE001, S110 - nothing was running
            pass
        raise ValueError(
            f"threads: could not start {threads} worker thread{'s' if threads != 1 else ''} "
            f"({error}); use fewer threads (adparm sweep --threads) or raise the process's "
            "thread limit (ulimit -u)"
        ) from error


def _run_batch(
    batch: _core.Batch,
    threads: int,
    on_end: Callable[[int, _core.Simulation], None],
    on_poll: Callable[[], None],
    window: int | None = None,
) -> None:
    """Starts ``batch`` on ``threads`` worker threads and polls it until every run has ended:
    ``on_end(i, run)`` receives each run as it ends (handed over by the core, which no longer
    holds it), ``on_poll()`` runs after each poll. Any exception (Ctrl-C) stops the workers
    (within one step) before it propagates."""
    _start_batch(batch, threads, window)
    try:
        while not batch.done:
            for i in batch.wait(POLL_SECONDS):
                on_end(i, batch.take(i))
            on_poll()
    except BaseException:
        batch.stop()
        raise


def _take_rest(
    batch: _core.Batch, skip: Iterable[int] = ()
) -> Iterator[tuple[int, _core.Simulation]]:
    """After batch.stop(): (index, run) of every run not yet handed over (ended, part-way or
    unstarted), one at a time, except those in ``skip`` (already handed over)."""
    skip = set(skip)
    ended = batch.wait(0.0)
    for i in [*ended, *(i for i in range(len(batch)) if i not in ended)]:
        if i in skip:
            continue
        skip.add(i)
        try:
            run = batch.take(i)
        except RuntimeError:  # taken by an on_end that a second interrupt cut short
            continue
        yield i, run


# Memory of a run at its peak, measured with bench/memory_peak.py (the growth of the peak resident
# set of a fresh process, ru_maxrss, over simulate()): the core's recording and the NumPy arrays
# the result takes over from it (2 x 8 bytes per recorded value), _point_bytes per extrapolation
# point, and RUN_BYTES of fixed cost.
RUN_BYTES = 1 << 20
# Drawing a run's figures (matplotlib's lines of every recorded row), measured with adparm run
# (/usr/bin/time's maximum resident set): about 1.7 times one copy of the recording.
FIGURE_COPIES = 1.7
# The core's bounds on a dynamic size (cpp/include/adparm/types.hpp: kMaxDof, kMaxBasisSize): the
# n-joint loop's vectors and matrices keep their coefficients inline, sized for these bounds.
CORE_MAX_DOF = 12
CORE_MAX_BASIS_SIZE = 128
# Bytes of one extrapolation point of the paper's two-link arm (8 functions, fixed sizes).
POINT_BYTES = 240


def _aligned(size: int) -> int:
    """``size`` rounded up to Eigen's 16-byte alignment."""
    return -(-size // 16) * 16


def _dynamic_sizes(config: Config) -> bool:
    """Whether ``config`` runs on the core's dynamic-size (n-joint) loop: a URDF arm or an
    expression basis (cpp/include/adparm/simulation.hpp)."""
    return config.plant.urdf is not None or config.controller.is_expression


def _point_bytes(config: Config) -> int:
    """Bytes the core holds per extrapolation point (cpp/include/adparm/extrapolation.hpp): the
    point x (2n values) and its prepared HJB terms (hjb.hpp's HjbPoint: the drift rate, K values;
    the input gradient B, K x n; the state cost). On the dynamic-size loop these are bounded Eigen
    types whose coefficients are inline and sized for the bounds (K <= 128, n <= 12: 1 KiB, 24 KiB
    and 200 bytes), and every point is zeroed when the points are allocated, so a point costs about
    25 KiB whatever n and K are; on the two-link arm's fixed sizes, 8 (K + K n + 2n + 1) bytes."""
    if _dynamic_sizes(config):
        k, n = CORE_MAX_BASIS_SIZE, 2 * CORE_MAX_DOF  # BasisMatrix<K, n> is bounded by 2 kMaxDof
        drift = _aligned(8 * k + 8)  # coefficients and the row count
        gradient = _aligned(8 * k * n + 16)  # coefficients, rows and columns
        state = _aligned(8 * 2 * CORE_MAX_DOF + 8)
        return _aligned(drift + gradient + 8) + state
    k, n = config.basis_size, config.dof
    return _aligned(8 * k) + _aligned(_aligned(8 * k * n) + 8) + 8 * 2 * n


def _recording_bytes(config: Config) -> int:
    """Bytes of one copy of the recording of ``config`` (all its rows): t, hjb_error, cost, n
    values of each joint series and the K critic and K actor weights per row."""
    steps = math.ceil(config.sim.T / config.sim.dt * (1.0 - 1e-12))
    rows = steps // config.sim.record_every + 2
    width = 3 + config.dof * len(_ARRAYS_2) + 2 * config.basis_size
    return 8 * rows * width


def _points_bytes(config: Config) -> int:
    """Bytes of the extrapolation points of ``config`` in the core."""
    return _point_bytes(config) * config.extrapolation.points


def _core_bytes(config: Config) -> int:
    """Bytes a run holds in the core while it runs (its recording, points, fixed cost)."""
    return _recording_bytes(config) + _points_bytes(config) + RUN_BYTES


def memory_needed(
    configs: list[Config], at_once: int | None = None, threads: int = 1, figures: bool = False
) -> int:
    """The peak memory, in bytes, of running ``configs``: every result kept (simulate and
    simulate_batch: the NumPy recordings of all runs, plus the core's copies of up to ``threads``
    runs at once), or, with ``at_once`` (sweep: runs summarised and freed as they end), at most
    ``at_once`` runs in memory, each with both copies. ``figures``: plus the figures of the
    largest run (``adparm run`` and ``reproduce``, FIGURE_COPIES recordings)."""
    if not configs:
        return 0
    if figures:
        largest = max(_recording_bytes(c) for c in configs)
        return memory_needed(configs, at_once, threads) + int(FIGURE_COPIES * largest)
    core = sorted((_core_bytes(c) for c in configs), reverse=True)
    if at_once is not None:
        return sum(core[:at_once]) + sum(
            sorted((_recording_bytes(c) for c in configs), reverse=True)[:at_once]
        )
    return sum(_recording_bytes(c) for c in configs) + sum(core[:threads])


def available_memory() -> int | None:
    """Bytes this machine can give without swapping: MemAvailable of /proc/meminfo (Linux), else
    half the physical memory; None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        return None


def _check_memory(
    configs: list[Config], at_once: int | None = None, threads: int = 1, figures: bool = False
) -> None:
    """Refuse runs whose peak memory (memory_needed) exceeds the memory available now."""
    available = available_memory()
    if available is None:  # pragma: no cover - not POSIX
        return
    needed = memory_needed(configs, at_once, threads, figures)
    if needed > available:
        which = "these runs" if len(configs) > 1 else "this run"
        field = "sim.record_every"
        change = "record fewer rows (a larger sim.record_every or a shorter sim.T)"
        if max(_points_bytes(c) for c in configs) > needed / 4:
            field = "extrapolation.points"
            change = "use fewer extrapolation.points, or " + change
        if len(configs) > 1 and at_once is None:
            change += ", or run fewer configs at once (adparm.sweep keeps only summary rows)"
        if figures:
            change += ", or write no figures (--no-figures)"
        raise ValueError(
            f"{field}: {which} would need about {needed / 2**30:.3g} GiB of memory, "
            f"more than the {available / 2**30:.3g} GiB available now; {change}"
        )


def _check_steps(configs: list[Config]) -> None:
    """Refuse a run whose sim.dt puts a fast rate of its closed loop beyond RK4's stability limit
    (rates.check_step: the message names the term, its rate and a dt that works)."""
    from .rates import check_step

    for i, config in enumerate(configs):
        if "sim.dt" in config.derived:  # "auto" chose it inside the limit from the same rates
            continue
        try:
            check_step(config)
        except ValueError as error:
            if len(configs) == 1:
                raise
            raise ValueError(f"configs[{i}]: {error}") from None


def simulate(config: Config, *, progress: bool = False, diagnose: bool = True) -> SimulationResult:
    """Simulate the closed loop of ``config`` in the C++ core (fixed-step RK4).

    Parameters
    ----------
    config : Config
        The run: arm, task, cost, controller and its gains, horizon (``adparm.paper_config()``
        is the paper's example).
    progress : bool, optional
        Show a tqdm progress bar in simulated seconds.
    diagnose : bool, optional
        Diagnose a finished learning run (``result.diagnostics``) and emit
        ``adparm.ApproximationWarning`` when the basis cannot represent V* or learning has not
        converged (the message says which and what to try).

    Returns
    -------
    SimulationResult
        One row per recorded step (every ``sim.record_every``-th step, and the last).

    Raises
    ------
    SimulationDiverged
        If the state or a recorded output becomes non-finite or leaves
        ``sim.divergence_bound``; ``.result`` holds the rows up to the last finite step.
    SimulationInterrupted
        On Ctrl-C, which stops the run within one step (the run goes on a worker thread; this
        thread polls every ``POLL_SECONDS``); ``.result`` holds the rows recorded so far.

    Examples
    --------
    >>> import adparm
    >>> result = adparm.simulate(adparm.paper_config().updated({"sim": {"T": 1.0}}))
    >>> result.status, result.t[-1]
    ('finished', np.float64(1.0))
    """
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    _check_steps([config])
    return _simulate(config, progress, diagnose)


def _simulate(config: Config, progress: bool, diagnose: bool) -> SimulationResult:
    """simulate() without the step check (a run that starts from another run's weights)."""
    settings = core_settings(config)
    _check_memory([config])
    batch = _core.Batch([settings])
    runs: dict[int, _core.Simulation] = {}
    total = batch.total_steps
    try:
        with _progress_bar(round(config.sim.T, 6), "s", "simulating", progress) as bar:

            def poll() -> None:
                bar.update(round(config.sim.T * batch.steps_done / total, 6) - bar.n)

            _run_batch(batch, 1, runs.__setitem__, poll)
    except KeyboardInterrupt:
        runs.update(_take_rest(batch, skip=runs))
        if 0 not in runs:  # pragma: no cover - the run was lost to a second interrupt
            raise
        run = runs[0]
        result = _result(run, config, batch.seconds(0))
        # the core's clock: step * dt (the last step shortened to T), as the recorded t
        reached = min(run.step * config.sim.dt, config.sim.T)
        raise SimulationInterrupted(
            f"simulation interrupted at t = {reached:.6g} s of sim.T = {config.sim.T:g} s; the "
            f"{result.t.size} rows recorded so far are in the exception's .result",
            result,
            reached,
        ) from None
    run = runs[0]
    result = _result(run, config, batch.seconds(0))
    if run.status == "diverged":
        raise SimulationDiverged(_divergence_message(run, result), result, run.divergence_time)
    if diagnose:
        from .truth import warn_if_approximate

        try:
            warn_if_approximate(result)
        except Exception as error:  # noqa: BLE001 - the diagnosis never loses a finished run
            from .summary import _failure

            warnings.warn(
                "adparm: " + _failure("the diagnosis (adparm.truth.diagnose)", error),
                RuntimeWarning,
                stacklevel=2,
            )
    return result


def _simulate_keeping_divergence(
    config: Config, progress: bool = False, check: bool = True
) -> tuple[SimulationResult, str | None]:
    """simulate(config) and None, or a diverged run's partial result and the error message
    (``check=False``: without the step check, for a run from another run's final weights)."""
    try:
        if check:
            return simulate(config, progress=progress), None
        return _simulate(config, progress, True), None
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
    """Simulate many independent runs on parallel C++ threads; one result per config, in order.

    Each run gives bit-for-bit the result of ``simulate(config)``, whatever the thread count.
    Every run's recording is held in memory (about 4.7 MB for a 150 s run at the default
    ``sim.record_every = 10``); for thousands of runs, :func:`adparm.sweep` keeps only summary
    rows.

    Parameters
    ----------
    configs : iterable of Config
        The runs.
    threads : int, optional
        Number of threads; None (default) uses every CPU this process may run on.
    progress : bool, optional
        Show a tqdm bar in steps over all runs.
    on_divergence : {"raise", "keep"}
        ``"raise"`` (default) lets every run end, then raises SimulationDiverged for the first
        run that diverged, with ``.index`` and ``.results`` (all results); ``"keep"`` returns
        the results, the diverged ones with ``status == "diverged"`` and their partial rows.

    Returns
    -------
    list of SimulationResult
        ``wall_time`` of each is the time spent advancing that run.

    Raises
    ------
    SimulationDiverged
        With ``on_divergence="raise"``, if a run diverged.
    SimulationInterrupted
        On Ctrl-C; ``.result`` lists every run's result so far.
    """
    if isinstance(configs, Config):
        raise TypeError("configs: expected an iterable of adparm.Config, got one Config")
    configs = list(configs)
    for i, config in enumerate(configs):
        if not isinstance(config, Config):
            raise TypeError(f"configs[{i}]: expected adparm.Config, got {type(config).__name__}")
    if on_divergence not in ("raise", "keep"):
        raise ValueError(f"on_divergence: expected 'raise' or 'keep', got {on_divergence!r}")
    workers = min(_check_threads(threads), max(1, len(configs)))  # no idle threads
    _check_steps(configs)
    settings = [core_settings(config) for config in configs]
    _check_memory(configs, threads=workers)
    batch = _core.Batch(settings)
    done_runs: dict[int, SimulationResult] = {}
    divergence: dict[int, tuple[str, float]] = {}
    pending: dict[int, _core.Simulation] = {}  # handed over, not yet converted

    def on_end(i: int, run: _core.Simulation) -> None:  # the core's copy is freed on return
        pending[i] = run
        done_runs[i] = _result(run, configs[i], batch.seconds(i))
        if run.status == "diverged":
            divergence[i] = (_divergence_message(run, done_runs[i]), run.divergence_time)
        del pending[i]

    try:
        with _progress_bar(batch.total_steps, "steps", "simulating", progress) as bar:
            _run_batch(batch, workers, on_end, lambda: bar.update(batch.steps_done - bar.n))
    except KeyboardInterrupt:
        rest = _take_rest(batch, skip={*done_runs, *pending})
        for i, run in itertools.chain(list(pending.items()), rest):
            done_runs[i] = _result(run, configs[i], batch.seconds(i))  # each, then freed
        results = [done_runs[i] for i in range(len(configs))]
        done = sum(result.status != "interrupted" for result in results)
        raise SimulationInterrupted(
            f"batch interrupted with {done} of {len(configs)} runs done; every run's result so "
            "far is in the exception's .result",
            results,
        ) from None
    results = [done_runs[i] for i in range(len(configs))]
    diverged = sorted(divergence)
    if diverged and on_divergence == "raise":
        i = diverged[0]
        message, when = divergence[i]
        raise SimulationDiverged(
            f"configs[{i}]: {message}; "
            f"{len(diverged)} of {len(configs)} runs diverged, all results are in .results",
            results[i],
            when,
            index=i,
            results=results,
        )
    return results
