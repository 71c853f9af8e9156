"""Saving and loading results: ``.npz`` (everything) and ``.csv`` (the time series, with a first
line holding the rest), both written atomically and both read back by :func:`load_result`."""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import tempfile
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from ._files import atomic_write
from .config import Config
from .dynamics import base_parameter_names
from .result import (
    ARRAYS_1,
    ARRAYS_2,
    ARRAYS_IDENTIFIER,
    ARRAYS_N,
    RECORDED_SERIES,
    SimulationResult,
    register,
)
from .simulation import available_memory

__all__ = ["FORMAT_VERSION", "columns", "load_result", "save_result", "table"]

FORMAT_VERSION = 3  # 3: tau_commanded and saturated_time (torque limits)

# (result attribute, column names) of each recorded series, in the core's order; one column per
# joint j = 1 ... n ("{j}") and per basis function i = 1 ... K ("{i}", in the order of
# adparm.basis_names(config)). A joint series' columns are its name and j, except those below.
_COLUMN_NAMES = {
    "e1": "e1_{j}",
    "e2": "e2_{j}",
    "critic_weights": "Wc{i}",
    "actor_weights": "Wa{i}",
    "model_parameters": "beta_hat{p}",  # p = 1 ... P, in the order of base_parameter_names
}
_COLUMNS: tuple[tuple[str, str], ...] = tuple(
    (name, _COLUMN_NAMES.get(name, name + "{j}" if width == "joints" else name))
    for name, width in RECORDED_SERIES
)


# The series of one value per row (widths "one" and "identifier"): a 1-d array of the result.
_ONE_COLUMN = tuple(name for name, width in RECORDED_SERIES if width in ("one", "identifier"))


def _columns(
    basis_size: int, joints: int = 2, parameters: int = 0
) -> list[tuple[str, tuple[str, ...]]]:
    out = []
    for attr, template in _COLUMNS:
        if attr in ARRAYS_IDENTIFIER and parameters == 0:
            continue  # the identifier's series: only with identification
        if "{i}" in template:
            names = tuple(template.format(i=i) for i in range(1, basis_size + 1))
        elif "{j}" in template:
            names = tuple(template.format(j=j) for j in range(1, joints + 1))
        elif "{p}" in template:
            names = tuple(template.format(p=p) for p in range(1, parameters + 1))
        else:
            names = (template,)
        out.append((attr, names))
    return out


def columns(basis_size: int = 8, joints: int = 2, parameters: int = 0) -> list[str]:
    """Column names of :func:`table`, the CSV file and ``to_dataframe()`` for a basis of
    ``basis_size`` functions (8; 6 for the structured basis) and an arm of ``joints`` joints;
    with identification (``parameters`` > 0 identified parameters) also beta_hat1 ...,
    stack_singular_value and stack_uncertainty."""
    return [name for _, names in _columns(basis_size, joints, parameters) for name in names]


def _shape(result: SimulationResult) -> tuple[int, int, int]:
    """(basis size, joints, identified parameters or 0) of ``result``'s columns."""
    parameters = 0 if result.model_parameters is None else result.model_parameters.shape[1]
    return result.critic_weights.shape[1], result.q.shape[1], parameters


def table(result: SimulationResult) -> np.ndarray:
    """The recorded time series as one (rows, len(columns(K))) array."""
    n = result.t.size
    return np.hstack(
        [
            np.asarray(getattr(result, attr)).reshape(n, len(names))
            for attr, names in _columns(*_shape(result))
        ]
    )


# The first line of a result's CSV file: this prefix, then JSON of what the columns do not hold.
CSV_PREFIX = "# adparm result "
# Its last line (a reader can tell a complete file from a cut one): this prefix, then the rows.
CSV_END = "# adparm end: "
# Rows formatted at a time when writing CSV (no copy of the whole recording).
_CSV_ROWS = 10_000


# The longest first line of a result's CSV file (JSON of the config and of the URDFs embedded)
# and the longest JSON a .npz holds; the deepest nesting of that JSON.
MAX_HEADER_BYTES = 64 * 2**20
MAX_JSON_DEPTH = 64
# URDF fields of a config whose file a result embeds (section, key).
_URDF_FIELDS = (("plant", "urdf"), ("model", "urdf"))
_JSON_STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"')


def _urdf_copies(config: dict[str, Any]) -> list[dict[str, str]]:
    """The URDF files ``config`` (Config.to_dict()) names, embedded: [{"field", "path",
    "sha256", "text"}], so that a result reads back the same arm once the file moves or
    changes."""
    out = []
    for section, key in _URDF_FIELDS:
        path = (config.get(section) or {}).get(key)
        if not path:
            continue
        data = Path(path).read_bytes()
        out.append(
            {
                "field": f"{section}.{key}",
                "path": str(path),
                "sha256": hashlib.sha256(data).hexdigest(),
                "text": data.decode("utf-8"),
            }
        )
    return out


def urdf_cache_folder() -> Path:
    """Where load_result writes the URDFs embedded in results: $ADPARM_CACHE, else
    $XDG_CACHE_HOME/adparm or ~/.cache/adparm, then urdf/ (one file per content: its sha256)."""
    root = os.environ.get("ADPARM_CACHE")
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(base, "adparm")
    return Path(root) / "urdf"


def _cached_urdf(path: Path, copy: Any) -> str:
    """The path of a cache file holding the URDF ``copy`` embedded in the result at ``path``
    (checked against its sha256), written if missing."""
    if not isinstance(copy, dict) or not all(
        isinstance(copy.get(k), str) for k in ("field", "path", "sha256", "text")
    ):
        raise _corrupt(path, "an embedded URDF is not {field, path, sha256, text}")
    data = copy["text"].encode("utf-8")
    digest = hashlib.sha256(data).hexdigest()
    if digest != copy["sha256"]:
        raise _corrupt(path, f"the URDF embedded for {copy['field']} does not match its sha256")
    name = Path(copy["path"]).name or "arm.urdf"
    if not name.lower().endswith(".urdf"):
        name += ".urdf"
    for folder in (urdf_cache_folder(), Path(tempfile.gettempdir()) / f"adparm-{os.getuid()}"):
        target = folder / digest / name
        try:
            if target.is_file() and hashlib.sha256(target.read_bytes()).hexdigest() == digest:
                return str(target)
            target.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(target, lambda temporary: Path(temporary).write_bytes(data))
            return str(target)
        except OSError:
            continue  # not writable: the next folder
    raise ValueError(
        f"{path}: cannot write the URDF embedded for {copy['field']} to {urdf_cache_folder()} "
        "(set ADPARM_CACHE to a writable folder)"
    )


def _with_embedded_urdfs(path: Path, config: dict[str, Any], copies: Any) -> dict[str, Any]:
    """``config`` with each URDF field pointing at a cache copy of the URDF embedded in the
    result (not at the file it was run with, which may have moved or changed)."""
    if copies is None:  # written before URDFs were embedded: the paths as recorded
        return config
    if not isinstance(copies, list):
        raise _corrupt(path, "the embedded URDFs are not a list")
    config = dict(config)
    for copy in copies:
        cached = _cached_urdf(path, copy)
        section, key = copy["field"].split(".", 1) if "." in copy["field"] else ("", "")
        if (section, key) not in _URDF_FIELDS or not isinstance(config.get(section), dict):
            raise _corrupt(path, f"an embedded URDF names no URDF field ({copy['field']!r})")
        config[section] = {**config[section], key: cached}
    return config


def _json(path: Path, text: str, what: str) -> Any:
    """``text`` parsed as JSON, refusing nesting deeper than MAX_JSON_DEPTH before parsing (a
    clear ValueError, not a RecursionError)."""
    bare = _JSON_STRING.sub("", text).encode("utf-8", "replace")  # brackets outside strings
    steps = np.frombuffer(bare, dtype=np.uint8)
    change = np.isin(steps, (91, 123)).astype(np.int64) - np.isin(steps, (93, 125))
    if change.size and int(np.cumsum(change).max()) > MAX_JSON_DEPTH:
        raise _corrupt(path, f"{what} nests deeper than {MAX_JSON_DEPTH} levels")
    try:
        return json.loads(text)
    except RecursionError:  # pragma: no cover - caught by the depth check
        raise _corrupt(path, f"{what} nests too deeply") from None


def _metadata(result: SimulationResult) -> dict[str, Any]:
    config = result.config.to_dict()
    return {
        "format_version": FORMAT_VERSION,
        "status": result.status,
        "wall_time": result.wall_time if np.isfinite(result.wall_time) else None,
        "covariance_reset_times": result.covariance_reset_times.tolist(),
        "saturated_time": result.saturated_time.tolist(),
        "config": config,
        "urdf": _urdf_copies(config),
    }


def write_result_csv(result: SimulationResult, path: Path) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as stream:
        stream.write(CSV_PREFIX + json.dumps(_metadata(result)) + "\n")
        stream.write(",".join(columns(*_shape(result))) + "\n")
        n = result.t.size
        for start in range(0, n, _CSV_ROWS):
            stop = min(n, start + _CSV_ROWS)
            block = np.hstack(
                [
                    np.asarray(getattr(result, attr))[start:stop].reshape(stop - start, len(names))
                    for attr, names in _columns(*_shape(result))
                ]
            )
            np.savetxt(stream, block, delimiter=",", fmt="%.18e")
        stream.write(f"{CSV_END}{n} rows\n")


def write_result_npz(result: SimulationResult, path: Path) -> None:
    names = (*ARRAYS_1, *_RESULT_ARRAYS, "covariance_reset_times", "saturated_time")
    names += tuple(name for name in ARRAYS_IDENTIFIER if getattr(result, name) is not None)
    config = result.config.to_dict()
    np.savez_compressed(
        path,
        **{name: getattr(result, name) for name in names},
        config_json=np.array(json.dumps(config)),
        urdf_json=np.array(json.dumps(_urdf_copies(config))),
        status=np.array(result.status),
        wall_time=np.array(result.wall_time),
        format_version=np.array(FORMAT_VERSION),
    )


_RESULT_ARRAYS = (*ARRAYS_2, *ARRAYS_N)


def save_result(result: SimulationResult, path: str | Path) -> Path:
    """Write ``result`` to ``path`` atomically (a temporary file renamed into place: never a
    truncated file). ``.npz`` keeps everything (arrays, config, status, wall time); ``.csv``
    writes a first line ``# adparm result {json}`` (config, status, wall time, covariance
    resets), a header line and the time series (read it with :func:`load_result`, or with
    ``pandas.read_csv(path, comment="#")``)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"path: expected a .npz or .csv file name, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = write_result_csv if suffix == ".csv" else write_result_npz
    return atomic_write(path, lambda temporary: writer(result, temporary))


def _corrupt(path: Path, why: str) -> ValueError:
    return ValueError(
        f"{path}: not a complete adparm result ({why}); the file is truncated, corrupt or not "
        "written by adparm's save()"
    )


def _load_csv(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    try:
        with open(path, encoding="utf-8") as stream:
            first = stream.readline(MAX_HEADER_BYTES + 1)
            if not first.startswith(CSV_PREFIX):
                raise _corrupt(path, f"the first line does not start with {CSV_PREFIX.strip()!r}")
            if len(first) > MAX_HEADER_BYTES:
                raise _corrupt(path, f"the first line is longer than {MAX_HEADER_BYTES} bytes")
            meta = _json(path, first[len(CSV_PREFIX) :], "the first line's JSON")
            header = stream.readline().strip().split(",")
            size = sum(1 for name in header if name.startswith("Wc"))  # the basis size
            joints = sum(1 for name in header if name.startswith("dq"))  # n
            parameters = sum(1 for name in header if name.startswith("beta_hat"))
            if header != columns(size, joints, parameters):
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
    width = len(columns(size, joints, parameters))
    if data.size == 0:
        data = np.zeros((0, width))
    if data.shape[1] != width:
        raise _corrupt(path, f"expected {width} columns, got {data.shape[1]}")
    fields: dict[str, Any] = {}
    start = 0
    for attr, names in _columns(size, joints, parameters):
        block = data[:, start : start + len(names)]
        fields[attr] = block[:, 0] if attr in _ONE_COLUMN else block
        start += len(names)
    fields["covariance_reset_times"] = np.array(meta.get("covariance_reset_times", []), float)
    if meta.get("saturated_time") is not None:
        fields["saturated_time"] = np.array(meta["saturated_time"], float)
    wall = meta.get("wall_time")
    extra = {
        "format_version": meta.get("format_version"),
        "config": meta.get("config"),
        "urdf": meta.get("urdf"),
        "status": meta.get("status"),
        "wall_time": float("nan") if wall is None else wall,
    }
    return fields, extra


# Small members of a .npz result: 0-d strings (JSON, status) and numbers.
_NPZ_SCALARS = ("format_version", "config_json", "urdf_json", "status", "wall_time")


def _npz_header(path: Path, archive: zipfile.ZipFile, name: str) -> tuple[tuple[int, ...], Any]:
    """(shape, dtype) a member of a .npz declares in its .npy header, read without its data."""
    with archive.open(name + ".npy") as member:
        version = np.lib.format.read_magic(member)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(member)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(member)
        else:
            raise _corrupt(path, f"{name}: .npy format version {version}")
    return shape, dtype


def _check_npz_sizes(path: Path, archive: zipfile.ZipFile, config: Config) -> None:
    """Refuse, before reading them, arrays whose declared shape or dtype is not the one a run of
    ``config`` records (float64; at most its rows, n joints, K weights), or that would not fit
    in memory: a small file cannot make load_result allocate gigabytes."""
    steps = math.ceil(config.sim.T / config.sim.dt * (1.0 - 1e-12))
    rows = steps // config.sim.record_every + 2
    n, k = config.dof, config.basis_size
    expected: dict[str, tuple[int, ...]] = {
        "covariance_reset_times": (steps + 1,),
        "saturated_time": (n,),
    }
    expected.update({name: (rows,) for name in ARRAYS_1})
    expected.update({name: (rows, n) for name in ARRAYS_2})
    expected.update({name: (rows, k) for name in ARRAYS_N})
    if config.identifier.enabled:
        expected["model_parameters"] = (rows, len(base_parameter_names(config)))
        expected["stack_singular_value"] = (rows,)
        expected["stack_uncertainty"] = (rows,)
    unknown = [
        member
        for member in archive.namelist()
        if member.removesuffix(".npy") not in (*expected, *_NPZ_SCALARS)
    ]
    if unknown:
        raise _corrupt(path, f"unknown members {', '.join(unknown[:5])}")
    total = 0
    for name, most in expected.items():
        if name + ".npy" not in archive.namelist():
            continue
        shape, dtype = _npz_header(path, archive, name)
        if dtype != np.dtype(float) or len(shape) != len(most):
            raise _corrupt(
                path,
                f"{name}: expected float64 of {len(most)} dimensions, got {dtype} of shape {shape}",
            )
        columns_ok = len(most) == 1 or shape[1] == most[1]
        if shape[0] > most[0] or not columns_ok:
            raise ValueError(
                f"{path}: {name} declares shape {shape}, more than the run of its config records "
                f"(at most {most}); refused before reading it"
            )
        total += 8 * math.prod(shape)
    available = available_memory()
    if available is not None and total > available:
        raise ValueError(
            f"{path}: its arrays would need {total / 2**30:.3g} GiB, more than the "
            f"{available / 2**30:.3g} GiB available now; refused before reading them"
        )


def _load_npz(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    try:
        with open(path, "rb") as stream, np.load(stream, allow_pickle=False) as data:
            missing = [k for k in _NPZ_SCALARS if k != "urdf_json" and k not in data.files]
            if missing:
                raise _corrupt(path, f"missing {', '.join(missing)}")
            archive = data.zip
            scalars: dict[str, Any] = {}
            for name in _NPZ_SCALARS:
                if name not in data.files:
                    continue
                shape, dtype = _npz_header(path, archive, name)
                if shape != () or dtype.itemsize > 4 * MAX_HEADER_BYTES or dtype.hasobject:
                    raise _corrupt(path, f"{name}: expected one value, got {dtype} {shape}")
                scalars[name] = data[name]
            try:
                extra = {
                    "format_version": int(scalars["format_version"]),
                    "config": _json(path, str(scalars["config_json"]), "config_json"),
                    "urdf": (
                        _json(path, str(scalars["urdf_json"]), "urdf_json")
                        if "urdf_json" in scalars
                        else None
                    ),
                    "status": str(scalars["status"]),
                    "wall_time": float(scalars["wall_time"]),
                }
            except (TypeError, ValueError) as error:
                if "not a complete adparm result" in str(error):
                    raise
                raise _corrupt(path, str(error)) from None
            extra["config"] = _config(path, extra)
            _check_npz_sizes(path, archive, extra["config"])
            fields: dict[str, Any] = {
                name: data[name] for name in data.files if name not in _NPZ_SCALARS
            }
    except (AttributeError, TypeError):  # np.load gave an array or a pickle, not an archive
        raise _corrupt(path, "not a .npz archive") from None
    except (zipfile.BadZipFile, EOFError, zlib.error, KeyError, OSError) as error:
        raise _corrupt(path, f"{type(error).__name__}: {error}") from None
    except ValueError as error:
        if "not a complete adparm result" in str(error) or "refused before" in str(error):
            raise
        raise _corrupt(path, str(error)) from None
    return fields, extra


def _config(path: Path, extra: dict[str, Any]) -> Config:
    """The run's Config, its URDF fields pointing at the copies embedded in the result."""
    version = extra["format_version"]
    if version != FORMAT_VERSION:
        raise ValueError(
            f"{path}: result format version {version}, this adparm reads version "
            f"{FORMAT_VERSION} (written by another adparm version)"
        )
    if not isinstance(extra["config"], dict):
        raise _corrupt(path, "no configuration")
    return Config.from_dict(_with_embedded_urdfs(path, extra["config"], extra.get("urdf")))


def load_result(path: str | Path) -> SimulationResult:
    """Read a result written by ``SimulationResult.save(path)`` (``.npz`` or ``.csv``); a
    truncated or corrupt file gives a ValueError saying so. A URDF arm's run reads back the URDF
    embedded in the file (written to urdf_cache_folder(), named by its sha256), not the file it
    was run with, which may since have moved or changed. Sizes are checked before anything is
    allocated: JSON nested deeper than MAX_JSON_DEPTH, a CSV first line longer than
    MAX_HEADER_BYTES, and .npz arrays larger than the run of the recorded config records (or
    than the memory available) are refused with a ValueError."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".csv"):
        raise ValueError(f"path: expected a .npz or .csv file written by save(), got {str(path)!r}")
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    fields, extra = (_load_csv if suffix == ".csv" else _load_npz)(path)
    config = extra["config"] if isinstance(extra["config"], Config) else _config(path, extra)
    try:
        return SimulationResult(
            **fields, config=config, status=extra["status"], wall_time=extra["wall_time"]
        )
    except (TypeError, ValueError) as error:
        raise _corrupt(path, str(error)) from None


def result_dataframe(result: SimulationResult) -> Any:
    """The time series of ``result`` as a pandas DataFrame (columns of :func:`columns`); needs
    pandas (``pip install pandas``). SimulationResult.to_dataframe calls it."""
    try:
        import pandas
    except ImportError as error:  # pragma: no cover - pandas is in the test extra
        raise ImportError("to_dataframe() needs pandas: pip install pandas") from error
    return pandas.DataFrame(
        table(result), columns=columns(result.critic_weights.shape[1], result.q.shape[1])
    )


register("save", lambda result, path: save_result(result, path))
register("to_dataframe", lambda result: result_dataframe(result))
