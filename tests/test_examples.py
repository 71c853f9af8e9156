"""The example configurations in examples/ load and do what their comments say."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import adparm

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.toml"))


def test_there_are_examples() -> None:
    assert {p.name for p in EXAMPLES} >= {"extrapolation.toml", "tracking.toml", "compare.toml"}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_and_learns_W_star(path: Path) -> None:
    config = adparm.load_config(path)
    result = adparm.simulate(config.updated({"sim": {"T": min(config.sim.T, 20.0)}}))
    assert result.status == "finished"
    if config.probe.until == 0.0:  # the extrapolation examples: W* within 1 % by t = 10 s
        target = adparm.optimal_weights(config)
        error = np.linalg.norm(result.critic_weights - target, axis=1) / np.linalg.norm(target)
        assert error[result.t >= 10.0].max() < 0.01
