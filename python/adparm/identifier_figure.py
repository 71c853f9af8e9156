"""The figure of an identifying run ([identifier], issue 25): the estimate beta_hat of each base
parameter relative to the plant's beta (known in simulation), and the history stack's minimum
singular value against its threshold. adparm.plotting re-exports plot_model_parameters."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .identification import identified_parameters, identifier_diagnosis
from .optimal import base_parameter_names, base_parameters

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import SimulationResult
from ._figure_style import (
    MARKERS,
    OKABE_ITO,
    WIDTH,
    Panel,
    draw,
    figure_title,
    legend_outside,
    mark_last_row,
    mark_probe_end,
    mark_stop,
)

#: Parameters named one by one in the legend; more (a URDF arm's 10-60) are drawn without.
_MAX_LEGEND_PARAMETERS = 12

_TWO_LINK_LABELS = {
    "p1": "p_1",
    "p2": "p_2",
    "p3": "p_3",
    "g1": "g_1",
    "g2": "g_2",
    "coulomb": "f_c",
    "viscous": "f_v",
}


def parameter_label(name: str) -> str:
    """A base parameter's legend label: mathtext for the two-link arm's symbols, the URDF
    arm's inertial parameter names as they are."""
    return f"${_TWO_LINK_LABELS[name]}$" if name in _TWO_LINK_LABELS else name


#: A plant parameter this small relative to the largest |beta_i| is drawn as 0 (not as a ratio).
ZERO_PARAMETER = 1e-9


def relative_parameters(result: SimulationResult) -> tuple[np.ndarray, list[int], list[int]]:
    """(beta_hat / beta over time for the drawn parameters, their indices, the indices of the
    identified parameters whose plant value is 0, which have no relative value). A plant value
    within ZERO_PARAMETER of the largest |beta_i| counts as 0: a URDF arm's base parameters hold
    round-off zeros (a planar arm's mc_z of 1e-17 beside 2 kg m), whose ratio would be noise."""
    beta = base_parameters(result.config, "plant")
    identified = identified_parameters(result.config)
    floor = ZERO_PARAMETER * float(np.abs(beta).max()) if beta.size else 0.0
    drawn = [i for i in identified if abs(beta[i]) > floor]
    zero = [i for i in identified if abs(beta[i]) <= floor]
    estimate = np.asarray(result.model_parameters, dtype=float)
    return estimate[:, drawn] / beta[drawn], drawn, zero


def _note(result: SimulationResult, zero: list[int]) -> str | None:
    """What the relative panel leaves out: the parameters not identified (at the model's value)
    and those with beta = 0 (their final estimate)."""
    names = base_parameter_names(result.config)
    identified = set(identified_parameters(result.config))
    kept = [names[i] for i in range(len(names)) if i not in identified]
    parts = []
    if kept:
        parts.append("not identified (the model's values): " + ", ".join(kept))
    if zero and result.t.size:
        final = np.asarray(result.model_parameters, dtype=float)[-1]
        parts.append(
            "plant value 0, not drawn: "
            + ", ".join(f"{names[i]} ends at {final[i]:.3g}" for i in zero)
        )
    # one line per part, wrapped to the panel: a list of URDF parameters runs past the figure
    return "\n".join(textwrap.fill(part, 120) for part in parts) or None


def _focus(axes: Axes, result: SimulationResult, values: np.ndarray) -> str | None:
    """Sets the y range of the ratios from the time the stack became informative (at least 0.9
    to 1.1) when earlier ratios reach further, and says so: a URDF arm's dozens of parameters
    swing far while the stack is not informative, which would flatten the convergence."""
    informative = identifier_diagnosis(result)
    start = None if informative is None else informative["informative_time"]
    if start is None or not values.size or not np.all(np.isfinite(values)):
        return None
    later = values[result.t >= start]
    low, high = min(float(later.min()), 0.9), max(float(later.max()), 1.1)
    if values.min() >= low and values.max() <= high:
        return None
    pad = 0.05 * (high - low)
    axes.set_ylim(low - pad, high + pad)
    return (
        f"y range of the values from t = {start:.3g} s (the stack informative); before, they "
        f"reach {values.min():.3g} to {values.max():.3g}"
    )


def _parameters_panel(result: SimulationResult) -> Panel:
    def panel(axes: Axes) -> None:
        values, drawn, zero = relative_parameters(result)
        names = base_parameter_names(result.config)
        beta = base_parameters(result.config, "plant")
        t = result.t
        few = len(drawn) <= _MAX_LEGEND_PARAMETERS
        every = max(1, t.size // 12)
        for j, i in enumerate(drawn):
            style: dict[str, Any] = {"color": OKABE_ITO[j % len(OKABE_ITO)]}
            if few:  # staggered markers: lines that coincide (near 1) still show each one
                offset = min(j * every // max(len(drawn), 1), max(t.size - 1, 0))
                style.update(marker=MARKERS[j % len(MARKERS)], markersize=4)
                style["markevery"] = (offset, every)
            symbol = parameter_label(names[i])
            many = f"{len(drawn)} base parameters,\neach estimate over\nthe plant's value"
            axes.plot(
                t,
                values[:, j],
                lw=1.2 if few else 0.9,
                alpha=1.0 if few else 0.75,
                label=f"{symbol}  (plant {beta[i]:.4g})" if few else (many if j == 0 else "_"),
                **style,
            )
        axes.axhline(1.0, color="k", lw=1.6, ls=(0, (4, 3)), zorder=5, label="plant's $\\beta$")
        if t.size and values.size:
            mark_last_row(axes, result, values[-1])
        axes.set_ylabel("$\\hat\\beta_i / \\beta_i$")
        axes.set_xlabel("time t (s)")
        focus = None if few else _focus(axes, result, values)  # many lines: a closer range
        note = "\n".join(part for part in (_note(result, zero), focus) if part)
        if note:  # above the panel, off the data; the figure's title moves above it
            import matplotlib

            title = axes.get_title()
            if title:
                axes.figure.suptitle(title, fontsize=matplotlib.rcParams["axes.titlesize"])
                axes.set_title("")
            axes.set_title(note, fontsize=7.5, loc="left", color="0.25")
        mark_probe_end(axes, result)
        mark_stop(axes, result)
        legend_outside(axes, title="estimate / plant" if few else None)

    return panel


def _singular_value_panel(result: SimulationResult) -> Panel:
    def panel(axes: Axes) -> None:
        threshold = result.config.identifier.singular_value_threshold
        sigma = np.asarray(result.stack_singular_value, dtype=float)
        positive = np.where(sigma > 0.0, sigma, np.nan)  # an empty stack (0) is not drawn
        axes.set_yscale("log")
        # the range before any line: the threshold and the values drawn (the threshold alone
        # would autoscale to an empty range)
        finite = positive[np.isfinite(positive)]
        low = min(float(np.min(finite)) if finite.size else threshold, threshold)
        high = max(float(np.max(finite)) if finite.size else threshold, threshold)
        axes.set_ylim(0.3 * low, 3.0 * high)
        if np.any(sigma > 0.0):  # an all-empty stack draws no line (nothing on a log axis)
            axes.plot(result.t, positive, color="k", lw=1.2, label="$\\sigma_{\\min}$ of the stack")
        axes.axhline(
            threshold,
            color=OKABE_ITO[1],
            lw=0.9,
            ls="--",
            label=f"threshold {threshold:g}\n(identifier.singular_value_\nthreshold)",
        )
        diagnosis = identifier_diagnosis(result)
        if diagnosis is not None and diagnosis["informative_time"] is not None:
            time = diagnosis["informative_time"]
            axes.axvline(
                time,
                color=OKABE_ITO[2],
                lw=1.1,
                ls="-.",
                label=f"informative from\nt = {time:.3g} s",
            )
        elif result.t.size:
            axes.text(
                0.01,
                0.96,
                "the stack never became informative"
                + ("" if finite.size else " (its minimum singular value stayed 0)"),
                transform=axes.transAxes,
                ha="left",
                va="top",
                fontsize=8,
                color=OKABE_ITO[1],
            )
        axes.set_ylabel("stack's minimum\nsingular value")
        axes.set_xlabel("time t (s)")
        mark_probe_end(axes, result, label=False)
        mark_stop(axes, result, label=False)
        legend_outside(axes)

    return panel


def plot_model_parameters(
    result: SimulationResult,
    *,
    ax: Axes | Sequence[Axes] | None = None,
    fig: Figure | None = None,
) -> Figure:
    """The online identifier's estimate against the plant (a run with ``identifier.enabled``).

    Parameters
    ----------
    result : SimulationResult
        An identifying run (``result.model_parameters`` is not None).
    ax : Axes or sequence of Axes, optional
        Draw into these: the first gets the estimates, a second the stack's singular value.
    fig : Figure, optional
        Add the two panels to this figure.

    Returns
    -------
    matplotlib.figure.Figure
        Top: each identified base parameter's estimate over the plant's value,
        beta_hat_i(t) / beta_i (parameters of different units share the axis), with the plant
        at 1 as black dashes; the parameters not identified, and those whose plant value is 0,
        are named over the panel. Bottom: the history stack's minimum singular value (log
        scale; an empty stack is not drawn) with ``identifier.singular_value_threshold`` and
        the time the stack became informative (or a note that it never did).
    """
    if result.model_parameters is None or result.stack_singular_value is None:
        raise ValueError(
            "identifier.enabled: the model_parameters figure needs an identifying run "
            "(this run has no model_parameters)"
        )
    panels = [_parameters_panel(result), _singular_value_panel(result)]
    title = figure_title("Identified model parameters against the plant's", result)
    return draw(panels, ax=ax, fig=fig, height=5.0, title=title, ratios=(2.0, 1.0), width=WIDTH)
