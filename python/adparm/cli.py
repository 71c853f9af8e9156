"""Command line: ``adparm reproduce``, ``adparm run CONFIG``, ``adparm compare [CONFIG]`` and
``adparm sweep [CONFIG] --grid section.key=v1,v2`` (also ``python -m adparm``).

Exit status (one per cause): 0 done; 1 a run diverged (its rows are written); 2 bad input (a
configuration, an option, an output path that cannot or must not be written, a folder another
adparm command is writing, a run that would not fit in memory), found before anything runs; 3 a
file could not be written (the message says what was kept and where); 130 interrupted by Ctrl-C
(SIGINT) and 143 by SIGTERM, after writing what was done."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from ._files import OutputError, OutputFolder
from .cli_parser import build_parser
from .comparison import (
    J_STAR_INTERRUPTED,
    Comparison,
    compare,
    controller_configs,
)
from .config import Config, load_config, paper_config
from .report import report_files, write_report, write_summary
from .result import post_run_failure
from .simulation import (
    SimulationDiverged,
    SimulationInterrupted,
    SimulationResult,
    check_memory,
    simulate,
)
from .units import norm_unit

__all__ = ["EXIT_BAD_INPUT", "EXIT_DIVERGED", "EXIT_WRITE_FAILED", "main"]

EXIT_DIVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_WRITE_FAILED = 3
# Interrupted: 128 + the signal's number (130 for SIGINT, 143 for SIGTERM), as a shell reports it.


class _Signals:
    """SIGINT and SIGTERM during a command. While computing (the run, and the steps after it:
    the summary, --check-dt, J*), the first one stops the computation (as a KeyboardInterrupt,
    so what was done is kept and written); later ones are noted, so that a repeated Ctrl-C
    cannot cut the stopping short. While ``finishing`` names what is being finished (the files
    being written), every signal is noted and that is finished (never a half-written set).
    ``received`` is the first signal's number."""

    def __init__(self, command: str) -> None:
        self.command = command
        self.received: int | None = None
        self.finishing: str | None = None
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: Any) -> None:
        first = self.received is None
        if first:
            self.received = signum
        if self.finishing is None and first:
            raise KeyboardInterrupt
        if first or signum == signal.SIGTERM or self.finishing is None:
            doing = f"finishing {self.finishing}" if self.finishing else "already stopping"
            print(
                f"\nadparm {self.command}: {signal.Signals(signum).name} received; {doing}",
                file=sys.stderr,
            )

    def __enter__(self) -> _Signals:
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)

    def writing_files(self) -> None:
        """From here on (to the command's end or the next ``computing``), signals are noted, not
        raised: the files being written are finished."""
        self.finishing = "the files being written"

    @contextmanager
    def computing(self) -> Iterator[None]:
        """Within: the first signal stops the computation again (as a KeyboardInterrupt)."""
        finishing, self.finishing = self.finishing, None
        try:
            yield
        finally:
            self.finishing = finishing

    def name(self) -> str:
        return signal.Signals(self.received or signal.SIGINT).name

    def status(self) -> int:
        return 128 + (self.received or signal.SIGINT)


def _say(command: str, text: str) -> None:
    print(f"adparm {command}: {text}", file=sys.stderr)


def _config(args: argparse.Namespace) -> Config:
    """The command's configuration (the paper's without a file) with --T and --dt applied
    (through Config.updated: a bad value is the configuration's error, naming sim.T or sim.dt)."""
    config = paper_config() if getattr(args, "config", None) is None else load_config(args.config)
    sim = {
        key: value
        for key, value in (("T", args.T), ("dt", getattr(args, "dt", None)))
        if value is not None
    }
    return config.updated({"sim": sim}) if sim else config


def _write_failed(command: str, folder: OutputFolder, error: OSError) -> int:
    """Reports a write that failed: what failed, and the complete files kept."""
    target = f" {error.filename}" if getattr(error, "filename", None) else ""
    count = len(folder.removed)
    removed = (
        f"; the earlier run's {count} file{'s' if count != 1 else ''} there were removed first"
        if count
        else ""
    )
    _say(
        command,
        f"could not write{target}: {error.strerror or error}; no partial file was left; "
        f"complete files kept: {folder.describe_written()}{removed}",
    )
    return EXIT_WRITE_FAILED


def _writing(
    signals: _Signals, folder: OutputFolder, progress: bool, write: Callable[[Callable], None]
) -> None:
    """With signals deferred from here on: removes the files of the earlier run this one
    replaces, then runs ``write(on_file)`` with a 'writing' progress bar in files."""
    signals.writing_files()
    with tqdm(total=len(folder.names), disable=not progress, desc="writing", unit="file") as bar:
        folder.remove_previous()
        write(lambda path: bar.update(1))


def _interrupted(command: str, signals: _Signals, what: str, kept: str) -> int:
    """Reports a Ctrl-C or SIGTERM after the partial results were written; returns 128 + signal."""
    _say(command, f"stopped by {signals.name()} {what}; wrote what was done: {kept}")
    return signals.status()


def _stopped_before_run(command: str, signals: _Signals) -> int:
    """A Ctrl-C or SIGTERM while reading the configuration or checking --out: one line."""
    _say(command, f"stopped by {signals.name()} before the run; nothing was written")
    return signals.status()


def _summary(result: SimulationResult, signals: _Signals) -> dict[str, Any]:
    """result.summary(), which reports a failed post-run step in "post_run_errors"; should the
    summary itself fail or be interrupted (a signal stops it as it stops a run), a minimal one
    that says so (the run's files are written all the same)."""
    try:
        summary = result.summary()
    except (Exception, KeyboardInterrupt) as error:  # noqa: BLE001 - never loses a finished run
        step = "the summary (adparm.summary.summarize)"
        if isinstance(error, KeyboardInterrupt):
            message = f"{step} was stopped by {signals.name()} before it finished"
        else:
            message = post_run_failure(step, error)
        t = result.t
        summary = {
            "status": result.status,
            "t_end": float(t[-1]) if t.size else None,
            "stopped_at": None,
            "T": result.config.sim.T,
            "final_e1": result.e1[-1].tolist() if t.size else None,
            "final_e1_norm": float(np.linalg.norm(result.e1[-1])) if t.size else None,
            "accumulated_cost": None,
            "accumulated_cost_without_probe": None,
            "covariance_resets": result.covariance_resets,
            "wall_time": float(result.wall_time),
            "optimal_weights": None,
            "optimal_weights_unavailable": message,
            "verdict": f"unknown: {message}",
            "deviations": [],
            "post_run_errors": [message],
        }
    summary.setdefault("post_run_errors", [])
    return summary


def _say_post_run_errors(command: str, summary: dict[str, Any]) -> None:
    """Says on stderr which post-run steps failed (they are in summary.md and summary.json)."""
    for problem in summary.get("post_run_errors") or ():
        _say(command, f"{problem}; the run and its files are complete (see summary.md)")


#: summary.json's post_run_errors line while --check-dt runs (after the run's files are written).
CHECK_PENDING = (
    "the step-size check (--check-dt) had not finished when this summary was written (it runs "
    "after the run's files are written)"
)


def _check_step_size(result: SimulationResult, signals: _Signals) -> tuple[Any, str | None]:
    """--check-dt after the run's files are written: (step_size_check, None), or (None, why it
    was not done). A signal stops it as it stops a run."""
    from .truth import check_step_size

    step = "the step-size check (--check-dt)"
    if signals.received is not None:  # a signal while the files were written: not started
        return None, f"{step} was not started: {signals.name()} received"
    try:
        with signals.computing():
            return check_step_size(result.config), None
    except KeyboardInterrupt:
        return None, f"{step} was stopped by {signals.name()} before it finished"
    except Exception as error:  # noqa: BLE001 - never loses the finished run
        return None, post_run_failure(step, error)


def _divergence_text(result: SimulationResult, error: SimulationDiverged) -> str:
    from .truth import divergence_causes

    config = result.config
    causes = divergence_causes(config, result)
    if result.t.size:
        e1 = float(np.linalg.norm(result.e1[-1]))
        last = f"final |e1| = {e1:.3g} rad at the last finite row (t = {result.t[-1]:.6g} s); "
    else:
        last = "not even the first row was finite; "
    return (
        f"diverged at t = {error.time:.6g} s of sim.T = {config.sim.T:g} s: {last}the state or an "
        f"output became non-finite or exceeded sim.divergence_bound = "
        f"{config.sim.divergence_bound:g}; the {result.t.size} rows up to then are written. "
        + f"What the config shows: {'; '.join(causes)}"
    )


def _locked(
    command: str,
    folder: OutputFolder,
    prepare: Callable[[], Any],
    proceed: Callable[[Any, _Signals], int],
) -> int:
    """A command's frame: with its signals handled and its output folder locked to its end,
    ``prepare()`` reads and checks the input (calling folder.check(), which takes the lock), then
    ``proceed(prepared, signals)`` runs. Bad input is exit 2 before anything is computed; a
    signal while preparing gives one line (exit 130 or 143)."""
    with _Signals(command) as signals, folder:
        try:
            prepared = prepare()
        except (OSError, ValueError, TypeError) as error:
            _say(command, str(error))
            return EXIT_BAD_INPUT
        except KeyboardInterrupt:
            return _stopped_before_run(command, signals)
        return proceed(prepared, signals)


def _run(args: argparse.Namespace) -> int:
    figures = not args.no_figures
    folder = OutputFolder(args.out, report_files(args.formats, figures), "report")

    def prepare() -> Config:
        config = _config(args)
        folder.check()  # the folder stays locked to the command's end
        check_memory([config], figures=figures)  # the run, its files and figures
        return config

    return _locked(
        args.command,
        folder,
        prepare,
        lambda config, signals: _run_checked(args, config, folder, signals),
    )


def _run_checked(
    args: argparse.Namespace, config: Config, folder: OutputFolder, signals: _Signals
) -> int:
    command = args.command
    progress = not args.no_progress
    interrupt: SimulationInterrupted | None = None
    diverged: SimulationDiverged | None = None
    try:
        # diagnose=False: no Python warning; the verdict is printed below in the CLI's words
        result = simulate(config, progress=progress, diagnose=False)
    except SimulationDiverged as error:
        diverged, result = error, error.result
    except SimulationInterrupted as stopped:
        interrupt, result = stopped, stopped.result
    except ValueError as error:  # the memory guard, before the run
        _say(command, str(error))
        return EXIT_BAD_INPUT
    if diverged is not None:  # the divergence first: what follows is not a result
        _say(command, _divergence_text(result, diverged))
    summary = _summary(result, signals)  # a signal stops it as it stops a run
    check_dt = getattr(args, "check_dt", False) and interrupt is None
    check_dt = check_dt and signals.received is None
    if check_dt:  # the check runs after the run's files are written
        summary["post_run_errors"].append(CHECK_PENDING)
    try:
        _writing(
            signals,
            folder,
            progress,
            lambda on_file: write_report(
                result,
                args.out,
                formats=args.formats,
                figures=not args.no_figures,
                summary=summary,
                folder=folder,
                on_file=on_file,
            ),
        )
        if check_dt:  # a signal stops it (the run's files are written), then the summary says so
            check, problem = _check_step_size(result, signals)
            summary["post_run_errors"].remove(CHECK_PENDING)
            if problem is None:
                summary["step_size_check"] = check
            else:
                summary["post_run_errors"].append(problem)
            write_summary(folder, summary)
    except OSError as error:
        return _write_failed(command, folder, error)
    if interrupt is not None:
        what = (
            f"at t = {interrupt.time:.6g} s of sim.T = {config.sim.T:g} s "
            f"({result.t.size} rows recorded)"
        )
        return _interrupted(command, signals, what, folder.describe_written())
    print(f"wrote {folder.describe_written()}")
    _say_post_run_errors(command, summary)
    error_value = summary.get("critic_relative_error")
    if error_value is not None:
        # the paper's 110 s only when the run reached it (a time beyond the run is never
        # quoted): summary.md says "not reached"
        claim = summary["critic_relative_error_at_claim"]
        at_claim = (
            f"{claim:.3g} at t = {summary['paper_claim_time']:g} s, " if claim is not None else ""
        )
        before = " (the last finite row, before the divergence)" if diverged else ""
        unit = norm_unit(summary.get("position_units", ["rad"]))  # "(rad; m on joint 1)"
        print(
            f"critic ||Wc - W*|| / ||W*||: {at_claim}{error_value:.3g} at t = "
            f"{summary['t_end']:g} s{before}; final |e1| = {summary['final_e1_norm']:.3g} {unit}"
        )
    check = summary.get("step_size_check")
    if check is not None:
        print(f"step size (first {check['transient']:g} s against dt/2): {check['verdict']}")
    if summary["verdict"] not in ("ok", "not a learning run", "diverged"):
        _say(command, f"verdict: {summary['verdict']}")
        for advice in (summary.get("diagnostics") or {}).get("advice") or ():
            _say(command, f"try: {advice}")
    if signals.received is not None:  # after the run: its files are complete
        _say(command, f"{signals.name()} received after the run; its files are complete")
        return signals.status()
    if diverged is not None:
        return EXIT_DIVERGED
    return 0


def _sweep(args: argparse.Namespace) -> int:
    command = "sweep"
    folder = OutputFolder(args.out.parent, [args.out.name], f"sweep:{args.out.name}")

    def prepare() -> Config:
        names = [name for name, _ in args.grid]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise ValueError(
                f"--grid: {', '.join(repeated)} given more than once; list all its values in "
                "one --grid"
            )
        if args.out.suffix not in (".csv", ".json", ".md"):
            raise ValueError(f"--out: expected a .csv, .json or .md file, got {str(args.out)!r}")
        if args.out.is_dir():
            raise OutputError(f"--out: {args.out} is a folder; give a .csv, .json or .md file")
        config = _config(args)
        folder.check()  # the folder stays locked to the command's end
        return config

    return _locked(
        command,
        folder,
        prepare,
        lambda config, signals: _sweep_checked(args, config, folder, signals),
    )


def _sweep_checked(
    args: argparse.Namespace, config: Config, folder: OutputFolder, signals: _Signals
) -> int:
    from .sweep import sweep

    command = "sweep"
    interrupt: SimulationInterrupted | None = None
    try:
        table = sweep(
            config,
            dict(args.grid),
            threads=args.threads,
            progress=not args.no_progress,
            optimal_cost=args.optimal_cost,
        )
    except SimulationInterrupted as stopped:
        interrupt, table = stopped, stopped.result
    except (ValueError, TypeError) as error:
        _say(command, str(error))
        return EXIT_BAD_INPUT
    signals.writing_files()
    try:
        folder.remove_previous(keep=[args.out.name])  # the table itself: replaced atomically
        folder.write(args.out.name, table.save)
    except OSError as error:
        return _write_failed(command, folder, error)
    if interrupt is not None:
        return _interrupted(
            command,
            signals,
            "(the points not done have no row)",
            f"{args.out} ({len(table)} runs)",
        )
    print(table.to_markdown(), end="")
    print(f"wrote {args.out} ({len(table)} runs)")
    if signals.received is not None:
        _say(command, f"{signals.name()} received while writing")
        return signals.status()
    off = [row["verdict"] for row in table if row["verdict"] not in ("ok", "not a learning run")]
    if off:
        _say(
            command,
            f"{len(off)} of {len(table)} runs did not find the optimum (see the verdict "
            f"column of {args.out}), e.g.: {off[0]}",
        )
    diverged = sum(row["status"] == "diverged" for row in table)
    if diverged:
        _say(
            command,
            f"{diverged} of {len(table)} runs diverged (status diverged in {args.out}); see "
            "adparm run on one of them for what to change",
        )
        return EXIT_DIVERGED
    return 0


def _kinds(text: str) -> tuple[str, ...]:
    return tuple(kind.strip() for kind in text.split(",") if kind.strip())


#: --identify's choices -> compare's identify.
_IDENTIFY = {"auto": None, "yes": True, "no": False}


def _compare(args: argparse.Namespace) -> int:
    command = "compare"
    names = ["compare.csv", "compare.json", "compare.md", "config.toml"]
    if not args.no_figures:
        names += [f"compare.{fmt}" for fmt in args.formats]
    folder = OutputFolder(args.out, names, "compare")

    def prepare() -> tuple[Config, tuple[str, ...]]:
        config = _config(args)
        kinds = _kinds(args.kinds)
        identify = _IDENTIFY[args.identify]
        runs = controller_configs(config, kinds, identify)  # every check before the first run
        folder.check()  # the folder stays locked to the command's end
        # every run is kept (adp twice: learning, then from the learned weights) for the table
        kept = [*runs.values(), *([runs["adp"]] if "adp" in runs else [])]
        check_memory(kept, figures=not args.no_figures)
        return config, kinds

    return _locked(
        command,
        folder,
        prepare,
        lambda prepared, signals: _compare_checked(args, *prepared, folder, signals),
    )


def _compare_checked(
    args: argparse.Namespace,
    config: Config,
    kinds: tuple[str, ...],
    folder: OutputFolder,
    signals: _Signals,
) -> int:
    command = "compare"
    interrupt: SimulationInterrupted | None = None
    try:
        # a signal during J* (after the runs) keeps the runs: compare raises with all of them
        comparison = compare(
            config,
            kinds,
            identify=_IDENTIFY[args.identify],
            progress=not args.no_progress,
            optimal_cost=True if args.optimal_cost else None,
        )
    except SimulationInterrupted as stopped:
        interrupt, comparison = stopped, stopped.result
    except ValueError as error:
        _say(command, str(error))
        return EXIT_BAD_INPUT
    try:
        _writing(
            signals,
            folder,
            not args.no_progress,
            lambda on_file: _write_comparison(args, folder, config, comparison, on_file),
        )
    except OSError as error:
        return _write_failed(command, folder, error)
    if interrupt is not None:
        runs = ", ".join(comparison.results) or "none"
        if J_STAR_INTERRUPTED in comparison.post_run_errors:
            what = f"during J*, after the runs (all complete: {runs}; J* is not in the table)"
        else:
            what = f"(runs so far, the last one partial: {runs})"
        return _interrupted(command, signals, what, folder.describe_written())
    print(comparison.table_markdown(), end="")
    print(f"wrote {folder.describe_written()}")
    for problem in comparison.post_run_errors:
        _say(command, f"{problem}; the runs and their files are complete")
    if signals.received is not None:
        _say(command, f"{signals.name()} received while writing")
        return signals.status()
    if comparison.diverged:
        _say(
            command,
            f"diverged: {', '.join(comparison.diverged)} (their rows are in the table, status "
            "diverged); adparm run with that controller.kind shows where and what to change",
        )
        return EXIT_DIVERGED
    return 0


def _write_comparison(
    args: argparse.Namespace,
    folder: OutputFolder,
    config: Config,
    comparison: Comparison,
    on_file: Callable,
) -> None:
    """Writes the comparison's files (each atomically, recorded in the folder's manifest)."""
    for name in ("compare.csv", "compare.json", "compare.md"):
        on_file(folder.write(name, lambda t, n=name: _save_one(comparison, n, t)))
    on_file(folder.write_text("config.toml", config.to_toml(resolved=True)))
    if not args.no_figures:
        try:
            drawn = comparison.plot()
        except Exception as error:  # noqa: BLE001 - drawing never loses the runs' tables
            _say(
                "compare",
                f"{post_run_failure('the figure compare', error)}; the tables are written",
            )
            return
        for path in folder.write_figures({"compare": drawn}, args.formats):
            on_file(path)


def _save_one(comparison: Comparison, name: str, temporary: Path) -> None:
    """Comparison.save writes all three tables; write the one named ``name`` to ``temporary``."""
    import json

    from .table import write_csv

    if name.endswith(".csv"):
        from .comparison import COMPARE_COLUMNS

        write_csv(temporary, COMPARE_COLUMNS, comparison.rows)
    elif name.endswith(".json"):
        temporary.write_text(json.dumps(comparison.to_json(), indent=2) + "\n", encoding="utf-8")
    else:
        temporary.write_text(
            "# adparm controller comparison\n\n" + comparison.table_markdown(), encoding="utf-8"
        )


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``adparm`` command; returns the exit status (see the module's doc)."""
    args = build_parser().parse_args(argv)
    if args.command == "compare":
        return _compare(args)
    if args.command == "sweep":
        return _sweep(args)
    return _run(args)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
