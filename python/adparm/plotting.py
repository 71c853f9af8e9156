"""Figures of a run (matplotlib): the paper's Figures 2-4 plus torques and the probing signal.

Each function takes a :class:`adparm.SimulationResult` and returns a matplotlib Figure sized for a
paper column pair (7 x 4.2 in, 9 pt text). Weights are labelled with the basis functions of
adparm.BASIS_NAMES; the analytic W* (ERRATA.md) is drawn dashed in the same colour when it exists.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .optimal import basis_names, optimal_weights

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from .comparison import Comparison
    from .simulation import SimulationResult

__all__ = [
    "FIGURES",
    "plot_actor_weights",
    "plot_comparison",
    "plot_critic_weights",
    "plot_errors",
    "plot_result",
    "plot_torques",
    "save_figures",
]

_FIGSIZE = (7.0, 4.2)
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


def _figure(rows: int = 1, figsize: tuple[float, float] = _FIGSIZE) -> Figure:
    from matplotlib.figure import Figure

    figure = Figure(figsize=figsize, layout="constrained")
    figure.subplots(rows, 1, sharex=True, squeeze=False)
    return figure


def _known_optimum(result: SimulationResult) -> np.ndarray | None:
    try:
        return optimal_weights(result.config)
    except ValueError:
        return None


def _weights(result: SimulationResult, weights: np.ndarray, title: str) -> Figure:
    import matplotlib

    with matplotlib.rc_context(_RC):
        figure = _figure()
        axes = figure.axes[0]
        target = _known_optimum(result)
        colours = matplotlib.colormaps["tab10"].colors
        for i, name in enumerate(basis_names(result.config)):
            colour = colours[i % len(colours)]
            axes.plot(result.t, weights[:, i], color=colour, lw=1.1, label=f"${_tex(name)}$")
            if target is not None:
                axes.axhline(target[i], color=colour, lw=0.9, ls="--")
        axes.set_xlabel("time t (s)")
        axes.set_ylabel("weight (-)")
        axes.set_title(title + ("  (dashed: analytic W*)" if target is not None else ""))
        axes.legend(ncols=4, loc="upper right", framealpha=0.85)
        _mark_probe_end(axes, result)
    return figure


def _tex(name: str) -> str:
    if name.startswith("e2^T M"):  # structured basis: e2^T M_k(q) e2
        k = name[len("e2^T M")]
        return rf"e_2^T M_{k}{'(q)' if '(q)' in name else ''}\, e_2"
    return name.replace("cos x2", r"\cos x_2").replace("x", "x_").replace("x__", "x_")


def _mark_probe_end(axes: Any, result: SimulationResult) -> None:
    until = result.config.probe.until
    if result.t.size and 0.0 < until < result.t[-1]:
        axes.axvline(until, color="0.4", lw=0.8, ls=":")


def plot_critic_weights(result: SimulationResult) -> Figure:
    """Figure 2: critic weights Wc(t) (eq. 23) with W* dashed."""
    return _weights(result, result.critic_weights, "Critic weights $\\hat W_c$ (Figure 2)")


def plot_actor_weights(result: SimulationResult) -> Figure:
    """Figure 3: actor weights Wa(t) (eq. 26) with W* dashed."""
    return _weights(result, result.actor_weights, "Actor weights $\\hat W_a$ (Figure 3)")


def _joint_panels(
    result: SimulationResult,
    title: str,
    panels: list[tuple[np.ndarray, str, str]],
    linewidth: float,
) -> Figure:
    """One panel per (array (n, 2), y label, legend label with {j} for the joint) over time."""
    import matplotlib

    with matplotlib.rc_context(_RC):
        figure = _figure(len(panels))
        for axes, (values, ylabel, label) in zip(figure.axes, panels, strict=True):
            for j in range(2):
                axes.plot(result.t, values[:, j], lw=linewidth, label=label.format(j=j + 1))
            axes.set_ylabel(ylabel)
            axes.legend(loc="upper right", ncols=2)
            _mark_probe_end(axes, result)
        figure.axes[-1].set_xlabel("time t (s)")
        figure.axes[0].set_title(title)
    return figure


def plot_errors(result: SimulationResult) -> Figure:
    """Figure 4: joint angles q, tracking errors e1 = qd - q and filtered errors e2."""
    panels = [
        (result.q, "q (rad)", "$q_{j}$"),
        (result.e1, "$e_1$ (rad)", "$e_{{1,{j}}}$"),
        (result.e2, "$e_2$ (rad/s)", "$e_{{2,{j}}}$"),
    ]
    return _joint_panels(result, "Joint angles and tracking errors (Figure 4)", panels, 1.0)


def plot_torques(result: SimulationResult) -> Figure:
    """Applied joint torques tau and the probing signal."""
    panels = [
        (result.tau, "torque $\\tau$ (N m)", "$\\tau_{j}$"),
        (result.probe, "probing signal (N m)", "probe$_{j}$"),
    ]
    return _joint_panels(result, "Applied torques and probing signal", panels, 0.8)


def plot_comparison(comparison: Comparison, *, time_scale: str = "symlog") -> Figure:
    """Controllers side by side (adparm.compare): tracking error e1 and applied torque tau of each
    joint in four panels over a shared time axis, one line per controller (same colour in every
    panel; optimal black dashed). The dotted line marks the end of the adp run's probing.

    ``time_scale``: ``"symlog"`` (default: linear up to 1 s, logarithmic after, so that the
    transients of the first second and the 100 s of probing both show) or ``"linear"``."""
    import matplotlib

    if time_scale not in ("symlog", "linear"):
        raise ValueError(f"time_scale: expected 'symlog' or 'linear', got {time_scale!r}")
    panels = [
        ("e1", 0, "$e_{1,1}$ (rad)"),
        ("e1", 1, "$e_{1,2}$ (rad)"),
        ("tau", 0, "$\\tau_1$ (N m)"),
        ("tau", 1, "$\\tau_2$ (N m)"),
    ]
    results = comparison.results
    with matplotlib.rc_context(_RC):
        figure = _figure(len(panels), figsize=(_FIGSIZE[0], 6.4))
        colours = matplotlib.colormaps["tab10"].colors
        for axes, (name, joint, ylabel) in zip(figure.axes, panels, strict=True):
            for i, (label, result) in enumerate(results.items()):
                reference = label == "optimal"  # black dashed, so that lines under it show
                axes.plot(
                    result.t,
                    getattr(result, name)[:, joint],
                    color="k" if reference else colours[i % len(colours)],
                    lw=1.1 if reference else 0.9,
                    ls="--" if reference else "-",
                    label=label + ("" if result.status == "finished" else f" ({result.status})"),
                )
            if "adp" in results:
                _mark_probe_end(axes, results["adp"])
            axes.set_ylabel(ylabel)
        last = figure.axes[-1]
        if time_scale == "symlog":
            last.set_xscale("symlog", linthresh=1.0)
        ends = [result.t[-1] for result in results.values() if result.t.size]
        if ends and max(ends) > 0.0:
            last.set_xlim(0.0, max(ends))
        scale_note = ", linear to 1 s, then logarithmic" if time_scale == "symlog" else ""
        last.set_xlabel(f"time t (s{scale_note})")
        figure.axes[0].legend(
            loc="lower center", bbox_to_anchor=(0.5, 1.0), ncols=min(len(results), 5)
        )
        figure.suptitle("Controllers compared: tracking errors and applied torques")
    return figure


#: Figure name -> function; the names are the file stems written by save_figures.
FIGURES = {
    "fig2_critic_weights": plot_critic_weights,
    "fig3_actor_weights": plot_actor_weights,
    "fig4_errors": plot_errors,
    "torques": plot_torques,
}


def plot_result(result: SimulationResult, which: Iterable[str] | None = None) -> dict[str, Figure]:
    """The figures named in ``which`` (default all of FIGURES), by name."""
    names = list(FIGURES) if which is None else list(which)
    unknown = [name for name in names if name not in FIGURES]
    if unknown:
        raise ValueError(f"which: unknown figure(s) {unknown}; known: {', '.join(FIGURES)}")
    return {name: FIGURES[name](result) for name in names}


def save_figures(
    figures: dict[str, Figure], directory: str | Path, formats: Iterable[str] = ("png", "svg")
) -> list[Path]:
    """Write each figure as ``<directory>/<name>.<format>``; returns the paths written."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, figure in figures.items():
        for fmt in formats:
            path = directory / f"{name}.{fmt}"
            figure.savefig(path, dpi=200, metadata=_metadata(fmt))
            written.append(path)
    return written


def _metadata(fmt: str) -> dict[str, Any] | None:
    # Leave out creation dates so that the same run writes the same files.
    if fmt == "svg":
        return {"Date": None}
    if fmt == "pdf":
        return {"CreationDate": None}
    return None
