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

import re
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ._files import save_figures
from .optimal import basis_names, optimal_weights
from .result import register, stop_time

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import SimulationResult

__all__ = [
    "FIGURES",
    "OKABE_ITO",
    "plot_actor_weights",
    "plot_comparison",
    "plot_critic_weights",
    "plot_errors",
    "plot_result",
    "plot_torques",
    "save_figures",
]

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
_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*")
_WIDTH = 7.5
_RC = {
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
_FLOOR = 1e-16  # log-scale panels show exact zeros at this value

Panel = Callable[["Axes"], None]


def _draw(
    panels: Sequence[Panel],
    *,
    ax: Axes | Sequence[Axes] | None,
    fig: Figure | None,
    height: float,
    title: str,
    ratios: Sequence[float] | None = None,
    width: float = _WIDTH,
) -> Figure:
    """Draw ``panels`` (functions of one Axes) into ``ax``, into new axes of ``fig``, or into a
    new figure of one column; returns the figure."""
    import matplotlib

    if ax is not None and fig is not None:
        raise ValueError("ax, fig: give at most one of them")
    with matplotlib.rc_context(_RC):
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


def _known_optimum(result: SimulationResult) -> np.ndarray | None:
    try:
        return optimal_weights(result.config)
    except ValueError:
        return None


def _label(name: str) -> str:
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


def _legend_outside(axes: Axes, **kwargs: Any) -> None:
    axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kwargs)


def _mark_probe_end(axes: Axes, result: SimulationResult, *, label: bool = True) -> None:
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


def _stop(result: SimulationResult) -> tuple[str, float] | None:
    """(status, time) of a run that did not finish, None for a finished one."""
    time = stop_time(result)
    return None if time is None else (result.status, time)


def _stop_label(result: SimulationResult) -> str:
    """ "diverged at t = 0.008 s" (empty for a finished run)."""
    stop = _stop(result)
    return "" if stop is None else f"{stop[0]} at t = {stop[1]:.4g} s"


def _title(title: str, result: SimulationResult) -> str:
    label = _stop_label(result)
    if not label:
        return title
    return f"{title}: {label.upper()[:1]}{label[1:]} (sim.T = {result.config.sim.T:g} s)"


def _mark_stop(axes: Axes, result: SimulationResult, *, label: bool = True) -> None:
    """A run that did not finish: a red vertical line where it stopped, the time after it shaded
    (a band of an eighth of the run, up to sim.T) and, if ``label``, "diverged at t = ... s"."""
    stop = _stop(result)
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


def _mark_last_row(axes: Axes, result: SimulationResult, values: np.ndarray) -> None:
    """A run that did not finish: its last recorded row's values marked in red at its time, a
    value beyond the axis at the axis' edge (a triangle pointing out), so the reader sees where
    the curves stop and what they were doing."""
    if _stop(result) is None or not result.t.size:
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


def _clip_transient(
    axes: Axes, values: np.ndarray, core: np.ndarray, *, least_margin: float = 1.0
) -> None:
    """Limit the y axis to ``core`` (the values that matter: W* and the second half of the run)
    with a margin (at least ``least_margin``) when the transient goes far beyond it, and say so
    on the panel."""
    low, high = float(np.min(core)), float(np.max(core))
    margin = max(0.3 * (high - low), least_margin)
    low, high = low - margin, high + margin
    v_low, v_high = float(np.min(values)), float(np.max(values))
    span = high - low
    if v_low >= low - 0.5 * span and v_high <= high + 0.5 * span:
        return  # the whole run fits without squeezing the final values
    axes.set_ylim(low, high)
    beyond = []
    if v_low < low:
        beyond.append(f"down to {v_low:.3g}")
    if v_high > high:
        beyond.append(f"up to {v_high:.3g}")
    axes.annotate(
        "transient clipped (" + ", ".join(beyond) + ")",
        xy=(0.995, 0.02),
        xycoords="axes fraction",
        ha="right",
        va="bottom",
        fontsize=7.5,
        color="0.3",
        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.8},
    )


def _weights_panel(result: SimulationResult, weights: np.ndarray, symbol: str) -> Panel:
    def panel(axes: Axes) -> None:
        target = _known_optimum(result)
        t = result.t
        every = max(1, t.size // 12)
        # stagger the markers of lines that end together (equal W*) so that each one shows
        values = target if target is not None else np.arange(weights.shape[1], dtype=float)
        offsets = []
        for i, value in enumerate(values):
            equal = np.flatnonzero(values == value)
            rank = int(np.flatnonzero(equal == i)[0])
            offsets.append(min(rank * every // len(equal), max(t.size - 1, 0)))
        for i, name in enumerate(basis_names(result.config)):
            label = _label(name)
            if target is not None:  # a value at round-off of 0 (a symmetric link's c) is 0
                value = 0.0 if abs(target[i]) < 1e-12 * np.abs(target).max() else target[i]
                label += f"  (W* = {value + 0.0:.4g})"
            axes.plot(
                t,
                weights[:, i],
                color=OKABE_ITO[i % len(OKABE_ITO)],
                lw=1.2,
                marker=_MARKERS[i % len(_MARKERS)],
                markersize=4,
                # staggered markers: lines that coincide (equal weights) still show each marker
                markevery=(offsets[i], every),
                label=label,
            )
        if target is not None:
            for i, value in enumerate(target):
                axes.axhline(
                    value,
                    color="k",
                    lw=1.6,
                    ls=(0, (4, 3)),
                    zorder=5,
                    label="analytic W*" if i == 0 else "_W*",
                )
            core = np.concatenate([target, weights[t.size // 2 :].ravel()])
        else:
            core = weights[t.size // 2 :].ravel() if t.size else np.zeros(1)
        if t.size:
            _clip_transient(axes, weights, core)
            _mark_last_row(axes, result, weights[-1])
        axes.set_ylabel(f"weight ${symbol}$\n{WEIGHT_UNIT}")
        axes.set_xlabel("time t (s)")
        _mark_probe_end(axes, result)
        _mark_stop(axes, result)
        _legend_outside(axes, title="basis function", ncols=_legend_columns(weights.shape[1]))

    return panel


#: The unit of a weight: V = W^T phi(x), so each weight carries the unit of V (the cost's) over
#: that of its basis term; the weights of one figure have different units.
WEIGHT_UNIT = "(unit of V / unit of its term)"

#: Weights named one by one in the legend of a weights figure: more are drawn in groups
#: (:func:`_weight_groups`) without per-weight legends. Legend rows per column.
_MAX_LEGEND_WEIGHTS = 12
_LEGEND_ROWS = 10


def _weight_groups(result: SimulationResult, size: int) -> list[tuple[str, str, np.ndarray]]:
    """The panels of a weights figure with more than _MAX_LEGEND_WEIGHTS weights, as (name,
    description, indices): a URDF arm's structured basis in its K block (the products of e1)
    and its inertia block (one function per base inertial parameter); any other basis in one."""
    names = basis_names(result.config)
    k = [i for i, name in enumerate(names) if name.startswith("e1_")]
    m = [i for i, name in enumerate(names) if name.startswith("e2'M_b e2")]
    if k and m and len(k) + len(m) == size:
        return [
            ("K block", "the products $e_{1,i}\\, e_{1,j}$", np.array(k)),
            (
                "inertia block",
                "$e_2^T M_b(q)\\, e_2$, one per\nbase inertial parameter",
                np.array(m),
            ),
        ]
    return [("all weights", "", np.arange(size))]


def _block_panel(
    result: SimulationResult, weights: np.ndarray, symbol: str, group: tuple[str, str, np.ndarray]
) -> Panel:
    """One group of many weights: each weight's distance to W* relative to the group's largest
    |W*| (W* is the zero line), or the weights themselves without a known W*; one legend entry
    per weight only for a small group, else a label on the panel."""
    name, description, index = group

    def panel(axes: Axes) -> None:
        target = _known_optimum(result)
        t = result.t
        names = basis_names(result.config)
        block = weights[:, index]
        if target is not None:
            reference = target[index]
            scale = float(np.max(np.abs(reference)))
            scale = scale if scale > 0.0 else 1.0
            values = (block - reference) / scale
            ylabel = f"$({symbol} - W^*) / \\max|W^*|$"
            axes.axhline(0.0, color="k", lw=1.6, ls=(0, (4, 3)), zorder=5, label="analytic W*")
            core = np.concatenate([[0.0], values[t.size // 2 :].ravel()])
        else:
            values = block
            ylabel = f"weight ${symbol}$\n{WEIGHT_UNIT}"
            core = values[t.size // 2 :].ravel() if t.size else np.zeros(1)
        few = index.size <= _MAX_LEGEND_WEIGHTS
        for j, i in enumerate(index):
            style: dict[str, Any] = {"color": OKABE_ITO[j % len(OKABE_ITO)]}
            if few:
                every = max(1, t.size // 12)
                style.update(marker=_MARKERS[j % len(_MARKERS)], markersize=4, markevery=every)
            axes.plot(
                t,
                values[:, j],
                lw=1.2 if few else 0.9,
                alpha=1.0 if few else 0.75,
                label=_label(names[i]) if few else "_weight",
                **style,
            )
        if t.size:
            _clip_transient(axes, values, core, least_margin=0.05 if target is not None else 1.0)
            _mark_last_row(axes, result, values[-1])
        if target is not None and values.size and np.ptp(axes.get_ylim()) < 0.02:
            axes.set_ylim(-0.01, 0.01)  # round-off about W* is not drawn as a movement
        axes.set_ylabel(ylabel)
        axes.set_xlabel("time t (s)")
        if not few:  # the panel's label where a legend would be
            scaled = "\n(each weight minus its W*,\nover the block's largest |W*|)"
            axes.text(
                1.01,
                1.0,
                f"{name}, {index.size} weights"
                + (f":\n{description}" if description else "")
                + (scaled if target is not None else ""),
                transform=axes.transAxes,
                ha="left",
                va="top",
                fontsize=8,
            )
        _mark_probe_end(axes, result)
        _mark_stop(axes, result)
        if few:
            _legend_outside(axes, title=name, ncols=_legend_columns(index.size))

    return panel


def _legend_columns(size: int) -> int:
    return max(1, -(-size // _LEGEND_ROWS))


def _relative_error_panel(
    result: SimulationResult,
    weights: np.ndarray,
    symbol: str,
    groups: Sequence[tuple[str, str, np.ndarray]] = (),
) -> Panel:
    """||W - W*|| / ||W*|| on a log scale (with each group's own error for a grouped figure), or
    without a known W* the distance to the final weights."""

    def panel(axes: Axes) -> None:
        target = _known_optimum(result)
        if target is None and result.t.size:
            # no analytic optimum: show how the weights settle, relative to where they end
            final = weights[-1]
            scale = max(float(np.linalg.norm(final)), np.finfo(float).tiny)
            change = np.linalg.norm(weights - final, axis=1) / scale
            axes.semilogy(
                result.t[:-1],
                np.maximum(change[:-1], _FLOOR),
                color="k",
                lw=1.2,
                label=f"$\\|{symbol}(t) - {symbol}(T)\\| / \\|{symbol}(T)\\|$\n(no analytic W*)",
            )
            _legend_outside(axes)
        elif target is not None:
            error = np.linalg.norm(weights - target, axis=1) / np.linalg.norm(target)
            axes.semilogy(
                result.t,
                np.maximum(error, _FLOOR),
                color="k",
                lw=1.2,
                label=f"$\\|{symbol} - W^*\\| / \\|W^*\\|$",
            )
            if groups:
                for (name, _, index), style in zip(groups, _BLOCK_STYLES, strict=False):
                    block = np.linalg.norm(weights[:, index] - target[index], axis=1)
                    norm = float(np.linalg.norm(target[index]))
                    axes.semilogy(
                        result.t,
                        np.maximum(block / (norm if norm > 0.0 else 1.0), _FLOOR),
                        lw=1.0,
                        label=name,
                        **style,
                    )
            tolerance = result.config.diagnostics.tolerance  # the verdict's band
            if not result.t.size:  # no rows: the tolerance line alone would give a flat range
                axes.set_ylim(1e-3 * tolerance, 10.0)
            axes.axhline(
                tolerance, color=OKABE_ITO[1], lw=0.9, ls="--", label=f"{100 * tolerance:g} %"
            )
            if groups and result.t.size:  # a block starting on W* does not stretch the axis
                least = float(np.min(np.maximum(error, _FLOOR)))
                axes.set_ylim(bottom=max(0.3 * _FLOOR, min(0.3 * least, 1e-3)))
            if result.t.size:
                _mark_last_error(axes, result, float(error[-1]))
            _legend_outside(axes)
        axes.set_ylabel("relative error" if target is not None else "relative distance")
        axes.set_xlabel("time t (s)")
        _mark_probe_end(axes, result, label=False)
        _mark_stop(axes, result, label=False)

    return panel


_BLOCK_STYLES = (
    {"color": OKABE_ITO[0], "ls": "-."},
    {"color": OKABE_ITO[2], "ls": (0, (1, 1.2))},
)


def _mark_last_error(axes: Axes, result: SimulationResult, error: float) -> None:
    """A run that did not finish: the relative error of its last row marked, and a note that it
    is not a result (an error of 1e-16 just before a divergence is no convergence)."""
    stop = _stop(result)
    if stop is None:
        return
    t_last = float(result.t[-1])
    axes.plot(
        [t_last],
        [max(error, _FLOOR)],
        marker="x",
        ms=6,
        mew=1.4,
        color=STOP_COLOR,
        ls="none",
        zorder=8,
        label="_last row",
    )
    e1 = float(np.linalg.norm(result.e1[-1]))
    low, high = np.log10(axes.get_ylim())
    top = np.log10(max(error, _FLOOR)) < 0.5 * (low + high)  # the text away from the curve's end
    axes.text(
        0.01,
        0.96 if top else 0.04,
        f"last row t = {t_last:.4g} s: error {error:.2g}, |e1| = {e1:.3g} rad; then "
        f"{stop[0]} at t = {stop[1]:.4g} s: not a result",
        transform=axes.transAxes,
        ha="left",
        va="top" if top else "bottom",
        fontsize=7.5,
        color=STOP_COLOR,
        zorder=9,
        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85},
    )


def _weights_figure(
    result: SimulationResult,
    weights: np.ndarray,
    symbol: str,
    title: str,
    ax: Axes | Sequence[Axes] | None,
    fig: Figure | None,
) -> Figure:
    size = weights.shape[1]
    title = _title(title, result)
    if size <= _MAX_LEGEND_WEIGHTS:
        panels = [
            _weights_panel(result, weights, symbol),
            _relative_error_panel(result, weights, symbol),
        ]
        return _draw(
            panels,
            ax=ax,
            fig=fig,
            height=5.2,
            title=title,
            ratios=(2.2, 1.0),
            width=_WIDTH + 1.3 * (_legend_columns(size) - 1),  # the legend's extra columns
        )
    groups = _weight_groups(result, size)
    known = _known_optimum(result) is not None
    panels = [_block_panel(result, weights, symbol, group) for group in groups]
    panels.append(_relative_error_panel(result, weights, symbol, groups if known else ()))
    legends = [group[2].size for group in groups if group[2].size <= _MAX_LEGEND_WEIGHTS]
    extra = max((_legend_columns(n) - 1 for n in legends), default=0)
    return _draw(
        panels,
        ax=ax,
        fig=fig,
        height=2.3 * len(groups) + 2.0,
        title=title,
        ratios=(*[1.6] * len(groups), 1.2),
        width=_WIDTH + 1.3 * extra,
    )


def plot_critic_weights(
    result: SimulationResult,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """Figure 2: the critic weights Wc(t) (eq. 23) and their relative error to W*.

    Parameters
    ----------
    result : SimulationResult
        A run (:func:`adparm.simulate`).
    ax : Axes or sequence of Axes, optional
        Draw into these: the first gets the weights, a second the log-scale relative error
        ||Wc - W*|| / ||W*||.
    fig : Figure, optional
        Add the two panels to this figure.

    Returns
    -------
    matplotlib.figure.Figure
        Top: each weight over time with the analytic W* as black dashes (values in the legend;
        markers tell apart weights whose curves coincide). If a transient would squeeze the final
        values into a thin band, the y axis is limited to the range that matters and the panel says
        how far the transient went. Bottom: the relative error on a log scale, with the verdict's
        tolerance (diagnostics.tolerance, 1 %) as a line.
        More than 12 weights (a URDF arm's structured basis) take one panel per block (the K
        block, the inertia block; ``ax`` then takes up to three Axes), each weight drawn as
        ``(W - W*) / max |W*|`` of its block, named in a legend only for a block of at most 12; the
        error panel adds each block's relative error. A run that diverged or was interrupted
        is marked where it stopped (see the module's notes).
    """
    return _weights_figure(
        result,
        result.critic_weights,
        "\\hat W_c",
        "Critic weights $\\hat W_c$ (Figure 2)",
        ax,
        fig,
    )


def plot_actor_weights(
    result: SimulationResult,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """Figure 3: the actor weights Wa(t) (eq. 26) and their relative error to W*.

    Parameters and layout as :func:`plot_critic_weights`.
    """
    return _weights_figure(
        result,
        result.actor_weights,
        "\\hat W_a",
        "Actor weights $\\hat W_a$ (Figure 3)",
        ax,
        fig,
    )


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
) -> Panel:
    def panel(axes: Axes) -> None:
        if note:  # above the panel, off the data
            axes.set_title(note, fontsize=7.5, loc="left", color="0.25")
        for j in range(values.shape[1]):  # one line per joint
            y = np.maximum(np.abs(values[:, j]), _FLOOR) if log else values[:, j]
            axes.plot(result.t, y, lw=1.0, label=label.format(j=j + 1), **_joint_style(j))
        if log:
            axes.set_yscale("log")
        axes.set_ylabel(ylabel)
        axes.set_xlabel("time t (s)")
        _mark_probe_end(axes, result, label=annotate_probe)
        _mark_stop(axes, result, label=annotate_probe)
        _legend_outside(axes)

    return panel


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
    panels = [
        _joint_panel(result, result.q, "q (rad)", "$q_{j}$", annotate_probe=True),
        _joint_panel(result, result.e1, "$e_1$ (rad)", "$e_{{1,{j}}}$"),
        _joint_panel(result, result.e2, "$e_2$ (rad/s)", "$e_{{2,{j}}}$"),
        _joint_panel(result, result.e1, "$|e_1|$ (rad)", "$|e_{{1,{j}}}|$", log=True),
    ]
    title = _title("Joint angles and tracking errors (Figure 4)", result)
    return _draw(panels, ax=ax, fig=fig, height=6.4, title=title)


def plot_torques(
    result: SimulationResult,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """The applied joint torques tau and the probing signal.

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
    panels = [
        _joint_panel(
            result, result.tau, "torque $\\tau$ (N m)", "$\\tau_{j}$", annotate_probe=True
        ),
        _joint_panel(
            result, result.probe, "probing signal (N m)", "probe$_{j}$", note=probe_note(result)
        ),
    ]
    title = _title("Applied torques and probing signal", result)
    return _draw(panels, ax=ax, fig=fig, height=4.2, title=title)


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
    if rms.size <= 3:
        sizes = (
            "probe "
            + ", ".join(f"{v:.3g}" for v in rms)
            + " N m, $\\tau$ "
            + ", ".join(f"{v:.3g}" for v in tau_rms)
            + " N m"
        )
    else:
        sizes = f"probe up to {rms.max():.3g} N m, $\\tau$ up to {tau_rms.max():.3g} N m"
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


def _compare_panels(joints: int) -> list[tuple[str, int, str]]:
    """(result attribute, joint, y label) of each row: e1 of every joint, then tau."""
    return [("e1", j, f"$e_{{1,{j + 1}}}$ (rad)") for j in range(joints)] + [
        ("tau", j, f"$\\tau_{j + 1}$ (N m)") for j in range(joints)
    ]


def plot_comparison(
    comparison: Any,
    *,
    time_scale: str = "symlog",
    ax: Sequence[Axes] | np.ndarray | None = None,
    fig: Figure | None = None,
) -> Figure:
    """Controllers side by side (:func:`adparm.compare`): e1 and tau of each joint.

    The learning run (``adp``, with its probing) has its own column on the left, on a linear
    time axis with the end of probing marked; the controllers that do not learn during the run
    (``adp (learned)``, ``rise``, ``pd``, ``optimal``) share the right-hand column, each in its
    own colour and line style (:data:`CONTROLLER_STYLES`). Without an ``adp`` row the figure has
    the right-hand column only.

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
    learning = {label: r for label, r in results.items() if label == "adp"}
    others = {label: r for label, r in results.items() if label != "adp"}
    groups = [g for g in (learning, others) if g]
    joints = next(iter(results.values())).q.shape[1] if results else 2
    panels = _compare_panels(joints)
    rows = len(panels)
    with matplotlib.rc_context(_RC):
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
                    figsize=(_WIDTH + 1.0 * (len(groups) - 1), 1.7 * rows), layout="constrained"
                )
            figure = fig
            grid = figure.subplots(rows, len(groups), sharex="col", squeeze=False)
            figure.suptitle("Controllers compared: tracking errors and applied torques")
        for column, group in enumerate(groups):
            is_learning = group is learning
            for row, (name, joint, ylabel) in enumerate(panels):
                axes = grid[row, column]
                for label, result in group.items():
                    style = _LEARNING_STYLE if is_learning else CONTROLLER_STYLES.get(label, {})
                    suffix = "" if result.status == "finished" else f" ({result.status})"
                    axes.plot(
                        result.t,
                        getattr(result, name)[:, joint],
                        label=label + suffix,
                        **style,
                    )
                if is_learning:
                    _mark_probe_end(axes, group["adp"], label=row == 0)
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
                title="learning run (with probing)"
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
}


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
        all of them) returns a dict name -> Figure.
    ax, fig : optional
        Passed to the plot function; only with a single name in ``which``.

    Returns
    -------
    Figure or dict of str to Figure
    """
    single = isinstance(which, str)
    names = list(FIGURES) if which is None else [which] if single else list(which)
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
