"""RK4 shows fourth-order convergence on smooth problems (the arm alone, and the closed loop
with every non-smooth part switched off)."""

from __future__ import annotations

import numpy as np

import adparm
from adparm import _core
from adparm.simulation import core_settings


def observed_orders(errors: list[float]) -> np.ndarray:
    return np.log2(np.array(errors[:-1]) / np.array(errors[1:]))


def test_rk4_fourth_order_on_the_arm() -> None:
    p = _core.ArmParameters()
    p.coulomb = 0.0
    x0 = np.array([0.4, -0.3, 1.0, -2.0])
    T = 2.0

    def final(dt: float) -> np.ndarray:
        return _core.simulate_open_loop(p, np.array([0.1, 0.1]), x0, dt, round(T / dt), False)[-1]

    reference = final(T / 65536)
    errors = [np.abs(final(T / n) - reference).max() for n in (512, 1024, 2048, 4096)]
    orders = observed_orders(errors)
    assert np.all(np.abs(orders - 4.0) < 0.3), orders


def test_rk4_fourth_order_on_the_smooth_closed_loop() -> None:
    # no sgn() anywhere (no Coulomb friction, beta1 = 0), no covariance reset, no projection
    # (the e2-block projection switches on and off: not smooth)
    config = adparm.paper_config().updated(
        {
            "actor": {"positive_e2": False},
            "plant": {"coulomb": 0.0},
            "control": {"beta1": 0.0},
            "critic": {"epsilon_T": 0.0},
            "sim": {"T": 0.5},
        }
    )

    def final(dt: float) -> np.ndarray:
        run = _core.Simulation(core_settings(config.updated({"sim": {"dt": dt}})))
        run.advance(run.steps)
        assert run.status == "finished" and not run.reset_times
        return run.state

    # the critic (eta_c = 800) is stiff: steps below ~1 ms are in RK4's asymptotic range
    reference = final(0.5 / 32768)
    errors = [np.abs(final(0.5 / n) - reference).max() for n in (1024, 2048, 4096)]
    orders = observed_orders(errors)
    assert np.all(np.abs(orders - 4.0) < 0.3), (errors, orders)
