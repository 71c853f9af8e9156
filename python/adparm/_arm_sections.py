"""The sections of the configuration that describe the arm and the task: [plant], [model] and
[task] (with its trajectories), the URDF probing they need (through the core, adparm.urdf) and
plain_value, the plain (TOML/JSON-ready) form of a field's value."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ._fields import (
    ARM_KEYS,
    DEFAULT_GRAVITY,
    MAX_SAMPLES,
    TWO_LINK_DEFAULTS,
    TWO_LINK_KEYS,
    Matrix,
    Vector,
    check_arm,
    check_keys,
    choice_value,
    friction_value,
    key_text,
    limit_vector,
    matrix_value,
    read_samples,
    rows_value,
    scalar_value,
    setting,
    torque_limits_value,
    value_text,
    vector_value,
)
from .urdf import example_robot_urdf, locked_joints_message, shared_arm

#: A URDF named "example-robot-data:ur5" is that robot of the example-robot-data package
#: (adparm.example_robot_urdf).
EXAMPLE_ROBOT_PREFIX = "example-robot-data:"


def urdf_path(value: Any, name: str) -> str:
    """An absolute path of an existing URDF file (a relative one is taken from the current
    directory; load_config makes it relative to the TOML file first), or
    "example-robot-data:NAME" for a robot of example-robot-data."""
    import os

    if not isinstance(value, (str, Path)) or not str(value):
        raise TypeError(f"{name}: expected the path of a URDF file, got {value_text(value)}")
    if isinstance(value, str) and value.startswith(EXAMPLE_ROBOT_PREFIX):
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


def locked_pairs(locked: Mapping[str, float] | None) -> LockedPairs:
    return tuple((name, float(value)) for name, value in (locked or {}).items())


@functools.lru_cache(maxsize=32)
def _urdf_info(
    path: str, mtime_ns: int, size: int, locked: LockedPairs = ()
) -> tuple[int, tuple[str, ...]]:
    """(n, joint names) of a URDF read by the core (once per file version and locked joints),
    after the checks of the text of its <inertial> elements (urdf_text.check_inertial_text)."""
    arm = shared_arm(path, locked_joints=dict(locked))
    return arm.dof, tuple(arm.joint_names)


def urdf_error(error: Exception, name: str) -> ValueError:
    """A ValueError naming ``name`` (plant.urdf or model.urdf), or its section's locked_joints
    field for a problem with the locked joints."""
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
        return _urdf_info(path, stat.st_mtime_ns, stat.st_size, locked_pairs(locked))
    except (OSError, ValueError) as error:
        raise urdf_error(error, name) from None


@functools.lru_cache(maxsize=64)
def _urdf_structured_size(path: str, mtime_ns: int, size: int, locked: LockedPairs = ()) -> int:
    return len(shared_arm(path, locked_joints=dict(locked)).structured_names())


def urdf_structured_size(
    path: str, name: str = "plant.urdf", locked: Mapping[str, float] | None = None
) -> int:
    """The number of functions of the structured basis of the URDF arm at ``path`` with the
    joints ``locked`` held (it depends on the kinematics only: n (n + 1) / 2 + the number of
    base inertial parameters)."""
    import os

    try:
        stat = os.stat(path)
        return _urdf_structured_size(path, stat.st_mtime_ns, stat.st_size, locked_pairs(locked))
    except (OSError, ValueError) as error:
        raise urdf_error(error, name) from None


def locked_joints_value(value: Any, name: str) -> dict[str, float] | None:
    """A table {joint name: position (rad or m)}; an empty one is None (nothing locked). The
    names and limits are checked against the URDF by the core (urdf_info)."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise TypeError(
            f"{name}: expected a table of joint names and positions such as "
            f"{{panda_finger_joint1 = 0.0}}, got {type(value).__name__} {value_text(value)}"
        )
    locked = {}
    for joint, position in value.items():
        if not isinstance(joint, str) or not joint:
            raise TypeError(
                f"{name}: joint names must be non-empty strings, got {value_text(joint)}"
            )
        locked[joint] = scalar_value(position, f"{name}.{key_text(joint)}")
    return locked or None


def check_urdf_arm(arm: Any, section: str) -> None:
    """With a URDF: the two-link keys stay unset, gravity has 3 entries; without: gravity and
    per-joint friction are refused (the two-link arm has g1, g2 and one coefficient)."""
    if arm.urdf is not None:
        for key in TWO_LINK_KEYS:
            value = getattr(arm, key)
            if (
                value is not None
                and value != TWO_LINK_DEFAULTS[key]
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

    p1: float = setting(
        5.0,
        "M(q) = [[p1 + 2 p3 cos q2, p2 + p3 cos q2], [p2 + p3 cos q2, p2]] (eq. 1); C follows "
        "from M. See :func:`adparm.two_link_parameters` for physical links.",
        core="plant.p1",
    )
    p2: float = setting(1.0, "See p1.", core="plant.p2")
    p3: float = setting(1.0, "See p1.", core="plant.p3")
    g1: float = setting(
        9.8 * 1.2,
        "G(q) = [g1 cos q1 + g2 cos(q1 + q2), g2 cos(q1 + q2)] (N m); the paper's 9.8 x 1.2.",
        core="plant.g1",
    )
    g2: float = setting(9.8, "See g1 (N m); the paper's 9.8.", core="plant.g2")
    # as printed: F = -0.1 sgn(dq)
    coulomb: float | Vector = setting(
        -0.1,
        "Friction F = coulomb sgn(dq) + viscous dq; the paper prints F = -0.1 sgn(dq). One "
        "number; with ``urdf`` one number or one per joint.",
        core="plant.coulomb",
    )
    # not in the paper; 0 keeps its plant
    viscous: float | Vector = setting(
        0.0,
        "Viscous friction coefficient. Not in the paper. One number; with ``urdf`` one number or "
        "one per joint.",
        core="plant.viscous",
    )
    disturbance: Vector = setting(
        (0.1, 0.1), "tau_d = [d1 sin t, d2 cos t] (N m).", core="disturbance"
    )
    torque_limits: float | Vector | str | None = setting(
        None,
        "Actuator torque limits ``|tau_i| <= limit_i`` (N m; not in the paper): one number, one "
        'per joint (``inf``: none on that joint) or ``"none"``. The drive applies the torque '
        "clipped; RISE does not wind up (``control.anti_windup``); the result records the "
        "saturated time. "
        "Left out: none on the two-link arm, the URDF's ``<limit effort>`` on a URDF arm (0 or "
        "none given: no limit there). ``[model]`` has none. See :doc:`/guide/torque-limits`.",
        via="torque_limits: 'none' empty, one number for every joint (PlantConfig.limit_vector)",
    )
    urdf: str | None = setting(
        None,
        "A URDF file of any fixed-base serial arm (through Pinocchio) instead of the two-link "
        "arm: relative to the TOML file (in a config built from a dict, to the current "
        "directory), stored absolute. The actuated joints are its revolute, continuous and "
        "prismatic joints in model order; n follows from it and every sized setting takes the "
        'n-joint default. ``"example-robot-data:ur5"`` names a robot of the example-robot-data '
        "package. p1 ... g2 may not be set with it; its default basis is ``structured`` (the "
        "arm's own: W* = [K; base inertial parameters]); the bases ``paper`` and ``augmented`` "
        "are refused. See :doc:`/guide/urdf-arms`.",
        via="the URDF arm: plant_urdf (translate.urdf_settings)",
    )
    gravity: Vector | None = setting(
        None,
        "Acceleration of gravity [gx, gy, gz] in the URDF's root frame (m/s^2); only with "
        "``urdf``.",
        via="the URDF arm: plant_urdf (translate.urdf_settings)",
    )
    locked_joints: dict[str, float] | None = setting(
        None,
        "Joints of the URDF held at a position, a table ``{name = position, ...}`` (rad or m), "
        "through Pinocchio's reduced model: their links become part of the parent body and n "
        "counts the free joints only. A mimic joint must be locked or follow a locked joint (it "
        "is then locked at multiplier x position + offset). An unknown name (the message lists "
        "the arm's joints) or a position outside the joint's limits is refused; only with "
        "``urdf``. See :doc:`/guide/urdf-arms`.",
        via="the URDF arm: plant_urdf (translate.urdf_settings)",
    )

    def __post_init__(self) -> None:
        for key in TWO_LINK_KEYS:
            object.__setattr__(self, key, scalar_value(getattr(self, key), f"plant.{key}"))
        locked = locked_joints_value(self.locked_joints, "plant.locked_joints")
        object.__setattr__(self, "locked_joints", locked)
        for key in ("coulomb", "viscous"):
            object.__setattr__(self, key, friction_value(getattr(self, key), f"plant.{key}"))
        disturbance = vector_value(self.disturbance, "plant.disturbance", None)
        object.__setattr__(self, "disturbance", disturbance)
        limits = torque_limits_value(self.torque_limits, "plant.torque_limits")
        object.__setattr__(self, "torque_limits", limits)
        if self.urdf is not None:
            object.__setattr__(self, "urdf", urdf_path(self.urdf, "plant.urdf"))
            urdf_info(self.urdf, "plant.urdf", self.locked_joints)
        if self.gravity is not None:
            object.__setattr__(self, "gravity", vector_value(self.gravity, "plant.gravity", 3))
        check_urdf_arm(self, "plant")
        check_arm(self.p1, self.p2, self.p3, "plant")

    def limit_vector(self, n: int) -> np.ndarray:
        """The limits of the n joints (inf: none there); empty without limits (the core's)."""
        return limit_vector(self.torque_limits, n)

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

    p1: float | None = setting(
        None,
        "The arm the controller believes (feedforward h, f, g and W*). Each key left out takes "
        "the plant's value; set one to introduce a model error.",
        core="model.p1",
    )
    p2: float | None = setting(None, "As p1.", core="model.p2")
    p3: float | None = setting(None, "As p1.", core="model.p3")
    g1: float | None = setting(None, "As p1.", core="model.g1")
    g2: float | None = setting(None, "As p1.", core="model.g2")
    coulomb: float | Vector | None = setting(None, "As p1.", core="model.coulomb")
    viscous: float | Vector | None = setting(None, "As p1.", core="model.viscous")
    urdf: str | None = setting(
        None,
        "Another URDF of the same joint count as the controller's believed arm (a model error); "
        "only with ``plant.urdf``.",
        via="the believed URDF arm: model_urdf (translate.urdf_settings)",
    )
    gravity: Vector | None = setting(
        None,
        "The believed gravity [gx, gy, gz]; only with ``plant.urdf``.",
        via="the believed URDF arm: model_urdf (translate.urdf_settings)",
    )
    locked_joints: dict[str, float] | None = setting(
        None,
        "The believed locked joints (a table as ``plant.locked_joints``); the model must have the "
        "plant's number of free joints; only with ``plant.urdf``.",
        via="the believed URDF arm: model_urdf (translate.urdf_settings)",
    )
    scale: float | None = setting(
        None,
        "A factor on the believed model's p1, p2, p3, g1, g2 (two-link arm) or every link's mass "
        "and inertia (URDF arm): its M, C and G are the other keys' times scale, friction left "
        "alone; left out: 1; e.g. 0.7 for a model 30 % light. In [0.1, 10]. The one key a sweep "
        "over the model's error varies (:doc:`/guide/unknown-dynamics`).",
        via="two-link: ModelConfig.resolve; URDF: model_urdf.inertia_scale (urdf_settings)",
    )

    def __post_init__(self) -> None:
        for key in TWO_LINK_KEYS:
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, scalar_value(value, f"model.{key}"))
        if self.scale is not None:
            scale = scalar_value(self.scale, "model.scale", minimum=0.1, maximum=10.0)
            object.__setattr__(self, "scale", scale)
        locked = locked_joints_value(self.locked_joints, "model.locked_joints")
        object.__setattr__(self, "locked_joints", locked)
        for key in ("coulomb", "viscous"):
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, friction_value(value, f"model.{key}"))
        if self.urdf is not None:
            # read with the locked joints in Config (they may be the plant's)
            object.__setattr__(self, "urdf", urdf_path(self.urdf, "model.urdf"))
        if self.gravity is not None:
            object.__setattr__(self, "gravity", vector_value(self.gravity, "model.gravity", 3))

    def resolve(self, plant: PlantConfig) -> dict[str, Any]:
        """The model's parameters with the plant's values filled in, p1 ... g2 times ``scale``."""
        values = {
            key: getattr(plant, key) if getattr(self, key) is None else getattr(self, key)
            for key in ARM_KEYS
        }
        if self.scale is not None and self.scale != 1.0:
            values.update({key: self.scale * values[key] for key in TWO_LINK_KEYS})
        return values

    def differs(self, plant: PlantConfig) -> bool:
        """Whether the believed arm differs from ``plant``: the two-link arm's parameters
        (model.scale included), or a URDF arm's file, gravity, friction or locked joints."""
        exact = ModelConfig()
        if plant.urdf is not None:
            return self.resolve_urdf(plant) != exact.resolve_urdf(plant)
        return self.resolve(plant) != exact.resolve(plant)

    def resolve_urdf(self, plant: PlantConfig) -> dict[str, Any]:
        """The believed URDF arm: urdf, gravity, coulomb, viscous, locked_joints, each the
        plant's when left out (a URDF plant only), and scale (None: 1, the URDF's inertia)."""
        return {
            "urdf": plant.urdf if self.urdf is None else self.urdf,
            "gravity": plant.resolved_gravity if self.gravity is None else self.gravity,
            "coulomb": plant.coulomb if self.coulomb is None else self.coulomb,
            "viscous": plant.viscous if self.viscous is None else self.viscous,
            "locked_joints": (
                plant.locked_joints if self.locked_joints is None else self.locked_joints
            ),
            "scale": None if self.scale == 1.0 else self.scale,
        }


@dataclass(frozen=True)
class SinusoidTrajectory:
    """qd_j(t) = offset_j + sum_k amplitude_jk sin(frequency_jk t + phase_jk) (rad, rad/s).

    amplitude, frequency and phase are each a vector (one sinusoid per joint) or a joints x k matrix
    (k sinusoids per joint); phase None is all zeros. In TOML: ``[task.qd]`` with
    ``kind = "sinusoid"``."""

    kind: ClassVar[str] = "sinusoid"
    amplitude: Vector | Matrix = setting(
        (0.5, 0.3),
        '``kind = "sinusoid"``: qd_j = offset_j + sum_k amplitude_jk sin(frequency_jk t + '
        "phase_jk) (rad). One per joint, or a joints x k matrix for k sinusoids per joint.",
        via="task.qd (desired.trajectory_settings)",
    )
    frequency: Vector | Matrix = setting(
        (1.0, 1.0), "rad/s, same shape as amplitude.", via="task.qd (desired.trajectory_settings)"
    )
    phase: Vector | Matrix | None = setting(
        None, "rad, same shape as amplitude.", via="task.qd (desired.trajectory_settings)"
    )
    offset: Vector | None = setting(
        None,
        "rad, one per joint; None (the default): the arm's rest position, 0 on the two-link "
        "arm and on a URDF arm task.qd's derived set-point (0 moved inside the joint limits).",
        via="task.qd (desired.trajectory_settings)",
    )

    def __post_init__(self) -> None:
        amplitude = rows_value(self.amplitude, "task.qd.amplitude", None)
        n = len(amplitude[0])
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "frequency", rows_value(self.frequency, "task.qd.frequency", n))
        phase = ((0.0,) * n,) * len(amplitude) if self.phase is None else self.phase
        object.__setattr__(self, "phase", rows_value(phase, "task.qd.phase", n))
        if self.offset is not None:  # one per joint; None: the arm's rest position (below)
            object.__setattr__(self, "offset", vector_value(self.offset, "task.qd.offset", None))
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

    Either ``file``, a CSV file with columns t, qd1, ..., qdn (a header line and # comments are
    skipped; a relative path in a TOML file is relative to that file), or ``t`` (m,) and ``q``
    (m, n) inline (n joints). The first sample must be at t <= 0 and the last at t >= sim.T. In
    TOML: ``[task.qd]`` with ``kind = "samples"``."""

    kind: ClassVar[str] = "samples"
    t: Vector = setting(
        (),
        '``kind = "samples"``: sample times (s), from t <= 0 to t >= sim.T; qd through a cubic '
        "spline (SciPy's CubicSpline).",
        via="task.qd (desired.trajectory_settings)",
    )
    q: Matrix = setting(
        (),
        "Samples of qd, one row [qd1, ..., qdn] per time (rad).",
        via="task.qd (desired.trajectory_settings)",
    )
    file: str | None = setting(
        None,
        "Instead of t and q: a CSV file with columns t, qd1, ..., qdn (relative to the TOML file).",
        via="task.qd (desired.trajectory_settings)",
    )
    boundary: str = setting(
        "not-a-knot",
        "Spline end conditions: ``not-a-knot``, ``clamped`` or ``natural``.",
        via="task.qd (desired.trajectory_settings)",
    )

    def __post_init__(self) -> None:
        if self.file is not None:
            if not isinstance(self.file, (str, Path)):
                raise TypeError(f"task.qd.file: expected a path, got {value_text(self.file)}")
            if not (is_empty(self.t) and is_empty(self.q)):
                raise ValueError("task.qd: give either file or t and q, not both")
            t, q = read_samples(Path(self.file))
            object.__setattr__(self, "file", str(self.file))
            object.__setattr__(self, "t", t)
            object.__setattr__(self, "q", q)
        object.__setattr__(self, "t", vector_value(self.t, "task.qd.t", None))
        if len(self.t) > MAX_SAMPLES:
            raise ValueError(f"task.qd.t: at most {MAX_SAMPLES} samples, got {len(self.t)}")
        q = matrix_value(self.q, "task.qd.q", None, None)
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
        choice_value(self.boundary, "task.qd.boundary", ("not-a-knot", "clamped", "natural"))
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


def is_empty(value: Any) -> bool:
    return isinstance(value, (tuple, list)) and len(value) == 0


TRAJECTORIES: dict[str, type] = {"sinusoid": SinusoidTrajectory, "samples": SampledTrajectory}
Trajectory = Vector | SinusoidTrajectory | SampledTrajectory


def trajectory_value(value: Any) -> Trajectory:
    if isinstance(value, (SinusoidTrajectory, SampledTrajectory)):
        return value
    if not isinstance(value, Mapping):
        return vector_value(value, "task.qd", None)
    values = dict(value)
    kinds = tuple(TRAJECTORIES)
    if "kind" not in values:
        raise ValueError(f"task.qd.kind: expected one of {', '.join(kinds)}, got nothing")
    kind = choice_value(values.pop("kind"), "task.qd.kind", kinds)
    cls = TRAJECTORIES[kind]
    check_keys(values, [f.name for f in dataclasses.fields(cls)], "task.qd")
    return cls(**values)


@dataclass(frozen=True)
class TaskConfig:
    """Initial joint state and desired trajectory qd (rad, rad/s).

    qd is a set-point (a pair, the paper's qd = 0), a SinusoidTrajectory or a SampledTrajectory
    (in TOML a ``[task.qd]`` table with ``kind = "sinusoid"`` or ``"samples"``). The feedforward
    uses qd, dqd and ddqd (eq. 5 in full). dq0 = 0 is our choice (the paper is silent)."""

    q0: Vector = setting((0.1598, 0.2257), "Initial joint angles (rad).", core="task.q0")
    dq0: Vector = setting(
        (0.0, 0.0),
        "Initial joint velocities (rad/s). The paper is silent; 0 here.",
        core="task.dq0",
    )
    qd: Trajectory = setting(
        (0.0, 0.0),
        "Desired trajectory: a constant set-point (rad), or a ``[task.qd]`` table (below and "
        ":doc:`/guide/tracking`).",
        via="task.qd (desired.trajectory_settings)",
    )

    def __post_init__(self) -> None:
        for key in ("q0", "dq0"):
            object.__setattr__(self, key, vector_value(getattr(self, key), f"task.{key}", None))
        object.__setattr__(self, "qd", trajectory_value(self.qd))

    @property
    def is_set_point(self) -> bool:
        """Whether qd is constant."""
        return not isinstance(self.qd, (SinusoidTrajectory, SampledTrajectory))


def plain_value(value: Any) -> Any:
    if isinstance(value, tuple):
        return [plain_value(v) for v in value]
    if isinstance(value, dict):  # plant.locked_joints, model.locked_joints
        return dict(value)
    if isinstance(value, SampledTrajectory):  # the samples inline, not the file
        return {
            "kind": value.kind,
            "t": plain_value(value.t),
            "q": plain_value(value.q),
            "boundary": value.boundary,
        }
    if isinstance(value, SinusoidTrajectory):
        fields = {f.name: plain_value(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"kind": value.kind, **fields}
    return value
