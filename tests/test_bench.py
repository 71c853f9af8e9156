"""bench/numpy_loop.py, the plain NumPy loop that bench/bench_python.py times against the core,
computes the same closed loop as adparm.simulate (no timing here)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import adparm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import numpy_loop  # noqa: E402

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

STEPS = 300


def assert_matches_core(config: adparm.Config, steps: int = STEPS) -> None:
    states = numpy_loop.NumpyPaperLoop(config).run(steps)
    index, pairs = numpy_loop.recorded_pairs(config, states)
    assert index[-1] == steps
    np.testing.assert_array_equal(index[:-1] % config.sim.record_every, 0)
    for name, (ours, core) in pairs.items():
        assert np.allclose(ours, core, rtol=1e-10, atol=1e-9), (
            f"{name}: max |difference| {np.abs(ours - core).max():.3e}"
        )


def test_paper_config_matches_core() -> None:
    config = adparm.paper_config()
    assert config.sim.record_every == 10
    assert_matches_core(config)


@pytest.mark.parametrize(
    "changes",
    [
        {"task": {"qd": [0.3, -0.2]}},
        {"critic": {"eta_c": 200.0}, "controller": {"rise": False}},
        {
            "controller": {"basis": "paper"},
            "model": {"p1": 4.5, "viscous": 0.2},
            "probe": {"ramp": 0.1},
            "sim": {"record_every": 7},
        },
    ],
    ids=["set-point", "eta_c-no-rise", "paper-basis-model-error"],
)
def test_variations_match_core(changes: dict) -> None:
    assert_matches_core(adparm.paper_config().updated(changes))


def test_covariance_reset_happens_within_the_compared_steps() -> None:
    config = adparm.paper_config().updated({"sim": {"T": STEPS * 1e-3}})
    assert adparm.simulate(config).covariance_resets > 0


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"controller": {"kind": "pd"}}, "controller.kind"),
        ({"extrapolation": {"points": 4}}, "extrapolation.points"),
        ({"task": {"qd": {"kind": "sinusoid"}}}, "task.qd"),
    ],
)
def test_out_of_scope_config_is_refused(changes: dict, field: str) -> None:
    with pytest.raises(ValueError, match=re.escape(field)):
        numpy_loop.NumpyPaperLoop(adparm.paper_config().updated(changes))
