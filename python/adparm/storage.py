"""Saving and loading results: ``.npz`` (everything, loadable) and ``.csv`` (the time series)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .config import Config

if TYPE_CHECKING:  # pragma: no cover
    from .simulation import SimulationResult

__all__ = ["FORMAT_VERSION", "columns", "load_result", "save_result", "table"]

FORMAT_VERSION = 2

# (result attribute, column names); weights in the order of adparm.BASIS_NAMES.
_COLUMNS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("t", ("t",)),
    ("q", ("q1", "q2")),
    ("dq", ("dq1", "dq2")),
    ("qd", ("qd1", "qd2")),
    ("e1", ("e1_1", "e1_2")),
    ("e2", ("e2_1", "e2_2")),
    ("tau", ("tau1", "tau2")),
    ("u", ("u1", "u2")),
    ("u_hat", ("u_hat1", "u_hat2")),
    ("mu", ("mu1", "mu2")),
    ("probe", ("probe1", "probe2")),
    ("critic_weights", ("Wc",)),  # Wc1 ... WcK, K the basis size
    ("actor_weights", ("Wa",)),
    ("hjb_error", ("hjb_error",)),
    ("cost", ("cost",)),
)


def _columns(basis_size: int) -> list[tuple[str, tuple[str, ...]]]:
    return [
        (attr, tuple(f"{names[0]}{i}" for i in range(1, basis_size + 1)))
        if attr in ("critic_weights", "actor_weights")
        else (attr, names)
        for attr, names in _COLUMNS
    ]


def columns(basis_size: int = 8) -> list[str]:
    """Column names of :func:`table`, the CSV file and ``to_dataframe()`` for a basis of
    ``basis_size`` functions (8; 6 for the structured basis)."""
    return [name for _, names in _columns(basis_size) for name in names]


def table(result: SimulationResult) -> np.ndarray:
    """The recorded time series as one (rows, len(columns(K))) array."""
    n = result.t.size
    size = result.critic_weights.shape[1]
    return np.hstack(
        [np.asarray(getattr(result, attr)).reshape(n, len(names)) for attr, names in _columns(size)]
    )


def save_result(result: SimulationResult, path: str | Path) -> Path:
    """Write ``result`` to ``path``: ``.npz`` keeps everything (arrays, config, status, wall
    time) for :func:`load_result`; ``.csv`` writes the time series with a header line."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"path: expected a .npz or .csv file name, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".csv":
        header = ",".join(columns(result.critic_weights.shape[1]))
        np.savetxt(path, table(result), delimiter=",", header=header, comments="")
        return path
    arrays = result.to_dict()
    arrays.pop("status")
    arrays.pop("wall_time")
    np.savez_compressed(
        path,
        **arrays,
        config_json=np.array(json.dumps(result.config.to_dict())),
        status=np.array(result.status),
        wall_time=np.array(result.wall_time),
        format_version=np.array(FORMAT_VERSION),
    )
    return path


def load_result(path: str | Path) -> SimulationResult:
    """Read a result written by ``SimulationResult.save(path)`` with a ``.npz`` name."""
    from .simulation import SimulationResult

    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise ValueError(f"path: expected a .npz file written by save(), got {str(path)!r}")
    with np.load(path, allow_pickle=False) as data:
        fields: dict[str, Any] = {name: data[name] for name in data.files}
    version = int(fields.pop("format_version", -1))
    if version != FORMAT_VERSION:
        raise ValueError(f"{path}: unsupported result format version {version}")
    config = Config.from_dict(json.loads(str(fields.pop("config_json"))))
    status = str(fields.pop("status"))
    wall_time = float(fields.pop("wall_time"))
    return SimulationResult(**fields, config=config, status=status, wall_time=wall_time)
