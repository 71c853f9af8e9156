"""How many extrapolation points does the critic need? Runs the paper's instance and a second
instance with a known W* (other K, alpha1, R and arm; Q from the ERRATA conditions) without
probing, for several point counts and modes and seeds, and prints the critic's relative error at
t = 10 s, the time from which it stays within 1 % (over the runs that got there), the runs that
diverged, and the median number of covariance resets.

    python bench/extrapolation_study.py [--seeds 5] [--epsilon-T 1e-3]
"""

from __future__ import annotations

import argparse

import numpy as np

import adparm


def instances() -> dict[str, adparm.Config]:
    K = [[2.0, 0.5], [0.5, 1.0]]
    alpha1 = [[5.0, 1.0], [1.0, 3.0]]
    R = [[0.5, 0.0], [0.0, 0.5]]
    other = adparm.paper_config().updated(
        {
            "cost": {"Q": adparm.solvable_cost(K, alpha1, R), "R": R},
            "control": {"alpha1": alpha1},
            "plant": {"p1": 3.0, "p2": 0.8, "p3": 0.5},
            "task": {"q0": [-0.4, 0.6]},
        }
    )
    return {"paper": adparm.paper_config(), "other": other}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--epsilon-T", type=float, default=None, help="default: the config's")
    args = parser.parse_args()
    cases = [(5, "fixed"), (10, "fixed"), (16, "grid"), (50, "fixed"), (5, "local"), (10, "local")]
    print(
        "| instance | points | mode | error at 10 s (median, max) | within 1 % from (max) | "
        "diverged | resets |",
        flush=True,
    )
    print("|---|---|---|---|---|---|---|")
    for name, base in instances().items():
        target = adparm.optimal_weights(base)
        for points, mode in cases:
            errors, since, resets, diverged = [], [], [], 0
            for seed in range(args.seeds if mode != "grid" else 1):
                config = base.updated(
                    {
                        "probe": {"until": 0.0},
                        "sim": {"T": 10.0},
                        "extrapolation": {"points": points, "mode": mode, "seed": seed},
                    }
                )
                if args.epsilon_T is not None:
                    config = config.updated({"critic": {"epsilon_T": args.epsilon_T}})
                try:
                    result = adparm.simulate(config)
                except adparm.SimulationDiverged:
                    diverged += 1
                    continue
                error = np.linalg.norm(result.critic_weights - target, axis=1)
                error /= np.linalg.norm(target)
                errors.append(error[-1])
                outside = np.nonzero(error >= 0.01)[0]
                if error[-1] < 0.01:
                    since.append(result.t[outside[-1] + 1] if outside.size else 0.0)
                resets.append(result.covariance_resets)
            runs = len(errors) + diverged
            errors = errors or [np.nan]
            reached = f"{max(since):.1f} s ({len(since)}/{runs})" if since else f"never (0/{runs})"
            print(
                f"| {name} | {points} | {mode} | {np.median(errors):.1e}, {max(errors):.1e} | "
                f"{reached} | "
                f"{diverged}/{runs} | {int(np.median(resets)) if resets else '-'} |"
            )


if __name__ == "__main__":
    main()
