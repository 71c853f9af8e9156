"""Builds of `adparm_bench` compared on its `--urdf` cases (planar 3-link and UR5, quadratic
and structured basis, N = 0 and 50 extrapolation points), in one of three ways:

    python bench/compare_urdf.py pairs OLD_BENCH NEW_BENCH [PAIRS] [SECONDS]
        interleaved runs (old, new, then new, old, ...), each `--urdf SECONDS` (default 1): per
        case the median ns per step of each build and the median of the per-pair ratios
        old / new (above 1: the new build is faster), with the range of the ratios.
    python bench/compare_urdf.py rounds ROUNDS SECONDS BENCH [BENCH ...]
        the same for two or more builds (e.g. the issue's, main's and this one), each round running
        every build once, in a changing order (every order once in six rounds for three builds;
        interleaved()): a Markdown table of the median us per RK4 step of each build and, for
        each build before the last, the median of the per-round ratios build / last
        (docs/design.md's tables for issue 26).
    python bench/compare_urdf.py callgrind OLD_BENCH NEW_BENCH [T1] [T2]
        instruction counts under valgrind's callgrind (deterministic, unaffected by the load of
        other jobs): each build runs `--urdf T` at two horizons (default 0.02 and 0.2 s), with a
        profile dumped after each case's timed runs (time_urdf_loop) and after its
        bench=urdf_profile replay (replay_pinocchio; that dump is not counted), and
        instructions per RK4 step =
        (count at T2 - count at T1) / (3 repeats x (steps at T2 - steps at T1)).

A ratio of wall times is what a user sees; a ratio of instruction counts ignores memory stalls
and the width of the vector instructions, but not the work removed.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

LINE = re.compile(
    r"bench=urdf_loop arm=(\S+) .*basis=(\S+) .*points=(\d+) steps=(\d+) .*"
    r"ns_per_step=([\d.]+) heap_allocations=(\d+) status=(\S+)"
)


def cases(output: str) -> list[tuple[str, int, float, int, str]]:
    """(case, steps, ns per step, heap allocations, status) of each bench line."""
    return [
        (f"{m[1]}/{m[2]}/N={m[3]}", int(m[4]), float(m[5]), int(m[6]), m[7])
        for m in LINE.finditer(output)
    ]


def run(binary: str, *arguments: str) -> str:
    return subprocess.run([binary, *arguments], capture_output=True, text=True, check=True).stdout


def interleaved(binaries: list[str], count: int, seconds: str) -> list[dict[str, list[float]]]:
    """ns per step of each case, per build (in the order given), over `count` rounds. Two builds:
    a, b, then b, a, and so on; more: rounds 2j and 2j + 1 run the builds rotated by j, forwards
    then backwards (three builds: every order once in six rounds)."""
    times: list[dict[str, list[float]]] = [{} for _ in binaries]
    n = len(binaries)
    for r in range(count):
        shift = (r // 2) % n if n > 2 else 0
        order = list(range(shift, n)) + list(range(shift))
        for b in order[::-1] if r % 2 else order:
            for case, _, ns, heap, status in cases(run(binaries[b], "--urdf", seconds)):
                if heap or status != "finished":
                    raise SystemExit(f"{binaries[b]}: {case}: {heap} heap allocations, {status}")
                times[b].setdefault(case, []).append(ns)
    return times


def rounds(binaries: list[str], count: int, seconds: str) -> None:
    times = interleaved(binaries, count, seconds)
    names = list(binaries)  # as given: two builds' binaries often share their file name
    last = names[-1]
    ratios = [f"{name} / {last}" for name in names[:-1]]
    print("| case | " + " | ".join(names + ratios) + " |")
    print("|---" * (len(names) + len(ratios) + 1) + "|")
    for case, final in times[-1].items():
        medians = [f"{statistics.median(t[case]) / 1000:.1f}" for t in times]
        per_round = [
            f"{statistics.median(a / b for a, b in zip(t[case], final, strict=True)):.2f}"
            for t in times[:-1]
        ]
        print(f"| {case} | " + " | ".join(medians + per_round) + " |")


def pairs(old: str, new: str, count: int, seconds: str) -> None:
    old_times, new_times = interleaved([old, new], count, seconds)
    print(f"{'case':28s} {'old ns':>9s} {'new ns':>9s} ratio (range)")
    for case, old_ns in old_times.items():
        new_ns = new_times[case]
        ratios = [a / b for a, b in zip(old_ns, new_ns, strict=True)]
        print(
            f"{case:28s} {statistics.median(old_ns):9.0f} {statistics.median(new_ns):9.0f} "
            f"{statistics.median(ratios):5.2f} ({min(ratios):.2f}-{max(ratios):.2f})"
        )


def instructions(binary: str, seconds: str, folder: Path) -> list[tuple[str, int, int]]:
    """(case, steps, instructions of the case: its 3 runs and their set-up) at one horizon."""
    out = folder / f"cg.{Path(binary).name}.{seconds}"
    output = subprocess.run(
        ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
         "--dump-after=*time_urdf_loop*", "--dump-after=*replay_pinocchio*",
         binary, "--urdf", seconds, "0", "50"],
        capture_output=True, text=True, check=True,
        env={"OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"},
    ).stdout  # fmt: skip
    found = cases(output)
    counts = []
    for dump in sorted(folder.glob(f"{out.name}.*"), key=lambda p: int(p.suffix[1:])):
        text = dump.read_text()
        if "time_urdf_loop" in re.search(r"^desc: Trigger: (.*)$", text, re.M).group(1):
            counts.append(int(re.search(r"^(?:summary|totals): (\d+)", text, re.M).group(1)))
    return [(case, steps, count) for (case, steps, *_), count in zip(found, counts, strict=True)]


def callgrind(old: str, new: str, t1: str, t2: str) -> None:
    with tempfile.TemporaryDirectory() as folder:
        per_step = {}
        for name, binary in (("old", old), ("new", new)):
            short = instructions(binary, t1, Path(folder))
            long = instructions(binary, t2, Path(folder))
            per_step[name] = {
                a[0]: (b[2] - a[2]) / (3 * (b[1] - a[1])) for a, b in zip(short, long, strict=True)
            }
    print(f"{'case':28s} {'old':>10s} {'new':>10s} ratio   (instructions per RK4 step)")
    for case, count in per_step["old"].items():
        print(f"{case:28s} {count:10.0f} {per_step['new'][case]:10.0f} "
              f"{count / per_step['new'][case]:5.2f}")  # fmt: skip


if __name__ == "__main__":
    if len(sys.argv) < 4:
        raise SystemExit(__doc__)
    if sys.argv[1] == "rounds":
        if len(sys.argv) < 6:
            raise SystemExit(__doc__)
        rounds(sys.argv[4:], int(sys.argv[2]), sys.argv[3])
        raise SystemExit(0)
    mode, old, new, *rest = sys.argv[1:]
    if mode == "pairs":
        pairs(old, new, int(rest[0]) if rest else 7, rest[1] if len(rest) > 1 else "1")
    elif mode == "callgrind":
        callgrind(old, new, rest[0] if rest else "0.02", rest[1] if len(rest) > 1 else "0.2")
    else:
        raise SystemExit(__doc__)
