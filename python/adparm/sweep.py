"""Parameter sweeps: every point of a grid of settings run from one base configuration, with one
row of summary metrics per point.

By default the runs go through :func:`adparm.simulate_batch` in this process (parallel C++
threads, a few runs in memory at a time). Given an ``executor`` (anything with
``concurrent.futures``' ``submit``: a ProcessPoolExecutor, or a dask.distributed Client's
``client.get_executor()`` for a cluster), each point is submitted as one task that runs it alone
(:func:`sweep_row`, the same numbers as :func:`adparm.simulate`) and returns its row, so only
configs and rows cross the wire.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import reprlib
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
from tqdm.auto import tqdm

import adparm._core as _core

from ._fields import did_you_mean
from ._files import write_text
from ._sections import SECTIONS
from .config import Config
from .simulation import (
    SimulationInterrupted,
    SimulationResult,
    check_threads,
    simulate_batch,
)
from .table import rows_dataframe, rows_json, rows_markdown, write_csv

if TYPE_CHECKING:  # pragma: no cover
    import pandas

__all__ = [
    "SWEEP_METRICS",
    "SWEEP_MODEL_METRICS",
    "SWEEP_OPTIMAL_METRICS",
    "SweepResult",
    "grid_points",
    "sweep",
    "sweep_row",
]

#: The metrics of each row (from adparm.summary.summarize), after the grid's own columns.
SWEEP_METRICS = (
    "status",
    "verdict",
    "post_run_errors",
    "t_end",
    "critic_relative_error",
    "actor_relative_error",
    "policy_relative_error",
    "critic_relative_error_at_claim",
    "critic_time_within_tolerance",
    "actor_time_within_tolerance",
    "final_e1_norm",
    "accumulated_cost",
    "covariance_resets",
    "saturated_time",
    "e2_block_min_eigenvalue",
    "hjb_residual_explored",
    "wall_time",
)

#: The columns a sweep adds when a point's model differs from the plant or identifies
#: (``[model]``, ``model.scale``, ``identifier.enabled``): the critic's final error against the
#: plant's W*, the believed base parameters' final error against the plant's (beta_hat of an
#: identifying run, else the model's) and whether the identifier's history stack ever became
#: informative (None without identification).
SWEEP_MODEL_METRICS = (
    "critic_relative_error_plant",
    "parameter_relative_error",
    "stack_informative",
)

#: The columns a sweep adds with ``optimal_cost``: compare's J (the quadratic cost of the input
#: the error system received), J* (with the plant's torque limits) and J / J* - 1.
SWEEP_OPTIMAL_METRICS = ("applied_cost", "optimal_cost", "cost_vs_optimal_cost")

# Runs built and not yet summarised, per thread, in the in-process sweep (each holds its recording
# until it is summarised and freed).
_RUNS_PER_THREAD = 8


def _check_name(name: Any, where: str) -> None:
    if not isinstance(name, str) or name.count(".") != 1:
        raise ValueError(
            f"{where}: key {name!r} must be 'section.key', e.g. 'critic.eta_c' or 'task.q0'"
        )
    section, key = name.split(".")
    if section not in SECTIONS:
        raise ValueError(
            f"{where}[{name!r}]: unknown config section {section!r}"
            f"{did_you_mean(section, list(SECTIONS))}; known sections: {', '.join(SECTIONS)}"
        )
    keys = [f.name for f in dataclasses.fields(SECTIONS[section])]
    if key not in keys:
        raise ValueError(
            f"{where}[{name!r}]: unknown key {key!r} in [{section}]{did_you_mean(key, keys)}; "
            f"known keys: {', '.join(keys)}"
        )


def _plain_value(value: Any) -> Any:
    """NumPy values as plain Python numbers and lists (for the table and its files)."""
    return value.tolist() if isinstance(value, (np.ndarray, np.generic)) else value


def _is_list(values: Any) -> bool:
    if isinstance(values, np.ndarray):
        return values.ndim > 0
    return isinstance(values, Sequence) and not isinstance(values, (str, bytes))


def _check_grid(grid: Mapping[str, Any]) -> dict[str, list[Any]]:
    if not grid:
        raise ValueError("grid: expected at least one 'section.key': [values] entry")
    checked = {}
    for name, values in grid.items():
        _check_name(name, "grid")
        if not _is_list(values):
            got = "a 0-d array" if isinstance(values, np.ndarray) else type(values).__name__
            raise TypeError(f"grid[{name!r}]: expected a list of values to try, got {got}")
        values = list(values)
        if not values:
            raise ValueError(f"grid[{name!r}]: expected at least one value")
        checked[name] = [_plain_value(v) for v in values]
    return checked


def _check_points(points: Sequence[Any]) -> list[dict[str, Any]]:
    if not points:
        raise ValueError("grid: expected at least one point")
    checked = []
    for i, point in enumerate(points):
        if not isinstance(point, Mapping) or not point:
            raise TypeError(
                f"grid[{i}]: expected a point {{'section.key': value}}, got {point!r:.60}"
            )
        for name in point:
            _check_name(name, f"grid[{i}]")
        if i > 0 and set(point) != set(checked[0]):
            raise ValueError(
                f"grid[{i}]: every point must set the same keys as grid[0] "
                f"({', '.join(checked[0])}), got {', '.join(point)}"
            )
        checked.append({name: _plain_value(point[name]) for name in (checked or [point])[0]})
    return checked


def grid_points(grid: Mapping[str, Sequence[Any]] | Sequence[Mapping[str, Any]]) -> list[dict]:
    """The points of a grid as {'section.key': value} dicts.

    ``grid`` is either a mapping {'section.key': [values]}, whose points are every combination
    of the values (the last key varies fastest, itertools.product order), or a list of points
    [{'section.key': value}, ...] taken as they are (e.g. Monte Carlo draws), all with the same
    keys."""
    if isinstance(grid, Mapping):
        checked = _check_grid(grid)
        combinations = itertools.product(*checked.values())
        return [dict(zip(checked, values, strict=True)) for values in combinations]
    if _is_list(grid):
        return _check_points(list(grid))
    raise TypeError(
        "grid: expected a mapping {'section.key': [values]}, e.g. {'critic.eta_c': [100, 800]}, "
        f"or a list of points [{{'section.key': value}}], got {type(grid).__name__}"
    )


def _point_config(base: Config, point: Mapping[str, Any]) -> Config:
    changes: dict[str, dict[str, Any]] = {}
    for name, value in point.items():
        section, key = name.split(".")
        changes.setdefault(section, {})[key] = value
    try:
        return base.updated(changes)
    except TypeError as error:
        raise TypeError(f"grid point {_point_text(point)}: {error}") from error
    except ValueError as error:
        raise ValueError(f"grid point {_point_text(point)}: {error}") from error


def _point_text(point: Mapping[str, Any]) -> str:
    """A short repr of a grid point (bounded nesting and length: no RecursionError)."""
    short = reprlib.Repr()
    short.maxlevel, short.maxlist, short.maxdict, short.maxstring = 4, 6, 8, 60
    return short.repr(dict(point))


_Solved = TypeVar("_Solved")

# The per-sweep J* cache (optimal_cost_cache): problem key -> (its lock, [J* and its failure] once
# solved), or None when no sweep is running in this process.
_optimal_costs: dict[str, Any] | None = None
_optimal_costs_lock = threading.Lock()


@contextmanager
def optimal_cost_cache() -> Iterator[None]:
    """Within, :func:`solve_once` solves each distinct J* problem once: a sweep's rows that differ
    only in settings J* does not depend on (the controller's gains, the learning, the
    extrapolation, ``cost.input_bound``: J charges the quadratic cost) share one IPOPT solve. The
    sweep holds it over its runs (in this process; an executor's worker processes solve their
    own); nested uses share the outer cache."""
    global _optimal_costs
    with _optimal_costs_lock:
        outer = _optimal_costs
        if outer is None:
            _optimal_costs = {}
    try:
        yield
    finally:
        if outer is None:
            with _optimal_costs_lock:
                _optimal_costs = None


def solve_once(config: Config, options: Mapping[str, Any], solve: Callable[[], _Solved]) -> _Solved:
    """``solve()``: J* of ``config`` with adparm.optimal_cost ``options`` (adparm.comparison.
    run_optimal_cost's), or, within :func:`optimal_cost_cache`, its result from an earlier call
    on the same problem; threads asking for the same problem at once wait for one solve."""
    cache = _optimal_costs
    if cache is None:
        return solve()
    key = _problem_key(config, options)
    with _optimal_costs_lock:
        entry = cache.setdefault(key, (threading.Lock(), []))
    lock, solved = entry
    with lock:
        if not solved:
            solved.append(solve())
        return solved[0]


def _problem_key(config: Config, options: Mapping[str, Any]) -> str:
    """What J* on the plant's error system (model=False: the believed model is not used)
    depends on, as text: the plant (arm, friction, gravity, limits, disturbance), the task, the
    cost, alpha1, sim.T (its horizon) and the options."""
    sections = config.to_dict()
    problem: dict[str, Any] = {name: sections[name] for name in ("plant", "task", "cost")}
    problem["alpha1"] = sections["control"]["alpha1"]
    problem["T"] = config.sim.T
    problem["options"] = {
        key: value.tolist() if hasattr(value, "tolist") else value
        for key, value in sorted(options.items())
    }
    return json.dumps(problem, sort_keys=True, default=repr)


def _metric_names(optimal_cost: Any, model: bool = False) -> tuple[str, ...]:
    names = (*SWEEP_METRICS, *(SWEEP_MODEL_METRICS if model else ()))
    if optimal_cost is None or optimal_cost is False:
        return names
    if optimal_cost is not True and not isinstance(optimal_cost, Mapping):
        raise TypeError(
            "optimal_cost: expected True, False or a dict of adparm.optimal_cost options (e.g. "
            f"{{'intervals': 40}}), got {type(optimal_cost).__name__}"
        )
    return (*names, *SWEEP_OPTIMAL_METRICS)


def _model_metrics(configs: Sequence[Config]) -> bool:
    """Whether a sweep's rows carry :data:`SWEEP_MODEL_METRICS`: some point's model differs from
    the plant or identifies."""
    return any(
        config.identifier.enabled or config.model.differs(config.plant) for config in configs
    )


def _metrics(
    result: SimulationResult,
    tolerance: float | None,
    optimal_cost: Any = None,
    model: bool = False,
) -> dict[str, Any]:
    if isinstance(optimal_cost, Mapping):
        optimal_cost = dict(optimal_cost)
    elif optimal_cost is False:
        optimal_cost = None
    summary = result.summary(tolerance=tolerance, optimal_cost=optimal_cost)
    return {name: summary.get(name) for name in _metric_names(optimal_cost, model)}


def sweep_row(
    config: Config,
    tolerance: float | None = None,
    optimal_cost: Any = None,
    model_metrics: bool | None = None,
) -> dict[str, Any]:
    """The metrics of one run of ``config`` (the task an executor runs; a diverged run gives its
    partial result's metrics with status "diverged"); ``optimal_cost`` as :func:`sweep`'s;
    ``model_metrics`` adds :data:`SWEEP_MODEL_METRICS` (None: when this config's model differs
    from the plant or identifies)."""
    if model_metrics is None:
        model_metrics = _model_metrics([config])
    result = simulate_batch([config], threads=1, on_divergence="keep")[0]
    return _metrics(result, tolerance, optimal_cost, model_metrics)


@dataclass(frozen=True)
class SweepResult:
    """One row per grid point: the point's values (columns ``parameters``, e.g.
    ``critic.eta_c``), then :data:`SWEEP_METRICS`. ``table["column"]`` is a NumPy array of that
    column (dtype object when it holds lists, strings or missing values)."""

    parameters: tuple[str, ...]
    rows: tuple[dict[str, Any], ...]
    #: The metric columns: SWEEP_METRICS, then SWEEP_OPTIMAL_METRICS when asked for.
    metrics: tuple[str, ...] = SWEEP_METRICS

    @property
    def columns(self) -> tuple[str, ...]:
        return (*self.parameters, *self.metrics)

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self.rows)

    def __getitem__(self, column: str) -> np.ndarray:
        if column not in self.columns:
            raise KeyError(
                f"{column!r}: not a column{did_you_mean(column, self.columns)}; columns: "
                + ", ".join(self.columns)
            )
        values = [row[column] for row in self.rows]
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
            return np.array(values, dtype=float)
        out = np.empty(len(values), dtype=object)
        out[:] = values
        return out

    def to_markdown(self) -> str:
        return rows_markdown(self.columns, self.rows)

    def to_json(self) -> dict[str, Any]:
        return rows_json(self.columns, self.rows)

    def to_dataframe(self) -> pandas.DataFrame:
        """The table as a pandas DataFrame. Needs pandas."""
        return rows_dataframe(self.columns, self.rows)

    def save(self, path: str | Path) -> Path:
        """Write ``.csv`` (lists as JSON text), ``.json`` or ``.md``, by the file's suffix."""
        path = Path(path)
        if path.suffix == ".csv":
            return write_csv(path, self.columns, self.rows)
        if path.suffix == ".json":
            write_text(path, json.dumps(self.to_json(), indent=2) + "\n")
        elif path.suffix == ".md":
            write_text(path, "# adparm sweep\n\n" + self.to_markdown())
        else:
            raise ValueError(f"path: expected a .csv, .json or .md file, got {str(path)!r}")
        return path


def sweep(
    base_config: Config,
    grid: Mapping[str, Sequence[Any]] | Sequence[Mapping[str, Any]],
    executor: Any = None,
    *,
    threads: int | None = None,
    tolerance: float | None = None,
    progress: bool = False,
    optimal_cost: Any = False,
) -> SweepResult:
    """Run ``base_config`` at every point of ``grid`` and tabulate the summary metrics.

    Every point's config is built and checked before anything runs. Runs that diverge are kept
    as rows with status "diverged".

    Parameters
    ----------
    base_config : Config
        The settings shared by every point.
    grid : mapping or sequence of mappings
        Either ``{"section.key": [values...]}``, e.g. ``{"critic.eta_c": [100, 800],
        "task.q0": [[0.1, 0.2], [0.5, -0.3]]}``, run at every combination (the last key varies
        fastest); or a list of points with the same keys, e.g.
        ``[{"task.q0": q0} for q0 in draws]`` for a Monte Carlo study, run as given.
    executor : concurrent.futures-style executor, optional
        Without one, the runs go through :func:`adparm.simulate_batch` on ``threads`` threads.
        With one (anything with ``submit``, e.g. ``ProcessPoolExecutor()`` or a dask
        ``Client(...).get_executor()``) each point is one task, and the executor sets the
        parallelism.
    threads : int, optional
        Threads of the in-process run; default every CPU this process may use.
    tolerance : float, optional
        Tolerance of the verdict and the time-within-tolerance metrics (default: each config's
        diagnostics.tolerance, 1 %).
    progress : bool, optional
        Show a progress bar.
    optimal_cost : bool or dict, optional
        True (or a dict of options for :func:`adparm.optimal_cost`, e.g. ``{"intervals": 40,
        "max_intervals": 40}``) adds the columns :data:`SWEEP_OPTIMAL_METRICS`: each row's J
        (``applied_cost``), J* (``optimal_cost``, on the plant's error system with its torque
        limits, as :func:`adparm.compare`'s) and ``cost_vs_optimal_cost`` = J / J* - 1. Off by
        default: it is one IPOPT solve per row, about a second on the paper's arm, 15 s on a
        3-joint URDF arm and minutes on a 6-joint one at the default intervals (fewer intervals
        and a short sim.T cut it; J* is then a coarser estimate, its error not in the row).

    Returns
    -------
    SweepResult
        One row per point: the point's values, then status, t_end, the critic's and actor's
        relative errors (at the end and at 110 s), the time from which each stays within
        ``tolerance``, final ``|e1|``, accumulated cost, covariance resets, saturated time
        and wall time; with ``optimal_cost`` also J, J* and J / J* - 1; when some point's
        model differs from the plant or identifies (e.g. a grid over ``model.scale`` or
        ``identifier.enabled``), also :data:`SWEEP_MODEL_METRICS`: the critic's error against
        the plant's W*, the believed parameters' error against the plant's and whether the
        identifier's stack became informative.

    Raises
    ------
    SimulationInterrupted
        On Ctrl-C; ``.result`` is the SweepResult of the points done so far (an executor's
        tasks not yet started are cancelled).
    """
    if not isinstance(base_config, Config):
        raise TypeError(f"base_config: expected adparm.Config, got {type(base_config).__name__}")
    if tolerance is not None and not 0.0 < tolerance < 1.0:
        raise ValueError(f"tolerance: expected a number in (0, 1), got {tolerance!r}")
    workers = check_threads(threads)
    _metric_names(optimal_cost)  # its check, before the points are built
    points = grid_points(grid)
    configs = [_point_config(base_config, point) for point in points]
    model = _model_metrics(configs)
    metrics = _metric_names(optimal_cost, model)
    parameters = tuple(points[0])
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise TypeError(
            "executor: expected a concurrent.futures-style executor with submit(), got "
            f"{type(executor).__name__}"
        )
    done: dict[int, dict[str, Any]] = {}  # point index -> metrics, as the runs finish
    try:
        with optimal_cost_cache():  # one J* per distinct problem (with optimal_cost)
            if executor is None:
                rows = _run_in_process(configs, workers, tolerance, progress, optimal_cost, model)
            else:
                rows = _run_on_executor(executor, configs, tolerance, progress, optimal_cost, model)
            for index, row in rows:
                done[index] = row
    except KeyboardInterrupt:
        table = _table(parameters, points, done, metrics)
        raise SimulationInterrupted(
            f"sweep interrupted with {len(done)} of {len(points)} points done; their rows are in "
            "the exception's .result",
            table,
        ) from None
    return _table(parameters, points, done, metrics)


def _table(
    parameters: tuple[str, ...],
    points: list[dict[str, Any]],
    done: Mapping[int, dict[str, Any]],
    metrics: tuple[str, ...] = SWEEP_METRICS,
) -> SweepResult:
    rows = tuple({**points[i], **done[i]} for i in sorted(done))
    return SweepResult(parameters=parameters, rows=rows, metrics=metrics)


def _run_in_process(
    configs: list[Config],
    threads: int,
    tolerance: float,
    progress: bool,
    optimal_cost: Any,
    model: bool = False,
) -> Iterator[tuple[int, dict[str, Any]]]:
    """(point index, metrics) of every run, as the runs end: one stream through the core's worker
    threads (no barrier between runs), each run summarised and freed as soon as it ends, so at
    most _RUNS_PER_THREAD runs per thread are held in memory, however many points."""
    from .simulation import check_memory, check_steps, core_settings, make_result, run_batch

    workers = min(threads, max(1, len(configs)))
    window = workers * _RUNS_PER_THREAD
    check_steps(configs)
    check_memory(configs, at_once=window + workers)
    batch = _core.Batch([core_settings(config) for config in configs], window)
    ended: dict[int, Any] = {}  # runs handed over by the core, not yet summarised
    rows: list[tuple[int, dict[str, Any]]] = []

    def summarise() -> None:
        while ended:
            i, run = ended.popitem()
            result = make_result(run, configs[i], batch.seconds(i))
            rows.append((i, _metrics(result, tolerance, optimal_cost, model)))

    def on_end(i: int, run: Any) -> None:  # summarised at once: the run is freed on return
        ended[i] = run
        summarise()

    with tqdm(total=len(configs), disable=not progress, desc="sweep", unit="run") as bar:
        try:
            run_batch(batch, workers, on_end, lambda: bar.update(len(rows) - bar.n))
            summarise()
        except KeyboardInterrupt:  # keep the rows of the runs that ended
            for i in batch.wait(0.0):  # after the stop: runs that ended before it
                ended[i] = batch.take(i)
            summarise()
            yield from rows
            raise
    yield from rows


def _run_on_executor(
    executor: Any,
    configs: list[Config],
    tolerance: float,
    progress: bool,
    optimal_cost: Any,
    model: bool = False,
) -> Iterator[tuple[int, dict[str, Any]]]:
    """(point index, metrics) of every task, in order; Ctrl-C cancels the tasks not started and
    keeps those that ended."""
    options = dict(optimal_cost) if isinstance(optimal_cost, Mapping) else optimal_cost
    futures = [executor.submit(sweep_row, config, tolerance, options, model) for config in configs]
    waiting = 0  # the first task whose row has not been yielded
    try:
        for waiting, future in enumerate(tqdm(futures, disable=not progress, desc="sweep")):
            yield waiting, future.result()
    except KeyboardInterrupt:
        for future in futures[waiting:]:
            future.cancel()
        for i, future in enumerate(futures[waiting:], start=waiting):
            if future.done() and not future.cancelled() and future.exception() is None:
                yield i, future.result()
        raise
