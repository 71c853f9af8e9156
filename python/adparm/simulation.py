"""Running the closed loop in the C++ core: simulate, simulate_batch, the polling of the core's
batch, and the memory and step checks before a run. The result type is adparm.result, the
Config -> core translation adparm.translate (both re-exported here)."""

from __future__ import annotations

import itertools
import math
import os
import warnings
from collections.abc import Callable, Iterable, Iterator

import numpy as np
from tqdm.auto import tqdm

import adparm._core as _core

from .basis_family import basis_for
from .config import Config
from .desired import desired_state
from .divergence import divergence_causes
from .rates import check_step
from .result import (
    ARRAYS_1,
    ARRAYS_2,
    ARRAYS_N,
    ApproximationWarning,
    SimulationDiverged,
    SimulationInterrupted,
    SimulationResult,
    make_result,
    post_run_failure,
    warn_if_approximate,
)
from .translate import core_settings, extrapolation_points

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


def _divergence_message(run: _core.Simulation, result: SimulationResult) -> str:
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


def _start_batch(batch: _core.Batch, threads: int) -> None:
    """batch.start; threads that cannot be created (the core's std::system_error, a
    RuntimeError) are a ValueError that says so and what to do, with no worker left running."""
    try:
        batch.start(threads)
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


def run_batch(
    batch: _core.Batch,
    threads: int,
    on_end: Callable[[int, _core.Simulation], None],
    on_poll: Callable[[], None],
) -> None:
    """Starts ``batch`` on ``threads`` worker threads and polls it until every run has ended:
    ``on_end(i, run)`` receives each run as it ends (handed over by the core, which no longer
    holds it), ``on_poll()`` runs after each poll. Any exception (Ctrl-C) stops the workers
    (within one step) before it propagates."""
    _start_batch(batch, threads)
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
    """Whether ``config`` runs on the core's dynamic-size (n-joint) loop (its basis family says:
    adparm.basis_family, the one place that picks it)."""
    return basis_for(config).dynamic_sizes


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
    values of each joint series and the K critic and K actor weights per row (with
    identification, beta_hat's 7 values, the stack's singular value and uncertainty too)."""
    steps = math.ceil(config.sim.T / config.sim.dt * (1.0 - 1e-12))
    rows = steps // config.sim.record_every + 2
    width = len(ARRAYS_1) + config.dof * len(ARRAYS_2) + config.basis_size * len(ARRAYS_N)
    if config.identifier.enabled:  # beta_hat (7 on the two-link arm), sigma_min, uncertainty
        width += 9 if config.plant.urdf is None else 10 * config.dof + 2 * config.dof + 2
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


def check_memory(
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


def check_steps(configs: list[Config]) -> None:
    """Refuse a run whose sim.dt puts a fast rate of its closed loop beyond RK4's stability limit
    (rates.check_step: the message names the term, its rate and a dt that works)."""
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
    check_steps([config])
    return _simulate(config, progress, diagnose)


def _simulate(config: Config, progress: bool, diagnose: bool) -> SimulationResult:
    """simulate() without the step check (a run that starts from another run's weights)."""
    settings = core_settings(config)
    check_memory([config])
    batch = _core.Batch([settings])
    runs: dict[int, _core.Simulation] = {}
    total = batch.total_steps
    try:
        with _progress_bar(round(config.sim.T, 6), "s", "simulating", progress) as bar:

            def poll() -> None:
                bar.update(round(config.sim.T * batch.steps_done / total, 6) - bar.n)

            run_batch(batch, 1, runs.__setitem__, poll)
    except KeyboardInterrupt:
        runs.update(_take_rest(batch, skip=runs))
        if 0 not in runs:  # pragma: no cover - the run was lost to a second interrupt
            raise
        run = runs[0]
        result = make_result(run, config, batch.seconds(0))
        # the core's clock: step * dt (the last step shortened to T), as the recorded t
        reached = min(run.step * config.sim.dt, config.sim.T)
        raise SimulationInterrupted(
            f"simulation interrupted at t = {reached:.6g} s of sim.T = {config.sim.T:g} s; the "
            f"{result.t.size} rows recorded so far are in the exception's .result",
            result,
            reached,
        ) from None
    run = runs[0]
    result = make_result(run, config, batch.seconds(0))
    if run.status == "diverged":
        raise SimulationDiverged(_divergence_message(run, result), result, run.divergence_time)
    if diagnose:
        try:
            warn_if_approximate(result)
        except ApproximationWarning as warning:  # warnings made errors (the caller's filter)
            warning.result = result  # type: ignore[attr-defined] - the finished run stays reachable
            raise
        except Exception as error:  # noqa: BLE001 - the diagnosis never loses a finished run
            warnings.warn(
                "adparm: " + post_run_failure("the diagnosis (adparm.truth.diagnose)", error),
                RuntimeWarning,
                stacklevel=2,
            )
    return result


def simulate_keeping_divergence(
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


def check_threads(threads: int | None) -> int:
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
    workers = min(check_threads(threads), max(1, len(configs)))  # no idle threads
    check_steps(configs)
    settings = [core_settings(config) for config in configs]
    check_memory(configs, threads=workers)
    # the core holds at most `workers` runs built and not yet handed over (memory_needed); a run
    # beyond them is built once to check it, and again when its turn comes
    batch = _core.Batch(settings, workers)
    done_runs: dict[int, SimulationResult] = {}
    divergence: dict[int, tuple[str, float]] = {}
    pending: dict[int, _core.Simulation] = {}  # handed over, not yet converted

    def on_end(i: int, run: _core.Simulation) -> None:  # the core's copy is freed on return
        pending[i] = run
        done_runs[i] = make_result(run, configs[i], batch.seconds(i))
        if run.status == "diverged":
            divergence[i] = (_divergence_message(run, done_runs[i]), run.divergence_time)
        del pending[i]

    try:
        with _progress_bar(batch.total_steps, "steps", "simulating", progress) as bar:
            run_batch(batch, workers, on_end, lambda: bar.update(batch.steps_done - bar.n))
    except KeyboardInterrupt:
        rest = _take_rest(batch, skip={*done_runs, *pending})
        for i, run in itertools.chain(list(pending.items()), rest):
            done_runs[i] = make_result(run, configs[i], batch.seconds(i))  # each, then freed
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
