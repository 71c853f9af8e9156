"""The memory guard's estimate against the measured peak: each case runs in a fresh process,
which reads its peak resident set (resource.getrusage(...).ru_maxrss) after the imports (also
those the run's diagnosis makes lazily, a one-off cost of the process) and the config, then after
adparm.simulate (and, with --save, after writing result.npz and result.csv); the growth is the
run's real peak, compared with adparm.simulation.memory_needed.

The last lines are machine-readable:
bench=memory case=NAME estimate_mib=E measured_mib=M ratio=E/M

    python bench/memory_peak.py [--save]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CASES = {
    "paper_1e6_rows": {"sim": {"T": 1000.0, "record_every": 1}},
    "paper_3e5_rows": {"sim": {"T": 300.0, "record_every": 1}},
    "points_1e5": {"extrapolation": {"points": 100_000}, "sim": {"T": 0.003}},
    "points_1e6": {"extrapolation": {"points": 1_000_000}, "sim": {"T": 0.001}},
}

CHILD = """
import json, resource, sys, tempfile, pathlib
import adparm
from adparm.simulation import memory_needed
import control, scipy.optimize  # imported lazily by the run's diagnosis: a one-off cost
config = adparm.paper_config().updated(json.loads(sys.argv[1]))
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
