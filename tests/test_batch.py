"""adparm.simulate_batch: parallel C++ threads give bit-for-bit the results of one-by-one runs."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import adparm

from conftest import assert_same_arrays

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

DIVERGING = {"init": {"critic_weights": [0.0] * 8, "actor_weights": [0.0] * 8}}


def assert_same_run(a: adparm.SimulationResult, b: adparm.SimulationResult) -> None:
    assert a.status == b.status
    assert_same_arrays(a, b)


@pytest.fixture(scope="module")
def configs() -> list[adparm.Config]:
    """Varied short runs: initial states, gains, a sinusoid to track with extrapolation points,
    a baseline controller, and different lengths."""
    base = adparm.paper_config().updated({"sim": {"T": 1.5}})
    return [
        base,
        base.updated({"task": {"q0": [0.5, -0.3]}, "critic": {"eta_c": 200.0}}),
        base.updated(
            {
                "task": {"qd": {"kind": "sinusoid", "amplitude": [0.2, 0.1], "frequency": [1, 2]}},
                "extrapolation": {"points": 5, "mode": "local", "seed": 3},
                "sim": {"T": 0.7},
            }
        ),
        base.updated({"controller": {"kind": "pd"}, "sim": {"T": 2.0}}),
        base.updated({"probe": {"amplitude": [30.0, 10.0]}, "sim": {"record_every": 7}}),
    ]


@pytest.fixture(scope="module")
def one_by_one(configs) -> list[adparm.SimulationResult]:
    return [adparm.simulate(config) for config in configs]


@pytest.mark.parametrize("threads", [1, 2, 3, 8])
def test_batch_equals_one_by_one_runs(configs, one_by_one, threads) -> None:
    results = adparm.simulate_batch(configs, threads=threads)
    assert len(results) == len(configs)
    for config, alone, batched in zip(configs, one_by_one, results, strict=True):
        assert batched.config is config
        assert_same_run(alone, batched)
        assert batched.wall_time > 0.0


def test_batch_polled_often_equals_one_by_one_runs(configs, one_by_one, monkeypatch) -> None:
    """Runs of different lengths, polled by Python every 0.1 ms while the workers run."""
    monkeypatch.setattr(adparm.simulation, "POLL_SECONDS", 1e-4)
    results = adparm.simulate_batch(configs, threads=2, progress=True)
    for alone, batched in zip(one_by_one, results, strict=True):
        assert_same_run(alone, batched)


def test_batch_is_deterministic_and_takes_any_iterable(configs) -> None:
    first = adparm.simulate_batch(iter(configs), threads=2)
    second = adparm.simulate_batch(tuple(configs), threads=2)
    for a, b in zip(first, second, strict=True):
        assert_same_run(a, b)


def test_batch_of_copies_is_identical_run_for_run() -> None:
    config = adparm.paper_config().updated({"sim": {"T": 1.0}})
    results = adparm.simulate_batch([config] * 6, threads=2)
    for result in results[1:]:
        assert_same_run(results[0], result)


def test_empty_batch_and_default_threads() -> None:
    assert adparm.simulate_batch([]) == []
    assert adparm.simulation.default_threads() >= 1


def test_more_threads_than_runs_or_than_a_c_int() -> None:
    config = adparm.paper_config().updated({"sim": {"T": 0.2}})
    results = adparm.simulate_batch([config, config], threads=2**40)
    assert_same_run(results[0], results[1])


def test_diverged_run_raises_after_the_others_finish(configs) -> None:
    bad = configs[0].updated(DIVERGING)
    with pytest.raises(adparm.SimulationDiverged, match=r"configs\[1\]: simulation diverged") as e:
        adparm.simulate_batch([configs[0], bad, configs[1]], threads=2)
    error = e.value
    assert error.index == 1 and error.time < 0.1
    assert [r.status for r in error.results] == ["finished", "diverged", "finished"]
    assert error.result is error.results[1]
    with pytest.raises(adparm.SimulationDiverged) as alone:
        adparm.simulate(bad)
    assert_same_run(alone.value.result, error.result)
    assert alone.value.time == error.time


def test_keep_returns_diverged_runs_as_results(configs) -> None:
    bad = configs[0].updated(DIVERGING)
    results = adparm.simulate_batch([bad, configs[0]], threads=2, on_divergence="keep")
    assert [r.status for r in results] == ["diverged", "finished"]
    assert np.all(np.isfinite(results[0].critic_weights))


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"threads": 0}, ValueError, "threads: expected an integer >= 1"),
        ({"threads": 1.5}, TypeError, "threads: expected an integer"),
        ({"threads": True}, TypeError, "threads: expected an integer"),
        ({"on_divergence": "ignore"}, ValueError, "on_divergence: expected 'raise' or 'keep'"),
    ],
)
def test_bad_arguments_are_refused(configs, kwargs, error, match) -> None:
    with pytest.raises(error, match=match):
        adparm.simulate_batch(configs[:1], **kwargs)


def test_bad_configs_are_refused() -> None:
    config = adparm.paper_config()
    with pytest.raises(TypeError, match="got one Config"):
        adparm.simulate_batch(config)
    with pytest.raises(TypeError, match=r"configs\[1\]: expected adparm.Config, got dict"):
        adparm.simulate_batch([config, {"sim": {"T": 1.0}}])


def test_core_batch_names_the_failing_settings() -> None:
    settings = adparm.simulation.core_settings(adparm.paper_config())
    broken = adparm.simulation.core_settings(adparm.paper_config())
    sim = broken.sim
    sim.dt = -1.0
    broken.sim = sim
    with pytest.raises(ValueError, match=r"settings\[1\]: sim.dt"):
        adparm._core.Batch([settings, broken])
    with pytest.raises(ValueError, match="threads: must be >= 1"):
        adparm._core.Batch([settings]).start(0)


def test_core_batch_streams_runs_through_a_window(configs, one_by_one) -> None:
    """Workers build at most `window` runs not yet taken; each run handed over equals its
    one-by-one run, and a stopped batch hands over the part-way and the unstarted runs."""
    settings = [adparm.simulation.core_settings(c) for c in configs]
    batch = adparm._core.Batch(settings, 1)
    assert batch.total_steps == sum(round(c.sim.T / c.sim.dt) for c in configs)
    batch.start(2)
    ended: list[int] = []
    while not batch.done:
        for i in batch.wait(0.05):
            ended.append(i)
            run = batch.take(i)
            result = adparm.simulation.make_result(run, configs[i], batch.seconds(i))
            assert_same_run(one_by_one[i], result)
    assert sorted(ended) == list(range(len(configs)))
    assert batch.steps_done == batch.total_steps
    with pytest.raises(RuntimeError, match="already taken"):
        batch.take(0)
    stopped = adparm._core.Batch(settings, 1)
    stopped.start(1)
    stopped.stop()
    runs = dict(adparm.simulation._take_rest(stopped))
    assert sorted(runs) == list(range(len(configs)))
    assert all(run.status in ("running", "finished") for run in runs.values())


@settings(max_examples=25, deadline=None)
@given(
    runs=st.integers(1, 6),
    threads=st.integers(1, 4),
    window=st.integers(1, 5),
    stop_after=st.sampled_from([None, 0.0, 0.002, 0.01]),
)
def test_any_threads_window_and_stop_give_one_by_one_numbers(runs, threads, window, stop_after):
    """The engine under any thread count, window and stop time: every run handed over, ended
    or not, continues to exactly the numbers of a one-by-one run."""
    base = adparm.paper_config().updated({"sim": {"T": 0.3}})
    configs = [base.updated({"task": {"q0": [0.1 + 0.05 * i, 0.2]}}) for i in range(runs)]
    settings_list = [adparm.simulation.core_settings(c) for c in configs]
    batch = adparm._core.Batch(settings_list, window)
    batch.start(threads)
    taken = {}
    if stop_after is not None:
        time.sleep(stop_after)
        batch.stop()
        taken.update(adparm.simulation._take_rest(batch))
    else:
        while not batch.done:
            for i in batch.wait(0.01):
                taken[i] = batch.take(i)
    assert sorted(taken) == list(range(runs))
    for i, run in taken.items():
        run.advance(run.steps)  # a part-way or unstarted run continues to its end
        alone = adparm._core.Simulation(settings_list[i])
        alone.advance(alone.steps)
        assert run.status == alone.status == "finished"
        for name, values in alone.recording().items():
            np.testing.assert_array_equal(run.recording()[name], values, err_msg=name)
