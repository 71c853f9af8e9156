"""The artefacts of a run written to a directory (used by ``adparm reproduce`` and ``adparm run``).

<out>/fig2_critic_weights.{png,svg}  fig3_actor_weights  fig4_errors  torques
<out>/summary.md, summary.json       metrics and deviations from the paper (adparm.summary)
<out>/result.npz, result.csv         the recorded run (adparm.load_result reads the .npz)
<out>/config.toml                    the configuration, for ``adparm run``
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .summary import summarize, summary_markdown

if TYPE_CHECKING:  # pragma: no cover
    from .simulation import SimulationResult

__all__ = ["check_formats", "write_report"]

FIGURE_FORMATS = ("png", "svg", "pdf")


def check_formats(formats: Iterable[str]) -> tuple[str, ...]:
    """``formats`` as a tuple; ValueError if one is not in FIGURE_FORMATS."""
    formats = tuple(formats)
    unknown = [fmt for fmt in formats if fmt not in FIGURE_FORMATS]
    if unknown:
        expected = ", ".join(FIGURE_FORMATS)
        raise ValueError(f"formats: unknown {unknown}; expected some of {expected}")
    return formats


def write_report(
    result: SimulationResult,
    directory: str | Path,
    *,
    formats: Iterable[str] = ("png", "svg"),
    figures: bool = True,
    summary: dict[str, Any] | None = None,
) -> list[Path]:
    """Write figures, summaries, the recorded result and the config to ``directory``; returns
    the paths written. ``summary`` is ``summarize(result)`` if the caller already has it."""
    formats = check_formats(formats)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    if summary is None:
        summary = summarize(result)
    written = []
    (directory / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    (directory / "summary.md").write_text(summary_markdown(summary))
    (directory / "config.toml").write_text(result.config.to_toml())
    written += [directory / name for name in ("summary.json", "summary.md", "config.toml")]
    written.append(result.save(directory / "result.npz"))
    written.append(result.save(directory / "result.csv"))
    if figures:
        from .plotting import save_figures

        written += save_figures(result.plot(), directory, formats)
    return written
