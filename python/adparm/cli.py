"""Command line: ``adparm reproduce``, ``adparm run CONFIG``, ``adparm compare [CONFIG]`` and
``adparm sweep [CONFIG] --grid section.key=v1,v2`` (also ``python -m adparm``)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from .comparison import DEFAULT_KINDS, Comparison, _controller_configs, compare
from .config import Config, load_config, paper_config, tomllib
from .report import FIGURE_FORMATS, check_formats, write_report
from .simulation import SimulationInterrupted, SimulationResult, _simulate_keeping_divergence

__all__ = ["main"]


def _formats(text: str) -> tuple[str, ...]:
    try:
        formats = check_formats(f.strip() for f in text.split(",") if f.strip())
    except ValueError:
        formats = ()
    if not formats:
        raise argparse.ArgumentTypeError(
            f"expected a comma-separated list of {', '.join(FIGURE_FORMATS)}, got {text!r}"
        )
    return formats


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="adparm",
        description="Exact linearization, RISE and online actor-critic ADP for a two-link arm.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def common(sub: argparse.ArgumentParser, default_out: str) -> None:
        sub.add_argument("--out", type=Path, default=Path(default_out), help="output directory")
        sub.add_argument(
            "--formats",
            type=_formats,
            default=("png", "svg"),
            help="figure formats, comma-separated (png, svg, pdf); default png,svg",
        )
        sub.add_argument("--no-figures", action="store_true", help="skip the figures")
        sub.add_argument("--no-progress", action="store_true", help="no progress bar")
        sub.add_argument("--T", type=float, default=None, help="override the horizon sim.T (s)")

    reproduce = commands.add_parser(
        "reproduce", help="run the paper's instance and write Figures 2-4, summary and data"
    )
    common(reproduce, "results")
    run = commands.add_parser("run", help="run a TOML configuration and write the same artefacts")
    run.add_argument("config", type=Path, help="TOML file ([plant] [task] [cost] ... [sim])")
    common(run, "results")
    for sub in (reproduce, run):
        sub.add_argument(
            "--check-dt",
            action="store_true",
            help="also run the first second with sim.dt and sim.dt/2 and report the integration "
            "error of the learning transient (summary field step_size_check)",
        )
    comparison = commands.add_parser(
        "compare",
        help="run the same arm, task and initial state under several controllers and tabulate "
        "cost, errors and torques",
        description="Run adp (the learning run and a second run from its learned weights without "
        "probing), rise, pd and optimal on the same arm, task and initial state; write "
        "compare.md/csv/json, the figure compare.<format> and config.toml.",
    )
    comparison.add_argument(
        "config",
        type=Path,
        nargs="?",
        default=None,
        help="TOML file (default: the paper's instance); controller.kind is replaced per run",
    )
    common(comparison, "compare")
    comparison.add_argument(
        "--kinds",
        default=",".join(DEFAULT_KINDS),
        help=f"controllers, comma-separated; default {','.join(DEFAULT_KINDS)}",
    )
    sweeping = commands.add_parser(
        "sweep",
        help="run a grid of settings and tabulate the summary metrics of each point",
        description="Run every combination of the --grid values from the configuration (the "
        "paper's instance without a file) in parallel threads and write one row of summary "
        "metrics per point. Exit status: 0, 1 if a run diverged (its row is kept), 2 for a bad "
        "grid or configuration.",
    )
    sweeping.add_argument("config", type=Path, nargs="?", default=None, help="base TOML file")
    sweeping.add_argument(
        "--grid",
        action="append",
        type=_grid_entry,
        required=True,
        metavar="SECTION.KEY=V1,V2,...",
        help="values to try, as TOML values separated by commas, e.g. critic.eta_c=100,800, "
        'task.q0=[0.1,0.2],[0.5,-0.3] or (strings in quotes) \'controller.kind="adp","pd"\'; '
        "one --grid per key",
    )
    sweeping.add_argument(
        "--out", type=Path, default=Path("sweep.csv"), help="table file: .csv, .json or .md"
    )
    sweeping.add_argument("--threads", type=int, default=None, help="threads (default: all CPUs)")
    sweeping.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweeping.add_argument("--T", type=float, default=None, help="override the horizon sim.T (s)")
    return parser


def _grid_entry(text: str) -> tuple[str, list]:
    name, separator, values = text.partition("=")
    if not separator or not name.strip() or not values.strip():
        raise argparse.ArgumentTypeError(f"expected SECTION.KEY=V1,V2,..., got {text!r}")
    try:
        parsed = tomllib.loads(f"values = [{values}]")["values"]
    except tomllib.TOMLDecodeError as error:
        raise argparse.ArgumentTypeError(
            f"{name.strip()}: expected TOML values separated by commas, got {values!r} ({error})"
        ) from error
    return name.strip(), parsed


def _sweep(args: argparse.Namespace) -> int:
    from .sweep import sweep

    try:
        names = [name for name, _ in args.grid]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise ValueError(
                f"--grid: {', '.join(repeated)} given more than once; list all its values in one "
                "--grid"
            )
        if args.out.suffix not in (".csv", ".json", ".md"):
            raise ValueError(f"--out: expected a .csv, .json or .md file, got {str(args.out)!r}")
        config = _config(args)
        args.out.parent.mkdir(parents=True, exist_ok=True)
        try:
            table = sweep(
                config, dict(args.grid), threads=args.threads, progress=not args.no_progress
            )
        except SimulationInterrupted as interrupt:
            interrupt.result.save(args.out)
            return _interrupted("sweep", interrupt, f"{args.out} ({len(interrupt.result)} runs)")
        table.save(args.out)
    except (OSError, ValueError, TypeError) as error:
        print(f"adparm sweep: {error}", file=sys.stderr)
        return 2
    print(table.to_markdown(), end="")
    print(f"wrote {args.out} ({len(table)} runs)")
    off = [row["verdict"] for row in table if row["verdict"] not in ("ok", "not a learning run")]
    if off:
        print(
            f"adparm sweep: {len(off)} of {len(table)} runs did not find the optimum (see the "
            f"verdict column), e.g.: {off[0]}",
            file=sys.stderr,
        )
    diverged = sum(row["status"] == "diverged" for row in table)
    if diverged:
        print(f"adparm sweep: {diverged} of {len(table)} runs diverged", file=sys.stderr)
        return 1
    return 0


def _kinds(text: str) -> tuple[str, ...]:
    return tuple(kind.strip() for kind in text.split(",") if kind.strip())


def _config(args: argparse.Namespace) -> Config:
    """The command's configuration (the paper's without a file) with --T applied."""
    config = paper_config() if getattr(args, "config", None) is None else load_config(args.config)
    return config if args.T is None else config.updated({"sim": {"T": args.T}})


def _compare(args: argparse.Namespace) -> int:
    try:
        config = _config(args)
        kinds = _kinds(args.kinds)
        _controller_configs(config, kinds)  # every check before the first run
    except (OSError, ValueError, TypeError) as error:
        print(f"adparm compare: {error}", file=sys.stderr)
        return 2
    try:
        comparison = compare(config, kinds, progress=not args.no_progress)
    except SimulationInterrupted as interrupt:
        written = _write_comparison(args, config, interrupt.result)
        return _interrupted("compare", interrupt, written)
    print(_write_comparison(args, config, comparison))
    if comparison.diverged:
        print(f"adparm compare: diverged: {', '.join(comparison.diverged)}", file=sys.stderr)
        return 1
    return 0


def _write_comparison(args: argparse.Namespace, config: Config, comparison: Comparison) -> str:
    """Writes the comparison's files and prints its table; returns what was written."""
    out = Path(args.out)
    comparison.save(out)
    (out / "config.toml").write_text(config.to_toml())
    if not args.no_figures:
        from .plotting import save_figures

        save_figures({"compare": comparison.plot()}, out, args.formats)
    print(comparison.table_markdown(), end="")
    figures = "" if args.no_figures else ", compare." + "/".join(args.formats)
    return f"wrote {out}/ (compare.md, compare.csv, compare.json, config.toml{figures})"


def _interrupted(command: str, interrupt: SimulationInterrupted, written: str) -> int:
    """Reports a Ctrl-C after the partial results were written; the exit status of SIGINT."""
    print(f"adparm {command}: {interrupt}; kept what was done: {written}", file=sys.stderr)
    return 130


def _write_run(args: argparse.Namespace, result: SimulationResult) -> dict:
    """Writes the report of a run (finished, diverged or interrupted); returns its summary."""
    summary = result.summary()
    if getattr(args, "check_dt", False):
        from .truth import check_step_size

        summary["step_size_check"] = check_step_size(result.config)
    write_report(
        result, args.out, formats=args.formats, figures=not args.no_figures, summary=summary
    )
    return summary


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``adparm`` command; returns the exit status."""
    args = _parser().parse_args(argv)
    if args.command == "compare":
        return _compare(args)
    if args.command == "sweep":
        return _sweep(args)
    try:
        config = _config(args)
    except (OSError, ValueError, TypeError) as error:
        print(f"adparm {args.command}: {error}", file=sys.stderr)
        return 2
    try:
        result, failure = _simulate_keeping_divergence(config, progress=not args.no_progress)
    except SimulationInterrupted as interrupt:
        _write_run(args, interrupt.result)
        return _interrupted(args.command, interrupt, f"{args.out}/")
    summary = _write_run(args, result)
    print(f"wrote {args.out}/ (summary.md, summary.json, result.npz, result.csv, figures)")
    error = summary.get("critic_relative_error")
    if error is not None:
        claim = summary["critic_relative_error_at_claim"]
        claim_text = "-" if claim is None else f"{claim:.3g}"
        print(
            f"critic ||Wc - W*|| / ||W*||: {claim_text} at t = {summary['paper_claim_time']:g} s, "
            f"{error:.3g} at t = {summary['t_end']:g} s; final |e1| = "
            f"{summary['final_e1_norm']:.3g} rad"
        )
    check = summary.get("step_size_check")
    if check is not None:
        print(f"step size (first {check['transient']:g} s against dt/2): {check['verdict']}")
    if summary["verdict"] not in ("ok", "not a learning run"):
        print(f"adparm {args.command}: verdict: {summary['verdict']}", file=sys.stderr)
    if failure is not None:
        print(f"adparm {args.command}: {failure}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
