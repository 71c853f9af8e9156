"""Arms from URDF files: the model terms of eq. (1) through Pinocchio's C++ library.

``UrdfArm`` reads a URDF (a fixed-base serial arm: revolute, continuous, prismatic and fixed
joints) and computes M(q), C(q, dq), G(q), F(dq) and M(q)^-1 in adparm's C++ core, with the same
conventions as the built-in two-link arm. ``example_robot_urdf`` finds the URDFs of the
``example-robot-data`` package (UR5, Panda, ...).
"""

from __future__ import annotations

import os
import sys
import sysconfig
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _core

__all__ = ["UrdfArm", "example_robot_urdf", "EXAMPLE_ROBOTS"]

#: Names accepted by example_robot_urdf, and their files under example-robot-data's robots/.
EXAMPLE_ROBOTS: dict[str, str] = {
    "ur3": "ur_description/urdf/ur3_robot.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
}


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

    The joints q are the URDF's revolute, continuous and prismatic joints, in Pinocchio's model
    order (``joint_names``); a continuous joint's q is its angle. A URDF that cannot be read or
    parsed, that has no such joint, or that has a floating, planar or mimic joint is refused with
    a ValueError naming the file and the problem.
    """

    def __init__(
        self,
        urdf: str | os.PathLike[str],
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        coulomb: float | ArrayLike = 0.0,
        viscous: float | ArrayLike = 0.0,
    ) -> None:
        path = Path(urdf)
        if not path.is_file():
            raise ValueError(f"URDF {path}: no such file")
        self._arm = _core.UrdfArm(
            str(path),
            gravity=_vector(gravity, 3, "gravity"),
            coulomb=_as_per_joint(coulomb, "coulomb"),
            viscous=_as_per_joint(viscous, "viscous"),
        )
        self.path = path

    def __repr__(self) -> str:
        return f"UrdfArm({str(self.path)!r}, dof={self.dof}, joints={self.joint_names})"

    @property
    def dof(self) -> int:
        """Number of joints n."""
        return self._arm.dof

    @property
    def joint_names(self) -> list[str]:
        return list(self._arm.joint_names)

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
        """The URDF's joint limits: "lower", "upper" (+-inf for a continuous joint), "velocity"
        and "effort" (inf where the URDF gives none)."""
        return self._arm.limits

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

    def base_parameters(
        self, samples: int = 100, seed: int = 0, tolerance: float = 1e-9
    ) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.float64]]:
        """A minimal set of inertial parameters of the kinetic energy (base parameters).

        Returns (values, columns, combination): values (r,) = combination (r, 10 n) @
        inertial_parameters, and M(q) = sum_i values[i] * mass_regressor(q)[columns[i]] for every
        q. The M_k(q) of `samples` random poses (seeded) are stacked and reduced by a QR
        decomposition with column pivoting: r is the rank, the pivot columns are independent
        and every other column is a fixed combination of them, folded into `values`.
        """
        from scipy.linalg import qr, solve_triangular

        n, p = self.dof, 10 * self.dof
        rng = np.random.default_rng(seed)
        lower = np.maximum(self.limits["lower"], -np.pi)
        upper = np.minimum(self.limits["upper"], np.pi)
        rows = np.triu_indices(n)
        W = np.concatenate(
            [
                self.mass_regressor(rng.uniform(lower, upper))[:, rows[0], rows[1]].T
                for _ in range(samples)
            ]
        )
        _, R, pivots = qr(W, mode="economic", pivoting=True)
        diagonal = np.abs(np.diag(R))
        rank = int(np.sum(diagonal > tolerance * diagonal[0]))
        independent, dependent = pivots[:rank], pivots[rank:]
        K = solve_triangular(R[:rank, :rank], R[:rank, rank:])
        combination = np.zeros((rank, p))
        combination[:, independent] = np.eye(rank)
        combination[:, dependent] = K
        columns = np.asarray(independent, dtype=np.intp)
        return combination @ self.inertial_parameters, columns, combination


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
    example-robot-data``): one of EXAMPLE_ROBOTS ("ur5", "panda", ...), or a path relative to
    its robots/ folder (e.g. "ur_description/urdf/ur3_robot.urdf")."""
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
