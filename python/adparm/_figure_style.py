"""The look shared by every figure of adparm.plotting: the Okabe-Ito palette, the rc settings,
the drawing of a panel, the probe-end and stop marks, labels and titles."""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .optimal import optimal_weights
from .result import stop_time

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import SimulationResult

#: The Okabe-Ito colour-blind-safe palette without black (black is kept for references):
#: blue, vermillion, bluish green, orange, reddish purple, sky blue, yellow-brown, grey.
OKABE_ITO = (
    "#0072B2",
    "#D55E00",
    "#009E73",
    "#E69F00",
    "#CC79A7",
    "#56B4E9",
    "#8C6D00",
    "#7F7F7F",
)
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*")
WIDTH = 7.5
RC = {
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "svg.hashsalt": "adparm",  # reproducible SVG ids
}
FLOOR = 1e-16  # log-scale panels show exact zeros at this value

Panel = Callable[["Axes"], None]


def draw(
    panels: Sequence[Panel],
    *,
    ax: Axes | Sequence[Axes] | None,
    fig: Figure | None,
    height: float,
    title: str,
    ratios: Sequence[float] | None = None,
    width: float = WIDTH,
) -> Figure:
    """Draw ``panels`` (functions of one Axes) into ``ax``, into new axes of ``fig``, or into a
    new figure of one column; returns the figure."""
    import matplotlib

    if ax is not None and fig is not None:
        raise ValueError("ax, fig: give at most one of them")
    with matplotlib.rc_context(RC):
        if ax is not None:
            axes = [ax] if not isinstance(ax, Sequence | np.ndarray) else list(np.ravel(ax))
            if not 1 <= len(axes) <= len(panels):
                raise ValueError(f"ax: expected 1 to {len(panels)} Axes, got {len(axes)}")
            figure = axes[0].figure
        else:
            if fig is None:
                from matplotlib.figure import Figure

                fig = Figure(figsize=(width, height), layout="constrained")
            figure = fig
            grid = figure.subplots(len(panels), 1, sharex=True, squeeze=False, height_ratios=ratios)
            axes = list(grid[:, 0])
            axes[0].set_title(title)
        for axes_i, panel in zip(axes, panels, strict=False):
            panel(axes_i)
        for axes_i in axes[:-1]:
            if axes_i.get_shared_x_axes().joined(axes_i, axes[-1]):
                axes_i.tick_params(labelbottom=False)
                axes_i.set_xlabel("")
    return figure


def known_optimum(result: SimulationResult) -> np.ndarray | None:
    try:
        return optimal_weights(result.config)
    except ValueError:
        return None


def figure_label(name: str) -> str:
    """A basis function's legend label: mathtext for the symbols, plain text for the names of a
    URDF arm's inertial parameters (which have underscores of their own)."""
    if name.startswith("e2'M_b e2"):  # URDF structured basis: e2'M_b e2 (I_yy link1)
        return r"$e_2^T M_b(q)\, e_2$" + name[len("e2'M_b e2") :]
    if name.startswith("e1_"):  # URDF structured basis: e1_i e1_j, e1_i^2
        return "$" + re.sub(r"e1_(\d+)", r"e_{1,\1}", name).replace(" ", r"\,") + "$"
    return f"${_tex(name)}$"


def _tex(name: str) -> str:
    if name.startswith("e2^T M"):  # structured basis: e2^T M_k(q) e2
        k = name[len("e2^T M")]
        return rf"e_2^T M_{k}{'(q)' if '(q)' in name else ''}\, e_2"
    return name.replace("cos x2", r"\cos x_2").replace("x", "x_").replace("x__", "x_")


def legend_outside(axes: Axes, **kwargs: Any) -> None:
    axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kwargs)


def mark_probe_end(axes: Axes, result: SimulationResult, *, label: bool = True) -> None:
    """A dotted vertical line where probing stops (if it stops inside the run), labelled."""
    until = result.config.probe.until
    if result.t.size and 0.0 < until < result.t[-1]:
        axes.axvline(until, color="0.3", lw=0.9, ls=":", zorder=1)
        if label:
            axes.annotate(
                "probing ends",
                xy=(until, 1.0),
                xycoords=("data", "axes fraction"),
                xytext=(3, -3),
                textcoords="offset points",
                ha="left",
                va="top",
                fontsize=7.5,
                color="0.3",
            )


#: The colour of a run's end when it did not finish (its divergence or interruption).
STOP_COLOR = "#C00000"


def figure_stop(result: SimulationResult) -> tuple[str, float] | None:
    """(status, time) of a run that did not finish, None for a finished one."""
    time = stop_time(result)
    return None if time is None else (result.status, time)


def _stop_label(result: SimulationResult) -> str:
    """ "diverged at t = 0.008 s" (empty for a finished run)."""
    stop = figure_stop(result)
    return "" if stop is None else f"{stop[0]} at t = {stop[1]:.4g} s"


def figure_title(title: str, result: SimulationResult) -> str:
    label = _stop_label(result)
    if not label:
        return title
    return f"{title}: {label.upper()[:1]}{label[1:]} (sim.T = {result.config.sim.T:g} s)"


def mark_stop(axes: Axes, result: SimulationResult, *, label: bool = True) -> None:
    """A run that did not finish: a red vertical line where it stopped, the time after it shaded
    (a band of an eighth of the run, up to sim.T) and, if ``label``, "diverged at t = ... s"."""
    stop = figure_stop(result)
    if stop is None:
        return
    status, time = stop
    right = min(result.config.sim.T, time + max(0.12 * time, result.config.sim.dt))
    if right > time:
        axes.axvspan(time, right, color=STOP_COLOR, alpha=0.12, lw=0, zorder=0)
    axes.axvline(time, color=STOP_COLOR, lw=1.5, zorder=6, label="_stop")
    if label:
        axes.annotate(
            f"{status} at t = {time:.4g} s",
            xy=(time, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(-4, -4),
            textcoords="offset points",
            ha="right",
            va="top",
            fontsize=8,
            fontweight="bold",
            color=STOP_COLOR,
            zorder=7,
            bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": STOP_COLOR, "alpha": 0.9},
        )


def mark_last_row(axes: Axes, result: SimulationResult, values: np.ndarray) -> None:
    """A run that did not finish: its last recorded row's values marked in red at its time, a
    value beyond the axis at the axis' edge (a triangle pointing out), so the reader sees where
    the curves stop and what they were doing."""
    if figure_stop(result) is None or not result.t.size:
        return
    t_last = float(result.t[-1])
    low, high = axes.get_ylim()
    last = np.asarray(values, dtype=float).reshape(-1)
    style = {"color": STOP_COLOR, "ls": "none", "zorder": 8, "clip_on": False}
    inside = last[(last >= low) & (last <= high)]
    if inside.size:
        axes.plot(np.full(inside.size, t_last), inside, marker="x", ms=5, mew=1.3, **style)
    for beyond, edge, marker in ((last > high, high, "^"), (last < low, low, "v")):
        if beyond.any():
            axes.plot([t_last], [edge], marker=marker, ms=7, **style)
