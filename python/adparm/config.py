"""Configuration of a run: frozen dataclasses, one per TOML section, validated on construction.

Every field has the paper's value (Section 4 of the paper, with the corrections of the docs page
"The paper and its corrections") or, where the paper leaves a setting open, this project's
documented choice. A key left out of a TOML file takes that default; an unknown section or key is
refused with a "did you mean" hint.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import numbers
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "ActorConfig",
    "Config",
    "ControlConfig",
    "ControllerConfig",
    "CostConfig",
    "CriticConfig",
    "DiagnosticsConfig",
    "ExtrapolationConfig",
    "InitConfig",
    "ModelConfig",
    "PlantConfig",
    "ProbeConfig",
    "SampledTrajectory",
    "SimConfig",
    "SinusoidTrajectory",
    "TaskConfig",
    "load_config",
    "paper_config",
]

Vector = tuple[float, ...]
Matrix = tuple[tuple[float, ...], ...]

#: The value of a setting that is derived for the run (sim.dt = "auto").
AUTO = "auto"


# --- field checks: each names the field ("section.key") and what it expects -------------------


def _text(value: Any, limit: int = 120) -> str:
    """repr(value) cut to ``limit`` characters, for messages (never raises)."""
    try:
        text = repr(value)
    except Exception:  # e.g. an int of more than 4300 digits
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _name(name: str, limit: int = 80) -> str:
    """A section or key name as given, cut to ``limit`` characters."""
    return name if len(name) <= limit else name[: limit - 3] + "..."


def _int_text(value: int) -> str:
    """str(value), or its size for an integer too long to print (Python refuses str() beyond 4300
    digits)."""
    if value.bit_length() < 128:
        return str(value)
    sign = "a negative" if value < 0 else "an"
    return f"{sign} integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"


def _scalar(value: Any, name: str, *, minimum: float | None = None, strict: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__} {_text(value)}")
    try:
        value = float(value)
    except OverflowError:  # an int or Fraction beyond the float range
        text = _int_text(int(value)) if isinstance(value, numbers.Integral) else _text(value)
        raise ValueError(f"{name}: must be finite, got {text}") from None
    if not math.isfinite(value):
        raise ValueError(f"{name}: must be finite, got {value}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        relation = ">" if strict else ">="
        raise ValueError(f"{name}: must be {relation} {minimum:g}, got {value:g}")
    return value


def _integer(value: Any, name: str, *, minimum: int, maximum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {_text(value)}")
    value = int(value)
    if value < minimum:
        raise ValueError(f"{name}: must be >= {minimum}, got {_int_text(value)}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name}: must be <= {maximum:_}, got {_int_text(value)}")
    return value


def _boolean(value: Any, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(
            f"{name}: expected true or false, got {type(value).__name__} {_text(value)}"
        )
    return bool(value)


def _choice(value: Any, name: str, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected one of {', '.join(choices)}, got {_text(value)}")
    if value not in choices:
        raise ValueError(
            f"{name}: expected one of {', '.join(choices)}, got {_text(value)}"
            f"{_hint(value, choices)}"
        )
    return value


def _is_number(value: Any) -> bool:
    """A real number that is not a bool (nor numpy's bool_)."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


#: Deepest nesting of lists and tables a config value may have (the deepest field needs 3).
MAX_DEPTH = 16


def _check_depth(value: Any, name: str) -> None:
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


def _plain_array(value: Any, name: str) -> Any:
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


def _array(value: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """A finite float array of ``shape`` (None: any length) from nested lists or an array of
    real numbers; strings, bools, complex numbers, None and mappings are refused (TypeError),
    as are ragged lists."""
    expected = f"an array of numbers of shape {_shape_text(shape)}"
    value = _plain_array(value, name)
    _check_depth(value, name)
    if isinstance(value, (str, bytes, Mapping, bool, np.bool_)) or value is None:
        raise TypeError(f"{name}: expected {expected}, got {_text(value)}")
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        raw = value  # its dtype tells the truth: no bool or string hides inside
    else:
        # dtype object keeps every element as given (np.asarray(..., dtype=float) would turn
        # "1" and True into 1.0); a ragged list becomes an array of lists, refused below
        try:
            raw = np.array(value, dtype=object)
        except (TypeError, ValueError) as error:
            raise TypeError(f"{name}: expected {expected}, got {_text(value)}") from error
        for element in raw.flat:
            if not _is_number(element):
                raise TypeError(
                    f"{name}: expected {expected}, got {_text(value)} (holds "
                    f"{type(element).__name__} {_text(element, 40)})"
                )
    if raw.ndim != len(shape) or any(
        size is not None and actual != size for actual, size in zip(raw.shape, shape, strict=False)
    ):
        raise ValueError(f"{name}: expected shape {_shape_text(shape)}, got {tuple(raw.shape)}")
    try:
        with np.errstate(over="ignore", invalid="ignore"):  # long double beyond float: inf
            array = raw.astype(float)
    except OverflowError:  # an int beyond the float range
        raise ValueError(f"{name}: must be finite, got {_text(value)}") from None
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: must be finite, got {_text(array.tolist())}")
    return array


def _ndim(value: Any) -> int:
    """np.ndim, or -1 for what is no array (a ragged list): the checks then name the field."""
    try:
        return int(np.ndim(value))
    except (TypeError, ValueError, RuntimeError):  # RuntimeError: more than 32 dimensions
        return -1


def _shape_text(shape: tuple[int | None, ...]) -> str:
    return (
        "("
        + ", ".join("n" if s is None else str(s) for s in shape)
        + ("," if len(shape) == 1 else "")
        + ")"
    )


def _rows(value: Any, name: str, columns: int | None) -> Matrix:
    """An (n,) vector (one column) or an (n, k) matrix, as an (n, k) matrix (n joints: checked
    by Config against the arm)."""
    if _ndim(value) == 1:
        return tuple((v,) for v in _vector(value, name, None))
    return _matrix(value, name, None, columns)


def _square(value: Any, name: str) -> Matrix:
    """A square matrix of any size (checked by Config against the arm's joint count)."""
    matrix = _matrix(value, name, None, None)
    if len(matrix) == 0 or len(matrix) != len(matrix[0]):
        raise ValueError(
            f"{name}: expected a square matrix, got shape ({len(matrix)}, "
            f"{len(matrix[0]) if matrix else 0})"
        )
    return matrix


def _gain(value: Any, name: str) -> float | Matrix:
    """A number (times the identity) or an n x n matrix."""
    if _is_number(value):
        return _scalar(value, name)
    return _square(value, name)


def _check_known(
    name: Any, known: Sequence[str], *, strings: str, unknown: str, listing: str
) -> None:
    """Refuses a ``name`` that is not one of ``known``: TypeError ``strings`` for a non-string,
    ValueError ``unknown`` (a template of ``{name}``) with a "did you mean" hint; both messages end
    with ``listing``."""
    if not isinstance(name, str):
        raise TypeError(f"{strings}, got {type(name).__name__} {_text(name)}; {listing}")
    if name not in known:
        raise ValueError(f"{unknown.format(name=_name(name))}{_hint(name, known)}; {listing}")


def _check_keys(values: Mapping[str, Any], keys: list[str], where: str) -> None:
    for key in values:
        _check_known(
            key,
            keys,
            strings=f"[{where}]: key names must be strings",
            unknown=f"unknown key {where}.{{name}}",
            listing=f"known keys of [{where}]: {', '.join(keys)}",
        )


def _vector(value: Any, name: str, size: int | None) -> Vector:
    if isinstance(value, (bool, np.bool_, numbers.Real)):
        raise TypeError(f"{name}: expected a list of {size or 'n'} numbers, got {_text(value)}")
    return tuple(float(v) for v in _array(value, name, (size,)))


def _matrix(value: Any, name: str, rows: int | None, cols: int | None) -> Matrix:
    return tuple(tuple(float(v) for v in row) for row in _array(value, name, (rows, cols)))


def _symmetric_positive_definite(matrix: Matrix, name: str) -> Matrix:
    """The C++ core's test (cost.hpp), on matrix / max|entry| so that no square overflows:
    symmetric to 1e-12 (relative, Frobenius norm), and positive definite: a Cholesky factor
    exists. Returns the exactly symmetric 0.5 (M + M^T): a matrix asymmetric by round-off (one
    ulp) is accepted here, so every later step (python-control's care, CasADi) gets it
    symmetric."""
    array = np.array(matrix)
    scale = np.abs(array).max()
    scaled = array / scale if scale > 0.0 else array
    if np.sum((scaled - scaled.T) ** 2) > 1e-24 * np.sum(scaled**2):
        raise ValueError(f"{name}: must be symmetric, got {_text(array.tolist(), 300)}")
    try:
        np.linalg.cholesky(scaled)
        positive_definite = scale > 0.0
    except np.linalg.LinAlgError:
        positive_definite = False
    if not positive_definite:
        raise ValueError(f"{name}: must be positive definite, got {_text(array.tolist(), 300)}")
    symmetric = 0.5 * (array + array.T)
    if not np.all(np.isfinite(symmetric)):  # 0.5 (a + b) overflows only where a + b does
        symmetric = 0.5 * array + 0.5 * array.T
    return tuple(tuple(float(v) for v in row) for row in symmetric)


def _check_arm(p1: float, p2: float, p3: float, section: str) -> None:
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


def _check_hurwitz(alpha1: Matrix, name: str) -> None:
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


_ARM_KEYS = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")
#: The keys of the built-in two-link arm only (refused together with a URDF arm).
_TWO_LINK_KEYS = ("p1", "p2", "p3", "g1", "g2")
#: The defaults of the two-link keys (a URDF arm leaves them so).
_TWO_LINK_DEFAULTS = {"p1": 5.0, "p2": 1.0, "p3": 1.0, "g1": 9.8 * 1.2, "g2": 9.8}
#: Gravity of a URDF arm when plant.gravity is left out (m/s^2, in the URDF's root frame).
DEFAULT_GRAVITY: Vector = (0.0, 0.0, -9.81)


def _friction(value: Any, name: str) -> float | Vector:
    """A friction coefficient: one number (every joint) or one per joint (checked against n)."""
    if _is_number(value):
        return _scalar(value, name)
    return _vector(value, name, None)


#: A URDF named "example-robot-data:ur5" is that robot of the example-robot-data package
#: (adparm.example_robot_urdf).
EXAMPLE_ROBOT_PREFIX = "example-robot-data:"


def _urdf_path(value: Any, name: str) -> str:
    """An absolute path of an existing URDF file (a relative one is taken from the current
    directory; load_config makes it relative to the TOML file first), or
    "example-robot-data:NAME" for a robot of example-robot-data."""
    import os

    if not isinstance(value, (str, Path)) or not str(value):
        raise TypeError(f"{name}: expected the path of a URDF file, got {_text(value)}")
    if isinstance(value, str) and value.startswith(EXAMPLE_ROBOT_PREFIX):
        from .urdf import example_robot_urdf

        robot = value[len(EXAMPLE_ROBOT_PREFIX) :]
        try:
            return str(example_robot_urdf(robot))
        except ModuleNotFoundError:
            raise ValueError(
                f"{name}: {value!r} needs the example-robot-data package "
                "(pip install example-robot-data)"
            ) from None
        except (ValueError, FileNotFoundError) as error:
            raise ValueError(f"{name}: {value!r}: {error}") from None
    path = os.path.abspath(Path(value).expanduser())
    if not Path(path).is_file():
        raise ValueError(f"{name}: no URDF file {str(path)!r}")
    return path


#: Joints held at a position, as the core takes them: ((name, position), ...).
LockedPairs = tuple[tuple[str, float], ...]


def _locked_pairs(locked: Mapping[str, float] | None) -> LockedPairs:
    return tuple((name, float(value)) for name, value in (locked or {}).items())


@functools.lru_cache(maxsize=32)
def _urdf_info(
    path: str, mtime_ns: int, size: int, locked: LockedPairs = ()
) -> tuple[int, tuple[str, ...]]:
    """(n, joint names) of a URDF read by the core (once per file version and locked joints),
    after the checks of the text of its <inertial> elements (urdf.check_inertial_text)."""
    from . import _core
    from .urdf import check_inertial_text

    check_inertial_text(path)
    arm = _core.UrdfArm(path, locked_joints=list(locked))
    return arm.dof, tuple(arm.joint_names)


def _urdf_error(error: Exception, name: str) -> ValueError:
    """A ValueError naming ``name`` (plant.urdf or model.urdf), or its section's locked_joints
    field for a problem with the locked joints."""
    from .urdf import locked_joints_message

    section = name.split(".")[0]
    text = locked_joints_message(str(error), section)
    return ValueError(text if text != str(error) else f"{name}: {error}")


def urdf_info(
    path: str, name: str = "plant.urdf", locked: Mapping[str, float] | None = None
) -> tuple[int, tuple[str, ...]]:
    """The free joint count and joint names of the URDF at ``path`` with the joints ``locked``
    held; a file that does not parse, has no free actuated joint, has a floating base or fails a
    physical check is refused with a ValueError naming ``name``, a problem with the locked joints
    naming its section's locked_joints (plant.locked_joints)."""
    import os

    try:
        stat = os.stat(path)
        return _urdf_info(path, stat.st_mtime_ns, stat.st_size, _locked_pairs(locked))
    except (OSError, ValueError) as error:
        raise _urdf_error(error, name) from None


@functools.lru_cache(maxsize=64)
def _urdf_structured_size(path: str, mtime_ns: int, size: int, locked: LockedPairs = ()) -> int:
    from . import _core

    arm = _core.UrdfArm(path, locked_joints=list(locked))
    return int(_core.UrdfStructuredBasis(arm).size)


def urdf_structured_size(
    path: str, name: str = "plant.urdf", locked: Mapping[str, float] | None = None
) -> int:
    """The number of functions of the structured basis of the URDF arm at ``path`` with the
    joints ``locked`` held (it depends on the kinematics only: n (n + 1) / 2 + the number of
    base inertial parameters)."""
    import os

    try:
        stat = os.stat(path)
        return _urdf_structured_size(path, stat.st_mtime_ns, stat.st_size, _locked_pairs(locked))
    except (OSError, ValueError) as error:
        raise _urdf_error(error, name) from None


def _locked_joints(value: Any, name: str) -> dict[str, float] | None:
    """A table {joint name: position (rad or m)}; an empty one is None (nothing locked). The
    names and limits are checked against the URDF by the core (urdf_info)."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise TypeError(
            f"{name}: expected a table of joint names and positions such as "
            f"{{panda_finger_joint1 = 0.0}}, got {type(value).__name__} {_text(value)}"
        )
    locked = {}
    for joint, position in value.items():
        if not isinstance(joint, str) or not joint:
            raise TypeError(f"{name}: joint names must be non-empty strings, got {_text(joint)}")
        locked[joint] = _scalar(position, f"{name}.{_name(joint)}")
    return locked or None


def _check_urdf_arm(arm: Any, section: str) -> None:
    """With a URDF: the two-link keys stay unset, gravity has 3 entries; without: gravity and
    per-joint friction are refused (the two-link arm has g1, g2 and one coefficient)."""
    if arm.urdf is not None:
        for key in _TWO_LINK_KEYS:
            value = getattr(arm, key)
            if (
                value is not None
                and value != _TWO_LINK_DEFAULTS[key]
                or (section == "model" and value is not None)
            ):
                raise ValueError(
                    f"{section}.{key}: a parameter of the built-in two-link arm; the arm of "
                    f"{section}.urdf takes its inertia and geometry from the URDF (leave "
                    f"{section}.{key} out)"
                )
        return
    if arm.gravity is not None:
        raise ValueError(
            f"{section}.gravity: only with {section}.urdf (the two-link arm's gravity terms are "
            f"{section}.g1 and {section}.g2)"
        )
    if arm.locked_joints is not None:
        raise ValueError(
            f"{section}.locked_joints: only with a URDF arm ({section}.urdf); the two-link arm "
            "has no joint to lock"
        )
    for key in ("coulomb", "viscous"):
        if isinstance(getattr(arm, key), tuple):
            raise ValueError(
                f"{section}.{key}: one number for the built-in two-link arm (one per joint needs "
                f"{section}.urdf)"
            )


# --- sections ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class PlantConfig:
    """The arm of eq. (1): M, C, G as in Section 4, F = coulomb sgn(dq) + viscous dq,
    tau_d = [disturbance[0] sin t, disturbance[1] cos t].

    ``urdf`` names a URDF file instead (any fixed-base serial arm, through Pinocchio; relative to
    the TOML file, or to the current directory for a config built from a dict; stored absolute),
    with ``gravity`` (default DEFAULT_GRAVITY) and coulomb, viscous as one number or one per
    joint; p1 ... g2 are then not used and may not be set. ``locked_joints`` ({name: position})
    holds joints of the URDF at a position (Pinocchio's reduced model): the arm's joints are
    the free ones."""

    p1: float = 5.0
    p2: float = 1.0
    p3: float = 1.0
    g1: float = 9.8 * 1.2
    g2: float = 9.8
    coulomb: float | Vector = -0.1  # as printed: F = -0.1 sgn(dq)
    viscous: float | Vector = 0.0  # not in the paper; 0 keeps its plant
    disturbance: Vector = (0.1, 0.1)
    urdf: str | None = None
    gravity: Vector | None = None
    locked_joints: dict[str, float] | None = None

    def __post_init__(self) -> None:
        for key in _TWO_LINK_KEYS:
            object.__setattr__(self, key, _scalar(getattr(self, key), f"plant.{key}"))
        locked = _locked_joints(self.locked_joints, "plant.locked_joints")
        object.__setattr__(self, "locked_joints", locked)
        for key in ("coulomb", "viscous"):
            object.__setattr__(self, key, _friction(getattr(self, key), f"plant.{key}"))
        disturbance = _vector(self.disturbance, "plant.disturbance", None)
        object.__setattr__(self, "disturbance", disturbance)
        if self.urdf is not None:
            object.__setattr__(self, "urdf", _urdf_path(self.urdf, "plant.urdf"))
            urdf_info(self.urdf, "plant.urdf", self.locked_joints)
        if self.gravity is not None:
            object.__setattr__(self, "gravity", _vector(self.gravity, "plant.gravity", 3))
        _check_urdf_arm(self, "plant")
        _check_arm(self.p1, self.p2, self.p3, "plant")

    @property
    def resolved_gravity(self) -> Vector:
        """plant.gravity, or DEFAULT_GRAVITY when left out."""
        return DEFAULT_GRAVITY if self.gravity is None else self.gravity


@dataclass(frozen=True)
class ModelConfig:
    """The arm the controller believes (feedforward h of eq. 5 and f, g of eq. 9). A key left
    out (None) takes the plant's value, so the default is an exact model. With a URDF plant,
    ``urdf`` may name another URDF of the same joint count (a model error), with its own
    ``gravity``, coulomb, viscous and ``locked_joints`` (each left out: the plant's)."""

    p1: float | None = None
    p2: float | None = None
    p3: float | None = None
    g1: float | None = None
    g2: float | None = None
    coulomb: float | Vector | None = None
    viscous: float | Vector | None = None
    urdf: str | None = None
    gravity: Vector | None = None
    locked_joints: dict[str, float] | None = None

    def __post_init__(self) -> None:
        for key in _TWO_LINK_KEYS:
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, _scalar(value, f"model.{key}"))
        locked = _locked_joints(self.locked_joints, "model.locked_joints")
        object.__setattr__(self, "locked_joints", locked)
        for key in ("coulomb", "viscous"):
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, _friction(value, f"model.{key}"))
        if self.urdf is not None:
            # read with the locked joints in Config (they may be the plant's)
            object.__setattr__(self, "urdf", _urdf_path(self.urdf, "model.urdf"))
        if self.gravity is not None:
            object.__setattr__(self, "gravity", _vector(self.gravity, "model.gravity", 3))

    def resolve(self, plant: PlantConfig) -> dict[str, Any]:
        """The model's parameters with the plant's values filled in."""
        return {
            key: getattr(plant, key) if getattr(self, key) is None else getattr(self, key)
            for key in _ARM_KEYS
        }

    def resolve_urdf(self, plant: PlantConfig) -> dict[str, Any]:
        """The believed URDF arm: urdf, gravity, coulomb, viscous, locked_joints, each the
        plant's when left out (a URDF plant only)."""
        return {
            "urdf": plant.urdf if self.urdf is None else self.urdf,
            "gravity": plant.resolved_gravity if self.gravity is None else self.gravity,
            "coulomb": plant.coulomb if self.coulomb is None else self.coulomb,
            "viscous": plant.viscous if self.viscous is None else self.viscous,
            "locked_joints": (
                plant.locked_joints if self.locked_joints is None else self.locked_joints
            ),
        }


@dataclass(frozen=True)
class SinusoidTrajectory:
    """qd_j(t) = offset_j + sum_k amplitude_jk sin(frequency_jk t + phase_jk) (rad, rad/s).

    amplitude, frequency and phase are each a vector (one sinusoid per joint) or a joints x k matrix
    (k sinusoids per joint); phase None is all zeros. In TOML: ``[task.qd]`` with
    ``kind = "sinusoid"``."""

    kind: ClassVar[str] = "sinusoid"
    amplitude: Vector | Matrix = (0.5, 0.3)
    frequency: Vector | Matrix = (1.0, 1.0)
    phase: Vector | Matrix | None = None
    offset: Vector = (0.0, 0.0)

    def __post_init__(self) -> None:
        amplitude = _rows(self.amplitude, "task.qd.amplitude", None)
        n = len(amplitude[0])
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "frequency", _rows(self.frequency, "task.qd.frequency", n))
        phase = ((0.0,) * n,) * len(amplitude) if self.phase is None else self.phase
        object.__setattr__(self, "phase", _rows(phase, "task.qd.phase", n))
        object.__setattr__(self, "offset", _vector(self.offset, "task.qd.offset", None))
        for key in ("frequency", "phase"):
            if len(getattr(self, key)[0]) != n:
                raise ValueError(
                    f"task.qd.{key}: expected {n} column(s) like task.qd.amplitude, "
                    f"got {len(getattr(self, key)[0])}"
                )


@dataclass(frozen=True)
class SampledTrajectory:
    """qd(t) through samples (t_i, qd_i), interpolated by a cubic spline
    (scipy.interpolate.CubicSpline with bc_type = boundary), which gives dqd and ddqd too.

    Either ``file``, a CSV file with columns t, qd1, qd2 (a header line and # comments are
    skipped; a relative path in a TOML file is relative to that file), or ``t`` (n,) and ``q``
    (n, 2) inline. The first sample must be at t <= 0 and the last at t >= sim.T. In TOML:
    ``[task.qd]`` with ``kind = "samples"``."""

    kind: ClassVar[str] = "samples"
    t: Vector = ()
    q: Matrix = ()
    file: str | None = None
    boundary: str = "not-a-knot"

    def __post_init__(self) -> None:
        if self.file is not None:
            if not isinstance(self.file, (str, Path)):
                raise TypeError(f"task.qd.file: expected a path, got {_text(self.file)}")
            if not (_empty(self.t) and _empty(self.q)):
                raise ValueError("task.qd: give either file or t and q, not both")
            t, q = _read_samples(Path(self.file))
            object.__setattr__(self, "file", str(self.file))
            object.__setattr__(self, "t", t)
            object.__setattr__(self, "q", q)
        object.__setattr__(self, "t", _vector(self.t, "task.qd.t", None))
        if len(self.t) > MAX_SAMPLES:
            raise ValueError(f"task.qd.t: at most {MAX_SAMPLES} samples, got {len(self.t)}")
        q = _matrix(self.q, "task.qd.q", None, None)
        if len(q) != len(self.t):
            width = len(q[0]) if q else 2
            raise ValueError(
                f"task.qd.q: expected shape ({len(self.t)}, {width}), one row per time in "
                f"task.qd.t, got ({len(q)}, {width})"
            )
        object.__setattr__(self, "q", q)
        if len(self.t) < 2:
            raise ValueError(f"task.qd.t: expected at least 2 samples, got {len(self.t)}")
        if not all(b > a for a, b in zip(self.t, self.t[1:], strict=False)):
            raise ValueError("task.qd.t: sample times must be strictly increasing")
        if self.t[0] > 0.0:
            raise ValueError(f"task.qd.t: the first sample must be at t <= 0, got {self.t[0]:g}")
        if not math.isfinite(self.t[-1] - self.t[0]):
            raise ValueError(
                f"task.qd.t: the samples must span a finite time, got {self.t[0]:g} to "
                f"{self.t[-1]:g}"
            )
        _choice(self.boundary, "task.qd.boundary", ("not-a-knot", "clamped", "natural"))
        try:
            with np.errstate(all="ignore"):
                finite = bool(np.all(np.isfinite(self.spline().c)))
        except ValueError:  # scipy: "`dydx` must contain only finite values"
            finite = False
        if not finite:
            raise ValueError(
                "task.qd.q: the cubic spline through the samples overflows (values too large, or "
                "samples too close in time for their values)"
            )

    def spline(self) -> Any:
        """The scipy CubicSpline through the samples (axis 0 is time)."""
        from scipy.interpolate import CubicSpline

        return CubicSpline(np.array(self.t), np.array(self.q), axis=0, bc_type=self.boundary)


def _empty(value: Any) -> bool:
    return isinstance(value, (tuple, list)) and len(value) == 0


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


def _read_samples(path: Path) -> tuple[Vector, Matrix]:
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


_TRAJECTORIES: dict[str, type] = {"sinusoid": SinusoidTrajectory, "samples": SampledTrajectory}
Trajectory = Vector | SinusoidTrajectory | SampledTrajectory


def _trajectory(value: Any) -> Trajectory:
    if isinstance(value, (SinusoidTrajectory, SampledTrajectory)):
        return value
    if not isinstance(value, Mapping):
        return _vector(value, "task.qd", None)
    values = dict(value)
    kinds = tuple(_TRAJECTORIES)
    if "kind" not in values:
        raise ValueError(f"task.qd.kind: expected one of {', '.join(kinds)}, got nothing")
    kind = _choice(values.pop("kind"), "task.qd.kind", kinds)
    cls = _TRAJECTORIES[kind]
    _check_keys(values, [f.name for f in dataclasses.fields(cls)], "task.qd")
    return cls(**values)


@dataclass(frozen=True)
class TaskConfig:
    """Initial joint state and desired trajectory qd (rad, rad/s).

    qd is a set-point (a pair, the paper's qd = 0), a SinusoidTrajectory or a SampledTrajectory
    (in TOML a ``[task.qd]`` table with ``kind = "sinusoid"`` or ``"samples"``). The feedforward
    uses qd, dqd and ddqd (eq. 5 in full). dq0 = 0 is our choice (the paper is silent)."""

    q0: Vector = (0.1598, 0.2257)
    dq0: Vector = (0.0, 0.0)
    qd: Trajectory = (0.0, 0.0)

    def __post_init__(self) -> None:
        for key in ("q0", "dq0"):
            object.__setattr__(self, key, _vector(getattr(self, key), f"task.{key}", None))
        object.__setattr__(self, "qd", _trajectory(self.qd))

    @property
    def is_set_point(self) -> bool:
        """Whether qd is constant."""
        return not isinstance(self.qd, (SinusoidTrajectory, SampledTrajectory))


_PAPER_Q: Matrix = (
    (40.0, 2.0, -4.0, 4.0),
    (2.0, 40.0, 4.0, -6.0),
    (-4.0, 4.0, 4.0, 0.0),
    (4.0, -6.0, 0.0, 4.0),
)


@dataclass(frozen=True)
class CostConfig:
    """r(x, u) = x^T Q x + u^T R u (eqs. 10-11); Q (4x4) and R (2x2) symmetric positive definite."""

    Q: Matrix = _PAPER_Q
    R: Matrix = ((0.25, 0.0), (0.0, 0.25))

    def __post_init__(self) -> None:
        object.__setattr__(self, "Q", _square(self.Q, "cost.Q"))
        object.__setattr__(self, "R", _square(self.R, "cost.R"))
        object.__setattr__(self, "Q", _symmetric_positive_definite(self.Q, "cost.Q"))
        object.__setattr__(self, "R", _symmetric_positive_definite(self.R, "cost.R"))


@dataclass(frozen=True)
class ControlConfig:
    """alpha1 of eq. (7) (the paper's "alpha") and the RISE gains of eqs. (27)-(28).

    -alpha1 must be Hurwitz (every eigenvalue of alpha1 with a positive real part), else the
    error e1 of de1 = -alpha1 e1 + e2 grows; the conditions of the analytic optimum (Q > 0) imply
    it.

    The paper prints no RISE gains. Defaults: ks = 10, alpha2 = 1, beta1 = 0.5, which satisfies
    condition (29) for the paper's disturbance (``|tau_d| <= 0.1``, ``|dtau_d/dt| <= 0.1``, so
    zeta1 + zeta2 / alpha2 = 0.2 < 0.5)."""

    alpha1: Matrix = ((15.6, 10.6), (10.6, 10.4))
    ks: float = 10.0
    alpha2: float = 1.0
    beta1: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha1", _square(self.alpha1, "control.alpha1"))
        _check_hurwitz(self.alpha1, "control.alpha1")
        for key in ("ks", "alpha2", "beta1"):
            object.__setattr__(
                self, key, _scalar(getattr(self, key), f"control.{key}", minimum=0.0)
            )


#: The covariance-reset threshold used when critic.epsilon_T is left out (None).
EPSILON_T_PROBING = 1e-6  # learning from the probing signal alone (docs: paper corrections)
EPSILON_T_EXTRAPOLATION = 1e-3  # with Bellman-error extrapolation: the paper's printed value


@dataclass(frozen=True)
class CriticConfig:
    """Normalised least squares of eqs. (23)-(24): gain eta_c, normalisation nu,
    Gamma(0) = gamma0 I, reset to gamma0 I when lambda_min(Gamma) < epsilon_T.

    Paper values, except that epsilon_T (paper: 1e-3) left out (None) depends on where the
    excitation comes from (Config.resolved_epsilon_T):

    - 1e-6 when the critic learns from the probing signal alone (no extrapolation points). With
      1e-3, Gamma is reset every few tens of ms under strong probing, each window is too short to
      inform the weakly excited e1 direction, and the critic stalls 10-40 % off W* (docs: "The
      paper and its corrections").
    - the printed 1e-3 with Bellman-error extrapolation. There the information grows steadily, and
      frequent resets keep the least-squares gain alive while the target (the value of the moving
      actor) moves; with 1e-6 the gain decays and the critic can take minutes (docs: user guide,
      "Bellman-error extrapolation")."""

    eta_c: float = 800.0
    nu: float = 1.0
    gamma0: float = 100.0
    epsilon_T: float | None = None

    def __post_init__(self) -> None:
        for key in ("eta_c", "nu"):
            object.__setattr__(self, key, _scalar(getattr(self, key), f"critic.{key}", minimum=0.0))
        object.__setattr__(
            self, "gamma0", _scalar(self.gamma0, "critic.gamma0", minimum=0.0, strict=True)
        )
        if self.epsilon_T is not None:
            epsilon_T = _scalar(self.epsilon_T, "critic.epsilon_T", minimum=0.0)
            object.__setattr__(self, "epsilon_T", epsilon_T)


@dataclass(frozen=True)
class ActorConfig:
    """Actor law (26): gains eta_a1, eta_a2 and the projection bound ||Wa|| <= weight_bound
    (the paper leaves the bound open; 100 is about 8 ||W*||).

    positive_e2 (default true; not in the paper): the projection also keeps the e2 block of the
    actor's value, e2^T P(cos q2) e2, positive definite with lambda_min(P) >= e2_margin at
    cos q2 = +-1 (hence at every q), for the paper and augmented bases. Without it, about one run
    in four with other probe phases or q(0) ends at the anti-stabilising solution of the HJB
    equation (the e2 block negated; docs/guide/truth.md). For the structured basis of a URDF
    arm the block is sum_b W_b M_b(q), kept positive definite at qd(0), q(0) and the joint
    positions of the extrapolation box (rates.check_positions). e2_margin is in the units of M
    (kg m^2); a URDF arm derives it (a tenth of lambda_min(M)) and weight_bound (10 ||W*||)."""

    eta_a1: float = 0.01
    eta_a2: float = 1.0
    weight_bound: float = 100.0
    positive_e2: bool = True
    e2_margin: float = 0.01

    def __post_init__(self) -> None:
        for key in ("eta_a1", "eta_a2", "e2_margin"):
            object.__setattr__(self, key, _scalar(getattr(self, key), f"actor.{key}", minimum=0.0))
        object.__setattr__(self, "positive_e2", _boolean(self.positive_e2, "actor.positive_e2"))
        object.__setattr__(
            self,
            "weight_bound",
            _scalar(self.weight_bound, "actor.weight_bound", minimum=0.0, strict=True),
        )


@dataclass(frozen=True)
class InitConfig:
    """Initial critic and actor weights (one per basis function, in the order of
    adparm.basis_names(config)); None (left out) takes the basis' default
    (Config.initial_weights):

    - paper and augmented bases: all ones (not printed in the paper). The initial actor
      must stabilise the model, and all-zero weights are inadmissible (omega = 0 at rest while the
      HJB error is x^T Q x > 0, so the critic diverges within milliseconds; simulate() then raises
      SimulationDiverged; docs: "The paper and its corrections").
    - structured basis: [1, 0, 1, p1, p2, p3], i.e. K = I for the e1 block and the inertia
      parameters of the believed model ([model], default the plant) for the e2 block. The actor's
      policy depends on the e2 block only (u_hat = -R^-1 M(q)^-1 M_w(q) e2 with M_w the inertia the
      weights describe), so these weights start at u_hat = -R^-1 e2, the optimal policy of the
      believed model; all-ones weights give an indefinite M_w on other arms and blow up."""

    critic_weights: Vector | None = None
    actor_weights: Vector | None = None

    def __post_init__(self) -> None:
        for key in ("critic_weights", "actor_weights"):
            if getattr(self, key) is not None:
                object.__setattr__(self, key, _vector(getattr(self, key), f"init.{key}", None))


@dataclass(frozen=True)
class ProbeConfig:
    """Probing signal added to the applied input u (persistence of excitation, eq. 25):
    probe_j(t) = ramp(t) sum_k amplitude_jk sin(frequencies_k t + phases_jk) for t < until,
    ramp(t) = min(1, t / ramp).

    The paper says only that "a probing signal is added"; the design is ours (docs: "The paper and
    its corrections", excitation). amplitude is one number (both joints), a pair (per joint, every
    sinusoid) or a 2 x n matrix (per joint and sinusoid, N m). Default: 4 sinusoids at 1, 2.7, 5.3,
    9.1 rad/s, each with the torque direction [71, 23] N m = 75 N m along M(qd) v_fast, where v_fast
    is the eigenvector of alpha1 with the larger eigenvalue (23.9 1/s): that mode of e1 is filtered
    hardest and is the critic's least excited direction. Phases k rad on both joints (None), so each
    sinusoid keeps that direction; until 100 s, no ramp; until = 0 turns probing off."""

    amplitude: Vector | Matrix = (71.0, 23.0)
    until: float = 100.0
    ramp: float = 0.0
    frequencies: Vector = (1.0, 2.7, 5.3, 9.1)
    phases: Matrix | None = None  # None: phase k rad for sinusoid k, on both joints

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "frequencies", _vector(self.frequencies, "probe.frequencies", None)
        )
        n = len(self.frequencies)
        if n > MAX_FREQUENCIES:
            raise ValueError(
                f"probe.frequencies: at most {MAX_FREQUENCIES} sinusoids (each costs every step "
                f"of the run), got {n}"
            )
        amplitude = self.amplitude
        if _is_number(amplitude):
            amplitude = _scalar(amplitude, "probe.amplitude")  # every joint and sinusoid
        elif _ndim(amplitude) == 2:
            amplitude = _matrix(amplitude, "probe.amplitude", None, n)
        else:
            amplitude = _vector(amplitude, "probe.amplitude", None)
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "until", _scalar(self.until, "probe.until", minimum=0.0))
        object.__setattr__(self, "ramp", _scalar(self.ramp, "probe.ramp", minimum=0.0))
        if self.phases is not None:
            object.__setattr__(self, "phases", _matrix(self.phases, "probe.phases", None, n))

    def amplitude_matrix(self, joints: int = 2) -> np.ndarray:
        """Amplitudes as a (joints, k) array (one column per sinusoid)."""
        k = len(self.frequencies)
        amplitude = np.array(self.amplitude, dtype=float)
        if amplitude.ndim == 0:
            return np.full((joints, k), float(amplitude))
        if amplitude.ndim == 1:
            amplitude = np.repeat(amplitude[:, None], k, axis=1)
        return amplitude.reshape(joints, k)

    def phase_matrix(self, joints: int = 2) -> np.ndarray:
        """Phases as a (joints, k) array, with the default filled in."""
        k = len(self.frequencies)
        if self.phases is not None:
            return np.array(self.phases, dtype=float).reshape(joints, k)
        return np.vstack([np.arange(k, dtype=float)] * joints)


CONTROLLER_KINDS = ("adp", "rise", "pd", "optimal")
BASIS_KINDS = ("augmented", "paper", "structured")
#: The basis of a URDF arm (plant.urdf) when controller.basis is left out.
URDF_DEFAULT_BASIS = "structured"
#: Built-in bases that a URDF arm refuses (written for the two-link arm).
URDF_REFUSED_BASES = ("augmented", "paper")
#: The number of functions of each built-in basis (the length of init.critic_weights and
#: actor_weights); an expression basis has one per term (ControllerConfig.basis_size).
BASIS_SIZES = {"augmented": 8, "paper": 8, "structured": 6}
#: Families that expand to terms (adparm.bases): a basis of these runs as an expression basis.
EXPRESSION_FAMILIES = ("quadratic", "polynomial")
_IDENTIFIER = re.compile(r"^[A-Za-z_]+$")


@functools.lru_cache(maxsize=64)
def _expression_basis(basis: tuple[str, ...], degree: int | None, joints: int) -> Any:
    """The compiled expression basis of controller.basis (parsed once per distinct basis);
    a ValueError names the field and the term."""
    from . import bases

    names = bases.variable_names(joints)
    known = BASIS_KINDS + EXPRESSION_FAMILIES
    for item in basis:
        name = item.strip()
        if _IDENTIFIER.match(name) and name not in known and name not in names:
            raise ValueError(
                f"controller.basis: unknown basis {name!r} (known: {', '.join(known)}, or terms "
                f"such as 'x1^2' in {', '.join(names)})" + _hint(name, known)
            )
    if name_in(basis, "structured"):
        raise ValueError(
            "controller.basis: 'structured' is a basis of its own; it cannot be combined with "
            "terms or families"
        )
    try:
        return bases.ExpressionBasis(list(basis), joints, degree=degree)
    except ValueError as error:
        text = str(error)
        if text.startswith("degree:"):
            raise ValueError(f"controller.{text}") from None
        text = text.removeprefix("basis: ")
        raise ValueError(f"controller.basis: {text}") from None


def name_in(basis: tuple[str, ...], name: str) -> bool:
    return any(item.strip() == name for item in basis)


EXTRAPOLATION_MODES = ("fixed", "grid", "local")
#: The largest controller.degree (adparm.bases.MAX_DEGREE; one joint reaches 128 functions at 22).
_MAX_DEGREE = 20


@dataclass(frozen=True)
class ControllerConfig:
    """Which input u the loop applies (tau = h_hat + mu - u, mu the RISE term):
    ``adp`` u = u_hat + probe (the paper; critic and actor learn), ``rise`` u = 0,
    ``pd`` u = -(kp e1 + kd de1), ``optimal`` u = -R^-1 e2 (the exact optimal policy).
    Only adp learns and probes. ``rise = false`` drops the RISE term mu (not with kind rise).
    kp, kd: a number (times I) or a 2 x 2 matrix, used by pd only (our choice 50 and 10).

    basis: the critic/actor basis. ``augmented`` (default) is the paper's 8 functions over the
    augmented state [x; qd] with cos x2 replaced by cos(qd2 - x2) = cos q2: identical to the
    paper's basis while qd2 = 0 (the paper's task), and exact for V* = x^T blockdiag(K, M(q)) x
    with the same W* for any qd(t). ``paper`` is the printed phi(x), exact only for qd2 = 0.
    ``structured`` has 6 functions, [e1_1^2, e1_1 e1_2, e1_2^2, e2^T M_k(q) e2 (k = 1..3)] with
    M(q) = p1 M1 + p2 M2 + p3 M3: exact for any qd(t) with W* = [K11, 2 K12, K22, p1, p2, p3], so
    the critic learns the arm's inertia parameters (docs, "The structured basis").
    ``quadratic`` (every x_i x_j, i <= j: 10 functions), ``polynomial`` with ``degree`` (even,
    >= 2: every monomial of even degree up to it) and a list of terms and families (e.g.
    ``["quadratic", "x3^2*cos(q2)"]``) are expression bases (adparm.bases; docs, "Bases"): parsed
    once, evaluated by the C++ core with exact Jacobians on its dynamic-size loop."""

    kind: str = "adp"
    basis: str | tuple[str, ...] = "augmented"
    degree: int | None = None
    rise: bool = True
    kp: float | Matrix = 50.0
    kd: float | Matrix = 10.0

    def __post_init__(self) -> None:
        _choice(self.kind, "controller.kind", CONTROLLER_KINDS)
        basis = self.basis
        if isinstance(basis, (list, tuple)):
            if not basis:
                raise ValueError("controller.basis: needs at least one term or family")
            if not all(isinstance(item, str) for item in basis):
                bad = next(item for item in basis if not isinstance(item, str))
                raise ValueError(f"controller.basis: each entry must be a string, got {bad!r}")
            basis = tuple(basis)
        elif not isinstance(basis, str):
            raise ValueError(
                f"controller.basis: expected a basis name or a list of terms, got {basis!r}"
            )
        object.__setattr__(self, "basis", basis)
        if self.degree is not None:
            object.__setattr__(
                self,
                "degree",
                _integer(self.degree, "controller.degree", minimum=2, maximum=_MAX_DEGREE),
            )
            if self.degree % 2:
                raise ValueError(
                    "controller.degree: must be even (a value function has even degree), "
                    f"got {self.degree}"
                )
            if not name_in(self.terms_spec, "polynomial"):
                raise ValueError(
                    "controller.degree: only with the 'polynomial' basis (controller.basis = "
                    f"{_plain(self.basis)!r})"
                )
        # an expression basis is parsed and checked by Config, for the arm's n joints (errors
        # name the field and the term)
        object.__setattr__(self, "rise", _boolean(self.rise, "controller.rise"))
        if self.kind == "rise" and not self.rise:
            raise ValueError(
                "controller.rise: kind = 'rise' is the RISE feedback alone, so rise must be true"
            )
        for key in ("kp", "kd"):
            object.__setattr__(self, key, _gain(getattr(self, key), f"controller.{key}"))

    @property
    def terms_spec(self) -> tuple[str, ...]:
        """controller.basis as a tuple of names and terms."""
        return (self.basis,) if isinstance(self.basis, str) else self.basis

    @property
    def is_expression(self) -> bool:
        """Whether the basis is an expression basis (anything but one built-in basis name)."""
        return not (isinstance(self.basis, str) and self.basis in BASIS_KINDS)

    def expression_basis(self, joints: int = 2) -> Any:
        """The compiled adparm.bases.ExpressionBasis of an expression basis (cached)."""
        if not self.is_expression:
            raise ValueError(f"controller.basis: {self.basis!r} is not an expression basis")
        return _expression_basis(self.terms_spec, self.degree, joints)

    def basis_size(self, joints: int = 2) -> int:
        """The number of basis functions K."""
        if self.is_expression:
            return self.expression_basis(joints).size
        return BASIS_SIZES[self.basis]

    def gain_matrix(self, key: str, joints: int = 2) -> np.ndarray:
        """kp or kd as a (joints x joints) array."""
        value = getattr(self, key)
        return value * np.eye(joints) if isinstance(value, float) else np.array(value)


#: The most extrapolation points a run may have. A point costs about 180 ns per RK4 step, so a
#: million of them take about 0.2 s per step: some 8 hours for the paper's 150 s at dt = 1 ms.
MAX_POINTS = 10**6
#: The largest sim.record_every: a run has at most 1e10 steps, so a larger value would change
#: nothing (only the first and the last step are recorded), and this one fits the core's integer.
MAX_RECORD_EVERY = 10**10


@dataclass(frozen=True)
class ExtrapolationConfig:
    """Bellman-error extrapolation: the critic and actor laws also average their terms over the
    HJB error at ``points`` extra states x (0: off, the paper; at most MAX_POINTS = 10^6, which
    already takes about 0.2 s per RK4 step). ``mode``: ``fixed`` (points drawn once, uniform in
    [-box, box]), ``grid`` (m points per axis, points = m^4) or ``local`` (points redrawn every
    step, uniform in x(t) + [-box, box]). ``box``: half-widths in x = [e1; e2], one number or 4.
    ``seed`` (0 <= seed < 2^32) seeds MT19937, drawn in the order of NumPy's
    ``RandomState(seed).random_sample((points, 4))``."""

    points: int = 0
    box: float | Vector = 1.0
    mode: str = "fixed"
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "points",
            _integer(self.points, "extrapolation.points", minimum=0, maximum=MAX_POINTS),
        )
        if _is_number(self.box):
            box: float | Vector = _scalar(self.box, "extrapolation.box", minimum=0.0, strict=True)
        else:
            box = _vector(self.box, "extrapolation.box", None)
            if min(box) <= 0.0:
                raise ValueError(f"extrapolation.box: half-widths must be > 0, got {list(box)}")
        object.__setattr__(self, "box", box)
        _choice(self.mode, "extrapolation.mode", EXTRAPOLATION_MODES)
        object.__setattr__(self, "seed", _integer(self.seed, "extrapolation.seed", minimum=0))
        if self.seed >= 2**32:
            raise ValueError(f"extrapolation.seed: must be < 2^32, got {_int_text(self.seed)}")
        if self.mode == "grid":
            m = round(self.points**0.25)
            if m**4 != self.points:
                raise ValueError(
                    "extrapolation.points: grid mode needs m^4 points (1, 16, 81, 256, ...), "
                    f"got {self.points}"
                )

    def box_vector(self, joints: int = 2) -> np.ndarray:
        """The half-widths as a (2 joints,) array."""
        return np.broadcast_to(np.array(self.box, dtype=float), (2 * joints,)).copy()


@dataclass(frozen=True)
class SimConfig:
    """Fixed-step RK4: horizon T (s), step dt (s), record every record_every-th step, and the
    bound on ``|q|``, ``|dq|``, ``|Wc|``, ``|Wa|`` beyond which a run stops as diverged. The paper
    prints no step; dt = 1 ms and T = 150 s (past its 110 s convergence claim) are our choices. If T
    is not a multiple of dt, the last step is shortened to end exactly at T. At most 1e10 steps (T /
    dt); 1 <= record_every <= MAX_RECORD_EVERY = 10^10.

    ``dt = "auto"`` (the default of a URDF arm) picks the largest 1, 2 or 5 x 10^k s, at most 1 ms,
    at which every fast rate of the closed loop (RISE through M^-1, the initial policy, the error
    dynamics, the critic) times dt is at most 0.6 of RK4's stability limit 2.785; the config then
    holds that number. simulate() refuses an explicit dt beyond the limit, naming the term, its
    rate and a dt that works. A URDF arm's T defaults to 10 s."""

    T: float = 150.0
    dt: float | str = 1e-3
    record_every: int = 10
    divergence_bound: float = 1e6

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _scalar(self.T, "sim.T", minimum=0.0, strict=True))
        if not (isinstance(self.dt, str) and self.dt == AUTO):  # "auto": Config resolves it
            object.__setattr__(self, "dt", _scalar(self.dt, "sim.dt", minimum=0.0, strict=True))
        object.__setattr__(
            self,
            "record_every",
            _integer(self.record_every, "sim.record_every", minimum=1, maximum=MAX_RECORD_EVERY),
        )
        object.__setattr__(
            self,
            "divergence_bound",
            _scalar(self.divergence_bound, "sim.divergence_bound", minimum=0.0, strict=True),
        )
        if self.dt == AUTO:
            return
        if self.dt > self.T:
            raise ValueError(f"sim.dt: must be <= sim.T = {self.T:g}, got {self.dt:g}")
        if self.T / self.dt > 1e10:
            raise ValueError(
                f"sim.dt: sim.T / sim.dt = {self.T / self.dt:.3g} steps is more than 1e10"
            )


@dataclass(frozen=True)
class DiagnosticsConfig:
    """What a run's verdict holds it to (adparm.truth.diagnose). ``tolerance``: "ok" needs the
    critic weights, the actor weights and the applied policy (``rms |u_hat - u*| / rms |u*|`` over
    the last 10 % of the run) each within this relative distance of the known optimum; also the
    band of the summary's "time within tolerance". 0 < tolerance < 1; default 1 %."""

    tolerance: float = 0.01

    def __post_init__(self) -> None:
        tolerance = _scalar(self.tolerance, "diagnostics.tolerance", minimum=0.0, strict=True)
        if tolerance >= 1.0:
            raise ValueError(f"diagnostics.tolerance: must be < 1, got {tolerance:g}")
        object.__setattr__(self, "tolerance", tolerance)


_SECTIONS: dict[str, type] = {
    "plant": PlantConfig,
    "model": ModelConfig,
    "task": TaskConfig,
    "cost": CostConfig,
    "control": ControlConfig,
    "critic": CriticConfig,
    "actor": ActorConfig,
    "init": InitConfig,
    "probe": ProbeConfig,
    "controller": ControllerConfig,
    "extrapolation": ExtrapolationConfig,
    "sim": SimConfig,
    "diagnostics": DiagnosticsConfig,
}


def _hint(name: str, choices: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, choices, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


@dataclass(frozen=True)
class Config:
    """A whole run: one frozen, checked section per TOML table.

    ``Config()`` and :func:`paper_config` are the paper's instance. Change it with
    :meth:`updated` (a copy), build one with :meth:`from_dict`, or read a TOML file with
    :func:`load_config`; :meth:`to_toml` writes one back. The docs page "Configuration
    reference" lists every field with its default and meaning.

    Attributes
    ----------
    plant, model : PlantConfig, ModelConfig
        The simulated arm and the arm the controller believes (default: the plant).
    task : TaskConfig
        Initial state and desired trajectory.
    cost : CostConfig
        Q and R of the cost (eqs. 10-11).
    control : ControlConfig
        alpha1 and the RISE gains.
    critic, actor, init : CriticConfig, ActorConfig, InitConfig
        The learning laws (eqs. 23-26) and the initial weights.
    probe : ProbeConfig
        The probing signal.
    controller : ControllerConfig
        Controller kind (adp, rise, pd, optimal) and basis.
    extrapolation : ExtrapolationConfig
        Bellman-error extrapolation points.
    sim : SimConfig
        Horizon, step, recording and divergence bound.
    diagnostics : DiagnosticsConfig
        The tolerance of the verdict.

    Examples
    --------
    >>> import adparm
    >>> config = adparm.paper_config().updated({"critic": {"eta_c": 100.0}})
    >>> config.critic.eta_c, config.sim.T
    (100.0, 150.0)
    """

    plant: PlantConfig = field(default_factory=PlantConfig)
    model: ModelConfig = field(default_factory=ModelConfig)
    task: TaskConfig = field(default_factory=TaskConfig)
    cost: CostConfig = field(default_factory=CostConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    critic: CriticConfig = field(default_factory=CriticConfig)
    actor: ActorConfig = field(default_factory=ActorConfig)
    init: InitConfig = field(default_factory=InitConfig)
    probe: ProbeConfig = field(default_factory=ProbeConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    extrapolation: ExtrapolationConfig = field(default_factory=ExtrapolationConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    diagnostics: DiagnosticsConfig = field(default_factory=DiagnosticsConfig)
    #: "section.key" of every setting given explicitly through from_dict/updated/load_config (a
    #: value "auto" is not explicit): a URDF arm derives the others (rates.urdf_defaults).
    _explicit: frozenset[str] = field(default=frozenset(), repr=False, compare=False)

    def __post_init__(self) -> None:
        for name, cls in _SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                raise TypeError(
                    f"{name}: expected {cls.__name__}, got {type(getattr(self, name)).__name__}"
                )
        if self.plant.urdf is not None and self.controller.basis == ControllerConfig.basis:
            # left at the two-link default: the URDF arm's default (from_dict refuses a
            # two-link basis set explicitly)
            controller = dataclasses.replace(self.controller, basis=URDF_DEFAULT_BASIS)
            object.__setattr__(self, "controller", controller)
        self._check_model()
        self._fit_to_arm()
        if self.plant.urdf is None:
            model = self.model.resolve(self.plant)
            _check_arm(model["p1"], model["p2"], model["p3"], "model")
        size = self.basis_size
        for key in ("critic_weights", "actor_weights"):
            value = getattr(self.init, key)
            if value is not None and len(value) != size:
                raise ValueError(
                    f"init.{key}: expected shape ({size},), one weight per function of "
                    f"controller.basis = {_plain(self.controller.basis)!r}, got ({len(value)},)"
                )
        if self.controller.is_expression:
            self._check_basis_at_start()
        if self.resolved_epsilon_T >= self.critic.gamma0:
            raise ValueError(
                f"critic.epsilon_T: must be < critic.gamma0 = {self.critic.gamma0:g}, "
                f"got {self.resolved_epsilon_T:g}"
            )
        qd = self.task.qd
        if isinstance(qd, SampledTrajectory) and qd.t[-1] < self.sim.T * (1.0 - 1e-12):
            raise ValueError(
                f"task.qd: the samples end at t = {qd.t[-1]:g} s, before sim.T = {self.sim.T:g} s"
            )
        self._resolve_step()

    def _check_basis_at_start(self) -> None:
        """An expression basis and its d phi / dx must be finite at the initial state: sqrt or
        log of a negative value there ends the run at t = 0 (or leaves V(x(0)) undefined)."""
        from .optimal import desired_state, initial_error_state

        problem = self.controller.expression_basis(self.dof).nonfinite(
            initial_error_state(self), desired_state(self, 0.0)[0]
        )
        if problem is not None:
            raise ValueError(
                f"controller.basis: at the initial state (task.q0, task.qd), {problem}"
            )

    def _resolve_step(self) -> None:
        """sim.dt = "auto" (a URDF arm's default, or given so): the largest 1, 2 or 5 x 10^k s
        with every fast rate of the closed loop inside RK4's stable region with margin
        (rates.auto_step), at most 1 ms."""
        auto = self.sim.dt == AUTO or (
            self.plant.urdf is not None and "sim.dt" not in self._explicit
        )
        if not auto:
            return
        from .rates import auto_step, closed_loop_rates

        dt = auto_step(closed_loop_rates(self), self.sim.T)
        object.__setattr__(self, "sim", dataclasses.replace(self.sim, dt=dt))
        self._derived["sim.dt"] = "auto: every fast rate of the closed loop * dt <= 0.6 * 2.785"

    @property
    def explicit_keys(self) -> frozenset[str]:
        """The settings ("section.key") given explicitly; a URDF arm derives the others."""
        return self._explicit

    @property
    def derived(self) -> dict[str, str]:
        """The settings derived for this arm (left out of the config), each with its reason."""
        return dict(self._derived)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: Config | None = None) -> Config:
        """Build a config from nested mappings ``{section: {key: value}}`` over ``base``
        (default: the paper's instance). Unknown sections and keys are refused."""
        if not isinstance(data, Mapping):
            raise TypeError(f"config: expected a mapping of sections, got {type(data).__name__}")
        if base is not None and not isinstance(base, Config):
            raise TypeError(f"base: expected adparm.Config or None, got {type(base).__name__}")
        base = cls() if base is None else base
        sections = {}
        explicit = set(base._explicit)
        for section, values in data.items():
            _check_known(
                section,
                list(_SECTIONS),
                strings="config: section names must be strings",
                unknown="unknown config section [{name}]",
                listing=f"known sections: {', '.join(_SECTIONS)}",
            )
            if not isinstance(values, Mapping):
                raise TypeError(
                    f"[{section}]: expected a table of keys, got {type(values).__name__}"
                )
            _check_keys(values, [f.name for f in dataclasses.fields(_SECTIONS[section])], section)
            for key, value in values.items():
                _check_depth(value, f"{section}.{key}")
                name = f"{section}.{key}"
                if isinstance(value, str) and value == AUTO:
                    explicit.discard(name)
                else:
                    explicit.add(name)
            sections[section] = dataclasses.replace(getattr(base, section), **values)
        _check_urdf_keys(data, sections.get("plant", base.plant))
        return dataclasses.replace(base, **sections, _explicit=frozenset(explicit))

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Nested plain dict (lists for arrays, model keys left at the plant's value omitted)."""
        out: dict[str, dict[str, Any]] = {}
        for name in _SECTIONS:
            section = {
                f.name: getattr(getattr(self, name), f.name)
                for f in dataclasses.fields(_SECTIONS[name])
            }
            if name == "plant" and self.plant.urdf is not None:  # the URDF gives the arm
                section = {k: v for k, v in section.items() if k not in _TWO_LINK_KEYS}
            out[name] = {key: _plain(value) for key, value in section.items() if value is not None}
        return out

    def _check_model(self) -> None:
        """The model's keys against the plant's kind of arm (URDF or the two-link arm)."""
        if self.plant.urdf is None:
            for key in ("urdf", "gravity", "locked_joints"):
                if getattr(self.model, key) is not None:
                    raise ValueError(
                        f"model.{key}: only with a URDF plant (plant.urdf); the two-link model "
                        "takes model.p1 ... model.g2"
                    )
            _check_urdf_arm(self.model, "model")
            return
        _check_urdf_arm(dataclasses.replace(self.model, urdf=self.plant.urdf), "model")
        if self.model.urdf is not None or self.model.locked_joints is not None:
            believed = self.model.resolve_urdf(self.plant)
            name = "model.urdf" if self.model.urdf is not None else "model.locked_joints"
            n = self.dof
            n_model = urdf_info(believed["urdf"], name, believed["locked_joints"])[0]
            if n_model != n:
                raise ValueError(
                    f"{name}: the model has n = {n_model} joints, the plant (plant.urdf) "
                    f"n = {n}; the model must leave the plant's joints free"
                )
        _refuse_two_link_basis(self.controller.basis)

    def _fit_to_arm(self) -> None:
        """A URDF arm (any joint count, two included) derives every setting the config leaves
        out from its believed model's inertia (rates.urdf_defaults; the two-link arm keeps the
        paper's); then every size is checked against n, naming the field and the expected
        shape."""
        object.__setattr__(self, "_derived", {})
        n = self.dof
        if self.plant.urdf is not None:
            # the sizes first (the derivation evaluates the arm at q0 and qd)
            for (section, key), value in _joint_defaults(n).items():
                if f"{section}.{key}" not in self._explicit:
                    current = getattr(self, section)
                    object.__setattr__(self, section, dataclasses.replace(current, **{key: value}))
            _check_sizes(self, n)
            from .rates import urdf_defaults

            values, reasons = urdf_defaults(self)
            for (section, key), value in values.items():
                current = getattr(self, section)
                object.__setattr__(self, section, dataclasses.replace(current, **{key: value}))
            self._derived.update(reasons)
        elif n != 2:  # an n-joint stand-in without a URDF (tests): the n-joint defaults
            for (section, key), value in _joint_defaults(n).items():
                current = getattr(self, section)
                if getattr(current, key) == getattr(_SECTIONS[section](), key):
                    object.__setattr__(self, section, dataclasses.replace(current, **{key: value}))
        _check_sizes(self, n)

    @property
    def dof(self) -> int:
        """The joint count n of the plant: 2 for the built-in two-link arm, the URDF's
        revolute, continuous and prismatic joints for plant.urdf that plant.locked_joints leaves
        free."""
        if self.plant.urdf is None:
            return 2
        return urdf_info(self.plant.urdf, "plant.urdf", self.plant.locked_joints)[0]

    def initial_weights(self, key: str = "critic_weights") -> np.ndarray:
        """init.critic_weights (or ``key = "actor_weights"``), or the basis' default when left
        out (InitConfig)."""
        value = getattr(self.init, key)
        if value is not None:
            return np.array(value, dtype=float)
        return self._default_initial_weights(key)

    def _default_initial_weights(self, key: str) -> np.ndarray:
        """The basis' default initial weights (InitConfig), whether or not init gives some."""
        if self.controller.is_expression:
            return self._expression_initial_weights(key)
        if self.controller.basis == "structured":
            if self.plant.urdf is not None:
                # K = I and the believed model's base parameters: u_hat = -R^-1 e2 at first
                from .urdf import config_arm

                return config_arm(self, model=True).structured_weights(np.eye(self.dof))
            p = self.model.resolve(self.plant)
            return np.array([1.0, 0.0, 1.0, p["p1"], p["p2"], p["p3"]])
        return np.ones(BASIS_SIZES[self.controller.basis])

    @property
    def basis_size(self) -> int:
        """The number of functions of controller.basis on this arm (the length of the weights):
        the structured basis of a URDF arm has n (n + 1) / 2 + one per base inertial parameter
        of the believed model's URDF."""
        if self.plant.urdf is not None and self.controller.basis == "structured":
            believed = self.model.resolve_urdf(self.plant)
            return urdf_structured_size(
                believed["urdf"],
                "model.urdf" if self.model.urdf else "plant.urdf",
                believed["locked_joints"],
            )
        return self.controller.basis_size(self.dof)

    def _expression_initial_weights(self, key: str) -> np.ndarray:
        """The weights of x^T blockdiag(I, M(qd(0))) x (the believed model's inertia at the
        desired position): the actor then starts at u_hat = -R^-1 e2, which stabilises."""
        from .optimal import arm_terms, desired_state

        n = self.dof
        qd = desired_state(self, 0.0)[0]
        M = arm_terms(self, qd, np.zeros(n), model=True)["M"]
        P = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
        try:
            return self.controller.expression_basis(n).quadratic_form_weights(P)
        except ValueError as error:
            raise ValueError(
                f"init.{key}: controller.basis = {_plain(self.controller.basis)!r} cannot "
                "represent the default initial value x^T blockdiag(I, M(qd)) x "
                f"({error}); set init.critic_weights and init.actor_weights"
            ) from None

    @property
    def resolved_epsilon_T(self) -> float:
        """critic.epsilon_T, or its default for this run when left out: 1e-6 when learning from
        the probing signal alone, the paper's 1e-3 with Bellman-error extrapolation."""
        if self.critic.epsilon_T is not None:
            return self.critic.epsilon_T
        return EPSILON_T_EXTRAPOLATION if self.extrapolation.points > 0 else EPSILON_T_PROBING

    def left_out_values(self) -> dict[str, tuple[Any, str]]:
        """The value each setting that adparm resolves when it is left out takes for this
        config, and why, as {"section.key": (value, reason)}, whether or not the config gives
        it: critic.epsilon_T, init.critic_weights and init.actor_weights, probe.phases, a URDF
        plant's gravity, and the model's keys (the plant's values: an exact model). The
        settings of :attr:`derived` are in the config's fields already."""
        out: dict[str, tuple[Any, str]] = {}
        epsilon = EPSILON_T_EXTRAPOLATION if self.extrapolation.points > 0 else EPSILON_T_PROBING
        out["critic.epsilon_T"] = (
            epsilon,
            "with Bellman-error extrapolation (extrapolation.points > 0)"
            if self.extrapolation.points > 0
            else "learning from the probing signal alone (extrapolation.points = 0)",
        )
        for key in ("critic_weights", "actor_weights"):
            out[f"init.{key}"] = (
                self._default_initial_weights(key).tolist(),
                f"the default of controller.basis = {_plain(self.controller.basis)!r}",
            )
        out["probe.phases"] = (
            self.probe.phase_matrix(self.dof).tolist(),
            "phase k rad for sinusoid k, on every joint",
        )
        exact = "the plant's (the controller's model is exact)"
        if self.plant.urdf is None:
            for key in _ARM_KEYS:
                out[f"model.{key}"] = (_plain(getattr(self.plant, key)), exact)
        else:
            out["plant.gravity"] = (list(self.plant.resolved_gravity), "the default gravity")
            for key, value in ModelConfig().resolve_urdf(self.plant).items():
                if value is not None:
                    out[f"model.{key}"] = (_plain(value), exact)
        return out

    def to_toml(self, *, resolved: bool = False) -> str:
        """The config as TOML text that load_config reads back to an equal config: each section
        in turn, matrices one row per line.

        With ``resolved=True`` (the config.toml that adparm writes beside a run), also every
        setting left out that adparm resolved (:meth:`left_out_values`: critic.epsilon_T, the
        initial weights, the probe phases, the model), each after a ``# resolved:`` comment,
        and a ``# derived for this arm:`` comment above each setting of :attr:`derived`. A run
        of that file is the same run: every value it used is written."""
        data = self.to_dict()
        notes: dict[str, str] = {
            name: f"derived for this arm: {reason}" for name, reason in self._derived.items()
        }
        if resolved:
            for name, (value, reason) in self.left_out_values().items():
                section, key = name.split(".", 1)
                if key not in data[section]:
                    data[section][key] = value
                    notes[name] = f"resolved (left out): {reason}"
        return toml_text(data, notes)

    def updated(self, changes: Mapping[str, Any]) -> Config:
        """A copy with ``changes`` (``{section: {key: value}}``) applied, e.g.
        ``config.updated({"critic": {"eta_c": 100}})``."""
        return Config.from_dict(changes, base=self)


def _check_urdf_keys(data: Mapping[str, Any], plant: PlantConfig) -> None:
    """With a URDF plant, refuses the two-link keys and bases given explicitly (even at their
    default values), naming the field."""
    if plant.urdf is None:
        return
    for section in ("plant", "model"):
        values = data.get(section, {})
        for key in _TWO_LINK_KEYS:
            if key in values:
                raise ValueError(
                    f"{section}.{key}: a parameter of the built-in two-link arm; a URDF arm "
                    "(plant.urdf) takes its inertia and geometry from the URDF (leave "
                    f"{section}.{key} out)"
                )
    _refuse_two_link_basis(data.get("controller", {}).get("basis"))


def _refuse_two_link_basis(basis: Any) -> None:
    """A URDF arm refuses the two-link bases (ValueError naming controller.basis)."""
    if isinstance(basis, str) and basis in URDF_REFUSED_BASES:
        works = ", ".join(
            repr(b) for b in (*BASIS_KINDS, *EXPRESSION_FAMILIES) if b not in URDF_REFUSED_BASES
        )
        raise ValueError(
            f"controller.basis: {basis!r} is a basis of the built-in two-link arm; with "
            f"plant.urdf use {works} or a list of terms (default {URDF_DEFAULT_BASIS!r})"
        )


def _joint_defaults(n: int) -> dict[tuple[str, str], Any]:
    """The defaults of the sized settings for an arm of n != 2 joints (the two-link arm keeps the
    paper's): tau_d amplitudes 0.1 and q0 = 0.1 rad on every joint, dq0 = 0, qd = 0; K = I,
    alpha1 = 2 I, R = I and Q = [[K alpha1 + alpha1^T K, -K], [-K, R^-1]] = [[4 I, -I], [-I, I]]
    (the exact-solution conditions: V* = e1^T e1 + e2^T M(q) e2 is exact); probe amplitude 1 N m
    on every joint and sinusoid."""
    eye = np.eye(n)
    Q = np.block([[4.0 * eye, -eye], [-eye, eye]])
    return {
        ("plant", "disturbance"): (0.1,) * n,
        ("task", "q0"): (0.1,) * n,
        ("task", "dq0"): (0.0,) * n,
        ("task", "qd"): (0.0,) * n,
        ("cost", "Q"): tuple(map(tuple, Q)),
        ("cost", "R"): tuple(map(tuple, eye)),
        ("control", "alpha1"): tuple(map(tuple, 2.0 * eye)),
        ("probe", "amplitude"): 1.0,
    }


def _check_shape(value: Any, name: str, shape: tuple[int, ...], n: int) -> None:
    actual = np.shape(value)
    if actual != shape:
        raise ValueError(
            f"{name}: expected shape {_shape_text(shape)}, got {_shape_text(actual)} "
            f"(the arm has n = {n} joints)"
        )


def _check_sizes(config: Config, n: int) -> None:
    """Every sized setting against the joint count n (ValueError naming the field)."""
    _check_shape(config.plant.disturbance, "plant.disturbance", (n,), n)
    for section in ("plant", "model"):
        for key in ("coulomb", "viscous"):
            value = getattr(getattr(config, section), key)
            if isinstance(value, tuple):
                _check_shape(value, f"{section}.{key}", (n,), n)
    _check_shape(config.task.q0, "task.q0", (n,), n)
    _check_shape(config.task.dq0, "task.dq0", (n,), n)
    qd = config.task.qd
    if isinstance(qd, SinusoidTrajectory):
        k = len(qd.amplitude[0])
        _check_shape(qd.offset, "task.qd.offset", (n,), n)
        for key in ("amplitude", "frequency", "phase"):
            _check_shape(getattr(qd, key), f"task.qd.{key}", (n, k), n)
    elif isinstance(qd, SampledTrajectory):
        _check_shape(qd.q, "task.qd.q", (len(qd.t), n), n)
    else:
        _check_shape(qd, "task.qd", (n,), n)
    _check_shape(config.cost.Q, "cost.Q", (2 * n, 2 * n), n)
    _check_shape(config.cost.R, "cost.R", (n, n), n)
    _check_shape(config.control.alpha1, "control.alpha1", (n, n), n)
    k = len(config.probe.frequencies)
    amplitude = config.probe.amplitude
    if not isinstance(amplitude, float):
        shape = (n, k) if np.ndim(amplitude) == 2 else (n,)
        _check_shape(amplitude, "probe.amplitude", shape, n)
    if config.probe.phases is not None:
        _check_shape(config.probe.phases, "probe.phases", (n, k), n)
    for key in ("kp", "kd"):
        gain = getattr(config.controller, key)
        if not isinstance(gain, float):
            _check_shape(gain, f"controller.{key}", (n, n), n)
    if not isinstance(config.extrapolation.box, float):
        _check_shape(config.extrapolation.box, "extrapolation.box", (2 * n,), n)


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, dict):  # plant.locked_joints, model.locked_joints
        return dict(value)
    if isinstance(value, SampledTrajectory):  # the samples inline, not the file
        return {
            "kind": value.kind,
            "t": _plain(value.t),
            "q": _plain(value.q),
            "boundary": value.boundary,
        }
    if isinstance(value, SinusoidTrajectory):
        fields = {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"kind": value.kind, **fields}
    return value


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
        items = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{" + (f" {items} " if items else "") + "}"
    if not isinstance(value, list):
        return _toml_scalar(value)
    inner = indent + "    "
    if _is_row(value):
        items = [_toml_scalar(v) for v in value]
        line = "[" + ", ".join(items) + "]"
        if len(indent) + len(line) <= _TOML_WIDTH:
            return line
        lines, current = [], ""
        for item in items:
            if current and len(inner) + len(current) + len(item) + 2 > _TOML_WIDTH:
                lines.append(inner + current.rstrip().rstrip(","))
                current = ""
            current += item + ", "
        lines.append(inner + current.rstrip().rstrip(","))
        return "[\n" + ",\n".join(lines) + ",\n" + indent + "]"
    rows = [inner + _toml_value(v, inner) for v in value]
    return "[\n" + ",\n".join(rows) + ",\n" + indent + "]"


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


def _deep_toml(text: str) -> str:
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
            return f"line {number}, key {_name(key)!r}: nested more than {MAX_DEPTH} levels deep"
    return f"nested more than {MAX_DEPTH} levels deep"


def paper_config() -> Config:
    """The paper's instance (Section 4, corrected) with our documented open choices."""
    return Config()


def load_config(path: str | Path) -> Config:
    """Read a TOML file of sections [plant] [model] [task] [cost] [control] [critic] [actor]
    [init] [probe] [controller] [extrapolation] [sim]; keys left out take the paper default. A
    relative ``task.qd.file`` is relative to the TOML file's folder."""
    path = Path(path)
    text = read_text_file(path, "config", MAX_CONFIG_BYTES)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: invalid TOML: {error}") from error
    except RecursionError:
        raise ValueError(f"{path}: {_deep_toml(text)}") from None
    for section in ("plant", "model"):  # a relative URDF path is relative to the TOML file
        values = data.get(section)
        if (
            isinstance(values, Mapping)
            and isinstance(values.get("urdf"), str)
            and not values["urdf"].startswith(EXAMPLE_ROBOT_PREFIX)
        ):
            data[section]["urdf"] = str(path.parent / Path(values["urdf"]).expanduser())
    qd = data.get("task", {}).get("qd") if isinstance(data.get("task"), Mapping) else None
    if isinstance(qd, Mapping) and isinstance(qd.get("file"), str):
        data["task"]["qd"] = {**qd, "file": str(path.parent / Path(qd["file"]).expanduser())}
    return Config.from_dict(data)
