"""The weight figures of a run (Figures 2 and 3 of the paper): each weight against the analytic
optimum W*, the grouped blocks of a large basis, and the relative error ||W - W*|| / ||W*||.
adparm.plotting re-exports plot_critic_weights and plot_actor_weights."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .optimal import basis_names

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import SimulationResult
from ._figure_style import (
    FLOOR,
    MARKERS,
    OKABE_ITO,
    STOP_COLOR,
    WIDTH,
    Panel,
    draw,
    figure_label,
    figure_stop,
    figure_title,
    known_optimum,
    legend_outside,
    mark_last_row,
    mark_probe_end,
    mark_stop,
)


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
        target = known_optimum(result)
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
            label = figure_label(name)
            if target is not None:  # a value at round-off of 0 (a symmetric link's c) is 0
                value = 0.0 if abs(target[i]) < 1e-12 * np.abs(target).max() else target[i]
                label += f"  (W* = {value + 0.0:.4g})"
            axes.plot(
                t,
                weights[:, i],
                color=OKABE_ITO[i % len(OKABE_ITO)],
                lw=1.2,
                marker=MARKERS[i % len(MARKERS)],
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
            mark_last_row(axes, result, weights[-1])
        axes.set_ylabel(f"weight ${symbol}$\n{WEIGHT_UNIT}")
        axes.set_xlabel("time t (s)")
        mark_probe_end(axes, result)
        mark_stop(axes, result)
        legend_outside(axes, title="basis function", ncols=_legend_columns(weights.shape[1]))

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
        target = known_optimum(result)
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
                style.update(marker=MARKERS[j % len(MARKERS)], markersize=4, markevery=every)
            axes.plot(
                t,
                values[:, j],
                lw=1.2 if few else 0.9,
                alpha=1.0 if few else 0.75,
                label=figure_label(names[i]) if few else "_weight",
                **style,
            )
        if t.size:
            _clip_transient(axes, values, core, least_margin=0.05 if target is not None else 1.0)
            mark_last_row(axes, result, values[-1])
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
        mark_probe_end(axes, result)
        mark_stop(axes, result)
        if few:
            legend_outside(axes, title=name, ncols=_legend_columns(index.size))

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
        target = known_optimum(result)
        if target is None and result.t.size:
            # no analytic optimum: show how the weights settle, relative to where they end
            final = weights[-1]
            scale = max(float(np.linalg.norm(final)), np.finfo(float).tiny)
            change = np.linalg.norm(weights - final, axis=1) / scale
            axes.semilogy(
                result.t[:-1],
                np.maximum(change[:-1], FLOOR),
                color="k",
                lw=1.2,
                label=f"$\\|{symbol}(t) - {symbol}(T)\\| / \\|{symbol}(T)\\|$\n(no analytic W*)",
            )
            legend_outside(axes)
        elif target is not None:
            error = np.linalg.norm(weights - target, axis=1) / np.linalg.norm(target)
            axes.semilogy(
                result.t,
                np.maximum(error, FLOOR),
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
                        np.maximum(block / (norm if norm > 0.0 else 1.0), FLOOR),
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
                least = float(np.min(np.maximum(error, FLOOR)))
                axes.set_ylim(bottom=max(0.3 * FLOOR, min(0.3 * least, 1e-3)))
            if result.t.size:
                _mark_last_error(axes, result, float(error[-1]))
            legend_outside(axes)
        axes.set_ylabel("relative error" if target is not None else "relative distance")
        axes.set_xlabel("time t (s)")
        mark_probe_end(axes, result, label=False)
        mark_stop(axes, result, label=False)

    return panel


_BLOCK_STYLES = (
    {"color": OKABE_ITO[0], "ls": "-."},
    {"color": OKABE_ITO[2], "ls": (0, (1, 1.2))},
)


def _mark_last_error(axes: Axes, result: SimulationResult, error: float) -> None:
    """A run that did not finish: the relative error of its last row marked, and a note that it
    is not a result (an error of 1e-16 just before a divergence is no convergence)."""
    stop = figure_stop(result)
    if stop is None:
        return
    t_last = float(result.t[-1])
    axes.plot(
        [t_last],
        [max(error, FLOOR)],
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
    top = np.log10(max(error, FLOOR)) < 0.5 * (low + high)  # the text away from the curve's end
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
    title = figure_title(title, result)
    if size <= _MAX_LEGEND_WEIGHTS:
        panels = [
            _weights_panel(result, weights, symbol),
            _relative_error_panel(result, weights, symbol),
        ]
        return draw(
            panels,
            ax=ax,
            fig=fig,
            height=5.2,
            title=title,
            ratios=(2.2, 1.0),
            width=WIDTH + 1.3 * (_legend_columns(size) - 1),  # the legend's extra columns
        )
    groups = _weight_groups(result, size)
    known = known_optimum(result) is not None
    panels = [_block_panel(result, weights, symbol, group) for group in groups]
    panels.append(_relative_error_panel(result, weights, symbol, groups if known else ()))
    legends = [group[2].size for group in groups if group[2].size <= _MAX_LEGEND_WEIGHTS]
    extra = max((_legend_columns(n) - 1 for n in legends), default=0)
    return draw(
        panels,
        ax=ax,
        fig=fig,
        height=2.3 * len(groups) + 2.0,
        title=title,
        ratios=(*[1.6] * len(groups), 1.2),
        width=WIDTH + 1.3 * extra,
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
