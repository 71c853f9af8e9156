"""The value checks of the configuration's fields, each naming the field ("section.key") and what
it expects; the "did you mean" hint; bounded reading of text files; the TOML text writer.

The bottom of the configuration schema: it knows no section (adparm._sections,
adparm._arm_sections) and no arm."""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

Vector = tuple[float, ...]
Matrix = tuple[tuple[float, ...], ...]

#: The value of a setting that is derived for the run (sim.dt = "auto").
AUTO = "auto"


def setting(default: Any, doc: str, *, core: str | None = None, via: str | None = None) -> Any:
    """A field of a configuration section: its default, its meaning ``doc`` (reStructuredText,
    shown by the docs' configuration reference) and where the core takes it: ``core``, the
    attribute of the core's Settings it is copied to as it is ("critic.eta_c";
    translate.core_settings copies every such field), or ``via``, how the core gets it instead (a
    conversion, a derived value, or not at all). In ``metadata``: "doc", "core", "via"."""
    if (core is None) == (via is None):
        raise TypeError("setting: give either core (the core attribute) or via (why not copied)")
    return dataclasses.field(default=default, metadata={"doc": doc, "core": core, "via": via})


# --- field checks: each names the field ("section.key") and what it expects -------------------


def value_text(value: Any, limit: int = 120) -> str:
    """repr(value) cut to ``limit`` characters, for messages (never raises)."""
    try:
        text = repr(value)
    except Exception:  # e.g. an int of more than 4300 digits
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def key_text(name: str, limit: int = 80) -> str:
    """A section or key name as given, cut to ``limit`` characters."""
    return name if len(name) <= limit else name[: limit - 3] + "..."


def int_text(value: int) -> str:
    """str(value), or its size for an integer too long to print (Python refuses str() beyond 4300
    digits)."""
    if value.bit_length() < 128:
        return str(value)
    sign = "a negative" if value < 0 else "an"
    return f"{sign} integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"


def scalar_value(
    value: Any,
    name: str,
    *,
    minimum: float | None = None,
    strict: bool = False,
    maximum: float | None = None,
) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(
            f"{name}: expected a number, got {type(value).__name__} {value_text(value)}"
        )
    try:
        value = float(value)
    except OverflowError:  # an int or Fraction beyond the float range
        text = int_text(int(value)) if isinstance(value, numbers.Integral) else value_text(value)
        raise ValueError(f"{name}: must be finite, got {text}") from None
    if not math.isfinite(value):
        raise ValueError(f"{name}: must be finite, got {value}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        relation = ">" if strict else ">="
        raise ValueError(f"{name}: must be {relation} {minimum:g}, got {value:g}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name}: must be <= {maximum:g}, got {value:g}")
    return value


def integer_value(value: Any, name: str, *, minimum: int, maximum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(
            f"{name}: expected an integer, got {type(value).__name__} {value_text(value)}"
        )
    value = int(value)
    if value < minimum:
        raise ValueError(f"{name}: must be >= {minimum}, got {int_text(value)}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name}: must be <= {maximum:_}, got {int_text(value)}")
    return value


def boolean_value(value: Any, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(
            f"{name}: expected true or false, got {type(value).__name__} {value_text(value)}"
        )
    return bool(value)


def choice_value(value: Any, name: str, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected one of {', '.join(choices)}, got {value_text(value)}")
    if value not in choices:
        raise ValueError(
            f"{name}: expected one of {', '.join(choices)}, got {value_text(value)}"
            f"{did_you_mean(value, choices)}"
        )
    return value


def is_number(value: Any) -> bool:
    """A real number that is not a bool (nor numpy's bool_)."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


#: Deepest nesting of lists and tables a config value may have (the deepest field needs 3).
MAX_DEPTH = 16


def check_depth(value: Any, name: str) -> None:
    """Refuses values nested deeper than MAX_DEPTH (lists, tuples, mappings, arrays), naming the
    field, before NumPy (32 dimensions at most) or a recursion meets them."""
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, Mapping):
            children = list(item.values())
        elif isinstance(item, (list, tuple)):
            children = list(item)
        elif isinstance(item, np.ndarray) and item.dtype == object:
            children = list(item.flat)
        else:
            continue
        if depth > MAX_DEPTH:
            raise ValueError(f"{name}: nested more than {MAX_DEPTH} levels deep")
        stack.extend((child, depth + 1) for child in children)


def plain_array(value: Any, name: str) -> Any:
    """np.matrix as a plain array; a masked array without masked entries as its data; a masked
    array with masked entries refused (NumPy would turn them into NaN or a fill value)."""
    if isinstance(value, np.ma.MaskedArray):
        if np.ma.count_masked(value):
            raise ValueError(
                f"{name}: a masked array with {np.ma.count_masked(value)} masked entries; give "
                "plain numbers (e.g. value.filled(...))"
            )
        return np.asarray(value.data)
    if isinstance(value, np.matrix):
        return np.asarray(value)
    return value


def array_value(value: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """A finite float array of ``shape`` (None: any length) from nested lists or an array of
    real numbers; strings, bools, complex numbers, None and mappings are refused (TypeError),
    as are ragged lists."""
    expected = f"an array of numbers of shape {shape_text(shape)}"
    value = plain_array(value, name)
    check_depth(value, name)
    if isinstance(value, (str, bytes, Mapping, bool, np.bool_)) or value is None:
        raise TypeError(f"{name}: expected {expected}, got {value_text(value)}")
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        raw = value  # its dtype tells the truth: no bool or string hides inside
    else:
        # dtype object keeps every element as given (np.asarray(..., dtype=float) would turn
        # "1" and True into 1.0); a ragged list becomes an array of lists, refused below
        try:
            raw = np.array(value, dtype=object)
        except (TypeError, ValueError) as error:
            raise TypeError(f"{name}: expected {expected}, got {value_text(value)}") from error
        for element in raw.flat:
            if not is_number(element):
                raise TypeError(
                    f"{name}: expected {expected}, got {value_text(value)} (holds "
                    f"{type(element).__name__} {value_text(element, 40)})"
                )
    if raw.ndim != len(shape) or any(
        size is not None and actual != size for actual, size in zip(raw.shape, shape, strict=False)
    ):
        raise ValueError(f"{name}: expected shape {shape_text(shape)}, got {tuple(raw.shape)}")
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # long double beyond float: inf
            array = raw.astype(float)
    except OverflowError:  # an int beyond the float range
        raise ValueError(f"{name}: must be finite, got {value_text(value)}") from None
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: must be finite, got {value_text(array.tolist())}")
    return array


def ndim_of(value: Any) -> int:
    """np.ndim, or -1 for what is no array (a ragged list): the checks then name the field."""
    try:
        return int(np.ndim(value))
    except (TypeError, ValueError, RuntimeError):  # RuntimeError: more than 32 dimensions
        return -1


def shape_text(shape: tuple[int | None, ...]) -> str:
    return (
        "("
        + ", ".join("n" if s is None else str(s) for s in shape)
        + ("," if len(shape) == 1 else "")
        + ")"
    )


def rows_value(value: Any, name: str, columns: int | None) -> Matrix:
    """An (n,) vector (one column) or an (n, k) matrix, as an (n, k) matrix (n joints: checked
    by Config against the arm)."""
    if ndim_of(value) == 1:
        return tuple((v,) for v in vector_value(value, name, None))
    return matrix_value(value, name, None, columns)


def square_matrix(value: Any, name: str) -> Matrix:
    """A square matrix of any size (checked by Config against the arm's joint count)."""
    matrix = matrix_value(value, name, None, None)
    if len(matrix) == 0 or len(matrix) != len(matrix[0]):
        raise ValueError(
            f"{name}: expected a square matrix, got shape ({len(matrix)}, "
            f"{len(matrix[0]) if matrix else 0})"
        )
    return matrix


def gain_value(value: Any, name: str) -> float | Matrix:
    """A number (times the identity) or an n x n matrix."""
    if is_number(value):
        return scalar_value(value, name)
    return square_matrix(value, name)


def check_known(
    name: Any, known: Sequence[str], *, strings: str, unknown: str, listing: str
) -> None:
    """Refuses a ``name`` that is not one of ``known``: TypeError ``strings`` for a non-string,
    ValueError ``unknown`` (a template of ``{name}``) with a "did you mean" hint; both messages end
    with ``listing``."""
    if not isinstance(name, str):
        raise TypeError(f"{strings}, got {type(name).__name__} {value_text(name)}; {listing}")
    if name not in known:
        raise ValueError(
            f"{unknown.format(name=key_text(name))}{did_you_mean(name, known)}; {listing}"
        )


def check_keys(values: Mapping[str, Any], keys: list[str], where: str) -> None:
    for key in values:
        check_known(
            key,
            keys,
            strings=f"[{where}]: key names must be strings",
            unknown=f"unknown key {where}.{{name}}",
            listing=f"known keys of [{where}]: {', '.join(keys)}",
        )


def vector_value(value: Any, name: str, size: int | None) -> Vector:
    if isinstance(value, (bool, np.bool_, numbers.Real)):
        raise TypeError(
            f"{name}: expected a list of {size or 'n'} numbers, got {value_text(value)}"
        )
    return tuple(float(v) for v in array_value(value, name, (size,)))


def matrix_value(value: Any, name: str, rows: int | None, cols: int | None) -> Matrix:
    return tuple(tuple(float(v) for v in row) for row in array_value(value, name, (rows, cols)))


def symmetric_positive_definite(matrix: Matrix, name: str) -> Matrix:
    """The C++ core's test (cost.hpp), on matrix / max|entry| so that no square overflows:
    symmetric to 1e-12 (relative, Frobenius norm), and positive definite: a Cholesky factor
    exists. Returns the exactly symmetric 0.5 (M + M^T): a matrix asymmetric by round-off (one
    ulp) is accepted here, so every later step (python-control's care, CasADi) gets it
    symmetric."""
    array = np.array(matrix)
    scale = np.abs(array).max()
    scaled = array / scale if scale > 0.0 else array
    if np.sum((scaled - scaled.T) ** 2) > 1e-24 * np.sum(scaled**2):
        raise ValueError(f"{name}: must be symmetric, got {value_text(array.tolist(), 300)}")
    try:
        np.linalg.cholesky(scaled)
        positive_definite = scale > 0.0
    except np.linalg.LinAlgError:
        positive_definite = False
    if not positive_definite:
        raise ValueError(
            f"{name}: must be positive definite, got {value_text(array.tolist(), 300)}"
        )
    symmetric = 0.5 * (array + array.T)
    if not np.all(np.isfinite(symmetric)):  # 0.5 (a + b) overflows only where a + b does
        symmetric = 0.5 * array + 0.5 * array.T
    return tuple(tuple(float(v) for v in row) for row in symmetric)


def check_arm(p1: float, p2: float, p3: float, section: str) -> None:
    """M(q) > 0 for every q: p2 > 0 and det M = p1 p2 - p2^2 - p3^2 cos^2 q2 > 0. The core
    (arm_model.hpp) computes the same expression and refuses it when it overflows."""
    if p2 <= 0.0:
        raise ValueError(f"{section}.p2: must be > 0, got {p2:g}")
    det = p1 * p2 - p2 * p2 - p3 * p3  # inf - inf = nan for huge values: refused too
    if not (det > 0.0 and math.isfinite(det)):
        raise ValueError(
            f"{section}.p1, {section}.p2, {section}.p3: M(q) must be positive definite for every q "
            f"(need p1 p2 - p2^2 - p3^2 > 0 and finite, got {det:g})"
        )


def check_hurwitz(alpha1: Matrix, name: str) -> None:
    """-alpha1 Hurwitz: every eigenvalue of alpha1 has a positive real part, i.e. (2 x 2) trace > 0
    and det > 0, evaluated on alpha1 / max|entry| exactly as the core does (closed_loop.hpp);
    n x n: the eigenvalues of alpha1 / max|entry|."""
    scale = max(abs(v) for row in alpha1 for v in row)
    hurwitz = False
    if scale > 0.0 and len(alpha1) == 2:
        (a, b), (c, d) = ((v / scale for v in row) for row in alpha1)
        hurwitz = a + d > 0.0 and a * d - b * c > 0.0
    elif scale > 0.0:
        hurwitz = bool(np.all(np.linalg.eigvals(np.array(alpha1) / scale).real > 0.0))
    if not hurwitz:
        eigenvalues = ", ".join(f"{v:.3g}" for v in np.linalg.eigvals(np.array(alpha1)))
        raise ValueError(
            f"{name}: every eigenvalue must have a positive real part (-alpha1 Hurwitz, else "
            f"e1 in de1 = -alpha1 e1 + e2 grows), got eigenvalues {eigenvalues}"
        )


ARM_KEYS = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")
#: The keys of the built-in two-link arm only (refused together with a URDF arm).
TWO_LINK_KEYS = ("p1", "p2", "p3", "g1", "g2")
#: The defaults of the two-link keys (a URDF arm leaves them so).
TWO_LINK_DEFAULTS = {"p1": 5.0, "p2": 1.0, "p3": 1.0, "g1": 9.8 * 1.2, "g2": 9.8}
#: Gravity of a URDF arm when plant.gravity is left out (m/s^2, in the URDF's root frame).
DEFAULT_GRAVITY: Vector = (0.0, 0.0, -9.81)


def friction_value(value: Any, name: str) -> float | Vector:
    """A friction coefficient: one number (every joint) or one per joint (checked against n)."""
    if is_number(value):
        return scalar_value(value, name)
    return vector_value(value, name, None)


#: plant.torque_limits = "none": the drive applies any torque.
NO_LIMIT = "none"


def torque_limits_value(value: Any, name: str) -> float | Vector | str | None:
    """Torque limits: None (left out), "none", one number > 0 or a list of numbers > 0 (inf: no
    limit on that joint; checked against n with the other sizes)."""
    if value is None:
        return None
    if isinstance(value, str):
        if value.strip().lower() == NO_LIMIT:
            return NO_LIMIT
        raise ValueError(
            f'{name}: expected a number, a list of numbers (N m) or "none", got {value_text(value)}'
        )
    numbers = [value] if is_number(value) else value
    if isinstance(numbers, Mapping) or np.ndim(numbers) != 1:
        raise TypeError(
            f"{name}: expected a number or a list of numbers (N m), got {value_text(value)}"
        )
    limits = []
    for i, item in enumerate(numbers):
        where = "" if is_number(value) else f" (joint {i + 1})"
        if not is_number(item):
            raise TypeError(f"{name}: expected numbers (N m){where}, got {value_text(item)}")
        try:
            limit = float(item)
        except OverflowError:  # an int beyond the float range: no limit in practice
            limit = math.inf
        if not limit > 0.0:  # NaN too
            raise ValueError(
                f"{name}: a limit must be > 0 N m (inf: no limit){where}, got {value_text(item)}"
            )
        limits.append(limit)
    return limits[0] if is_number(value) else tuple(limits)


def limit_vector(limits: float | Vector | str | None, n: int) -> np.ndarray:
    """Torque limits of n joints as an array (inf: no limit on that joint), or an empty array
    when there are none (left out or "none": the core's Settings.torque_limits)."""
    if limits is None or limits == NO_LIMIT:
        return np.zeros(0)
    if isinstance(limits, float):
        return np.full(n, limits)
    return np.array(limits, dtype=float)


#: Limits on what a run may ask for: sinusoids of the probing signal, trajectory samples, and the
#: size of the files read (a configuration, a samples file).
MAX_FREQUENCIES = 1_000
MAX_SAMPLES = 1_000_000
MAX_CONFIG_BYTES = 16 * 2**20
MAX_SAMPLES_FILE_BYTES = 256 * 2**20


def read_text_file(path: str | Path, what: str, limit: int) -> str:
    """The UTF-8 text of the regular file ``path`` (a leading byte-order mark is dropped); a
    FIFO, a device, a folder, a file larger than ``limit`` bytes or one that is not UTF-8 text
    is refused with a ValueError naming ``what`` and the file."""
    import os
    import stat

    path = Path(path)
    try:
        descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except (OSError, ValueError) as error:  # ValueError: a NUL in the path
        raise ValueError(f"{what}: cannot read {str(path)!r}: {error}") from None
    try:
        info = os.fstat(descriptor)
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"{what}: {str(path)!r} is not a regular file")
        if info.st_size > limit:
            raise ValueError(
                f"{what}: {str(path)!r} is {info.st_size} bytes, more than the {limit} bytes "
                "adparm reads"
            )
        with os.fdopen(descriptor, "rb", closefd=False) as stream:
            data = stream.read(limit + 1)
    except OSError as error:
        raise ValueError(f"{what}: cannot read {str(path)!r}: {error}") from None
    finally:
        os.close(descriptor)
    if len(data) > limit:
        raise ValueError(f"{what}: {str(path)!r} is more than the {limit} bytes adparm reads")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise ValueError(
            f"{what}: {str(path)!r} is not UTF-8 text (byte 0x{data[error.start]:02x} at "
            f"offset {error.start})"
        ) from None


def did_you_mean(name: str, choices: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, choices, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


#: The width toml_text keeps a vector's line within (a longer vector is wrapped).
_TOML_WIDTH = 100
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _toml_key(key: str) -> str:
    import json

    return key if _BARE_KEY.match(key) else json.dumps(key)


def _toml_scalar(value: Any) -> str:
    import tomli_w

    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def _is_row(value: Any) -> bool:
    return isinstance(value, list) and not any(isinstance(v, (list, dict)) for v in value)


def _toml_value(value: Any, indent: str = "") -> str:
    """A TOML value: a matrix (a list of flat lists) one row per line, a vector on one line or
    wrapped within _TOML_WIDTH, a table inline."""
    if isinstance(value, dict):
        pairs = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{" + (f" {pairs} " if pairs else "") + "}"
    if not isinstance(value, list):
        return _toml_scalar(value)
    inner = indent + "    "
    if _is_row(value):
        items = [_toml_scalar(v) for v in value]
        line = "[" + ", ".join(items) + "]"
        if len(indent) + len(line) <= _TOML_WIDTH:
            return line
        lines: list[str] = []
        current = ""
        for item in items:
            if current and len(inner) + len(current) + len(item) + 2 > _TOML_WIDTH:
                lines.append(inner + current.rstrip().rstrip(","))
                current = ""
            current += item + ", "
        lines.append(inner + current.rstrip().rstrip(","))
        return "[\n" + ",\n".join(lines) + ",\n" + indent + "]"
    nested = [inner + _toml_value(v, inner) for v in value]
    return "[\n" + ",\n".join(nested) + ",\n" + indent + "]"


def toml_text(data: Mapping[str, Mapping[str, Any]], notes: Mapping[str, str] = {}) -> str:  # noqa: B006
    """``{section: {key: value}}`` as TOML: a table per section, the keys whose values are
    tables of scalars and vectors as sub-tables ([section.key]) after the others, matrices one
    row per line, and each key named in ``notes`` ("section.key") after a comment line."""
    import textwrap

    previous: list[str | None] = [None]

    def comment(name: str) -> list[str]:
        """The note's comment lines, once for consecutive keys with the same note."""
        note = notes.get(name)
        if note is None or note == previous[0]:
            previous[0] = note
            return []
        previous[0] = note
        return textwrap.wrap(
            notes[name], width=_TOML_WIDTH - 2, initial_indent="# ", subsequent_indent="#   "
        )

    lines: list[str] = []
    for section, values in data.items():
        tables = {
            key: value
            for key, value in values.items()
            if isinstance(value, dict)
            and value
            and not any(isinstance(v, dict) for v in value.values())
        }
        lines.append(f"[{_toml_key(section)}]")
        previous[0] = None
        for key, value in values.items():
            if key not in tables:
                lines += comment(f"{section}.{key}")
                lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
        lines.append("")
        for key, value in tables.items():
            previous[0] = None
            lines += comment(f"{section}.{key}")
            lines.append(f"[{_toml_key(section)}.{_toml_key(key)}]")
            for sub, item in value.items():
                lines.append(f"{_toml_key(sub)} = {_toml_value(item)}")
            lines.append("")
    return "\n".join(lines)


def deep_toml(text: str) -> str:
    """Where a TOML text nests too deep for the reader: the first line with more than MAX_DEPTH
    open brackets, and its key."""
    for number, line in enumerate(text.splitlines(), start=1):
        depth = deepest = 0
        for char in line:
            depth += char in "[{"
            depth -= char in "]}"
            deepest = max(deepest, depth)
        if deepest > MAX_DEPTH:
            key = line.split("=", 1)[0].strip() if "=" in line else "?"
            return f"line {number}, key {key_text(key)!r}: nested more than {MAX_DEPTH} levels deep"
    return f"nested more than {MAX_DEPTH} levels deep"


def read_samples(path: Path) -> tuple[Vector, Matrix]:
    """The samples of task.qd.file: rows t, qd1, ..., qdn (comma-separated, # comments, an
    optional header line), as (t, q) tuples; a ValueError naming task.qd.file and the line."""
    lines = read_text_file(path, "task.qd.file", MAX_SAMPLES_FILE_BYTES).splitlines()
    rows = []
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        try:
            rows.append([float(v) for v in text.split(",")])
        except ValueError as error:
            if rows:  # only a first line may be a header
                raise ValueError(f"task.qd.file: {path}:{number}: not numbers: {line!r}") from error
            continue
        columns = len(rows[0])  # t, qd1, ..., qdn (n checked by Config)
        if len(rows[-1]) != columns or columns < 2:
            expected = "t, qd1, qd2" if columns == 3 else "t, qd1, ..., qdn"
            raise ValueError(
                f"task.qd.file: {path}:{number}: expected {max(columns, 2)} columns {expected}, "
                f"got {line!r}"
            )
    if not rows:
        raise ValueError(f"task.qd.file: {path} holds no samples")
    array = np.array(rows)
    return tuple(array[:, 0]), tuple(map(tuple, array[:, 1:]))
