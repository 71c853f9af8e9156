"""The memory guard's estimate against the measured peak: each case runs in a fresh process,
which reads its peak resident set (resource.getrusage(...).ru_maxrss) after the imports (also
those the run's diagnosis makes lazily, a one-off cost of the process) and the config, then after
adparm.simulate (and, with --save, after writing result.npz and result.csv); the growth is the
run's real peak, compared with adparm.simulation.memory_needed. The cases cover the paper's
two-link arm (fixed sizes: a long recording, many points) and the dynamic-size loop (an expression
basis, the planar 3-link URDF and the UR5 with the structured basis: about 25 KiB per point),
each short (three steps) where the points dominate.

The last lines are machine-readable:
bench=memory case=NAME estimate_mib=E measured_mib=M ratio=E/M

    python bench/memory_peak.py [--save]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
POLYNOMIAL = {"basis": "polynomial", "degree": 4}
# name: (config file or None for adparm.paper_config(), changes, steps or None to keep sim.T)
CASES = {
    "paper_1e6_rows": (None, {"sim": {"T": 1000.0, "record_every": 1}}, None),
    "paper_3e5_rows": (None, {"sim": {"T": 300.0, "record_every": 1}}, None),
    "points_1e5": (None, {"extrapolation": {"points": 100_000}}, 3),
    "points_1e6": (None, {"extrapolation": {"points": 1_000_000}}, 1),
    "polynomial4_2e4": (None, {"controller": POLYNOMIAL, "extrapolation": {"points": 20_000}}, 3),
    "polynomial4_1e5": (None, {"controller": POLYNOMIAL, "extrapolation": {"points": 100_000}}, 3),
    "planar3_structured_1e4": (
        "examples/planar_3link.toml",
        {"controller": {"basis": "structured"}, "extrapolation": {"points": 10_000}},
        3,
    ),
    "ur5_structured_5e3": (
        "examples/ur5.toml",
        {"controller": {"basis": "structured"}, "extrapolation": {"points": 5_000}},
        3,
    ),
}

CHILD = """
import json, resource, sys, tempfile, pathlib
import adparm
from adparm.simulation import memory_needed
import control, scipy.optimize  # imported lazily by the run's diagnosis: a one-off cost
file, changes, steps = json.loads(sys.argv[1])
config = adparm.load_config(file) if file else adparm.paper_config()
if steps:  # a short run at an explicit step (URDF arms default to sim.dt = "auto", T = 10 s)
    changes = {**changes, "sim": {"dt": 0.001, "T": steps * 0.001}}
config = config.updated(changes)
save = sys.argv[2] == "1"
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
result = adparm.simulate(config)
if save:
    with tempfile.TemporaryDirectory() as folder:
        result.save(pathlib.Path(folder) / "result.npz")
        result.save(pathlib.Path(folder) / "result.csv")
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"estimate": memory_needed([config]), "measured": after - before}))
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--save", action="store_true", help="also write result.npz and .csv")
    parser.add_argument("--case", action="append", choices=sorted(CASES), help="some cases")
    args = parser.parse_args(argv)
    worst = 0.0
    for name in args.case or CASES:
        out = subprocess.run(
            [sys.executable, "-c", CHILD, json.dumps(CASES[name]), "1" if args.save else "0"],
            check=True,
            capture_output=True,
            cwd=ROOT,
            text=True,
        )
        data = json.loads(out.stdout.splitlines()[-1])
        ratio = data["estimate"] / data["measured"]
        worst = max(worst, ratio, 1 / ratio)
        print(
            f"bench=memory case={name} save={int(args.save)} "
            f"estimate_mib={data['estimate'] / 2**20:.1f} "
            f"measured_mib={data['measured'] / 2**20:.1f} ratio={ratio:.2f}"
        )
    print(f"bench=memory worst_factor={worst:.2f}")
    return 0 if worst <= 1.5 else 1


if __name__ == "__main__":
    raise SystemExit(main())
