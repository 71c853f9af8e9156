"""Controllers side by side: the same arm, task and initial state under each controller kind.

:func:`compare` runs ``adp`` (the online learning run as configured), ``adp (learned)`` (a second
run from the same initial state that starts from the learning run's final weights, with probing
off), ``adp (identifying)`` (the learning run with ``identifier.enabled = true``, when the model
differs from the plant), ``rise`` (RISE feedback alone, u = 0), ``pd`` and ``optimal``
(u* = -R^-1 e2, the exact optimal policy), and tabulates the accumulated cost of eq. (10),
tracking errors and torques of each run, and of the learning runs the critic's final error against
the plant's W* and the believed parameters' error against the plant's.

Every row's cost J = int_0^T x^T Q x + u^T R u charges the input the error system receives,
u = h + tau_d - tau (eq. 4, h of the plant; :func:`applied_input`): with tau = h_hat + mu - u_c
that is the controller's u_c less the RISE term mu, plus the disturbance and the model's error.
Along the run M de2 = -C e2 + u holds for that u, so the optimum J* of the same cost on the
plant's error system (adparm.optimal_cost) is a lower bound of every row's J. ``result.cost``
charges u_c alone (the input the ADP controller optimises); RISE's effort would be free there.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._fields import check_known
from ._files import write_text
from ._sections import CONTROLLER_KINDS
from .against_plant import (
    applied_cost,
    applied_input,
    believed_parameter_error,
    plant_critic_error,
    run_optimal_cost,
)
from .config import Config
from .result import post_run_failure, presenter
from .simulation import (
    SimulationInterrupted,
    SimulationResult,
    check_steps,
    simulate_keeping_divergence,
)
from .table import plain, rows_dataframe, rows_json, rows_markdown, write_csv

if TYPE_CHECKING:  # pragma: no cover
    import pandas
    from matplotlib.figure import Figure

__all__ = [
    "COMPARE_COLUMNS",
    "DEFAULT_KINDS",
    "IDENTIFYING_LABEL",
    "J_STAR_INTERRUPTED",
    "LEARNED_LABEL",
    "Comparison",
    "applied_cost",
    "applied_input",
    "believed_parameter_error",
    "compare",
    "model_differs",
    "plant_critic_error",
    "run_optimal_cost",
]

#: The controller kinds :func:`compare` runs by default (all of them).
DEFAULT_KINDS = ("adp", "rise", "pd", "optimal")

#: Label of the second adp run (final weights of the learning run, no probing, still learning).
LEARNED_LABEL = "adp (learned)"

#: Label of the identifying controller: the learning run with identifier.enabled = true.
IDENTIFYING_LABEL = "adp (identifying)"

#: The post_run_errors line of a comparison whose J* a signal (Ctrl-C, SIGTERM) stopped.
J_STAR_INTERRUPTED = (
    "J* (adparm.optimal_cost) was interrupted before it finished; the runs are complete"
)

#: The keys of each row of :attr:`Comparison.rows`, in column order.
COMPARE_COLUMNS = (
    "controller",
    "accumulated_cost",
    "cost_vs_optimal",
    "cost_vs_optimal_cost",
    "rms_e1",
    "final_e1",
    "peak_torque",
    "critic_relative_error_plant",
    "parameter_relative_error",
    "t_end",
    "wall_time",
    "status",
)

# column -> (markdown header, format)
_MARKDOWN = {
    "controller": ("controller", "{}"),
    "accumulated_cost": ("J (eq. 10, applied u)", "{:.6g}"),
    "cost_vs_optimal": ("J / J_optimal - 1", "{:.3g}"),
    "cost_vs_optimal_cost": ("J / J* - 1", "{:.3g}"),
    "rms_e1": ("e1 RMS (rad)", "{:.3g}"),
    "final_e1": ("e1 final (rad)", "{:.3g}"),
    "peak_torque": ("tau peak (N m)", "{:.4g}"),
    "critic_relative_error_plant": ("critic vs plant's W*", "{:.3g}"),
    "parameter_relative_error": ("beta_hat vs beta", "{:.3g}"),
    "t_end": ("t end (s)", "{:g}"),
    "wall_time": ("wall time (s)", "{:.3g}"),
    "status": ("status", "{}"),
}


#: compare computes J* by default on URDF arms up to this many joints (the UR5's solve takes
#: minutes; compare(..., optimal_cost=True) computes it on any arm).
COMPARE_URDF_MAX_DOF = 3


def _check_kinds(kinds: str | Iterable[str]) -> tuple[str, ...]:
    if isinstance(kinds, str):
        kinds = (kinds,)
    try:
        kinds = tuple(kinds)
    except TypeError as error:
        raise TypeError(
            f"kinds: expected a sequence of {', '.join(CONTROLLER_KINDS)}, got {kinds!r}"
        ) from error
    if not kinds:
        raise ValueError(f"kinds: expected at least one of {', '.join(CONTROLLER_KINDS)}")
    for kind in kinds:
        check_known(
            kind,
            CONTROLLER_KINDS,
            strings="kinds: controller kinds must be strings",
            unknown="kinds: unknown controller kind {name!r}",
            listing=f"known kinds: {', '.join(CONTROLLER_KINDS)}",
        )
    duplicates = sorted({kind for kind in kinds if kinds.count(kind) > 1})
    if duplicates:
        named = ", ".join(repr(kind) for kind in duplicates)
        raise ValueError(f"kinds: each kind at most once, got {named} more than once")
    return kinds


def model_differs(config: Config) -> bool:
    """Whether the arm the controller believes ([model], with model.scale) differs from the
    plant: the two-link arm's parameters, or a URDF arm's file, gravity, friction or locked
    joints (``ModelConfig.differs``)."""
    return config.model.differs(config.plant)


def _identifying_config(config: Config, identify: bool | None, kinds: tuple[str, ...]) -> Any:
    """The identifying run's config (kind adp, identifier.enabled = true), or why there is none
    (a str): ``identify`` None adds it when the model differs from the plant, True always, False
    never. ValueError, naming ``identify``, when True cannot be done."""
    if identify is not None and not isinstance(identify, bool):
        raise TypeError(f"identify: expected True, False or None, got {identify!r}")
    if identify is False:
        return "identify = False"
    forced = identify is True
    reason = None
    if "adp" not in kinds:
        reason = "'adp' is not among the kinds"
    elif config.identifier.enabled:
        reason = "the config sets identifier.enabled = true: every row identifies as configured"
    elif not forced and not model_differs(config):
        reason = "the model is the plant (the identifier would start at the truth)"
    if reason is not None:
        if forced:
            raise ValueError(f"identify: no identifying run to add: {reason}")
        return reason
    try:
        return config.updated({"controller": {"kind": "adp"}, "identifier": {"enabled": True}})
    except ValueError as error:  # e.g. an arm the identifier does not support yet
        if forced:
            raise ValueError(f"identify: {error}") from error
        return f"identification is not available here ({error})"


def controller_configs(
    config: Config, kinds: str | Iterable[str] = DEFAULT_KINDS, identify: bool | None = False
) -> dict[str, Config]:
    """The config of each kind (controller.kind replaced), and with ``identify`` (as
    :func:`compare`'s) the identifying run's under :data:`IDENTIFYING_LABEL`, checked before
    anything runs. ValueError/TypeError for bad kinds or a kind the config cannot run."""
    return _run_configs(config, kinds, identify)[0]


def _run_configs(
    config: Config, kinds: str | Iterable[str], identify: bool | None
) -> tuple[dict[str, Config], str | None]:
    """controller_configs, and why there is no identifying run (None when there is one)."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    configs = {}
    kinds = _check_kinds(kinds)
    for kind in kinds:
        if kind == "rise" and not config.controller.rise:
            raise ValueError(
                "kinds: 'rise' is the RISE feedback alone and needs controller.rise = true, but "
                "this configuration sets it false; leave 'rise' out of kinds"
            )
        configs[kind] = config.updated({"controller": {"kind": kind}})
    identifying = _identifying_config(config, identify, kinds)
    if isinstance(identifying, str):
        return configs, identifying
    # after adp (and its learned run), before the controllers that do not learn
    ordered = {}
    for kind, kind_config in configs.items():
        ordered[kind] = kind_config
        if kind == "adp":
            ordered[IDENTIFYING_LABEL] = identifying
    return ordered, None


def _learned_config(config: Config, learning: SimulationResult) -> Config:
    """``config`` (kind adp) started from the final weights of ``learning``, probing off."""
    if learning.t.size == 0:  # pragma: no cover - the core always records t = 0
        critic = config.initial_weights("critic_weights")
        actor = config.initial_weights("actor_weights")
    else:
        critic, actor = learning.critic_weights[-1], learning.actor_weights[-1]
    return config.updated(
        {
            "init": {"critic_weights": critic.tolist(), "actor_weights": actor.tolist()},
            "probe": {"until": 0.0},
        }
    )


def _rms_norm(t: np.ndarray, values: np.ndarray) -> float:
    """sqrt(1/T int |v(t)|^2 dt) over the recorded rows (trapezoid rule in t)."""
    if t.size == 0:
        return math.nan
    squares = np.sum(values**2, axis=1)
    span = t[-1] - t[0]
    if span <= 0.0:
        return float(np.sqrt(squares[-1]))
    integral = np.sum(0.5 * (squares[1:] + squares[:-1]) * np.diff(t))
    return float(np.sqrt(integral / span))


def _row(
    label: str,
    result: SimulationResult,
    cost: float,
    optimal_cost: float | None,
    best_cost: float | None = None,
    critic_error: float | None = None,
    parameter_error: float | None = None,
) -> dict[str, Any]:
    empty = result.t.size == 0
    return {
        "controller": label,
        "accumulated_cost": cost,
        "cost_vs_optimal": (
            None
            if optimal_cost is None or result.status != "finished"
            else cost / optimal_cost - 1.0
        ),
        "cost_vs_optimal_cost": (
            None if best_cost is None or result.status != "finished" else cost / best_cost - 1.0
        ),
        "rms_e1": _rms_norm(result.t, result.e1),
        "final_e1": math.nan if empty else float(np.linalg.norm(result.e1[-1])),
        "peak_torque": math.nan if empty else float(np.abs(result.tau).max()),
        "critic_relative_error_plant": critic_error,
        "parameter_relative_error": parameter_error,
        "t_end": math.nan if empty else float(result.t[-1]),
        "wall_time": float(result.wall_time),
        "status": result.status,
    }


@dataclass(frozen=True)
class Comparison:
    """Runs of the same arm, task and initial state under several controllers.

    ``results``: label -> SimulationResult (labels: the kinds, plus ``"adp (learned)"`` and,
    when the model differs from the plant, ``"adp (identifying)"`` after ``"adp"``). ``rows``:
    one dict per label, keys :data:`COMPARE_COLUMNS`:

    - accumulated_cost: J of eq. (10) on the applied input u = h + tau_d - tau
      (:func:`applied_cost`: the controller's input less the RISE term, plus the disturbance
      and the model's error), the input the error system received;
    - cost_vs_optimal: J / J_optimal - 1; None when ``optimal`` did not run, did not finish or
      cost 0, and for a diverged run (its J covers a shorter time);
    - cost_vs_optimal_cost: J / J* - 1 with J* (``optimal_cost``, an
      :class:`adparm.truth.OptimalCost`) the least cost any input reaches over the same time
      from the same x(0) on the plant's error system (adparm.optimal_cost with model=False;
      over sim.T without a terminal cost when sim.T is shorter than its default horizon; with
      the plant's torque limits, which the applied torque obeys, widened by the disturbance's
      amplitude, which J's input u = h + tau_d - tau holds). It is a lower bound of every
      row's J: a row is below 0 by at most J*'s stated error (None for a moving qd or when J*
      fails, e.g. IPOPT, or a URDF arm with locked joints);
    - rms_e1: ``sqrt(1/T int |e1|^2 dt)`` over the recorded rows (trapezoid rule), rad;
    - final_e1: ``|e1|`` at the last row, rad;
    - peak_torque: max ``|tau|`` over every joint and row, N m;
    - critic_relative_error_plant: ||Wc(T) - W*|| / ||W*|| with the *plant's* W*
      (:func:`plant_critic_error`; the learning runs only, None where W* is not known): a run
      that believes a wrong model ends at the model's W*, an identifying one at the plant's;
    - parameter_relative_error: the largest relative error of the believed base parameters at
      the end against the plant's (:func:`believed_parameter_error`): beta_hat(T) of the
      identifying run, the model's of every other run (0 for an exact model);
    - t_end: the last recorded time (earlier than sim.T for a diverged run), s;
    - wall_time (s) and status (finished, diverged or interrupted) of the run.

    ``identifying_note``: why there is no ``"adp (identifying)"`` row (None when there is one,
    or when :func:`compare` was not asked for it)."""

    results: dict[str, SimulationResult]
    rows: list[dict[str, Any]]
    optimal_cost: float | None = None
    #: The steps after the runs that failed (e.g. J*), one line each; the runs are complete.
    post_run_errors: tuple[str, ...] = ()
    #: The largest estimated relative quadrature error of a row's J (applied_cost).
    quadrature_error: float = 0.0
    #: Why compare added no identifying run (None: it did, or identify = False).
    identifying_note: str | None = None

    @property
    def diverged(self) -> list[str]:
        """Labels of the runs that diverged."""
        return [row["controller"] for row in self.rows if row["status"] == "diverged"]

    def cost_note(self) -> str:
        """What J and J* are, with J*'s tolerance (the note under the Markdown table)."""
        rise = self._rise()
        quadrature = (
            f" (the part beyond u_c by Simpson's rule on the recorded rows, estimated relative "
            f"error <= {self.quadrature_error:.1e})"
            if self.quadrature_error
            else ""
        )
        text = (
            "J = int_0^T x^T Q x + u^T R u (eq. 10) charges the input the error system "
            "received, u = h + tau_d - tau = u_c - mu + tau_d + (h - h_hat): the controller's "
            "input u_c (adp: u_hat + probe)"
            + (", less the RISE term mu" if rise else "")
            + ", plus the disturbance and the model's error"
            + quadrature
            + ". "
        )
        best = self.optimal_cost
        if best is None:
            text += (
                "J* = - (not computed: a moving qd, a URDF arm of more than "
                f"{COMPARE_URDF_MAX_DOF} joints without optimal_cost=True (adparm compare "
                "--optimal-cost), optimal_cost=False, or a failed solve). "
            )
        else:
            note = getattr(best, "note", "")
            horizon = (
                f"over [0, {best.horizon:g} s]"
                if not getattr(best, "terminal", True)
                else "over an infinite horizon"
                if hasattr(best, "terminal")
                else ""
            )
            text += (
                f"J* = {float(best):.6g} is the least cost any input reaches from x(0) on the "
                f"plant's error system {horizon} (adparm.optimal_cost, model=False), a lower "
                "bound of every J" + (f"; its {note}. " if note else ". ")
            )
            if rise:
                text += "RISE adds mu to every controller's input, so even optimal is above J*. "
        text += (
            "e1 RMS = sqrt(1/T int |e1|^2 dt), e1 final = |e1(T)|, tau peak = max |tau_j| "
            "over the joints. critic vs plant's W* = ||Wc(T) - W*|| / ||W*|| with the plant's "
            "W* (learning runs); beta_hat vs beta = the largest relative error of the believed "
            "base parameters at the end against the plant's (the model's, or the identifying "
            "run's estimate)."
        )
        if IDENTIFYING_LABEL in self.results:
            text += (
                f" {IDENTIFYING_LABEL} is the adp learning run with identifier.enabled = true: it "
                "identifies the plant's parameters online and uses the estimate in place of the "
                "model."
            )
        elif self.identifying_note:
            text += f" No identifying run: {self.identifying_note}."
        return text

    def table_markdown(self) -> str:
        """The rows as a Markdown table (``-`` for a missing value), with a note on the cost."""
        lines = [rows_markdown(COMPARE_COLUMNS, self.rows, _MARKDOWN).rstrip("\n")]
        lines += ["", self.cost_note()]
        if self.post_run_errors:  # the runs are complete; a step after them failed
            lines += ["", *(f"Not computed: {problem}" for problem in self.post_run_errors)]
        return "\n".join(lines) + "\n"

    def _rise(self) -> bool:
        return any(result.config.controller.rise for result in self.results.values())

    def to_dataframe(self) -> pandas.DataFrame:
        """The rows as a pandas DataFrame indexed by controller. Needs pandas."""
        return rows_dataframe(COMPARE_COLUMNS, self.rows).set_index("controller")

    def to_json(self) -> dict[str, Any]:
        """The content of compare.json: {"columns", "rows", "cost", "optimal_cost",
        "post_run_errors"}, non-finite numbers as null. "cost" says what J is (cost_note);
        "optimal_cost" is J* with its error, tolerance, intervals, horizon and terminal flag
        (null when not computed)."""
        best = self.optimal_cost
        return {
            **rows_json(COMPARE_COLUMNS, self.rows),
            "cost": self.cost_note(),
            "quadrature_error": plain(self.quadrature_error),
            "optimal_cost": None if best is None else plain(_optimal_cost_json(best)),
            "post_run_errors": list(self.post_run_errors),
            "identifying_note": self.identifying_note,
        }

    def save(self, directory: str | Path) -> list[Path]:
        """Write compare.csv, compare.json and compare.md to ``directory``; returns the paths."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        paths = [directory / f"compare.{ext}" for ext in ("csv", "json", "md")]
        write_csv(paths[0], COMPARE_COLUMNS, self.rows)
        write_text(paths[1], json.dumps(self.to_json(), indent=2) + "\n")
        write_text(paths[2], "# adparm controller comparison\n\n" + self.table_markdown())
        return paths

    def plot(
        self, *, time_scale: str = "symlog", ax: Any = None, fig: Figure | None = None
    ) -> Figure:
        """e1 and tau of each joint under each controller (:func:`adparm.plotting.plot_comparison`):
        the learning run in its own column, the other controllers together, each in its own
        colour and line style. ``time_scale`` (``"symlog"`` or ``"linear"``) sets the time axis
        of the controllers' column; ``ax`` (a 4 x n grid of Axes) or ``fig`` draw into yours."""
        return presenter("plot_comparison")(self, time_scale=time_scale, ax=ax, fig=fig)


def compare(
    config: Config,
    kinds: str | Sequence[str] = DEFAULT_KINDS,
    *,
    identify: bool | None = None,
    progress: bool = False,
    optimal_cost: bool | Mapping[str, Any] | None = None,
) -> Comparison:
    """Run ``config`` under several controllers on the same arm, task and initial state.

    Only ``controller.kind`` changes between the runs. A run that diverges is kept, with status
    "diverged" and its partial result.

    Parameters
    ----------
    config : Config
        The shared settings.
    kinds : str or sequence of str, optional
        Controller kinds among ``adp``, ``rise``, ``pd`` and ``optimal`` (default all four).
        ``adp`` gives two rows: ``"adp"``, the online learning run exactly as configured
        (probing included), and ``"adp (learned)"``, a second run from the same initial state
        whose critic and actor start at the learning run's final weights, with probing off and
        learning still on.
    identify : bool or None, optional
        The identifying controller, ``"adp (identifying)"``: the learning run with
        ``identifier.enabled = true`` (:doc:`/guide/unknown-dynamics`), which starts from the
        model and identifies the plant's parameters online. None (default): added when ``adp``
        is among the kinds and the model differs from the plant (``[model]``, ``model.scale``;
        with an exact model it would start at the truth: one more run for the same row), unless
        the config already identifies (then every row does, as configured); the table's note
        says why it was not added. True: added whenever ``adp`` runs (ValueError, naming
        ``identify``, when it cannot be). False: never.
    progress : bool, optional
        Show a progress bar.
    optimal_cost : bool or dict, optional
        J* of the J / J* - 1 column. None: computed, except on URDF arms of more than
        COMPARE_URDF_MAX_DOF (3) joints (minutes per solve on the UR5); True, or a dict of
        adparm.optimal_cost options (e.g. ``{"intervals": 40, "rtol": 1e-2}``, a coarser J*
        whose error the note states): computed on any arm; False: not computed.

    Returns
    -------
    Comparison
        ``.results`` (label -> SimulationResult), ``.rows`` (cost, errors, torque, wall time),
        ``.plot()``, ``.save()``, ``.to_dataframe()``.

    Raises
    ------
    ValueError
        For an unknown or repeated kind (with a "did you mean" hint), for ``rise`` when
        ``controller.rise`` is false, or for ``identify=True`` when there can be no identifying
        run.
    SimulationInterrupted
        On Ctrl-C; ``.result`` is the Comparison of the runs so far (the one interrupted with
        status "interrupted"), or, during J* after the runs, of every run, with
        :data:`J_STAR_INTERRUPTED` in its ``post_run_errors``.
    """
    if not (optimal_cost is None or isinstance(optimal_cost, (bool, Mapping))):
        wanted = "None, True, False or a dict of adparm.optimal_cost options"
        raise TypeError(f"optimal_cost: expected {wanted}, got {type(optimal_cost).__name__}")
    configs, note = _run_configs(config, kinds, identify)
    check_steps(list(configs.values()))  # every run's step, before the first one runs
    results: dict[str, SimulationResult] = {}
    label = ""
    try:
        for kind, kind_config in configs.items():
            label = kind
            results[label] = _run(kind_config, progress)
            if kind == "adp":
                label = LEARNED_LABEL
                # from the learning run's final weights: not the user's step to check
                learned = _learned_config(kind_config, results[kind])
                results[label] = simulate_keeping_divergence(learned, progress, check=False)[0]
    except KeyboardInterrupt as interrupt:
        if isinstance(interrupt, SimulationInterrupted):
            results[label] = interrupt.result
        raise SimulationInterrupted(
            f"comparison interrupted during the {label!r} run; the runs so far are in the "
            "exception's .result",
            dataclasses.replace(_comparison(results), identifying_note=note),
        ) from None
    # after the runs: a failure of J* loses no run (post_run_errors), nor does Ctrl-C, which
    # raises SimulationInterrupted with every run and says that J* was interrupted
    try:
        best, problem = _optimal_cost(config, optimal_cost)
    except KeyboardInterrupt:
        stopped = _comparison(results)
        problems = (*stopped.post_run_errors, J_STAR_INTERRUPTED)
        stopped = dataclasses.replace(stopped, post_run_errors=problems, identifying_note=note)
        raise SimulationInterrupted(
            "comparison interrupted during J* (adparm.optimal_cost), after the runs; every run "
            "is complete, in the exception's .result",
            stopped,
        ) from None
    comparison = dataclasses.replace(_comparison(results, best), identifying_note=note)
    if problem is not None:
        problems = (*comparison.post_run_errors, problem)
        comparison = dataclasses.replace(comparison, post_run_errors=problems)
    return comparison


def _optimal_cost_json(best: float) -> dict[str, Any]:
    keys = ("error", "rtol", "converged", "intervals", "horizon", "terminal", "active_until")
    return {"value": float(best), **{key: getattr(best, key, None) for key in keys}}


def _optimal_cost(config: Config, wanted: Any = None) -> tuple[float | None, str | None]:
    """:func:`run_optimal_cost` as compare's ``optimal_cost`` asks."""
    large = config.plant.urdf is not None and config.dof > COMPARE_URDF_MAX_DOF
    if wanted is False or (wanted is None and large):
        return None, None
    return run_optimal_cost(config, **(dict(wanted) if isinstance(wanted, Mapping) else {}))


def _run(config: Config, progress: bool) -> SimulationResult:
    return simulate_keeping_divergence(config, progress)[0]


def _comparison(results: dict[str, SimulationResult], best: float | None = None) -> Comparison:

    costs: dict[str, tuple[float, float]] = {}
    learned: dict[str, tuple[float | None, float | None]] = {}  # critic and parameter errors
    problems: list[str] = []
    for label, result in results.items():
        try:
            costs[label] = applied_cost(result)
        except Exception as error:  # noqa: BLE001 - the run is kept, its J is not known
            costs[label] = (math.nan, math.nan)
            problems.append(post_run_failure(f"J of {label!r} (applied_cost)", error))
        try:
            learned[label] = (plant_critic_error(result), believed_parameter_error(result))
        except Exception as error:  # noqa: BLE001 - the run is kept, its errors are not known
            learned[label] = (None, None)
            problems.append(post_run_failure(f"the errors against the plant of {label!r}", error))
    optimal = results.get("optimal")
    optimal_cost = None
    if optimal is not None and optimal.status == "finished" and costs["optimal"][0] > 0.0:
        optimal_cost = costs["optimal"][0]
    best = best if best is not None and best > 0.0 else None
    rows = [
        _row(label, result, costs[label][0], optimal_cost, best, *learned[label])
        for label, result in results.items()
    ]
    # rows too short for an estimate (fewer than 3 rows every other row) give none
    errors = [error for _, error in costs.values() if not math.isnan(error)]
    return Comparison(
        results=results,
        rows=rows,
        optimal_cost=best,
        post_run_errors=tuple(problems),
        quadrature_error=max(errors, default=0.0),
    )
