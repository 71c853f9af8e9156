"""Issue 21's targets, measured: every fixed-base arm of example-robot-data and random serial
chains of 3-7 joints, each given only ``[plant] urdf`` (the Panda: and its fingers locked), a
random cost of the exact family (so W* is known), initial critic and actor weights 20 % off W*
and ``[sim] T = 10``. Prints per arm the derived RISE gain ks, the step, the verdict, the
critic's and the policy's error at the end, the time from which critic and actor stay within 1 %
of W*, and the computing time per simulated second. Then the second target: runs on a 3-joint
arm and the UR5 from random initial positions (+-0.5 rad around the default) with random costs:
how many end within 1 %, and whether every run outside 1 % says so in its verdict (none
silent).

    python bench/every_arm.py [--arms ur3,chain4,...] [--seed 0] [--T 10] [--runs 20]
                              [--skip-table] [--skip-runs] [--from-defaults]

With --from-defaults the table's runs start from the default weights instead (a user's first
run with their own cost: docs, URDF arms, "Your own cost").

The random cost is of the exact family in the arm's own units: with D = the derived default
R^-1 (10 M_ii(qd) per joint: an optimal policy acting at about 10/s),
K = D^1/2 K~ D^1/2, alpha1 = D^-1/2 K~^-1 N~ D^1/2 (its rates those of K~^-1 N~, 1-4/s) and
R = D^-1/2 R~ D^-1/2, with K~ symmetric positive definite (eigenvalues 0.5-2), N~ + N~^T
positive definite and R~ a random fraction (0.3-0.9) of the largest R~ for which
Q = solvable_cost(K, alpha1, R) is positive semi-definite. A cost drawn without the arm's units
(tests/test_urdf_learning.py's on a 3-joint arm) asks a 0.3 kg SO-100 for a policy thousands
of times faster than the UR10's, which only a tiny step integrates.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

import adparm
from adparm.urdf import EXAMPLE_LOCKED_JOINTS

#: The fixed-base arms of example-robot-data the target names (the Panda with its fingers
#: locked) and the random chains (name: joints).
EXAMPLE_ARMS = ("ur3", "ur5", "ur10", "kinova", "z1", "xarm7", "so100", "so101", "finger_edu")
CHAINS = {f"chain{n}": n for n in range(3, 8)}
ARMS = (*EXAMPLE_ARMS, "panda", *CHAINS)
TOLERANCE = 0.01


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _rpy(rotation: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw of a rotation matrix (URDF: R = Rz(yaw) Ry(pitch) Rx(roll))."""
    pitch = float(np.arcsin(-np.clip(rotation[2, 0], -1.0, 1.0)))
    roll = float(np.arctan2(rotation[2, 1], rotation[2, 2]))
    yaw = float(np.arctan2(rotation[1, 0], rotation[0, 0]))
    return roll, pitch, yaw


def random_chain_urdf(rng: np.random.Generator, joints: int) -> str:
    """A random serial chain of revolute joints: link i a solid box of length 0.15-0.5 m along
    its frame's x, width 0.03-0.08 m, mass 0.3-3 kg (its inertia that of the box about its centre
    of mass, rotated by a random rotation: physical, the triangle inequality holds), its centre
    of mass at 40-60 % of its length; the next joint at its end, turned by a random rotation, and
    each joint's axis a random unit vector; limits +-pi, no effort limit."""
    lines = ['<?xml version="1.0"?>', f'<robot name="chain{joints}">', '  <link name="base"/>']
    parent = "base"
    origin = np.zeros(3)
    for i in range(joints):
        length = rng.uniform(0.15, 0.5)
        width = rng.uniform(0.03, 0.08)
        mass = rng.uniform(0.3, 3.0)
        principal = (
            mass / 12.0 * np.array([2 * width**2, length**2 + width**2, length**2 + width**2])
        )
        rotation = _rotation(rng)
        inertia = rotation @ np.diag(principal) @ rotation.T
        com = rng.uniform(0.4, 0.6) * length
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        roll, pitch, yaw = _rpy(_rotation(rng)) if i else (0.0, 0.0, 0.0)
        link = f"link{i + 1}"
        lines += [
            f'  <joint name="joint{i + 1}" type="revolute">',
            f'    <parent link="{parent}"/><child link="{link}"/>',
            f'    <origin xyz="{origin[0]:.6f} {origin[1]:.6f} {origin[2]:.6f}" '
            f'rpy="{roll:.6f} {pitch:.6f} {yaw:.6f}"/>',
            f'    <axis xyz="{axis[0]:.6f} {axis[1]:.6f} {axis[2]:.6f}"/>',
            '    <limit lower="-3.14159" upper="3.14159" effort="0" velocity="10"/>',
            "  </joint>",
            f'  <link name="{link}">',
            "    <inertial>",
            f'      <origin xyz="{com:.6f} 0 0" rpy="0 0 0"/>',
            f'      <mass value="{mass:.6f}"/>',
            f'      <inertia ixx="{inertia[0, 0]:.9f}" ixy="{inertia[0, 1]:.9f}" '
            f'ixz="{inertia[0, 2]:.9f}" iyy="{inertia[1, 1]:.9f}" iyz="{inertia[1, 2]:.9f}" '
            f'izz="{inertia[2, 2]:.9f}"/>',
            "    </inertial>",
            "  </link>",
        ]
        parent, origin = link, np.array([length, 0.0, 0.0])
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def arm_plant(name: str, folder: Path, seed: int = 0) -> dict[str, Any]:
    """The [plant] section of an arm of ARMS: its URDF (a chain's written into folder, drawn
    with the seed) and, for the Panda, its locked fingers."""
    if name in CHAINS:
        path = folder / f"{name}_seed{seed}.urdf"
        rng = np.random.default_rng([seed, CHAINS[name]])
        text = random_chain_urdf(rng, CHAINS[name])
        if not path.exists() or path.read_text() != text:  # another process may be reading it
            partial = path.with_suffix(f".{os.getpid()}.part")
            partial.write_text(text)
            os.replace(partial, path)  # atomic: a reader sees the old or the new file, whole
        return {"urdf": str(path)}
    plant: dict[str, Any] = {"urdf": f"example-robot-data:{name}"}
    if name in EXAMPLE_LOCKED_JOINTS:
        plant["locked_joints"] = dict(EXAMPLE_LOCKED_JOINTS[name])
    return plant


def random_exact_cost(rng: np.random.Generator, default_R: np.ndarray) -> dict[str, np.ndarray]:
    """A random cost of the exact family in the units of an arm's derived R (module docstring):
    K, alpha1, R and Q = solvable_cost(K, alpha1, R), Q positive semi-definite."""
    n = default_R.shape[0]
    scale = np.diag(np.sqrt(1.0 / np.diag(default_R)))  # D^1/2
    unscale = np.linalg.inv(scale)
    basis, _ = np.linalg.qr(rng.normal(size=(n, n)))
    K_unit = basis @ np.diag(rng.uniform(0.5, 2.0, n)) @ basis.T
    B = rng.normal(size=(n, n))
    N_unit = K_unit @ (np.diag(rng.uniform(1.0, 4.0, n)) + 0.3 * (B - B.T) / np.sqrt(n))
    Q11_unit = N_unit + N_unit.T
    if np.linalg.eigvalsh(Q11_unit).min() <= 0.0:  # keep N~ + N~^T positive definite
        N_unit += (0.1 - np.linalg.eigvalsh(Q11_unit).min()) * np.eye(n)
        Q11_unit = N_unit + N_unit.T
    # R~^-1 >= K~ Q11~^-1 K~ keeps Q positive semi-definite (its Schur complement)
    limit = np.linalg.inv(K_unit @ np.linalg.solve(Q11_unit, K_unit))
    limit = 0.5 * (limit + limit.T)
    R_unit = np.diag(rng.uniform(0.3, 0.9, n) * np.diag(limit))
    # a diagonal R~ below the limit in the Loewner order: shrink until it is
    while np.linalg.eigvalsh(limit - R_unit).min() < 0.0:
        R_unit *= 0.8
    K = scale @ K_unit @ scale
    alpha1 = np.linalg.solve(K, scale @ N_unit @ scale)
    R = unscale @ R_unit @ unscale
    K, R = 0.5 * (K + K.T), 0.5 * (R + R.T)
    Q = adparm.solvable_cost(K, alpha1, R)
    assert np.linalg.eigvalsh(0.5 * (Q + Q.T)).min() >= -1e-9 * np.abs(Q).max()
    return {"K": K, "alpha1": alpha1, "R": R, "Q": Q}


def off_by(rng: np.random.Generator, weights: np.ndarray, fraction: float) -> np.ndarray:
    """weights with each entry multiplied by 1 +- fraction (random signs): ||W - W*|| / ||W*||
    is exactly the fraction."""
    return weights * (1.0 + fraction * rng.choice([-1.0, 1.0], weights.size))


def target_config(
    plant: dict[str, Any],
    rng: np.random.Generator,
    *,
    T: float = 10.0,
    q0_spread: float = 0.0,
    off: float | None = 0.2,
) -> adparm.Config:
    """The target's run: the plant only, a random exact cost, critic and actor weights each
    ``off`` from W* (drawn apart; None: the default weights, a user's first run with their own
    cost) and sim.T; with q0_spread > 0, q0 = the default q0 + uniform (-spread, spread) per
    joint, clipped into the joint limits."""
    base = adparm.Config.from_dict({"plant": plant})
    cost = random_exact_cost(rng, np.array(base.cost.R))
    data: dict[str, Any] = {
        "plant": plant,
        "cost": {"Q": cost["Q"].tolist(), "R": cost["R"].tolist()},
        "control": {"alpha1": cost["alpha1"].tolist()},
        "sim": {"T": T},
    }
    if q0_spread > 0.0:
        limits = adparm.urdf.config_arm(base).limits
        q0 = np.asarray(base.task.q0) + rng.uniform(-q0_spread, q0_spread, base.dof)
        low = np.nan_to_num(np.asarray(limits["lower"], dtype=float), nan=-np.inf)
        high = np.nan_to_num(np.asarray(limits["upper"], dtype=float), nan=np.inf)
        data["task"] = {"q0": np.clip(q0, low, high).tolist()}
    if off is None:
        return adparm.Config.from_dict(data)
    W = adparm.optimal_weights(adparm.Config.from_dict(data))
    data["init"] = {
        "critic_weights": off_by(rng, W, off).tolist(),
        "actor_weights": off_by(rng, W, off).tolist(),
    }
    return adparm.Config.from_dict(data)


def time_within(result: adparm.SimulationResult, tolerance: float = TOLERANCE) -> float | None:
    """The time from which the critic's and the actor's ||W - W*|| / ||W*|| both stay below the
    tolerance (None: not at the end)."""
    W = adparm.optimal_weights(result.config)
    error = np.maximum(
        np.linalg.norm(result.critic_weights - W, axis=1),
        np.linalg.norm(result.actor_weights - W, axis=1),
    ) / np.linalg.norm(W)
    if error[-1] >= tolerance:
        return None
    outside = np.nonzero(error >= tolerance)[0]
    return float(result.t[outside[-1] + 1]) if outside.size else 0.0


def measure(config: adparm.Config) -> dict[str, Any]:
    """Runs a config and returns the row of the table (the refusal or divergence as verdict)."""
    row: dict[str, Any] = {
        "joints": config.dof,
        "dt": config.sim.dt,
        "T": config.sim.T,
        "ks": config.control.ks,
    }
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", adparm.ApproximationWarning)
            result = adparm.simulate(config, diagnose=False)
    except adparm.SimulationDiverged as error:
        row.update(verdict=f"diverged: {error}", status="diverged")
        return row
    except ValueError as error:
        row.update(verdict=f"refused: {error}", status="refused")
        return row
    row["compute_per_second"] = result.wall_time / config.sim.T
    row["status"] = result.status
    diagnostics = result.diagnostics
    row["wall"] = time.perf_counter() - start
    row["verdict"] = diagnostics["verdict"]
    row["critic"] = diagnostics.get("critic_relative_error")
    row["actor"] = diagnostics.get("actor_relative_error")
    row["policy"] = diagnostics.get("policy_relative_error")
    row["within"] = time_within(result)
    row["ok"] = (
        row["verdict"] == "ok"
        and max(row["critic"], row["actor"], row["policy"]) < TOLERANCE
        and result.status == "finished"
    )
    return row


def _number(value: float | None, form: str = ".2g") -> str:
    return "-" if value is None else format(value, form)


def table(
    names: list[str], folder: Path, seed: int, T: float, off: float | None = 0.2
) -> list[dict[str, Any]]:
    print(
        "| arm | joints | ks | dt (s) | verdict | critic error | policy error | "
        "within 1 % from (s) | compute per simulated s (s) |",
        flush=True,
    )
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for name in names:
        rng = np.random.default_rng([seed, ARMS.index(name)])  # the row's cost: not the order
        row = measure(target_config(arm_plant(name, folder, seed), rng, T=T, off=off))
        rows.append(row)
        verdict = row["verdict"] if len(row["verdict"]) < 300 else row["verdict"][:300] + " ..."
        print(
            f"| {name} | {row['joints']} | {row['ks']:.3g} | {row['dt']:.2g} | {verdict} | "
            f"{_number(row.get('critic'))} | {_number(row.get('policy'))} | "
            f"{_number(row.get('within'), '.2f')} | {_number(row.get('compute_per_second'))} |",
            flush=True,
        )
    return rows


def repeated(name: str, folder: Path, runs: int, seed: int, T: float) -> dict[str, Any]:
    within, silent, failed = 0, 0, []
    for run in range(runs):
        rng = np.random.default_rng([seed, 1000 + run])
        row = measure(target_config(arm_plant(name, folder, seed), rng, T=T, q0_spread=0.5))
        worst = max(row.get(key) or np.inf for key in ("critic", "actor", "policy"))
        if row.get("ok"):
            within += 1
        else:
            failed.append((run, row["verdict"][:200], worst))
            if row["verdict"] == "ok":
                silent += 1
    print(f"{name}: {within}/{runs} within 1 %, {silent} outside 1 % with verdict ok", flush=True)
    for run, verdict, worst in failed:
        print(f"  run {run}: worst error {worst:.3g}: {verdict}", flush=True)
    return {"within": within, "runs": runs, "silent": silent}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", default=",".join(ARMS))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--T", type=float, default=10.0)
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--repeat-arms", default="chain3,ur5")
    parser.add_argument("--skip-table", action="store_true")
    parser.add_argument("--skip-runs", action="store_true")
    parser.add_argument(
        "--from-defaults",
        action="store_true",
        help="the table's runs start from the default weights (a first run with one's own cost)",
    )
    parser.add_argument("--folder", default="/tmp/adparm-every-arm")
    args = parser.parse_args()
    folder = Path(args.folder)
    folder.mkdir(parents=True, exist_ok=True)
    if not args.skip_table:
        table(args.arms.split(","), folder, args.seed, args.T, None if args.from_defaults else 0.2)
    if not args.skip_runs:
        for name in args.repeat_arms.split(","):
            repeated(name, folder, args.runs, args.seed, args.T)


if __name__ == "__main__":
    main()
