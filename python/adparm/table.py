"""Rows of metrics (one dict per row) written as CSV, JSON and Markdown, shared by
:class:`adparm.Comparison` and :class:`adparm.SweepResult`. Non-finite numbers become null in
JSON and empty cells in CSV; lists, tuples, arrays and tables (e.g. a ``task.qd`` trajectory)
are written as JSON text in CSV and Markdown cells."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._arm_sections import plain_value as config_plain
from ._files import atomic_write

if TYPE_CHECKING:  # pragma: no cover
    import pandas

__all__ = ["plain", "rows_dataframe", "rows_json", "rows_markdown", "write_csv"]


def plain(value: Any) -> Any:
    """JSON-ready: None for non-finite floats (JSON has no NaN); lists for tuples and arrays;
    dicts for mappings and for the trajectory dataclasses of a config."""
    value = config_plain(value)  # SinusoidTrajectory, SampledTrajectory -> dict
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "tolist"):  # NumPy scalars and arrays
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    return value


def _cell(value: Any) -> str:
    value = plain(value)
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value)


def write_csv(path: Path, columns: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> Path:
    """One header line and one line per row (written atomically)."""

    def write(temporary: Path) -> None:
        with temporary.open("w", newline="", encoding="utf-8") as stream:
            writer = csv.writer(stream, lineterminator="\n")
            writer.writerow(columns)
            for row in rows:
                writer.writerow([_cell(row.get(column)) for column in columns])

    return atomic_write(path, write)


def rows_json(columns: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """{"columns": [...], "rows": [{column: value}]} with non-finite numbers as null."""
    return {
        "columns": list(columns),
        "rows": [{column: plain(row.get(column)) for column in columns} for row in rows],
    }


def rows_markdown(
    columns: Sequence[str],
    rows: Sequence[Mapping[str, Any]],
    formats: Mapping[str, tuple[str, str]] | None = None,
) -> str:
    """A Markdown table; ``formats`` maps a column to (header, format string), ``-`` marks a
    missing value. The first column is left-aligned, the others right-aligned."""
    formats = formats or {}
    headers = [formats.get(column, (column, "{}"))[0] for column in columns]
    lines = [
        "| " + " | ".join(_escaped(header) for header in headers) + " |",
        "|" + "|".join("---" if i == 0 else "---:" for i in range(len(headers))) + "|",
    ]
    for row in rows:
        cells = []
        for column in columns:
            value = plain(row.get(column))
            if value is None:
                cells.append("-")
            elif column in formats:
                cells.append(formats[column][1].format(value))
            elif isinstance(value, float):
                cells.append(f"{value:.4g}")
            elif isinstance(value, dict):
                cells.append(json.dumps(value))
            else:
                cells.append(str(value))
        lines.append("| " + " | ".join(_escaped(cell) for cell in cells) + " |")
    return "\n".join(lines) + "\n"


def _escaped(cell: str) -> str:
    """A cell's text as Markdown keeps it in its column: a verdict's "||Wc - W*||" would end it."""
    return cell.replace("|", "\\|").replace("\n", " ")


def rows_dataframe(columns: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> pandas.DataFrame:
    """The rows as a pandas DataFrame (pandas imported here; it is an optional dependency)."""
    try:
        import pandas
    except ImportError as error:  # pragma: no cover - pandas is in the test extra
        raise ImportError("this table needs pandas: pip install pandas") from error
    return pandas.DataFrame([{c: row.get(c) for c in columns} for row in rows], columns=columns)
