"""The paper preset end to end: it runs, stays bounded, regulates, and is reproducible."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import adparm

from conftest import assert_same_arrays
from numpy_reference import arm_terms, plant_parameters

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


@pytest.fixture(scope="module")
def paper_result() -> adparm.SimulationResult:
    return adparm.simulate(adparm.paper_config())


def test_paper_preset_runs_and_records(paper_result) -> None:
    r = paper_result
    c = r.config
    rows = round(c.sim.T / c.sim.dt) // c.sim.record_every + 1
    assert r.status == "finished"
    assert r.t.shape == (rows,) and r.q.shape == (rows, 2) and r.critic_weights.shape == (rows, 8)
    np.testing.assert_allclose(np.diff(r.t), c.sim.dt * c.sim.record_every, rtol=1e-9)
    assert r.t[-1] == pytest.approx(c.sim.T)
    np.testing.assert_array_equal(r.q[0], c.task.q0)
    np.testing.assert_array_equal(r.critic_weights[0], c.initial_weights())
    for name in ("t", "q", "dq", "e1", "e2", "tau", "critic_weights", "actor_weights", "hjb_error"):
        assert np.all(np.isfinite(getattr(r, name))), name
    with pytest.raises(ValueError):
        r.q[0, 0] = 1.0  # read-only


def test_paper_preset_keeps_q_bounded_and_reaches_the_set_point(paper_result) -> None:
    r = paper_result
    assert np.abs(r.q).max() < 1.2  # the probe swings the arm by up to about 1 rad
    after_probe = r.t >= r.config.probe.until + 10.0
    assert np.abs(r.e1[after_probe]).max() < 1e-4
    np.testing.assert_allclose(r.e1, np.array(r.config.task.qd) - r.q, atol=1e-15)


def test_recorded_probe_and_torque_are_consistent(paper_result) -> None:
    r = paper_result
    during = r.t < r.config.probe.until
    assert np.abs(r.probe[during]).max() > 1.0
    assert np.all(r.probe[~during] == 0.0)
    # tau = h + mu - (u_hat + probe), h of eq. (5), at every recorded row
    alpha1 = np.array(r.config.control.alpha1)
    parameters = plant_parameters(r.config)
    for i in range(0, r.t.size, 97):
        M, C, G, F = arm_terms(parameters, r.q[i], r.dq[i])
        h = M @ alpha1 @ (-r.dq[i]) + C @ alpha1 @ r.e1[i] + G + F
        np.testing.assert_allclose(r.tau[i], h + r.mu[i] - r.u_hat[i] - r.probe[i], atol=1e-10)


def test_same_config_gives_identical_results(paper_result) -> None:
    assert_same_arrays(paper_result, adparm.simulate(adparm.paper_config()))
    # random extrapolation points drawn anew at every step, from the same seed
    local = adparm.paper_config().updated(
        {"sim": {"T": 2.0}, "extrapolation": {"points": 10, "mode": "local", "seed": 7}}
    )
    assert_same_arrays(adparm.simulate(local), adparm.simulate(local))


def test_leaving_the_divergence_bound_stops_the_run() -> None:
    # W* has entries up to 8 while Wc(0) = 1: a bound of 5 is crossed as the critic learns
    config = adparm.paper_config().updated({"sim": {"T": 20.0, "divergence_bound": 5.0}})
    with pytest.raises(adparm.SimulationDiverged, match="sim.divergence_bound = 5") as caught:
        adparm.simulate(config)
    partial = caught.value.result
    assert 0.0 < partial.t[-1] <= caught.value.time < 20.0
    for name in ("q", "dq", "critic_weights", "actor_weights"):
        assert np.abs(getattr(partial, name)).max() <= 5.0, name


def test_recordings_larger_than_memory_are_refused_before_running() -> None:
    huge = adparm.paper_config().updated({"sim": {"T": 1e7, "record_every": 1}})  # 1e10 rows
    with pytest.raises(ValueError, match="sim.record_every: this run would need about .* GiB"):
        adparm.simulate(huge)
    with pytest.raises(
        ValueError, match="sim.record_every: these runs would need .* fewer configs"
    ):
        adparm.simulate_batch([adparm.paper_config(), huge])


def test_memory_guard_uses_the_memory_available_now(monkeypatch) -> None:
    """A run estimated at 10 GiB is refused when only 8 GiB are available, whatever the RAM."""
    config = adparm.paper_config().updated({"sim": {"T": 10.0}})
    need = adparm.simulation.memory_needed([config])
    assert need > 2 * adparm.simulation._recording_bytes(config)
    monkeypatch.setattr(adparm.simulation, "available_memory", lambda: need - 1)
    with pytest.raises(ValueError, match="would need about .* GiB of memory, more than"):
        adparm.simulate(config)
    monkeypatch.setattr(adparm.simulation, "available_memory", lambda: need)
    assert adparm.simulate(config).status == "finished"
    many = adparm.paper_config().updated({"extrapolation": {"points": 10**5}, "sim": {"T": 1.0}})
    monkeypatch.setattr(adparm.simulation, "available_memory", lambda: 1000)
    with pytest.raises(
        ValueError, match="^extrapolation.points: .* use fewer extrapolation.points"
    ):
        adparm.simulate(many)


def test_zero_initial_weights_are_inadmissible() -> None:
    config = adparm.paper_config().updated(
        {"init": {"critic_weights": [0.0] * 8, "actor_weights": [0.0] * 8}, "sim": {"T": 5.0}}
    )
    with pytest.raises(adparm.SimulationDiverged, match="diverged at t =") as caught:
        adparm.simulate(config)
    partial = caught.value.result
    assert partial.status == "diverged"
    assert 0.0 < caught.value.time < 1.0  # within the first second (ERRATA: milliseconds)
    assert partial.t.size >= 1 and partial.t[-1] < caught.value.time
    for name in ("q", "critic_weights", "actor_weights"):
        assert np.all(np.isfinite(getattr(partial, name))), name


def test_horizon_not_a_multiple_of_the_record_step_or_of_dt() -> None:
    # 12.5 steps: twelve of dt and a last half step ending exactly at T
    r = adparm.simulate(adparm.paper_config().updated({"sim": {"T": 0.0125, "record_every": 4}}))
    np.testing.assert_allclose(r.t, [0.0, 0.004, 0.008, 0.012, 0.0125], rtol=0, atol=1e-15)


def test_probing_off_and_exact_optimal_weights_keep_them() -> None:
    # started at W* with no probing, disturbance or friction, the critic has nothing to learn
    config = adparm.paper_config()
    W = adparm.optimal_weights(config)
    config = config.updated(
        {
            "init": {"critic_weights": W, "actor_weights": W},
            "probe": {"until": 0.0},
            "plant": {"disturbance": [0.0, 0.0], "coulomb": 0.0},
            "sim": {"T": 5.0},
        }
    )
    r = adparm.simulate(config)
    assert np.abs(r.hjb_error).max() < 1e-9
    np.testing.assert_allclose(r.critic_weights[-1], W, atol=1e-8)
    np.testing.assert_allclose(r.actor_weights[-1], W, atol=1e-8)


def test_result_checks_its_arrays(paper_result) -> None:
    arrays = paper_result.to_dict()
    arrays["q"] = arrays["q"][:-1]
    for key in ("status", "wall_time"):
        arrays.pop(key)
    with pytest.raises(ValueError, match=r"q: expected shape"):
        adparm.SimulationResult(**arrays, config=paper_result.config)


@pytest.mark.parametrize("chunk", [1, 3, 10, 37])
@pytest.mark.parametrize(("T", "record_every"), [(0.2, 10), (0.1037, 7)])
def test_chunked_runs_record_the_same_rows(chunk, T, record_every) -> None:
    """A row due at a step's end is written from the next step's first RK4 stage, or when the
    chunk ends there: chunk boundaries on and off the record step, and a last step shortened to
    end at T, give identical recordings."""
    from adparm import _core
    from adparm.simulation import core_settings

    config = adparm.paper_config().updated({"sim": {"T": T, "record_every": record_every}})
    whole = _core.Simulation(core_settings(config))
    whole.advance(whole.steps)
    chunked = _core.Simulation(core_settings(config))
    while chunked.status == "running":
        chunked.advance(chunk)
        rows = chunked.recording()["t"]
        if chunked.status == "running":
            last = config.sim.dt * (chunked.step // record_every) * record_every
            assert rows[-1] == pytest.approx(last)
        else:
            assert rows[-1] == pytest.approx(T)
    expected, actual = whole.recording(), chunked.recording()
    assert expected.keys() == actual.keys()
    for name in expected:
        np.testing.assert_array_equal(actual[name], expected[name], err_msg=name)


def test_divergence_mid_chunk_keeps_the_last_finite_state_as_the_last_row() -> None:
    config = adparm.paper_config().updated(
        {"init": {"critic_weights": [0.0] * 8, "actor_weights": [0.0] * 8}, "sim": {"T": 5.0}}
    )
    for record_every in (1, 3, 10):
        c = config.updated({"sim": {"record_every": record_every}})
        with pytest.raises(adparm.SimulationDiverged) as caught:
            adparm.simulate(c)
        partial = caught.value.result
        assert partial.t[-1] == pytest.approx(caught.value.time - c.sim.dt)
        assert np.all(np.diff(partial.t) > 0.0)
    # the core's state after divergence is the last finite one, that of the last row
    from adparm import _core
    from adparm.simulation import core_settings

    run = _core.Simulation(core_settings(config))
    run.advance(run.steps)
    assert run.status == "diverged"
    state, last = run.state, run.recording()
    assert np.all(np.isfinite(state))
    np.testing.assert_array_equal(state[0:2], last["q"][-1])
    np.testing.assert_array_equal(state[4:12], last["critic_weights"][-1])
    assert run.step * config.sim.dt == pytest.approx(run.divergence_time)


def test_the_core_table_of_recorded_series_is_what_a_result_holds() -> None:
    # one table (C++ kRecordedSeries) names the series: the core's recording, the result's arrays
    # and the CSV columns all follow it
    from adparm.result import RECORDED_SERIES
    from adparm.translate import core_settings

    names = [name for name, _ in RECORDED_SERIES]
    assert names[0] == "t" and len(set(names)) == len(names)
    fields = {f.name for f in dataclasses.fields(adparm.SimulationResult)}
    assert set(names) <= fields
    config = adparm.paper_config().updated({"sim": {"T": 0.01}})
    run = adparm._core.Simulation(core_settings(config))
    run.advance(100)
    assert list(run.recording()) == names
    result = adparm.simulate(config)
    first = [n for w in ("one", "joints", "basis") for n, width in RECORDED_SERIES if width == w]
    assert list(result.to_dict())[: len(first)] == first
    # the identifier's series: None without identification
    assert result.model_parameters is None and result.stack_singular_value is None


def test_an_approximation_warning_made_an_error_keeps_the_run() -> None:
    # under filterwarnings = error the warning itself is raised (not re-worded as a failed
    # diagnosis), and the finished run stays reachable from it
    import warnings

    config = adparm.paper_config().updated({"sim": {"T": 0.5}})
    with warnings.catch_warnings():
        warnings.simplefilter("error", adparm.ApproximationWarning)
        with pytest.raises(adparm.ApproximationWarning, match="not converged") as caught:
            adparm.simulate(config)
    result = caught.value.result
    assert isinstance(result, adparm.SimulationResult) and result.status == "finished"
    assert result.t[-1] == pytest.approx(0.5)
