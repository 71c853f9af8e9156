"""The critic's dense kernels (cpp/include/adparm/dense_kernels.hpp): Gamma Omega, the rank-s
update of Gamma and the stacked points' products of the n-joint loop, built for AVX2 + FMA and for
AVX-512 and chosen at run time for the CPU; the environment variable ADPARM_KERNELS (auto,
portable, avx2, avx512), read when a loop is built, forces a choice.

- Each kernel set this CPU runs against the portable path (Eigen's products: the code, and the
  bits, of the loop before the kernels), an independent implementation of the same products: the
  same covariance resets at the same steps and the same recordings to round-off, on the planar
  3-link arm with both bases and extrapolation points (also with an input bound) and on the UR5
  example (110 points: two gathered blocks; and without points: the low-rank RK4 step); a basis
  of pairs (the quadratic family, terms c x_a x_b), whose points' products never form B_i, on the
  UR5 and the 3-link arm, and the 3-link arm's pairs with one other term (the general path). The
  kernels sum in another order and with fused multiply-adds, so single products differ in the
  last bits, which the learning laws amplify (as between the fixed and dynamic paths,
  test_dynamic_sizes.py).
- Each is deterministic: bit for bit the same run after run and on 1 or 2 threads.
- A value the CPU cannot run or that is not known is refused, naming the variable.
- auto chooses AVX-512 for loops with points, AVX2 first for one sample per evaluation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.simulation import core_settings

# Short learning runs here have not converged and say so; that warning is not what is tested.
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

ARRAYS = ("q", "dq", "tau", "u_hat", "critic_weights", "actor_weights", "hjb_error", "cost")


def _cpu_flags() -> set[str]:
    cpuinfo = Path("/proc/cpuinfo")
    if not cpuinfo.exists():
        return set()
    for line in cpuinfo.read_text().splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


FLAGS = _cpu_flags()
AVAILABLE = [
    name
    for name, needs in (("avx2", {"avx2", "fma"}), ("avx512", {"avx2", "fma", "avx512f"}))
    if needs <= FLAGS
]


def _planar(basis: str) -> adparm.Config:
    return adparm.load_config("examples/planar_3link.toml").updated(
        {"controller": {"basis": basis}, "extrapolation": {"points": 10}, "sim": {"T": 0.5}}
    )


def _ur5_quadratic(points: int) -> adparm.Config:
    return adparm.load_config("examples/ur5.toml").updated(
        {
            "controller": {"basis": "quadratic"},
            "extrapolation": {"points": points},
            "sim": {"T": 0.2},
            "actor": {"eta_a1": 0.05},  # the points' share in the actor's law too (derived: 0)
        }
    )


#: Pairs c x_a x_b of the planar 3-link arm's error state (x1 ... x6; e2 = x4 ... x6): squares,
#: coefficients, pairs within e1, across e1 and e2 and within e2.
PAIRS = [
    "x1^2",
    "x2^2",
    "x1*x2",
    "x3^2",
    "2*x1*x4",
    "0.5*x2*x5",
    "-x3*x6",
    "0.5*x4^2",
    "x4*x5",
    "x5^2",
    "x5*x6",
    "x6^2",
    "x4*x6",
    "x3*x4",
]


CONFIGS = {
    "planar_quadratic": lambda: _planar("quadratic"),
    "planar_structured": lambda: _planar("structured"),
    # an input bound: the points' bounded policy and its slopes in the actor's gradient
    "planar_bounded": lambda: _planar("quadratic").updated({"cost": {"input_bound": [4.0] * 3}}),
    "ur5": lambda: adparm.load_config("examples/ur5.toml").updated({"sim": {"T": 0.2}}),
    # a basis of pairs (the quadratic family) at fixed points: the points' shares without their
    # B_i (ClosedLoop::learn_from_pairs), the 50 points' omega_i written straight into the
    # critic's block, the 110 points' through a copy (more samples than one block holds)
    "ur5_quadratic": lambda: _ur5_quadratic(50),
    "ur5_quadratic_two_blocks": lambda: _ur5_quadratic(110),
    # pairs with coefficients and squares; and the same with one term that is not a pair (the
    # points' B_i then: learn_from_points_batched)
    "planar_pairs": lambda: _planar("quadratic").updated(
        {"controller": {"basis": PAIRS}, "actor": {"eta_a1": 0.05}}
    ),
    "planar_not_pairs": lambda: _planar("quadratic").updated(
        {"controller": {"basis": [*PAIRS, "x4*x5*cos(q2)"]}, "actor": {"eta_a1": 0.05}}
    ),
    # no points, 55 functions: one sample per evaluation, the low-rank RK4 step (its end in the
    # kernels) and the trajectory's products with B
    "ur5_no_points": lambda: adparm.load_config("examples/ur5.toml").updated(
        {"extrapolation": {"points": 0}, "sim": {"T": 0.2}}
    ),
}


def run(config: adparm.Config, kernels: str, monkeypatch) -> tuple[_core.Simulation, dict]:
    monkeypatch.setenv("ADPARM_KERNELS", kernels)
    simulation = _core.Simulation(core_settings(config))
    while simulation.status == "running":
        simulation.advance(997)
    assert simulation.status == "finished"
    return simulation, simulation.recording()


@pytest.fixture(scope="module")
def configs() -> dict[str, adparm.Config]:
    return {name: make() for name, make in CONFIGS.items()}


@pytest.mark.skipif(not AVAILABLE, reason="this CPU has neither AVX2 + FMA nor AVX-512")
@pytest.mark.parametrize("case", sorted(CONFIGS))
def test_kernels_agree_with_the_portable_path(configs, case, monkeypatch) -> None:
    portable, expected = run(configs[case], "portable", monkeypatch)
    for kernels in AVAILABLE:
        simulation, got = run(configs[case], kernels, monkeypatch)
        assert simulation.step == portable.step
        np.testing.assert_array_equal(simulation.reset_times, portable.reset_times)
        for name in ARRAYS:
            scale = max(np.abs(expected[name]).max(), 1.0)
            np.testing.assert_allclose(
                got[name], expected[name], rtol=0, atol=1e-10 * scale, err_msg=f"{kernels} {name}"
            )
        # not the same bits: the kernels did run (a wrong dispatch would pass silently otherwise)
        assert not np.array_equal(got["critic_weights"], expected["critic_weights"]), kernels


@pytest.mark.parametrize("kernels", ["portable", *AVAILABLE])
def test_each_kernel_set_is_the_same_run_after_run_and_on_any_thread_count(
    configs, kernels, monkeypatch
) -> None:
    config = configs["planar_quadratic"]
    _, first = run(config, kernels, monkeypatch)
    _, second = run(config, kernels, monkeypatch)
    for name in ARRAYS:
        np.testing.assert_array_equal(first[name], second[name], err_msg=name)
    one = adparm.simulate_batch([config, config], threads=1)
    two = adparm.simulate_batch([config, config], threads=2)
    for a, b in zip(one, two, strict=True):
        np.testing.assert_array_equal(a.critic_weights, b.critic_weights)
        np.testing.assert_array_equal(a.critic_weights, first["critic_weights"])
        np.testing.assert_array_equal(a.q, b.q)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("avx3", "ADPARM_KERNELS: unknown value 'avx3' (auto, portable, avx2 or avx512)"),
        ("AVX2", "ADPARM_KERNELS: unknown value 'AVX2'"),
    ],
)
def test_an_unknown_value_is_refused_naming_the_variable(value, message, monkeypatch) -> None:
    monkeypatch.setenv("ADPARM_KERNELS", value)
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        _core.Simulation(core_settings(adparm.paper_config()))


@pytest.mark.skipif("avx512f" in FLAGS, reason="this CPU runs every kernel set")
def test_a_kernel_set_the_cpu_cannot_run_is_refused(monkeypatch) -> None:
    monkeypatch.setenv("ADPARM_KERNELS", "avx512")
    with pytest.raises(ValueError, match="ADPARM_KERNELS=avx512: .*lacks AVX-512F"):
        _core.Simulation(core_settings(adparm.paper_config()))


def test_auto_is_the_default(configs, monkeypatch) -> None:
    """auto: AVX-512 (if the CPU has it) for a loop with extrapolation points, AVX2 first for one
    sample per evaluation (dense_kernels.hpp), else the other set, else portable."""
    blocks = AVAILABLE[-1] if AVAILABLE else "portable"
    single = AVAILABLE[0] if AVAILABLE else "portable"
    for case, best in (("planar_structured", blocks), ("ur5_no_points", single)):
        _, automatic = run(configs[case], "auto", monkeypatch)
        monkeypatch.delenv("ADPARM_KERNELS")
        simulation = _core.Simulation(core_settings(configs[case]))
        simulation.advance(10**9)
        _, chosen = run(configs[case], best, monkeypatch)
        np.testing.assert_array_equal(
            simulation.recording()["critic_weights"], chosen["critic_weights"], err_msg=case
        )
        np.testing.assert_array_equal(
            automatic["critic_weights"], chosen["critic_weights"], err_msg=case
        )
        if len(AVAILABLE) == 2:  # the other set gives other bits: the choice is observable
            other = AVAILABLE[1] if best == AVAILABLE[0] else AVAILABLE[0]
            _, different = run(configs[case], other, monkeypatch)
            assert not np.array_equal(different["critic_weights"], chosen["critic_weights"]), case
