"""Figures of a run (matplotlib): the paper's Figures 2-4, the torques, and a controller comparison.

Every function returns a :class:`matplotlib.figure.Figure` and draws its panels either into a new
figure (default, 9 pt text, sized for a page width), into a figure you pass as ``fig=`` (the panels
are added to it), or into axes you pass as ``ax=`` (one Axes or a sequence; the function draws as
many of its panels as you give axes, in order, so ``ax=one_axes`` draws the main panel only).

Design choices, the same in every figure:

- colours from the Okabe-Ito palette (distinguishable with the common colour-vision
  deficiencies), and a second cue (line style or markers) wherever lines can coincide;
- the analytic optimum W* (see :func:`adparm.optimal_weights`) drawn on top of the curves as
  thick black dashes, its values in the legend, and a log-scale panel of the relative error
  ||W - W*|| / ||W*||;
- legends outside the data, to the right of the panels;
- the end of probing marked and labelled;
- a run that did not finish (diverged, interrupted) says so: a red vertical line where it
  stopped, labelled "diverged at t = ... s", the time after it shaded, the title saying so, and
  the last recorded row marked (a value beyond the axis at its edge), so that the rows before a
  divergence are not read as a result;
- more than 12 weights (a URDF arm's structured basis: 30-80) are drawn in groups, the K block
  and the inertia block, each relative to W*, without per-weight legends; the relative-error
  panel (with each block's error) carries the story.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ._files import save_figures
from .result import register

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import SimulationResult
from ._figure_style import (
    FLOOR,
    OKABE_ITO,
    RC,
    STOP_COLOR,
    WIDTH,
    Panel,
    draw,
    figure_title,
    legend_outside,
    mark_probe_end,
    mark_stop,
)
from .identifier_figure import plot_model_parameters
from .units import effort_units, position_units, unit_label
from .weight_figures import WEIGHT_UNIT, plot_actor_weights, plot_critic_weights

__all__ = [
    "FIGURES",
    "IDENTIFIER_FIGURES",
    "OKABE_ITO",
    "STOP_COLOR",
    "WEIGHT_UNIT",
    "plot_actor_weights",
    "plot_comparison",
    "plot_critic_weights",
    "figure_names",
    "plot_errors",
    "plot_model_parameters",
    "plot_result",
    "plot_torques",
    "save_figures",
]

_JOINT_STYLES = ({"color": OKABE_ITO[0], "ls": "-"}, {"color": OKABE_ITO[1], "ls": "--"})
_LINE_STYLES = ("-", "--", "-.", ":")


def _joint_style(j: int) -> dict[str, Any]:
    """Joint j's line: the two-link arm's two styles, then Okabe-Ito colours with cycling dashes
    (any n joints stay apart in colour and dash)."""
    if j < len(_JOINT_STYLES):
        return _JOINT_STYLES[j]
    return {"color": OKABE_ITO[j % len(OKABE_ITO)], "ls": _LINE_STYLES[j % len(_LINE_STYLES)]}


def _joint_panel(
    result: SimulationResult,
    values: np.ndarray,
    ylabel: str,
    label: str,
    *,
    log: bool = False,
    annotate_probe: bool = False,
    note: str | None = None,
    limits: np.ndarray | None = None,
) -> Panel:
    def panel(axes: Axes) -> None:
        if note:  # above the panel, off the data
            title = axes.get_title()  # the first panel holds the figure's title (draw): above
            if title:
                import matplotlib

                axes.figure.suptitle(title, fontsize=matplotlib.rcParams["axes.titlesize"])
                axes.set_title("")
            axes.set_title(note, fontsize=7.5, loc="left", color="0.25")
        for j in range(values.shape[1]):  # one line per joint
            y = np.maximum(np.abs(values[:, j]), FLOOR) if log else values[:, j]
            axes.plot(result.t, y, lw=1.0, label=label.format(j=j + 1), **_joint_style(j))
        if limits is not None:
            _draw_limits(axes, values, limits)
        if log:
            axes.set_yscale("log")
        axes.set_ylabel(ylabel)
        axes.set_xlabel("time t (s)")
        mark_probe_end(axes, result, label=annotate_probe)
        mark_stop(axes, result, label=annotate_probe)
        legend_outside(axes)

    return panel


#: A torque limit is drawn when it lies within this factor of the panel's largest |tau|; one
#: further out would flatten the torques, and the panel's note gives it instead.
LIMIT_SCALE = 2.0


def _draw_limits(axes: Axes, values: np.ndarray, limits: np.ndarray) -> None:
    """Each +-limit as thin dashed lines, in its joint's colour (grey when several joints share
    it; one legend entry per value), for the limits within LIMIT_SCALE of the largest |value|
    (torque_note names the others)."""
    largest = float(np.max(np.abs(values))) if values.size else 0.0
    shown = [j for j, v in enumerate(limits) if np.isfinite(v) and v <= LIMIT_SCALE * largest]
    for limit in dict.fromkeys(float(limits[j]) for j in shown):  # each value once, in order
        joints = [j for j in shown if limits[j] == limit]
        color = _joint_style(joints[0])["color"] if len(joints) == 1 else "0.4"
        name = f"limit$_{{{','.join(str(j + 1) for j in joints)}}}$ $\\pm${limit:.3g}"
        for sign, label in ((1.0, name), (-1.0, None)):
            axes.axhline(sign * limit, color=color, ls=(0, (5, 2)), lw=0.9, alpha=0.7, label=label)


def _joint_list(joints: list[int]) -> str:
    return ("joint " if len(joints) == 1 else "joints ") + ", ".join(str(j + 1) for j in joints)


def torque_note(result: SimulationResult) -> str | None:
    """The note over the torque panel of :func:`plot_torques` when the run has torque limits:
    the time each joint was clipped, and the limits too far beyond the torques to be drawn."""
    config = result.config
    limits = config.plant.limit_vector(config.dof)
    if limits.size == 0:
        return None
    largest = float(np.max(np.abs(result.tau))) if result.tau.size else 0.0
    clipped = [f"{j + 1}: {v:.3g} s" for j, v in enumerate(result.saturated_time) if v > 0.0]
    text = "dashed: torque limits; " + (
        "clipped on joint " + ", ".join(clipped) if clipped else "never clipped"
    )
    far = [j for j, v in enumerate(limits) if np.isfinite(v) and v > LIMIT_SCALE * largest]
    units = effort_units(config)
    for limit in dict.fromkeys(float(limits[j]) for j in far):
        same = [j for j in far if limits[j] == limit]
        unit = unit_label([units[j] for j in same])
        text += f"; off the scale: {_joint_list(same)} at $\\pm${limit:.3g} {unit}"
    return text


def plot_errors(
    result: SimulationResult,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """Figure 4: joint angles q, tracking errors e1 = qd - q and e2, and ``|e1|`` on a log scale.

    Parameters
    ----------
    result : SimulationResult
        A run.
    ax : Axes or sequence of Axes, optional
        Up to four Axes, for q, e1, e2 and ``|e1|`` (log scale) in this order.
    fig : Figure, optional
        Add the four panels to this figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    units = position_units(result.config)  # "m" on a prismatic joint
    position, rate = unit_label(units), unit_label(units, "/s")
    panels = [
        _joint_panel(result, result.q, f"q ({position})", "$q_{j}$", annotate_probe=True),
        _joint_panel(result, result.e1, f"$e_1$ ({position})", "$e_{{1,{j}}}$"),
        _joint_panel(result, result.e2, f"$e_2$ ({rate})", "$e_{{2,{j}}}$"),
        _joint_panel(result, result.e1, f"$|e_1|$ ({position})", "$|e_{{1,{j}}}|$", log=True),
    ]
    title = figure_title("Joint angles and tracking errors (Figure 4)", result)
    return draw(panels, ax=ax, fig=fig, height=6.4, title=title)


def plot_torques(
    result: SimulationResult,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """The applied joint torques tau and the probing signal.

    With torque limits (``plant.torque_limits``) the torque panel draws each joint's +-limit as
    dashed lines in its colour, and a note over it (:func:`torque_note`) gives the time each joint
    was clipped (and a limit too far beyond the torques to draw).

    The probe's panel is drawn on its own scale: with the paper's probe it is several times
    larger than tau. A note over it (:func:`probe_note`) says why: the probe is part of u and
    tau = h_hat + mu - u, and the feedforward h_hat and RISE's mu follow the motion it causes and
    take most of it out of tau (how much, joint by joint, and the RMS of both while probing).

    Parameters
    ----------
    result : SimulationResult
        A run.
    ax : Axes or sequence of Axes, optional
        Up to two Axes, for tau and the probing signal.
    fig : Figure, optional
        Add the two panels to this figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    config = result.config
    limits = config.plant.limit_vector(config.dof)
    effort = unit_label(effort_units(config))  # "N" on a prismatic joint
    panels = [
        _joint_panel(
            result,
            result.tau,
            f"torque $\\tau$ ({effort})",
            "$\\tau_{j}$",
            annotate_probe=True,
            note=torque_note(result),
            limits=limits if limits.size else None,
        ),
        _joint_panel(
            result,
            result.probe,
            f"probing signal ({effort})",
            "probe$_{j}$",
            note=probe_note(result),
        ),
    ]
    title = figure_title("Applied torques and probing signal", result)
    return draw(panels, ax=ax, fig=fig, height=4.2, title=title)


def probe_note(result: SimulationResult) -> str | None:
    """The note over the probing panel of :func:`plot_torques`, which is drawn on its own scale:
    the probe is part of u and tau = h_hat + mu - u, and the feedforward h_hat and RISE's mu
    follow the motion the probe causes. When probing lasts at least one period of its slowest
    sinusoid, how much of the probe they take out of tau, per joint: 1 - the least-squares share
    of -probe in tau over the probing time (said only when it is within 0-100 %). The RMS of
    the probe and of tau while probing. None without probing."""
    config = result.config.probe
    on = result.t < config.until if result.t.size else np.zeros(0, dtype=bool)
    probe, tau = result.probe[on], result.tau[on]
    if probe.shape[0] < 2:
        return None
    centred = probe - probe.mean(axis=0)
    power = np.sum(centred**2, axis=0)
    joints = power > 0.0
    if not joints.any():
        return None
    kept = -np.sum((tau - tau.mean(axis=0)) * centred, axis=0)[joints] / power[joints]
    cancelled = 100.0 * (1.0 - kept)
    slowest = 2.0 * np.pi / min(config.frequencies) if min(config.frequencies) > 0 else np.inf
    long_enough = float(result.t[on][-1] - result.t[on][0]) >= slowest
    rms = np.sqrt(np.mean(probe**2, axis=0))[joints]
    tau_rms = np.sqrt(np.mean(tau**2, axis=0))[joints]
    units = [u for u, on in zip(effort_units(result.config), joints, strict=True) if on]
    if rms.size <= 3:

        def listed(values: np.ndarray) -> str:  # "100, 32.5 N m"; "100 N, 32.5 N m" when mixed
            if len(set(units)) == 1:
                return ", ".join(f"{v:.3g}" for v in values) + f" {units[0]}"
            return ", ".join(f"{v:.3g} {u}" for v, u in zip(values, units, strict=True))

        sizes = f"probe {listed(rms)}, $\\tau$ {listed(tau_rms)}"
    else:
        unit = unit_label(units)
        sizes = f"probe up to {rms.max():.3g} {unit}, $\\tau$ up to {tau_rms.max():.3g} {unit}"
    head = (
        "The probe is part of u, and $\\tau = \\hat h + \\mu - u$: the feedforward $\\hat h$ "
        "and RISE's $\\mu$ follow the motion it causes\n"
    )
    if long_enough and cancelled.min() >= 0.0 and cancelled.max() <= 100.0:
        span = (
            f"{cancelled.min():.0f} %"
            if round(cancelled.min()) == round(cancelled.max())
            else f"{cancelled.min():.0f}-{cancelled.max():.0f} %"
        )
        return (
            head + f"and cancel {span} of it in $\\tau$ (least squares while probing; RMS: {sizes})"
        )
    return head + f"(RMS while probing: {sizes})"


#: Line style of each controller in :func:`plot_comparison`: colour, dashes and width differ, and
#: "optimal" is drawn thin and black on top of "adp (learned)", which is drawn wide and light, so
#: both show where they coincide.
CONTROLLER_STYLES = {
    "adp (learned)": {"color": OKABE_ITO[5], "ls": "-", "lw": 3.2, "alpha": 0.9, "zorder": 2},
    "rise": {"color": OKABE_ITO[2], "ls": "-.", "lw": 1.3, "zorder": 3},
    "pd": {"color": OKABE_ITO[1], "ls": (0, (1, 1.5)), "lw": 1.5, "zorder": 3},
    "optimal": {"color": "k", "ls": (0, (4, 2.5)), "lw": 1.1, "zorder": 4},
}
_LEARNING_STYLE = {"color": OKABE_ITO[0], "ls": "-", "lw": 0.7}

#: The learning runs of a comparison (the left-hand column) and their styles: the run as
#: configured, and the identifying controller (identifier.enabled = true, adparm.compare).
LEARNING_STYLES = {
    "adp": _LEARNING_STYLE,
    "adp (identifying)": {"color": OKABE_ITO[3], "ls": (0, (5, 2)), "lw": 0.9, "zorder": 3},
}


def _compare_panels(positions: list[str], efforts: list[str]) -> list[tuple[str, int, str]]:
    """(result attribute, joint, y label) of each row: e1 of every joint, then tau (units per
    joint: rad and N m, m and N on a prismatic joint)."""
    return [("e1", j, f"$e_{{1,{j + 1}}}$ ({u})") for j, u in enumerate(positions)] + [
        ("tau", j, f"$\\tau_{j + 1}$ ({u})") for j, u in enumerate(efforts)
    ]


def _draw_compare_limit(axes: Axes, group: dict[str, SimulationResult], joint: int) -> None:
    """The joint's torque limit on a comparison's tau panel: +-limit dashed grey (legend "limit
    +-x") within LIMIT_SCALE of the largest applied |tau| of the group, else named over the
    panel ("off scale"); nothing without a limit."""
    results = list(group.values())
    config = results[0].config
    limits = config.plant.limit_vector(config.dof)
    if limits.size == 0 or not np.isfinite(limits[joint]):
        return
    limit = float(limits[joint])
    largest = max((float(np.abs(r.tau[:, joint]).max()) for r in results if r.t.size), default=0)
    if limit > LIMIT_SCALE * largest:
        unit = effort_units(config)[joint]
        axes.set_title(f"limit $\\pm${limit:.3g} {unit} (off scale)", fontsize=7, loc="right")
        return
    for sign in (1.0, -1.0):
        line = axes.axhline(sign * limit, color="0.4", ls=(0, (5, 2)), lw=0.9, alpha=0.8)
    line.set_label(f"limit $\\pm${limit:.3g}")
    axes.legend(handles=[line], loc="upper right", fontsize=7, frameon=False)


def plot_comparison(
    comparison: Any,
    *,
    time_scale: str = "symlog",
    ax: Sequence[Axes] | np.ndarray | None = None,
    fig: Figure | None = None,
) -> Figure:
    """Controllers side by side (:func:`adparm.compare`): e1 and tau of each joint.

    The learning runs (``adp`` and, when compared, the identifying ``adp (identifying)``, with
    their probing) have their own column on the left, on a linear time axis with the end of
    probing marked, each in its style (:data:`LEARNING_STYLES`); the controllers that do not
    learn during the run
    (``adp (learned)``, ``rise``, ``pd``, ``optimal``) share the right-hand column, each in its
    own colour and line style (:data:`CONTROLLER_STYLES`). Without an ``adp`` row the figure has
    the right-hand column only. With ``plant.torque_limits`` each tau panel draws its joint's
    limit as dashed grey lines (or names it over the panel when it is more than twice the
    largest applied torque).

    Parameters
    ----------
    comparison : Comparison
        The result of :func:`adparm.compare`.
    time_scale : {"symlog", "linear"}
        Time axis of the controllers' column: ``"symlog"`` (default) is linear up to 1 s and
        logarithmic after, so that both the first second and the long run show.
    ax : 2-d array of Axes, optional
        2 n rows for n joints (e1 of each joint, then tau of each joint: four for the two-link
        arm) and one column per group (learning run, controllers), as ``fig.subplots(4, 2)``
        returns.
    fig : Figure, optional
        Add the panels to this figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    if time_scale not in ("symlog", "linear"):
        raise ValueError(f"time_scale: expected 'symlog' or 'linear', got {time_scale!r}")
    if ax is not None and fig is not None:
        raise ValueError("ax, fig: give at most one of them")
    results = comparison.results
    learning = {label: r for label, r in results.items() if label in LEARNING_STYLES}
    others = {label: r for label, r in results.items() if label not in LEARNING_STYLES}
    groups = [g for g in (learning, others) if g]
    config = next(iter(results.values())).config if results else None
    panels = (
        _compare_panels(position_units(config), effort_units(config))
        if config is not None
        else _compare_panels(["rad"] * 2, ["N m"] * 2)
    )
    rows = len(panels)
    with matplotlib.rc_context(RC):
        if ax is not None:
            grid = np.asarray(ax, dtype=object).reshape(rows, -1)
            if grid.shape[1] != len(groups):
                raise ValueError(
                    f"ax: expected {rows} x {len(groups)} Axes (one column per group), "
                    f"got {np.asarray(ax, dtype=object).shape}"
                )
            figure = grid[0, 0].figure
        else:
            if fig is None:
                from matplotlib.figure import Figure

                fig = Figure(
                    figsize=(WIDTH + 1.0 * (len(groups) - 1), 1.7 * rows), layout="constrained"
                )
            figure = fig
            grid = figure.subplots(rows, len(groups), sharex="col", squeeze=False)
            figure.suptitle("Controllers compared: tracking errors and applied torques")
        for column, group in enumerate(groups):
            is_learning = group is learning
            for row, (name, joint, ylabel) in enumerate(panels):
                axes = grid[row, column]
                for label, result in group.items():
                    styles = LEARNING_STYLES if is_learning else CONTROLLER_STYLES
                    style = styles.get(label, {})
                    suffix = "" if result.status == "finished" else f" ({result.status})"
                    axes.plot(
                        result.t,
                        getattr(result, name)[:, joint],
                        label=label + suffix,
                        **style,
                    )
                if name == "tau":  # the plant's torque limit of this joint
                    _draw_compare_limit(axes, group, joint)
                if is_learning:
                    mark_probe_end(axes, next(iter(group.values())), label=row == 0)
                if column == 0:
                    axes.set_ylabel(ylabel)
                if row < rows - 1:
                    axes.tick_params(labelbottom=False)
            top, bottom = grid[0, column], grid[-1, column]
            ends = [r.t[-1] for r in group.values() if r.t.size]
            if is_learning:
                bottom.set_xlabel("time t (s)")
                if ends and max(ends) > 0.0:
                    bottom.set_xlim(0.0, max(ends))
            else:
                if time_scale == "symlog":
                    bottom.set_xscale("symlog", linthresh=1.0)
                if ends and max(ends) > 0.0:
                    bottom.set_xlim(0.0, max(ends))
                note = ", linear to 1 s, then logarithmic" if time_scale == "symlog" else ""
                bottom.set_xlabel(f"time t (s{note})")
            top.legend(
                title=(
                    "learning runs (with probing)"
                    if len(group) > 1
                    else "learning run (with probing)"
                )
                if is_learning
                else "learned and fixed controllers",
                loc="lower center",
                bbox_to_anchor=(0.5, 1.02),
                ncols=min(len(group), 4),
                borderaxespad=0.0,
            )
    return figure


#: Figure name -> function; the names are the file stems written by save_figures.
FIGURES = {
    "fig2_critic_weights": plot_critic_weights,
    "fig3_actor_weights": plot_actor_weights,
    "fig4_errors": plot_errors,
    "torques": plot_torques,
    "model_parameters": plot_model_parameters,
}

#: The figures drawn only for an identifying run (``identifier.enabled``).
IDENTIFIER_FIGURES = ("model_parameters",)


def figure_names(result: SimulationResult) -> list[str]:
    """The names of :data:`FIGURES` that ``result`` has: all of them for an identifying run
    (``result.model_parameters`` is not None), the others without :data:`IDENTIFIER_FIGURES`."""
    identified = result.model_parameters is not None
    return [name for name in FIGURES if identified or name not in IDENTIFIER_FIGURES]


def plot_result(
    result: SimulationResult,
    which: str | Iterable[str] | None = None,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> dict[str, Figure] | Figure:
    """The figures of a run by name.

    Parameters
    ----------
    result : SimulationResult
        A run.
    which : str or iterable of str, optional
        Names from :data:`FIGURES`. A single name returns that figure alone; a list (or None,
        all of them: :func:`figure_names`, ``model_parameters`` only for an identifying run)
        returns a dict name -> Figure.
    ax, fig : optional
        Passed to the plot function; only with a single name in ``which``.

    Returns
    -------
    Figure or dict of str to Figure
    """
    single = isinstance(which, str)
    names = figure_names(result) if which is None else [which] if single else list(which)
    unknown = [name for name in names if name not in FIGURES]
    if unknown:
        raise ValueError(f"which: unknown figure(s) {unknown}; known: {', '.join(FIGURES)}")
    if not single and (ax is not None or fig is not None):
        raise ValueError("ax, fig: name one figure in which (e.g. which='fig4_errors')")
    if single:
        return FIGURES[names[0]](result, ax=ax, fig=fig)
    return {name: FIGURES[name](result) for name in names}


register("plot", lambda result, which=None, **kwargs: plot_result(result, which, **kwargs))
register("plot_comparison", lambda comparison, **kwargs: plot_comparison(comparison, **kwargs))
