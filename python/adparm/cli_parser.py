"""The command line's parser: the subcommands run, reproduce, sweep and compare, their options
and help, and the parsing of --grid entries (adparm.cli runs them)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .comparison import (
    DEFAULT_KINDS,
)
from .config import tomllib
from .report import FIGURE_FORMATS, check_formats


def formats_option(text: str) -> tuple[str, ...]:
    try:
        formats = check_formats(f.strip() for f in text.split(",") if f.strip())
    except ValueError:
        formats = ()
    if not formats:
        raise argparse.ArgumentTypeError(
            f"expected a comma-separated list of {', '.join(FIGURE_FORMATS)}, got {text!r}"
        )
    return formats


EXIT_STATUS_TEXT = (
    "exit status: 0 done; 1 a run diverged (its rows are written); 2 bad input or output path "
    "(nothing was run); 3 a file could not be written; 130 Ctrl-C, 143 SIGTERM (what was done is "
    "written)"
)


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Each option's default after its help, except flags and defaults the help already says."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default in (None, False) or "default" in (action.help or ""):
            return action.help or ""
        return super()._get_help_string(action)


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="adparm",
        description="Exact linearization, RISE and online actor-critic ADP for robot arms: run "
        "the paper's instance or your own configuration and write figures, summaries and data.",
        epilog=EXIT_STATUS_TEXT,
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"adparm {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def add(name: str, help: str, description: str) -> argparse.ArgumentParser:
        return commands.add_parser(
            name,
            help=help,
            description=description,
            epilog=EXIT_STATUS_TEXT,
            formatter_class=HelpFormatter,
        )

    def common(sub: argparse.ArgumentParser, default_out: str, *, dt: bool = True) -> None:
        sub.add_argument(
            "--out",
            type=Path,
            default=Path(default_out),
            help="output folder (created if needed; adparm overwrites only files it wrote)",
        )
        sub.add_argument(
            "--formats",
            type=formats_option,
            default="png,svg",
            help="figure formats, comma-separated (png, svg, pdf)",
        )
        sub.add_argument("--no-figures", action="store_true", help="write no figures")
        sub.add_argument("--no-progress", action="store_true", help="show no progress bar")
        horizon_options(sub, dt=dt)

    reproduce = add(
        "reproduce",
        "run the paper's instance and write Figures 2-4, summary and data",
        "Run the paper's two-link instance (Section 4, with the corrections of the errata) and "
        "write to --out: result.npz and result.csv (every recorded step), config.toml, "
        "summary.json and summary.md (metrics and deviations from the paper) and the figures "
        "fig2_critic_weights, fig3_actor_weights, fig4_errors and torques.",
    )
    common(reproduce, "results", dt=False)  # the paper's step; --T shortens the run
    run = add(
        "run",
        "run a TOML configuration and write the same files",
        "Run the configuration in CONFIG (keys left out take the paper's values) and write the "
        "same files as reproduce to --out.",
    )
    run.add_argument("config", type=Path, help="TOML file ([plant] [task] [cost] ... [sim])")
    common(run, "results")
    for sub in (reproduce, run):
        sub.add_argument(
            "--check-dt",
            action="store_true",
            help="also run the first second with sim.dt and sim.dt/2 and report the integration "
            "error of the learning transient (summary field step_size_check)",
        )
    comparison = add(
        "compare",
        "run the same arm, task and initial state under several controllers and tabulate "
        "cost, errors and torques",
        "Run adp (the learning run and a second run from its learned weights without "
        "probing; when the model differs from the plant, also the learning run that identifies "
        "the plant's parameters online), rise, pd and optimal on the same arm, task and initial "
        "state; write compare.md/csv/json, the figure compare.<format> and config.toml to "
        "--out.",
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
        "--optimal-cost",
        action="store_true",
        help="compute J* (the J / J* - 1 column) on any arm: by default it is left out on URDF "
        "arms of more than 3 joints, whose IPOPT solve takes minutes",
    )
    comparison.add_argument(
        "--kinds",
        default=",".join(DEFAULT_KINDS),
        help="controllers, comma-separated",
    )
    comparison.add_argument(
        "--identify",
        choices=("auto", "yes", "no"),
        default="auto",
        help="add the identifying controller, adp (identifying): the learning run with "
        "identifier.enabled = true; auto: when the model differs from the plant",
    )
    sweeping = add(
        "sweep",
        "run a grid of settings and tabulate the summary metrics of each point",
        "Run every combination of the --grid values from the configuration (the "
        "paper's instance without a file) in parallel threads and write one row of summary "
        "metrics per point to --out (a diverged run keeps its row, status diverged).",
    )
    sweeping.add_argument("config", type=Path, nargs="?", default=None, help="base TOML file")
    sweeping.add_argument(
        "--grid",
        action="append",
        type=grid_entry,
        required=True,
        metavar="SECTION.KEY=V1,V2,...",
        help="values to try, as TOML values separated by commas, e.g. critic.eta_c=100,800, "
        'task.q0=[0.1,0.2],[0.5,-0.3] or (strings in quotes) \'controller.kind="adp","pd"\'; '
        "one --grid per key",
    )
    sweeping.add_argument(
        "--out", type=Path, default=Path("sweep.csv"), help="table file: .csv, .json or .md"
    )
    sweeping.add_argument(
        "--threads",
        type=int,
        default=None,
        help="threads (default: every CPU this process can use)",
    )
    sweeping.add_argument("--no-progress", action="store_true", help="show no progress bar")
    sweeping.add_argument(
        "--optimal-cost",
        action="store_true",
        help="add each row's J, J* and J / J* - 1 (as compare's; one IPOPT solve per distinct "
        "problem, shared by rows that differ only in settings J* does not depend on: about a "
        "second on the paper's arm, minutes on a 6-joint arm)",
    )
    horizon_options(sweeping)
    return parser


def horizon_options(sub: argparse.ArgumentParser, *, dt: bool = True) -> None:
    """--T (sim.T) and, unless dt is False, --dt (sim.dt): checked by Config.updated."""
    sub.add_argument(
        "--T",
        type=number_or_text,
        default=None,
        metavar="SECONDS",
        help="horizon sim.T in s (default: the config's)",
    )
    if dt:
        sub.add_argument(
            "--dt",
            type=number_or_text,
            default=None,
            metavar="SECONDS",
            help='RK4 step sim.dt in s, or "auto" (default: the config\'s)',
        )


def number_or_text(text: str) -> float | str:
    """A float if ``text`` reads as one, else ``text`` itself (e.g. "auto"), so that the
    configuration's own check names the setting and what it accepts."""
    try:
        return float(text)
    except ValueError:
        return text.strip()


#: The deepest nesting of brackets and braces in a --grid value (TOML's reader recurses).
MAX_GRID_NESTING = 32


def grid_nesting(text: str) -> int:
    """The deepest nesting of [ ] and { } in ``text`` outside quoted strings (an upper bound)."""
    depth = deepest = 0
    quote = ""
    for char in text:
        if quote:
            quote = "" if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in "]}":
            depth -= 1
    return deepest


def grid_entry(text: str) -> tuple[str, list]:
    name, separator, values = text.partition("=")
    if not separator or not name.strip() or not values.strip():
        raise argparse.ArgumentTypeError(f"expected SECTION.KEY=V1,V2,..., got {text!r}")
    depth = grid_nesting(values)
    if depth > MAX_GRID_NESTING:
        raise argparse.ArgumentTypeError(
            f"{name.strip()}: values nested {depth} deep; at most {MAX_GRID_NESTING}"
        )
    try:
        parsed = tomllib.loads(f"values = [{values}]")["values"]
    except (RecursionError, MemoryError):  # a safety net below the bound above
        raise argparse.ArgumentTypeError(f"{name.strip()}: values nested too deeply") from None
    except tomllib.TOMLDecodeError as error:
        raise argparse.ArgumentTypeError(
            f"{name.strip()}: expected TOML values separated by commas, got {values!r} ({error})"
        ) from error
    return name.strip(), parsed
