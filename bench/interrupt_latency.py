"""Ctrl-C latency: the time from the interrupt to adparm.SimulationInterrupted, for a run whose
steps are cheap (the paper's loop) and for costly steps (100,000 extrapolation points, about
20 ms a step), and for a 16-run batch on 2 threads. The core reads its stop flag before every
step, so the latency is at most one step plus Python's poll interval (POLL_SECONDS) and the copy
of the rows recorded so far.

The last lines are machine-readable:
bench=interrupt case=NAME after_s=A latency_s=L rows=R

    python bench/interrupt_latency.py [--repeats 3]
"""

from __future__ import annotations

import _thread
import argparse
import threading
import time

import adparm

CASES = {
    "paper": (adparm.paper_config().updated({"sim": {"T": 20_000.0}}), 1),
    "points_1e5": (
        adparm.paper_config().updated({"extrapolation": {"points": 100_000}, "sim": {"T": 100.0}}),
        1,
    ),
    "batch_16x2": (adparm.paper_config().updated({"sim": {"T": 20_000.0}}), 16),
}


def latency(config: adparm.Config, runs: int, after: float) -> tuple[float, int]:
    sent = {}

    def interrupt() -> None:
        sent["at"] = time.perf_counter()
        _thread.interrupt_main()

    timer = threading.Timer(after, interrupt)
    timer.start()
    try:
        if runs == 1:
            adparm.simulate(config)
        else:
            adparm.simulate_batch([config] * runs, threads=2)
    except adparm.SimulationInterrupted as stop:
        elapsed = time.perf_counter() - sent["at"]
        result = stop.result
        rows = result.t.size if runs == 1 else sum(r.t.size for r in result)
        return elapsed, rows
    finally:
        timer.cancel()
    raise RuntimeError("the run ended before the interrupt")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--after", type=float, default=1.0, help="seconds before Ctrl-C")
    args = parser.parse_args(argv)
    worst = 0.0
    for name, (config, runs) in CASES.items():
        for _ in range(args.repeats):
            seconds, rows = latency(config, runs, args.after)
            worst = max(worst, seconds) if name == "points_1e5" else worst
            print(
                f"bench=interrupt case={name} after_s={args.after} latency_s={seconds:.3f} "
                f"rows={rows}"
            )
    return 0 if worst <= 0.5 else 1


if __name__ == "__main__":
    raise SystemExit(main())
