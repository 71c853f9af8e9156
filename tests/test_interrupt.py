"""Ctrl-C during a long run: it stops between two chunks and keeps what was recorded."""

from __future__ import annotations

import _thread
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest

import adparm

from conftest import assert_same_arrays, signal_reproduce

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

# Far longer than the interrupt delay: about 15 s of computation for the paper's loop.
LONG_T = 20_000.0


@contextmanager
def interrupt_after(seconds: float) -> Iterator[None]:
    """Raise KeyboardInterrupt in the main thread after ``seconds``, as Ctrl-C does."""
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def long_config(**sim) -> adparm.Config:
    return adparm.paper_config().updated({"sim": {"T": LONG_T, **sim}})


def test_simulate_keeps_the_rows_recorded_before_ctrl_c() -> None:
    config = long_config()
    with pytest.raises(adparm.SimulationInterrupted, match="interrupted at t =") as caught:
        with interrupt_after(0.3):
            adparm.simulate(config)
    interrupt = caught.value
    assert isinstance(interrupt, KeyboardInterrupt)  # an uncaught one stops a script as usual
    partial = interrupt.result
    assert partial.status == "interrupted"
    assert 0.0 < partial.t[-1] <= interrupt.time < LONG_T
    # the rows are those of a run that ends where the recording stops
    shorter = adparm.simulate(config.updated({"sim": {"T": float(partial.t[-1])}}))
    assert_same_arrays(shorter, partial)


def test_interrupted_results_save_and_load(tmp_path) -> None:
    with pytest.raises(adparm.SimulationInterrupted) as caught:
        with interrupt_after(0.2):
            adparm.simulate(long_config())
    loaded = adparm.load_result(caught.value.result.save(tmp_path / "partial.npz"))
    assert loaded.status == "interrupted"
    assert_same_arrays(caught.value.result, loaded)
    assert caught.value.result.summary()["status"] == "interrupted"


def test_simulate_batch_keeps_every_run() -> None:
    short = adparm.paper_config().updated({"sim": {"T": 0.5}})
    configs = [short, long_config(), long_config(record_every=7)]
    with pytest.raises(adparm.SimulationInterrupted, match="1 of 3 runs done") as caught:
        with interrupt_after(0.5):
            adparm.simulate_batch(configs, threads=2)
    results = caught.value.result
    assert [r.status for r in results] == ["finished", "interrupted", "interrupted"]
    assert_same_arrays(adparm.simulate(short), results[0])
    for result in results[1:]:
        assert 0.0 < result.t[-1] < LONG_T
        assert np.all(np.isfinite(result.q))


def test_sweep_keeps_the_rows_of_the_points_done() -> None:
    base = adparm.paper_config().updated({"sim": {"T": 0.5}})
    with pytest.raises(adparm.SimulationInterrupted, match="1 of 2 points done") as caught:
        with interrupt_after(0.5):
            adparm.sweep(base, {"sim.T": [0.5, LONG_T]}, threads=2)
    table = caught.value.result
    assert isinstance(table, adparm.SweepResult)
    assert [row["sim.T"] for row in table] == [0.5]
    assert table["status"].tolist() == ["finished"]


def test_compare_keeps_the_runs_so_far() -> None:
    config = adparm.paper_config().updated({"sim": {"T": LONG_T}})
    with pytest.raises(adparm.SimulationInterrupted, match="during the 'adp' run") as caught:
        with interrupt_after(0.3):
            adparm.compare(config, ["adp", "pd"])
    comparison = caught.value.result
    assert list(comparison.results) == ["adp"]
    assert comparison.results["adp"].status == "interrupted"
    assert comparison.rows[0]["status"] == "interrupted"


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
def test_cli_ctrl_c_writes_the_partial_result_and_exits_130(tmp_path) -> None:
    out = tmp_path / "run"
    returncode, stderr = signal_reproduce(out, LONG_T, signal.SIGINT)
    assert returncode == 130, stderr.decode(errors="replace")
    assert b"stopped by SIGINT at t =" in stderr and b".result" not in stderr
    partial = adparm.load_result(out / "result.npz")
    assert partial.status == "interrupted"
    assert 0.0 < partial.t[-1] < LONG_T
    assert (out / "summary.json").is_file()
