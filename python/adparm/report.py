"""The artefacts of a run written to a directory (used by ``adparm reproduce`` and ``adparm run``).

<out>/fig2_critic_weights.{png,svg}  fig3_actor_weights  fig4_errors  torques
<out>/summary.md, summary.json       metrics and deviations from the paper (adparm.summary)
<out>/result.npz, result.csv         the recorded run (adparm.load_result reads the .npz)
<out>/config.toml                    the configuration, for ``adparm run``
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._files import OutputFolder
from .result import post_run_failure
from .summary import summarize, summary_markdown

if TYPE_CHECKING:  # pragma: no cover
    from .simulation import SimulationResult

__all__ = ["check_formats", "report_files", "write_report"]

FIGURE_FORMATS = ("png", "svg", "pdf")


def check_formats(formats: Iterable[str]) -> tuple[str, ...]:
    """``formats`` as a tuple without repeats (``png,png`` is ``png``: each figure is written
    once); ValueError if one is not in FIGURE_FORMATS."""
    formats = tuple(dict.fromkeys(formats))
    unknown = [fmt for fmt in formats if fmt not in FIGURE_FORMATS]
    if unknown:
        expected = ", ".join(FIGURE_FORMATS)
        raise ValueError(f"formats: unknown {unknown}; expected some of {expected}")
    return formats


def report_files(formats: Iterable[str] = ("png", "svg"), figures: bool = True) -> list[str]:
    """The names of the files write_report may write (model_parameters.* only for an
    identifying run)."""
    from .plotting import FIGURES

    names = ["result.npz", "result.csv", "config.toml", "summary.json", "summary.md"]
    if figures:
        names += [f"{name}.{fmt}" for name in FIGURES for fmt in check_formats(formats)]
    return names


def write_report(
    result: SimulationResult,
    directory: str | Path,
    *,
    formats: Iterable[str] = ("png", "svg"),
    figures: bool = True,
    summary: dict[str, Any] | None = None,
    folder: OutputFolder | None = None,
    on_file: Callable[[Path], None] | None = None,
) -> list[Path]:
    """Write the recorded result, the config, summaries and figures to ``directory``; returns
    the paths written. Each file is written atomically (never a truncated file). ``summary`` is
    ``summarize(result)`` if the caller already has it (its ``post_run_errors`` gains the
    figures that could not be drawn); ``folder`` (the command line's OutputFolder of
    ``directory``) records each file in its manifest; ``on_file(path)`` is called after each
    file (progress)."""
    formats = check_formats(formats)
    directory = Path(directory)
    if folder is None:
        directory.mkdir(parents=True, exist_ok=True)
        folder = OutputFolder(directory, report_files(formats, figures), "report")
    if summary is None:
        summary = summarize(result)
    done = on_file or (lambda path: None)
    from .storage import write_result_csv, write_result_npz

    written = []
    for name, writer in (("result.npz", write_result_npz), ("result.csv", write_result_csv)):
        written.append(folder.write(name, lambda temporary, w=writer: w(result, temporary)))
        done(written[-1])
    written.append(folder.write_text("config.toml", result.config.to_toml(resolved=True)))
    done(written[-1])
    # the figures before the summaries, so that a figure that cannot be drawn is reported in them;
    # a failure to draw (not to write) loses neither the run nor the other files
    failed: list[str] = []
    if figures:
        from .plotting import figure_names

        for name in figure_names(
            result
        ):  # one figure at a time: progress, and one figure in memory
            try:
                drawn = result.plot([name])
            except Exception as error:  # noqa: BLE001 - reported in the summary
                failed.append(post_run_failure(f"the figure {name}", error))
                continue
            paths = folder.write_figures(drawn, formats)
            written += paths
            for path in paths:
                done(path)
    if failed:
        summary["post_run_errors"] = [*summary.get("post_run_errors", []), *failed]
    for path in write_summary(folder, summary):
        written.append(path)
        done(path)
    return written


def write_summary(folder: OutputFolder, summary: dict[str, Any]) -> list[Path]:
    """Write summary.json and summary.md of ``summary`` into ``folder``; returns the paths."""
    return [
        folder.write_text("summary.json", json.dumps(summary, indent=2) + "\n"),
        folder.write_text("summary.md", summary_markdown(summary)),
    ]
