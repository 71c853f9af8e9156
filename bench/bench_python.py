"""How much faster is adparm.simulate (the C++ core) than the same closed loop written plainly in
NumPy (bench/numpy_loop.py)? Both run the paper's instance (adparm.paper_config()).

- core: adparm.simulate over --seconds of simulated time (default 110 s), best of 3 wall times;
- NumPy: NumpyPaperLoop.run over --steps steps (default 2000), one wall time;
- equal results: the NumPy states against adparm.simulate of the same --steps horizon, at the
  core's recorded rows (every sim.record_every-th step and the last), as the largest difference
  of q, dq, Wc, Wa and cost, each relative to that array's largest magnitude; exits 1 above 1e-9.

The last line is machine-readable:
bench=python_vs_numpy steps_core=... us_per_step_core=... us_per_step_numpy=... ratio=...
max_relative_difference=..., ratio = NumPy us/step / core us/step measured in this run.

    python bench/bench_python.py [--steps 2000] [--seconds 110]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy_loop  # noqa: E402

import adparm  # noqa: E402

TOLERANCE = 1e-9
CORE_REPEATS = 3


def time_core(config: adparm.Config) -> tuple[float, int]:
    """Best wall time (s) of adparm.simulate(config) over CORE_REPEATS runs, and its steps."""
    best = float("inf")
    for _ in range(CORE_REPEATS):
        start = time.perf_counter()
        adparm.simulate(config)
        best = min(best, time.perf_counter() - start)
    return best, round(config.sim.T / config.sim.dt)


def max_relative_difference(
    config: adparm.Config, states: np.ndarray
) -> tuple[float, dict[str, float]]:
    """Largest difference between the NumPy states (steps + 1, 87) and adparm.simulate over the
    same horizon at the core's recorded rows, per array relative to its largest magnitude."""
    differences = {}
    for name, (ours, core) in numpy_loop.recorded_pairs(config, states)[1].items():
        scale = max(float(np.abs(core).max()), np.finfo(float).tiny)
        differences[name] = float(np.abs(ours - core).max()) / scale
    return max(differences.values()), differences


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000, help="NumPy steps (default 2000)")
    parser.add_argument(
        "--seconds", type=float, default=110.0, help="core horizon in s (default 110)"
    )
    args = parser.parse_args(argv)
    if args.steps < 1:
        parser.error("--steps: must be >= 1")
    if args.seconds <= 0.0:
        parser.error("--seconds: must be > 0")

    config = adparm.paper_config()
    core_seconds, core_steps = time_core(config.updated({"sim": {"T": args.seconds}}))
    us_core = core_seconds / core_steps * 1e6
    print(
        f"core:  {core_steps} steps in {core_seconds:.4f} s (best of {CORE_REPEATS}), "
        f"{us_core:.3f} us/step"
    )

    loop = numpy_loop.NumpyPaperLoop(config)
    start = time.perf_counter()
    states = loop.run(args.steps)
    numpy_seconds = time.perf_counter() - start
    us_numpy = numpy_seconds / args.steps * 1e6
    print(f"numpy: {args.steps} steps in {numpy_seconds:.4f} s, {us_numpy:.1f} us/step")

    difference, per_array = max_relative_difference(config, states)
    print("max relative difference: " + ", ".join(f"{k} {v:.2e}" for k, v in per_array.items()))
    ratio = us_numpy / us_core
    print(f"numpy / core: {ratio:.0f}x")
    print(
        f"bench=python_vs_numpy steps_core={core_steps} us_per_step_core={us_core:.4f} "
        f"us_per_step_numpy={us_numpy:.2f} ratio={ratio:.1f} "
        f"max_relative_difference={difference:.3e}"
    )
    if not difference <= TOLERANCE:
        print(f"FAIL: max relative difference {difference:.3e} > {TOLERANCE:g}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
