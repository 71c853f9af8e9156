"""Arms from URDF files: the model terms of eq. (1) through Pinocchio's C++ library.

``UrdfArm`` reads a URDF (a fixed-base serial arm: revolute, continuous, prismatic and fixed
joints; joints may be locked at a position) and computes M(q), C(q, dq), G(q), F(dq) and
M(q)^-1 in adparm's C++ core, with the same conventions as the built-in two-link arm.
``example_robot_urdf`` finds the URDFs of the ``example-robot-data`` package (UR5, Panda, ...).
"""

from __future__ import annotations

import copy
import functools
import os
import sys
import sysconfig
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

import adparm._core as _core

from .urdf_text import check_inertial_text

__all__ = [
    "EXAMPLE_LOCKED_JOINTS",
    "EXAMPLE_ROBOTS",
    "UrdfArm",
    "example_robot_urdf",
    "shared_arm",
]

#: Names accepted by example_robot_urdf, and their files under example-robot-data's robots/:
#: every fixed-base arm of the package (4.x). The Panda needs its fingers locked (they mimic
#: each other) and Baxter every joint but one arm's (docs: Arms from URDF files).
EXAMPLE_ROBOTS: dict[str, str] = {
    "ur3": "ur_description/urdf/ur3_robot.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "ur3_limited": "ur_description/urdf/ur3_joint_limited_robot.urdf",
    "ur5_limited": "ur_description/urdf/ur5_joint_limited_robot.urdf",
    "ur10_limited": "ur_description/urdf/ur10_joint_limited_robot.urdf",
    "ur3_gripper": "ur_description/urdf/ur3_gripper.urdf",
    "ur5_gripper": "ur_description/urdf/ur5_gripper.urdf",
    "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
    "double_pendulum_continuous": (
        "double_pendulum_description/urdf/double_pendulum_continuous.urdf"
    ),
    "double_pendulum_simple": "double_pendulum_description/urdf/double_pendulum_simple.urdf",
    "asr_twodof": "asr_twodof_description/urdf/TwoDofs.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "z1": "z1_description/urdf/z1.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "so100": "so_arm_description/urdf/so100.urdf",
    "so101": "so_arm_description/urdf/so101.urdf",
    "finger_edu": "finger_edu_description/robots/finger_edu.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "panda_collision": "panda_description/urdf/panda_collision.urdf",
    "talos_arm": "talos_data/robots/talos_left_arm.urdf",
    "baxter": "baxter_description/urdf/baxter.urdf",
}

#: The joints to lock for the robots of EXAMPLE_ROBOTS that need some (their mimic joints, or
#: for Baxter everything but the left arm), as the docs and tests use them.
EXAMPLE_LOCKED_JOINTS: dict[str, dict[str, float]] = {
    "panda": {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0},
    "panda_collision": {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0},
    "baxter": {
        name: 0.0
        for name in (
            "head_pan",
            "right_s0",
            "right_s1",
            "right_e0",
            "right_e1",
            "right_w0",
            "right_w1",
            "right_w2",
            "l_gripper_l_finger_joint",
            "l_gripper_r_finger_joint",
            "r_gripper_l_finger_joint",
            "r_gripper_r_finger_joint",
        )
    },
}


def locked_joints_message(message: str, section: str) -> str:
    """The core's message about locked joints ("locked_joints: ...") for the field of a config
    section: "plant.locked_joints: ...", "lock it: [plant] locked_joints = {...}". Any other
    message is returned as is."""
    head = "locked_joints: "
    if not message.startswith(head):
        return message
    message = f"{section}.locked_joints: " + message[len(head) :]
    return message.replace(
        "lock it: locked_joints = {", f"lock it: [{section}] locked_joints = {{", 1
    )


def _locked_list(locked_joints: Mapping[str, float] | None) -> list[tuple[str, float]]:
    if locked_joints is None:
        return []
    if not isinstance(locked_joints, Mapping):
        raise TypeError(
            "locked_joints: expected a mapping of joint names to positions, got "
            f"{type(locked_joints).__name__}"
        )
    return [(str(name), float(value)) for name, value in locked_joints.items()]


def _as_per_joint(value: float | ArrayLike, name: str) -> float | NDArray[np.float64]:
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return float(array)
    if array.ndim != 1:
        raise ValueError(f"{name}: expected one number or one per joint, got shape {array.shape}")
    return array


def _vector(value: ArrayLike, size: int, name: str) -> NDArray[np.float64]:
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise ValueError(f"{name}: expected shape ({size},), got {array.shape}")
    return array


class UrdfArm:
    """A fixed-base serial arm read from a URDF, its dynamics computed by Pinocchio.

    Parameters
    ----------
    urdf:
        Path of the URDF file.
    gravity:
        Acceleration of gravity in the URDF's root frame, m/s^2 (default [0, 0, -9.81]).
    coulomb, viscous:
        Friction F(dq) = coulomb * sign(dq) + viscous * dq: one number for every joint or one
        per joint (default 0). The URDF's own <dynamics> tags are not read.
    locked_joints:
        Joints held at a position, {name: rad or m} (Pinocchio's reduced model): their links
        become part of the parent body, and q has the free joints only. A mimic joint must be
        locked or follow a locked joint (it is then locked at multiplier * position + offset).

    The joints q are the URDF's revolute, continuous and prismatic joints left free, in
    Pinocchio's model order (``joint_names``); a continuous joint's q is its angle. A URDF that
    cannot be read or parsed, that has no free such joint, that has a floating or planar joint
    or a free mimic joint, or that fails a physical check (an <inertial> that does not read, a
    negative mass, an inertia that is not positive semi-definite or breaks the triangle
    inequality, a moved body without mass or rotational inertia, a zero joint axis) is refused
    with a ValueError naming the file and the link or joint. A problem with the locked joints
    (an unknown name, a position outside the joint's limits) is a ValueError starting
    "locked_joints: ".
    """

    def __init__(
        self,
        urdf: str | os.PathLike[str],
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        coulomb: float | ArrayLike = 0.0,
        viscous: float | ArrayLike = 0.0,
        locked_joints: Mapping[str, float] | None = None,
    ) -> None:
        path = Path(urdf)
        if not path.is_file():
            raise ValueError(f"URDF {path}: no such file")
        check_inertial_text(path)
        _count_parse()
        self._arm = _core.UrdfArm(
            str(path),
            gravity=_vector(gravity, 3, "gravity"),
            coulomb=_as_per_joint(coulomb, "coulomb"),
            viscous=_as_per_joint(viscous, "viscous"),
            locked_joints=_locked_list(locked_joints),
        )
        self.path = path

    def __repr__(self) -> str:
        return f"UrdfArm({str(self.path)!r}, dof={self.dof}, joints={self.joint_names})"

    def with_gravity_and_friction(
        self,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        coulomb: float | ArrayLike = 0.0,
        viscous: float | ArrayLike = 0.0,
    ) -> UrdfArm:
        """The arm ``UrdfArm(path, gravity, coulomb, viscous, locked_joints)`` would read (the
        same numbers), without reading the URDF again: it shares this arm's parsed model (and
        its structured basis, which neither changes)."""
        arm = copy.copy(self)
        arm._arm = self._arm.with_gravity_and_friction(
            gravity=_vector(gravity, 3, "gravity"),
            coulomb=_as_per_joint(coulomb, "coulomb"),
            viscous=_as_per_joint(viscous, "viscous"),
        )
        return arm

    def with_inertia_scaled(self, scale: float) -> UrdfArm:
        """This arm with every link's mass and inertia times ``scale`` > 0 (M, C and G times it:
        ``model.scale``), without reading the URDF again. 1: this arm."""
        if scale == 1.0:
            return self
        arm = copy.copy(self)
        arm._arm = self._arm.with_inertia_scaled(float(scale))
        arm.__dict__.pop("_structured_basis", None)  # its weights hold the inertia
        return arm

    @property
    def dof(self) -> int:
        """Number of joints n."""
        return self._arm.dof

    @property
    def joint_names(self) -> list[str]:
        return list(self._arm.joint_names)

    @property
    def locked_joints(self) -> dict[str, float]:
        """The locked joints and their positions: those given, then the mimic joints that
        follow one of them."""
        return dict(self._arm.locked_joints)

    @property
    def joint_types(self) -> list[str]:
        """URDF type of each joint: "revolute", "continuous" or "prismatic"."""
        return list(self._arm.joint_types)

    @property
    def gravity(self) -> NDArray[np.float64]:
        return self._arm.gravity

    @property
    def coulomb(self) -> NDArray[np.float64]:
        return self._arm.coulomb

    @property
    def viscous(self) -> NDArray[np.float64]:
        return self._arm.viscous

    @property
    def limits(self) -> dict[str, NDArray[np.float64]]:
        """The URDF's joint limits: "lower", "upper" (+-inf for a continuous joint, and for a
        joint whose lower equals upper: a URDF that leaves them out reads 0 and 0, which no
        moving joint means), "velocity" and "effort" (inf where the URDF gives none)."""
        return dict(self._arm.limits)

    @property
    def inertial_parameters(self) -> NDArray[np.float64]:
        """pi (10 n,): per joint, of the body it moves, m, m c (3), I (xx, xy, yy, xz, yz, zz),
        with the first moment m c and the inertia I about the joint frame's origin."""
        return self._arm.inertial_parameters

    def terms(self, q: ArrayLike, dq: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """M, M_inv, C (n, n) and G, F (n,) at joint positions q and velocities dq (n,)."""
        n = self.dof
        return self._arm.terms(_vector(q, n, "q"), _vector(dq, n, "dq"))

    def mass_regressor(self, q: ArrayLike) -> NDArray[np.float64]:
        """M_k(q) = dM/dpi_k for every inertial parameter, shape (10 n, n, n):
        M(q) = sum_k inertial_parameters[k] * mass_regressor(q)[k]."""
        n = self.dof
        side_by_side = self._arm.mass_regressor(_vector(q, n, "q"))
        return side_by_side.reshape(n, 10 * n, n).transpose(1, 0, 2)

    @property
    def inertial_parameter_names(self) -> list[str]:
        """Names of the 10 n inertial parameters: "m link1", "mc_x link1", ..., "I_zz linkn"
        (the body each joint moves, by its URDF link name)."""
        return list(self._arm.inertial_parameter_names)

    def base_parameters(
        self, samples: int = 100, seed: int = 0, tolerance: float = 1e-9
    ) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.float64]]:
        """A minimal set of inertial parameters of the kinetic energy (base parameters).

        Returns (values, columns, combination): values (r,) = combination (r, 10 n) @
        inertial_parameters, and M(q) = sum_i values[i] * mass_regressor(q)[columns[i]] for every
        q. The upper-triangle entries of the M_k(q) of `samples` random poses (a seeded
        generator, within the joint limits clipped to [-pi, pi]) are stacked and reduced by a QR
        decomposition with column pivoting: r is the number of pivots above `tolerance` times the
        largest, the pivot columns (in increasing order) are independent and every other column
        is a fixed combination of them, folded into `values`. Computed by the C++ core, the same
        computation that chooses the structured basis' functions (``structured_basis``).
        """
        values, columns, combination = self._arm.base_parameters(
            samples=int(samples), seed=int(seed), tolerance=float(tolerance)
        )
        return values, np.asarray(columns, dtype=np.intp), combination

    def identifier_parameters(self) -> tuple[NDArray[np.float64], list[str], list[str]]:
        """The online identifier's base parameters of this arm (issue 25; guide: Unknown
        dynamics): (values, names, groups), beta = [the kinetic energy's base parameters
        (``base_parameters()``, group "inertia"); the parameters gravity sees beyond them
        ("gravity"); coulomb per joint; viscous per joint ("friction")], in which M ddq + C dq +
        G + F = Y beta (``identifier_regressors``). Computed by the C++ core
        (urdf_regressor.hpp)."""
        values, names, groups = self._arm.identifier_parameters()
        return np.asarray(values, dtype=float), list(names), list(groups)

    def identifier_regressors(
        self, q: ArrayLike, dq: ArrayLike, ddq: ArrayLike, dq_r: ArrayLike, ddq_r: ArrayLike
    ) -> dict[str, NDArray[np.float64]]:
        """The online identifier's regressors (n, P) in ``identifier_parameters()``' beta: Y
        (M ddq + C dq + G + F), Y_r (M ddq_r + C(q, dq) dq_r + G + F(dq)), Y_M (M dq) and Y_N
        (G + F - C^T dq)."""
        n = self.dof
        out = self._arm.identifier_regressors(
            _vector(q, n, "q"),
            _vector(dq, n, "dq"),
            _vector(ddq, n, "ddq"),
            _vector(dq_r, n, "dq_r"),
            _vector(ddq_r, n, "ddq_r"),
        )
        return {key: np.asarray(value) for key, value in out.items()}

    def _structured(self) -> _core.UrdfStructuredBasis:
        basis = getattr(self, "_structured_basis", None)
        if basis is None:
            basis = self._structured_basis = _core.UrdfStructuredBasis(self._arm)
        return basis

    def structured_names(self) -> list[str]:
        """Names of the structured basis' functions: "e1_1^2", "e1_1 e1_2", ..., "e1_n^2", then
        "e2'M_b e2 (m link2)", ... (one per base parameter, ``base_parameters()``)."""
        return list(self._structured().names)

    def structured_weights(
        self, K: ArrayLike, inertial_parameters: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """The structured basis' exact weights W* for V* = e1^T K e1 + e2^T M(q) e2:
        [K_ii on squares, K_ij + K_ji on cross terms; the base parameters' values].

        With ``inertial_parameters`` (10 n,) of another arm of the same kinematics (the plant,
        when this arm is the believed model), its base parameters combination @ pi instead:
        W* of that arm in this arm's basis (exact when the arms differ in their inertias only).
        """
        n = self.dof
        K = np.asarray(K, dtype=float)
        if K.shape != (n, n):
            raise ValueError(f"K: expected shape ({n}, {n}), got {K.shape}")
        if inertial_parameters is None:
            return self._structured().optimal_weights(K)
        pi = _vector(inertial_parameters, 10 * n, "inertial_parameters")
        return self._structured().optimal_weights(K, pi)

    def structured_basis(
        self, x: ArrayLike, qd: ArrayLike, dqd: ArrayLike | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The structured basis of this arm at error states x (..., 2n) = [e1; e2] with desired
        positions qd and velocities dqd (n,) or (..., n); dqd defaults to 0.

        phi = [e1_i e1_j (i <= j); e2^T M_b(q) e2 per base parameter b], q = qd - e1. Returns
        phi (..., N), its exact Jacobian d phi / dx (..., N, 2n) and the desired rate
        (d phi / d qd) dqd (..., N), computed by the C++ core from Pinocchio's kinematics
        derivatives (no finite difference).
        """
        n = self.dof
        x = np.asarray(x, dtype=float)
        if x.ndim == 0 or x.shape[-1] != 2 * n:
            raise ValueError(f"x: expected shape (..., {2 * n}), got {x.shape}")
        batch = x.shape[:-1]

        def rows(value: ArrayLike | None, name: str) -> NDArray[np.float64]:
            array = np.zeros(n) if value is None else np.asarray(value, dtype=float)
            if array.ndim == 0 or array.shape[-1] != n:
                raise ValueError(f"{name}: expected shape (..., {n}), got {array.shape}")
            try:
                array = np.broadcast_to(array, batch + (n,))
            except ValueError:
                raise ValueError(
                    f"{name}: shape {array.shape} does not broadcast to x's {batch + (n,)}"
                ) from None
            return np.ascontiguousarray(array.reshape(-1, n))

        flat_qd, flat_dqd = rows(qd, "qd"), rows(dqd, "dqd")
        phi, jacobian, rate = self._structured().evaluate_rows(
            np.ascontiguousarray(x.reshape(-1, 2 * n)), flat_qd, flat_dqd
        )
        size = phi.shape[-1]
        return (
            phi.reshape(batch + (size,)),
            jacobian.reshape(batch + (size, 2 * n)),
            rate.reshape(batch + (size,)),
        )


def config_arm(config: Any, *, model: bool = False) -> UrdfArm:
    """The URDF arm of ``config``'s plant (``model=True``: the arm the controller believes,
    [model] with the plant's values where it leaves them out). Only for a URDF plant."""
    plant = config.plant
    if plant.urdf is None:
        raise ValueError("plant.urdf: the config's arm is the built-in two-link arm, not a URDF")
    arm = (
        config.model.resolve_urdf(plant)
        if model
        else {
            "urdf": plant.urdf,
            "gravity": plant.resolved_gravity,
            "coulomb": plant.coulomb,
            "viscous": plant.viscous,
            "locked_joints": plant.locked_joints,
        }
    )
    return shared_arm(
        arm["urdf"],
        arm["gravity"],
        arm["coulomb"],
        arm["viscous"],
        arm["locked_joints"],
        arm.get("scale"),
    )


def _hashable(value: Any) -> Any:
    """A number, or a tuple of numbers for a vector (a cache key)."""
    if isinstance(value, (int, float, np.floating, np.integer)):
        return float(value)
    return tuple(float(v) for v in np.asarray(value, dtype=float).reshape(-1))


_parses = 0
_parses_lock = threading.Lock()


def _count_parse() -> None:
    global _parses  # noqa: PLW0603 - a process-wide counter, as the core's
    with _parses_lock:
        _parses += 1


def parse_count() -> int:
    """How many URDF files ``UrdfArm`` has read so far, in every thread (``shared_arm`` reads
    a file once; ``with_gravity_and_friction`` reads none): what tests check "parsed once" by,
    beside the core's own count, ``adparm._core.urdf_parse_count()``."""
    with _parses_lock:
        return _parses


@functools.lru_cache(maxsize=32)
def _parsed_arm(
    path: str, mtime_ns: int, size: int, locked: tuple[tuple[str, float], ...], thread: int
) -> UrdfArm:
    return UrdfArm(path, locked_joints=dict(locked) or None)


@functools.lru_cache(maxsize=32)
def _shared_arm(
    path: str,
    mtime_ns: int,
    size: int,
    gravity: tuple[float, ...],
    coulomb: float | tuple[float, ...],
    viscous: float | tuple[float, ...],
    locked: tuple[tuple[str, float], ...],
    thread: int,
    inertia_scale: float = 1.0,
) -> UrdfArm:
    parsed = _parsed_arm(path, mtime_ns, size, locked, thread)
    if gravity != (0.0, 0.0, -9.81) or coulomb != 0.0 or viscous != 0.0:
        parsed = parsed.with_gravity_and_friction(gravity, coulomb, viscous)
    return parsed.with_inertia_scaled(inertia_scale)


def shared_arm(
    urdf: str | os.PathLike[str],
    gravity: ArrayLike = (0.0, 0.0, -9.81),
    coulomb: float | ArrayLike = 0.0,
    viscous: float | ArrayLike = 0.0,
    locked_joints: Mapping[str, float] | None = None,
    inertia_scale: float | None = None,
) -> UrdfArm:
    """``UrdfArm(urdf, gravity, coulomb, viscous, locked_joints)``, read once per version of the
    file (its modification time and size), locked joints and thread, and shared: a config's
    checks, defaults, basis and optimum all use the one parse (other gravity or friction: its
    ``with_gravity_and_friction``; inertia_scale: ``with_inertia_scaled``). Do not change it."""
    scale = 1.0 if inertia_scale is None else float(inertia_scale)
    try:
        stat = os.stat(urdf)
        key = (
            _hashable(gravity),
            _hashable(coulomb),
            _hashable(viscous),
            tuple((str(k), float(v)) for k, v in (locked_joints or {}).items()),
        )
    except (OSError, TypeError, ValueError):  # UrdfArm names the problem
        return UrdfArm(urdf, gravity, coulomb, viscous, locked_joints).with_inertia_scaled(scale)
    return _shared_arm(
        str(urdf), stat.st_mtime_ns, stat.st_size, *key, threading.get_ident(), scale
    )


def _example_robot_data_root() -> Path | None:
    candidates: list[Path] = []
    for key in ("purelib", "platlib"):
        candidates.append(Path(sysconfig.get_paths()[key]))
    candidates += [Path(p) for p in sys.path if p]
    for base in candidates:
        root = base / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if root.is_dir():
            return root
    return None


def example_robot_urdf(name: str) -> Path:
    """The path of a URDF of the ``example-robot-data`` package (``pip install
    example-robot-data``): a name of EXAMPLE_ROBOTS, or a path relative to its robots/ folder
    (e.g. "ur_description/urdf/ur3_robot.urdf"). In a config, ``[plant] urdf =
    "example-robot-data:NAME"`` names the same file.

    Every robot of EXAMPLE_ROBOTS is a plant as it is ("ur3", "ur5", "ur10", "kinova", "z1",
    "xarm7", "talos_arm", ...) except three, which need joints locked: "panda" and
    "panda_collision" (their finger joints mimic each other) and "baxter" (two arms and a head
    on one tree: all but the left arm). ``EXAMPLE_LOCKED_JOINTS[name]`` gives the joints to lock
    as ``plant.locked_joints``; without them the config is refused, naming plant.locked_joints.

    Examples
    --------
    >>> import adparm
    >>> from adparm.urdf import EXAMPLE_LOCKED_JOINTS
    >>> adparm.example_robot_urdf("ur5").name
    'ur5_robot.urdf'
    >>> lock = EXAMPLE_LOCKED_JOINTS["panda"]
    >>> plant = {"urdf": "example-robot-data:panda", "locked_joints": lock}
    >>> adparm.Config.from_dict({"plant": plant}).dof
    7
    """
    root = _example_robot_data_root()
    if root is None:
        raise ModuleNotFoundError(
            "example_robot_urdf needs the example-robot-data package: pip install "
            "example-robot-data (or adparm's test extra: pip install 'adparm[test]')"
        )
    relative = EXAMPLE_ROBOTS.get(name, name)
    path = root / relative
    if not path.is_file():
        known = ", ".join(sorted(EXAMPLE_ROBOTS))
        raise ValueError(
            f"example_robot_urdf: no robot {name!r} (known names: {known}; or a path under {root})"
        )
    return path
