"""How robust is the default probing design? Re-runs the paper's instance to t = 110 s with random
probe phases, probe amplitude scaled by 0.8-1.2 and q(0) moved by up to +-0.3 rad, and counts
the runs whose critic ends within 2 % of W*.

    python bench/probe_robustness.py [--runs 60] [--seed 2024] [--epsilon-T 1e-6]
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import adparm


def perturbed(base: adparm.Config, rng: np.random.Generator) -> adparm.Config:
    n = len(base.probe.frequencies)
    phases = rng.uniform(0.0, 2.0 * np.pi, n)
    return base.updated(
        {
            "probe": {
                "amplitude": (base.probe.amplitude_matrix() * rng.uniform(0.8, 1.2)).tolist(),
                "phases": [phases.tolist(), phases.tolist()],  # keep each sinusoid's direction
            },
            "task": {"q0": (np.array(base.task.q0) + rng.uniform(-0.3, 0.3, 2)).tolist()},
        }
    )


def error_at_end(config: adparm.Config) -> float:
    try:
        result = adparm.simulate(config)
    except adparm.SimulationDiverged:
        return float("inf")
    target = adparm.optimal_weights(config)
    return float(np.linalg.norm(result.critic_weights[-1] - target) / np.linalg.norm(target))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=60)
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--epsilon-T", type=float, default=None)
    args = parser.parse_args()
    base = adparm.paper_config().updated({"sim": {"T": 110.0, "record_every": 100}})
    if args.epsilon_T is not None:
        base = base.updated({"critic": {"epsilon_T": args.epsilon_T}})
    rng = np.random.default_rng(args.seed)
    configs = [base] + [perturbed(base, rng) for _ in range(args.runs - 1)]
    with ProcessPoolExecutor() as pool:
        errors = np.array(list(pool.map(error_at_end, configs)))
    ok = errors < 0.02
    print(
        f"epsilon_T={base.critic.epsilon_T:g} runs={errors.size} within_2pct={ok.sum()} "
        f"default_error={errors[0]:.3g} median_error={np.median(errors):.3g} "
        f"failures={np.round(errors[~ok], 3).tolist()}"
    )


if __name__ == "__main__":
    main()
