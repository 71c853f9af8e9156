"""Saving and loading results: ``.npz`` (everything) and ``.csv`` (the time series, with a first
line holding the rest), both written atomically and both read back by :func:`load_result`."""

from __future__ import annotations

import json
import zipfile
import zlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .config import Config

if TYPE_CHECKING:  # pragma: no cover
    from .simulation import SimulationResult

__all__ = ["FORMAT_VERSION", "columns", "load_result", "save_result", "table"]

FORMAT_VERSION = 2

# (result attribute, column names); one column per joint j = 1 ... n ("{j}") and per basis function
# i = 1 ... K ("{i}", in the order of adparm.basis_names(config)).
_COLUMNS: tuple[tuple[str, str], ...] = (
    ("t", "t"),
    ("q", "q{j}"),
    ("dq", "dq{j}"),
    ("qd", "qd{j}"),
    ("e1", "e1_{j}"),
    ("e2", "e2_{j}"),
    ("tau", "tau{j}"),
    ("u", "u{j}"),
    ("u_hat", "u_hat{j}"),
    ("mu", "mu{j}"),
    ("probe", "probe{j}"),
    ("critic_weights", "Wc{i}"),
    ("actor_weights", "Wa{i}"),
    ("hjb_error", "hjb_error"),
    ("cost", "cost"),
)


def _columns(basis_size: int, joints: int = 2) -> list[tuple[str, tuple[str, ...]]]:
    out = []
    for attr, template in _COLUMNS:
        if "{i}" in template:
            names = tuple(template.format(i=i) for i in range(1, basis_size + 1))
        elif "{j}" in template:
            names = tuple(template.format(j=j) for j in range(1, joints + 1))
        else:
            names = (template,)
        out.append((attr, names))
    return out


def columns(basis_size: int = 8, joints: int = 2) -> list[str]:
    """Column names of :func:`table`, the CSV file and ``to_dataframe()`` for a basis of
    ``basis_size`` functions (8; 6 for the structured basis) and an arm of ``joints`` joints."""
    return [name for _, names in _columns(basis_size, joints) for name in names]


def table(result: SimulationResult) -> np.ndarray:
    """The recorded time series as one (rows, len(columns(K))) array."""
    n = result.t.size
    size, joints = result.critic_weights.shape[1], result.q.shape[1]
    return np.hstack(
        [
            np.asarray(getattr(result, attr)).reshape(n, len(names))
            for attr, names in _columns(size, joints)
        ]
    )


# The first line of a result's CSV file: this prefix, then JSON of what the columns do not hold.
CSV_PREFIX = "# adparm result "
# Its last line (a reader can tell a complete file from a cut one): this prefix, then the rows.
CSV_END = "# adparm end: "
# Rows formatted at a time when writing CSV (no copy of the whole recording).
_CSV_ROWS = 10_000


def _metadata(result: SimulationResult) -> dict[str, Any]:
    return {
        "format_version": FORMAT_VERSION,
        "status": result.status,
        "wall_time": result.wall_time if np.isfinite(result.wall_time) else None,
        "covariance_reset_times": result.covariance_reset_times.tolist(),
        "config": result.config.to_dict(),
    }


def _write_csv(result: SimulationResult, path: Path) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as stream:
        stream.write(CSV_PREFIX + json.dumps(_metadata(result)) + "\n")
        size, joints = result.critic_weights.shape[1], result.q.shape[1]
        stream.write(",".join(columns(size, joints)) + "\n")
        n = result.t.size
        for start in range(0, n, _CSV_ROWS):
            stop = min(n, start + _CSV_ROWS)
            block = np.hstack(
                [
                    np.asarray(getattr(result, attr))[start:stop].reshape(stop - start, len(names))
                    for attr, names in _columns(size, joints)
                ]
            )
            np.savetxt(stream, block, delimiter=",", fmt="%.18e")
        stream.write(f"{CSV_END}{n} rows\n")


def _write_npz(result: SimulationResult, path: Path) -> None:
    names = ("t", "hjb_error", "cost", *_RESULT_ARRAYS, "covariance_reset_times")
    np.savez_compressed(
        path,
        **{name: getattr(result, name) for name in names},
        config_json=np.array(json.dumps(result.config.to_dict())),
        status=np.array(result.status),
        wall_time=np.array(result.wall_time),
        format_version=np.array(FORMAT_VERSION),
    )


_RESULT_ARRAYS = tuple(attr for attr, _ in _COLUMNS if attr not in ("t", "hjb_error", "cost"))


def save_result(result: SimulationResult, path: str | Path) -> Path:
    """Write ``result`` to ``path`` atomically (a temporary file renamed into place: never a
    truncated file). ``.npz`` keeps everything (arrays, config, status, wall time); ``.csv``
    writes a first line ``# adparm result {json}`` (config, status, wall time, covariance
    resets), a header line and the time series (read it with :func:`load_result`, or with
    ``pandas.read_csv(path, comment="#")``)."""
    from ._files import atomic_write

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"path: expected a .npz or .csv file name, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = _write_csv if suffix == ".csv" else _write_npz
    return atomic_write(path, lambda temporary: writer(result, temporary))


def _corrupt(path: Path, why: str) -> ValueError:
    return ValueError(
        f"{path}: not a complete adparm result ({why}); the file is truncated, corrupt or not "
        "written by adparm's save()"
    )


def _load_csv(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    try:
        with open(path, encoding="utf-8") as stream:
            first = stream.readline()
            if not first.startswith(CSV_PREFIX):
                raise _corrupt(path, f"the first line does not start with {CSV_PREFIX.strip()!r}")
            meta = json.loads(first[len(CSV_PREFIX) :])
            header = stream.readline().strip().split(",")
            size = sum(1 for name in header if name.startswith("Wc"))  # the basis size
            joints = sum(1 for name in header if name.startswith("dq"))  # n
            if header != columns(size, joints):
                raise _corrupt(path, "the header line does not name adparm's columns")
            lines = stream.read().splitlines()
            if not lines or lines[-1] != f"{CSV_END}{len(lines) - 1} rows":
                raise _corrupt(path, f"no last line {CSV_END.strip()!r} with the number of rows")
            data = np.loadtxt(lines[:-1], delimiter=",", ndmin=2)
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise _corrupt(path, str(error)) from None
    except ValueError as error:
        if "not a complete adparm result" in str(error):
            raise
        raise _corrupt(path, str(error)) from None
    if not isinstance(meta, dict):
        raise _corrupt(path, "the first line holds no JSON object")
    width = len(columns(size, joints))
    if data.size == 0:
        data = np.zeros((0, width))
    if data.shape[1] != width:
        raise _corrupt(path, f"expected {width} columns, got {data.shape[1]}")
    fields: dict[str, Any] = {}
    start = 0
    for attr, names in _columns(size, joints):
        block = data[:, start : start + len(names)]
        fields[attr] = block[:, 0] if attr in ("t", "hjb_error", "cost") else block
        start += len(names)
    fields["covariance_reset_times"] = np.array(meta.get("covariance_reset_times", []), float)
    wall = meta.get("wall_time")
    extra = {
        "format_version": meta.get("format_version"),
        "config": meta.get("config"),
        "status": meta.get("status"),
        "wall_time": float("nan") if wall is None else wall,
    }
    return fields, extra


def _load_npz(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    try:
        with open(path, "rb") as stream, np.load(stream, allow_pickle=False) as data:
            fields: dict[str, Any] = {name: data[name] for name in data.files}
    except (AttributeError, TypeError):  # np.load gave an array or a pickle, not an archive
        raise _corrupt(path, "not a .npz archive") from None
    except (zipfile.BadZipFile, EOFError, zlib.error, KeyError, OSError) as error:
        raise _corrupt(path, f"{type(error).__name__}: {error}") from None
    except ValueError as error:
        if "not a complete adparm result" in str(error):
            raise
        raise _corrupt(path, str(error)) from None
    missing = [
        k for k in ("format_version", "config_json", "status", "wall_time") if k not in fields
    ]
    if missing:
        raise _corrupt(path, f"missing {', '.join(missing)}")
    try:
        extra = {
            "format_version": int(fields.pop("format_version")),
            "config": json.loads(str(fields.pop("config_json"))),
            "status": str(fields.pop("status")),
            "wall_time": float(fields.pop("wall_time")),
        }
    except (TypeError, ValueError) as error:
        raise _corrupt(path, str(error)) from None
    return fields, extra


def load_result(path: str | Path) -> SimulationResult:
    """Read a result written by ``SimulationResult.save(path)`` (``.npz`` or ``.csv``); a
    truncated or corrupt file gives a ValueError saying so."""
    from .simulation import SimulationResult

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"path: expected a .npz or .csv file written by save(), got {str(path)!r}")
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    fields, extra = (_load_csv if suffix == ".csv" else _load_npz)(path)
    version = extra["format_version"]
    if version != FORMAT_VERSION:
        raise ValueError(
            f"{path}: result format version {version}, this adparm reads version "
            f"{FORMAT_VERSION} (written by another adparm version)"
        )
    if not isinstance(extra["config"], dict):
        raise _corrupt(path, "no configuration")
    config = Config.from_dict(extra["config"])
    try:
        return SimulationResult(
            **fields, config=config, status=extra["status"], wall_time=extra["wall_time"]
        )
    except (TypeError, ValueError) as error:
        raise _corrupt(path, str(error)) from None
