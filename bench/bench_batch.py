"""Parallel batches and sweeps: adparm.simulate_batch on 1 thread against all CPUs, for --runs
paper runs (default 16, from different initial positions, 110 s each), and the same runs as an
adparm.sweep over task.q0. Checks that every batched run equals its one-thread run bit for bit
(exits 1 otherwise).

The last lines are machine-readable:
bench=batch runs=16 steps=110000 threads=1 seconds=... (and threads=N ... speedup=...)
(cpu_ratio: CPU time of all threads over that of one thread; near 1 means the threads add no
work, so on otherwise idle cores the speed-up approaches the thread count. On a loaded machine
speedup measures the load, not adparm: read it when the cores are free.)
bench=sweep runs=16 threads=N seconds=... runs_per_second=...

    python bench/bench_batch.py [--runs 16] [--seconds 110] [--threads N]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import adparm
from adparm.simulation import default_threads


def configs(runs: int, seconds: float) -> list[adparm.Config]:
    base = adparm.paper_config().updated({"sim": {"T": seconds}})
    q0 = np.array(base.task.q0)
    return [
        base.updated({"task": {"q0": (q0 + [0.01 * i, -0.005 * i]).tolist()}}) for i in range(runs)
    ]


def timed_batch(batch: list[adparm.Config], threads: int) -> tuple[float, float, list]:
    """Wall seconds, CPU seconds of all threads, results."""
    start, cpu = time.perf_counter(), time.process_time()
    results = adparm.simulate_batch(batch, threads=threads)
    return time.perf_counter() - start, time.process_time() - cpu, results


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=16, help="paper runs (default 16)")
    parser.add_argument("--seconds", type=float, default=110.0, help="simulated s per run")
    parser.add_argument("--threads", type=int, default=default_threads(), help="parallel threads")
    args = parser.parse_args(argv)

    batch = configs(args.runs, args.seconds)
    steps = round(args.seconds / batch[0].sim.dt)
    serial, serial_cpu, one = timed_batch(batch, 1)
    parallel, parallel_cpu, many = timed_batch(batch, args.threads)
    identical = all(
        np.array_equal(a.critic_weights, b.critic_weights) and np.array_equal(a.q, b.q)
        for a, b in zip(one, many, strict=True)
    )
    for threads, seconds, cpu in ((1, serial, serial_cpu), (args.threads, parallel, parallel_cpu)):
        print(
            f"bench=batch runs={args.runs} steps={steps} threads={threads} seconds={seconds:.4f} "
            f"cpu_seconds={cpu:.4f} us_per_step={1e6 * seconds / (args.runs * steps):.4f} "
            f"speedup={serial / seconds:.2f} cpu_ratio={cpu / serial_cpu:.3f} "
            f"identical={int(identical)}"
        )

    grid = {"task.q0": [c.task.q0 for c in batch]}
    start = time.perf_counter()
    table = adparm.sweep(batch[0], grid, threads=args.threads)
    seconds = time.perf_counter() - start
    print(
        f"bench=sweep runs={len(table)} threads={args.threads} seconds={seconds:.4f} "
        f"runs_per_second={len(table) / seconds:.1f}"
    )
    return 0 if identical else 1


if __name__ == "__main__":
    raise SystemExit(main())
