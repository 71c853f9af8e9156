"""The paper loop's AVX-512 evaluation (cpp/include/adparm/vector_loop.hpp): the two-link arm with
the augmented basis evaluated in vector registers on a CPU with AVX-512, chosen at run time; the
environment variable ADPARM_KERNELS=portable (or avx2) forces the portable evaluation.

- Against the portable evaluation (an independent implementation of the same laws: Eigen's
  fixed-size products and libm's sincos): the same covariance resets at the same steps, and
  recordings that differ no more than a rounding of the initial state makes them differ (the
  portable run from q0(0) (1 + 4 eps), within 10 times), on the paper's run, a tracking run, a
  believed model that is not the plant and an input bound (whose sample stays on the portable
  laws, built with FMA). The vector path sums in another order, with fused multiply-adds and its
  own sincos (within 2 ulp of libm's), so the last bits differ and the learning laws amplify them
  as they amplify any rounding (measured: 1e-10 to 2e-9 of the weights' scale over 5 s, the
  nudge's 7e-11 to 7e-10).
- It is deterministic: bit for bit the same run after run and on 1 or 2 threads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.simulation import core_settings

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

ARRAYS = ("q", "dq", "tau", "u_hat", "critic_weights", "actor_weights", "hjb_error", "cost")


def _has_avx512() -> bool:
    cpuinfo = Path("/proc/cpuinfo")
    if not cpuinfo.exists():
        return False
    for line in cpuinfo.read_text().splitlines():
        if line.startswith("flags"):
            return {"avx512f", "avx512dq", "avx512vl", "fma"} <= set(line.split(":", 1)[1].split())
    return False


AVX512 = _has_avx512()

CONFIGS = {
    "paper": {"sim": {"T": 5.0}},
    "tracking": {"task": {"qd": {"kind": "sinusoid"}}, "sim": {"T": 5.0}},
    "model_error": {"model": {"p1": 4.0}, "sim": {"T": 5.0}},
    "input_bound": {"cost": {"input_bound": [20.0, 20.0]}, "sim": {"T": 5.0}},
}


def run(
    changes: dict, kernels: str, monkeypatch, nudge: float = 0.0
) -> tuple[_core.Simulation, dict]:
    monkeypatch.setenv("ADPARM_KERNELS", kernels)
    config = adparm.paper_config().updated(changes)
    if nudge:
        q0 = list(config.task.q0)
        q0[0] *= 1.0 + nudge
        config = config.updated({"task": {"q0": q0}})
    simulation = _core.Simulation(core_settings(config))
    while simulation.status == "running":
        simulation.advance(997)
    assert simulation.status == "finished"
    return simulation, simulation.recording()


@pytest.mark.skipif(not AVX512, reason="this CPU has no AVX-512")
@pytest.mark.parametrize("case", sorted(CONFIGS))
def test_the_vector_evaluation_agrees_with_the_portable_one(case, monkeypatch) -> None:
    portable, expected = run(CONFIGS[case], "portable", monkeypatch)
    simulation, got = run(CONFIGS[case], "auto", monkeypatch)
    _, nudged = run(CONFIGS[case], "portable", monkeypatch, nudge=4 * np.finfo(float).eps)
    assert simulation.step == portable.step
    np.testing.assert_array_equal(simulation.reset_times, portable.reset_times)
    for name in ARRAYS:
        scale = max(np.abs(expected[name]).max(), 1.0)
        rounding = np.abs(nudged[name] - expected[name]).max()
        difference = np.abs(got[name] - expected[name]).max()
        assert difference <= 10.0 * rounding + 1e-11 * scale, (case, name, difference, rounding)
    # not the same bits: the vector path did run (a wrong dispatch would pass silently otherwise)
    assert not np.array_equal(got["critic_weights"], expected["critic_weights"])
    # avx2 (the dense kernels' other set) keeps the portable evaluation, bit for bit
    _, avx2 = run(CONFIGS[case], "avx2", monkeypatch)
    for name in ARRAYS:
        np.testing.assert_array_equal(avx2[name], expected[name], err_msg=f"avx2 {name}")


@pytest.mark.parametrize("kernels", ["portable", "auto"])
def test_each_evaluation_is_the_same_run_after_run_and_on_any_thread_count(
    kernels, monkeypatch
) -> None:
    _, first = run(CONFIGS["paper"], kernels, monkeypatch)
    _, second = run(CONFIGS["paper"], kernels, monkeypatch)
    for name in ARRAYS:
        np.testing.assert_array_equal(first[name], second[name], err_msg=name)
    config = adparm.paper_config().updated({"sim": {"T": 2.0}})
    one = adparm.simulate_batch([config, config], threads=1)
    two = adparm.simulate_batch([config, config], threads=2)
    for a, b in zip(one + two, one[:1] * 4, strict=True):
        np.testing.assert_array_equal(a.critic_weights, b.critic_weights)
