"""The example configurations in examples/ load and do what their comments say."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import adparm

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.toml"))


def test_there_are_examples() -> None:
    assert {p.name for p in EXAMPLES} >= {
        "extrapolation.toml",
        "tracking.toml",
        "compare.toml",
        "planar_3link.toml",
        "ur5.toml",
    }


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_and_learns_W_star(path: Path) -> None:
    config = adparm.load_config(path)
    changed = config.updated({"sim": {"T": min(config.sim.T, 20.0)}})
    if config.plant.urdf is not None and config.controller.is_expression:
        # an expression basis on a URDF arm: no known W*, said honestly
        with pytest.warns(adparm.ApproximationWarning, match="the optimum is not known"):
            result = adparm.simulate(changed)
        assert result.status == "finished"
        error = np.abs(result.q - np.array(config.task.qd)).max(axis=1)
        assert error[0] > 0.1 and error[result.t >= 10.0].max() < 1e-3  # at the set-point
        return
    result = adparm.simulate(changed)
    assert result.status == "finished"
    if config.probe.until == 0.0:  # extrapolation examples: W* within 1 % by 10 s (or T / 2)
        target = adparm.optimal_weights(config)
        error = np.linalg.norm(result.critic_weights - target, axis=1) / np.linalg.norm(target)
        assert error[result.t >= min(10.0, 0.5 * result.t[-1])].max() < 0.01
