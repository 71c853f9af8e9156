"""How much faster is the C++ core than the same closed loop of a URDF arm written plainly in
NumPy + Pinocchio's Python bindings (bench/numpy_pinocchio_loop.py)?

Runs, in one invocation:
- the C++ bench's URDF loop cases (``adparm_bench --urdf SECONDS N...``: the planar 3-link arm of
  examples/arms and example-robot-data's UR5, the quadratic expression basis and the structured
  basis, N fixed extrapolation points; best of 3), and prints its lines;
- the NumPy + Pinocchio loop of the same planar 3-link cases (same settings, basis and N: see
  ``numpy_pinocchio_loop.bench_settings``; the structured basis with the core's base parameters)
  over --steps steps, one wall time each;
and prints one machine-readable line per basis and N:
bench=urdf_speed arm=planar_3link basis=B points=N functions=K ns_per_step_core=...
ns_per_step_numpy=... ratio=...   (ratio = NumPy ns/step / core ns/step, measured in this run)

    python bench/urdf_speed.py [--bench build/adparm_bench] [--points 0 50] [--steps 300]
        [--seconds 2]

The bench binary comes from the plain CMake build (docs, "Performance"): cmake -S . -B build &&
cmake --build build --target adparm_bench.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy_pinocchio_loop as npl  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PLANAR_3LINK = ROOT / "examples" / "arms" / "planar_3link.urdf"


def core_lines(bench: Path, seconds: float, points: list[int]) -> list[str]:
    """The bench's URDF loop lines (it exits non-zero if a run did not finish or allocated)."""
    command = [str(bench), "--urdf", repr(seconds)] + [str(p) for p in points]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return [line for line in done.stdout.splitlines() if line.startswith("bench=urdf_loop")]


def field(line: str, key: str) -> str:
    match = re.search(rf"\b{key}=(\S+)", line)
    if match is None:
        raise ValueError(f"no {key}= in {line!r}")
    return match.group(1)


def numpy_ns_per_step(basis_name: str, points: int, steps: int) -> tuple[float, int, bool]:
    """ns per RK4 step of the NumPy + Pinocchio loop on the planar 3-link case with the basis
    ("quadratic" or "structured"), the basis size, and whether the states stayed finite."""
    arm = npl.PinocchioArm(PLANAR_3LINK, [0.0, 0.0, -9.81], coulomb=0.0, viscous=0.1)
    if basis_name == "structured":
        import adparm  # the core's base parameters (the same functions in the same order)

        values, columns, _ = adparm.UrdfArm(PLANAR_3LINK).base_parameters()
        basis = npl.StructuredBasis(arm, values, columns, np.zeros(arm.dof))
    else:
        basis = npl.QuadraticBasis(arm.dof)
    loop = npl.NumpyPinocchioLoop(arm, basis, npl.bench_settings(arm, basis, points))
    start = time.perf_counter()
    states = loop.run(steps)
    seconds = time.perf_counter() - start
    return 1e9 * seconds / steps, basis.size, bool(np.isfinite(states).all())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bench", type=Path, default=ROOT / "build" / "adparm_bench")
    parser.add_argument("--points", type=int, nargs="+", default=[0, 50])
    parser.add_argument("--steps", type=int, default=300, help="NumPy steps (default 300)")
    parser.add_argument("--seconds", type=float, default=2.0, help="core horizon (default 2 s)")
    args = parser.parse_args(argv)
    if args.steps < 1:
        parser.error("--steps: must be >= 1")
    if not args.bench.is_file():
        parser.error(f"--bench: no file {args.bench} (build it: see the module docstring)")

    lines = core_lines(args.bench, args.seconds, args.points)
    for line in lines:
        print(line)
    status = 0
    for basis in ("quadratic", "structured"):
        for points in args.points:
            core = [
                line
                for line in lines
                if field(line, "arm") == "planar_3link"
                and field(line, "basis") == basis
                and int(field(line, "points")) == points
            ]
            if len(core) != 1:
                raise SystemExit(
                    f"no planar_3link {basis} line with points={points} from the bench"
                )
            ns_core = float(field(core[0], "ns_per_step"))
            ns_numpy, size, finite = numpy_ns_per_step(basis, points, args.steps)
            if size != int(field(core[0], "functions")):
                raise SystemExit("the NumPy loop's basis size differs from the bench's")
            ratio = ns_numpy / ns_core
            print(
                f"bench=urdf_speed arm=planar_3link basis={basis} points={points} "
                f"functions={size} ns_per_step_core={ns_core:.1f} "
                f"ns_per_step_numpy={ns_numpy:.1f} ratio={ratio:.1f} numpy_finite={int(finite)}"
            )
            sys.stdout.flush()
            if not finite:
                status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
