"""cost.input_bound = "auto": lambda_i = (limit_i - max |h_i| over the desired trajectory - the
probe's amplitude) / 2 (adparm.rates.auto_input_bound), checked against the paper's two-link
equations written out in NumPy and against Pinocchio's Python bindings on the UR5."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import adparm

AUTO = {"input_bound": "auto"}
NO_PROBE = {"until": 0.0}


def paper_h(config: adparm.Config, t: np.ndarray) -> np.ndarray:
    """h = M ddqd + C dqd + G + F of the paper's arm (Section 4) along a sinusoid qd, (m, 2)."""
    plant, qd = config.plant, config.task.qd
    a, w = np.array(qd.amplitude)[:, 0], np.array(qd.frequency)[:, 0]  # one sinusoid per joint
    q = np.array(qd.offset) + a * np.sin(w * t[:, None])
    dq = a * w * np.cos(w * t[:, None])
    ddq = -a * w**2 * np.sin(w * t[:, None])
    p1, p2, p3, g1, g2 = plant.p1, plant.p2, plant.p3, plant.g1, plant.g2
    c2, s2 = np.cos(q[:, 1]), np.sin(q[:, 1])
    h = np.empty_like(q)
    h[:, 0] = (
        (p1 + 2 * p3 * c2) * ddq[:, 0]
        + (p2 + p3 * c2) * ddq[:, 1]
        - p3 * s2 * dq[:, 1] * dq[:, 0]
        - p3 * s2 * (dq[:, 0] + dq[:, 1]) * dq[:, 1]
        + g1 * np.cos(q[:, 0])
        + g2 * np.cos(q[:, 0] + q[:, 1])
    )
    h[:, 1] = (
        (p2 + p3 * c2) * ddq[:, 0]
        + p2 * ddq[:, 1]
        + p3 * s2 * dq[:, 0] ** 2
        + g2 * np.cos(q[:, 0] + q[:, 1])
    )
    return h + plant.coulomb * np.sign(dq) + plant.viscous * dq


def test_set_point_of_the_paper_arm_leaves_half_the_headroom_over_gravity() -> None:
    # qd = 0 at rest: h = G(0) = [g1 + g2, g2] = [21.56, 9.8] N m, no friction; the disturbance
    # [0.1 sin t, 0.1 cos t] N m, which RISE cancels
    config = adparm.paper_config().updated(
        {"plant": {"torque_limits": [100.0, 40.0]}, "probe": NO_PROBE, "cost": AUTO}
    )
    expected = [(100.0 - 9.8 * 2.2 - 0.1) / 2.0, (40.0 - 9.8 - 0.1) / 2.0]
    np.testing.assert_allclose(config.cost.input_bound, expected, rtol=1e-12)
    assert "cost.input_bound" in config.derived
    assert "half the headroom" in config.derived["cost.input_bound"]


def test_the_probe_takes_its_summed_amplitude_off_the_headroom() -> None:
    # 4 sinusoids of amplitude [5, 2] N m: at most [20, 8] N m on the joints
    config = adparm.paper_config().updated(
        {
            "plant": {"torque_limits": [100.0, 40.0]},
            "probe": {"amplitude": [5.0, 2.0]},
            "cost": AUTO,
        }
    )
    expected = [(100.0 - 9.8 * 2.2 - 0.1 - 20.0) / 2.0, (40.0 - 9.8 - 0.1 - 8.0) / 2.0]
    np.testing.assert_allclose(config.cost.input_bound, expected, rtol=1e-12)
    assert "probe" in config.derived["cost.input_bound"]


def test_a_moving_target_takes_the_largest_feedforward_over_the_horizon() -> None:
    qd = {"kind": "sinusoid", "amplitude": [0.5, 0.3], "frequency": [3.0, 4.0], "phase": [0, 0]}
    config = adparm.paper_config().updated(
        {
            "plant": {
                "torque_limits": [150.0, 60.0],
                "coulomb": -0.1,
                "viscous": 0.5,
                "disturbance": [1.0, 2.0],
            },
            "task": {"qd": qd},
            "probe": NO_PROBE,
            "sim": {"T": 4.0},
            "cost": AUTO,
        }
    )
    h = np.abs(paper_h(config, np.linspace(0.0, 4.0, 200))).max(axis=0)
    np.testing.assert_allclose(config.cost.input_bound, (np.array([149.0, 58.0]) - h) / 2, 1e-9)
    # more than at the set-point qd(0): the trajectory's acceleration and velocity count
    at_start = np.abs(paper_h(config, np.zeros(1)))[0]
    assert np.all(h > at_start + 5.0)


def test_the_ur5_takes_its_urdf_efforts_less_its_gravity_torque() -> None:
    config = adparm.Config.from_dict({"plant": {"urdf": "example-robot-data:ur5"}, "cost": AUTO})
    effort = np.array([150.0, 150.0, 150.0, 28.0, 28.0, 28.0])
    assert config.plant.torque_limits == tuple(effort)
    assert config.probe.until == 0.0  # the URDF default: no probing
    model = pin.buildModelFromUrdf(str(config.plant.urdf))
    data = model.createData()
    qd = np.array(config.task.qd, dtype=float)
    gravity = pin.rnea(model, data, qd, np.zeros(6), np.zeros(6))
    # the derived disturbance: min(0.1, 0.1 M_jj(qd)) N m per joint (the wrists' M_jj < 1 kg m^2)
    inertia = np.diag(pin.crba(model, data, qd))
    disturbance = np.minimum(0.1, 0.1 * inertia)
    assert disturbance[5] < 0.1
    np.testing.assert_allclose(config.plant.disturbance, disturbance, rtol=1e-3)
    expected = (effort - np.abs(gravity) - np.asarray(config.plant.disturbance)) / 2
    np.testing.assert_allclose(config.cost.input_bound, expected, 1e-9)


def test_auto_runs_exactly_as_its_numbers() -> None:
    base = adparm.paper_config().updated(
        {
            "plant": {"torque_limits": [60.0, 20.0]},
            "probe": NO_PROBE,
            "extrapolation": {"points": 10},
            "sim": {"T": 0.5},
        }
    )
    auto = base.updated({"cost": AUTO})
    numbers = base.updated({"cost": {"input_bound": list(auto.cost.input_bound)}})
    assert auto == numbers
    a, b = adparm.simulate(auto, diagnose=False), adparm.simulate(numbers, diagnose=False)
    for key in ("q", "critic_weights", "actor_weights", "tau", "u_hat", "cost"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key))
    # the saved config holds the numbers and reads back to the same config
    assert adparm.Config.from_dict(auto.to_dict()) == auto


def test_auto_is_derived_again_when_the_config_changes() -> None:
    config = adparm.paper_config().updated(
        {"plant": {"torque_limits": [100.0, 40.0]}, "probe": NO_PROBE, "cost": AUTO}
    )
    lowered = config.updated({"plant": {"torque_limits": [60.0, 40.0]}})
    np.testing.assert_allclose(lowered.cost.input_bound, [(60.0 - 21.66) / 2, 15.05], 1e-12)
    fixed = config.updated({"cost": {"input_bound": 3.0}}).updated({"sim": {"T": 1.0}})
    assert fixed.cost.input_bound == 3.0
    assert "cost.input_bound" not in fixed.derived


def test_a_joint_without_a_limit_is_left_practically_unbounded() -> None:
    config = adparm.paper_config().updated(
        {"plant": {"torque_limits": [100.0, float("inf")]}, "probe": NO_PROBE, "cost": AUTO}
    )
    np.testing.assert_allclose(config.cost.input_bound, [39.17, adparm.rates.UNLIMITED_BOUND])


@pytest.mark.parametrize("limits", [None, "none", float("inf")])
def test_auto_without_any_limit_is_refused(limits) -> None:
    changes = {"probe": NO_PROBE, "cost": AUTO}
    if limits is not None:
        changes["plant"] = {"torque_limits": limits}
    with pytest.raises(ValueError, match=r"cost\.input_bound: .*plant\.torque_limits"):
        adparm.paper_config().updated(changes)


def test_a_limit_below_the_feedforward_is_refused_naming_the_joint() -> None:
    with pytest.raises(ValueError, match=r"cost\.input_bound: .*joint 2 .*does not hold"):
        adparm.paper_config().updated(
            {"plant": {"torque_limits": [100.0, 9.0]}, "probe": NO_PROBE, "cost": AUTO}
        )
    # the paper's probe (4 x 71 N m on joint 1) leaves no headroom under 100 N m
    with pytest.raises(ValueError, match=r"joint 1 .*probe\.amplitude"):
        adparm.paper_config().updated({"plant": {"torque_limits": [100.0, 40.0]}, "cost": AUTO})


def test_an_unresolved_auto_section_says_so() -> None:
    with pytest.raises(ValueError, match=r"cost\.input_bound: \"auto\" is resolved"):
        adparm.CostConfig(input_bound="auto").bound_vector(2)


def test_a_sweep_over_the_bound_on_the_ur5_carries_the_saturated_time() -> None:
    # the exact saturated family on the UR5 with its derived cost (building it used to fail: the
    # n-joint Q was checked against the old R), its URDF's torque limits and the structured basis
    base = adparm.Config.from_dict(
        {
            "plant": {"urdf": "example-robot-data:ur5"},
            "cost": {"input_bound": "auto", "e2_cost": "logcosh"},
            "sim": {"T": 0.3},
        }
    )
    assert base.controller.basis == "structured"
    assert base.plant.torque_limits == (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)
    table = adparm.sweep(base, {"cost.input_bound": [0.5, "auto"]})
    assert [row["cost.input_bound"] for row in table] == [0.5, "auto"]
    for row in table:
        assert row["status"] == "finished"
        assert len(row["saturated_time"]) == 6  # seconds the drive clipped, per joint
        assert all(0.0 <= s <= 0.3 for s in row["saturated_time"])
        assert row["critic_relative_error"] is not None  # the family's W* is known
    # the rows carry no J / J* - 1: the numerical optimum on the UR5 takes minutes
    # (adparm.optimal_cost; adparm compare leaves it out on arms of more than 3 joints)
    assert not any("optimal" in key or "J*" in key for key in table.rows[0])


def test_another_word_is_refused() -> None:
    with pytest.raises(ValueError, match=r'cost\.input_bound: expected .* or "auto", got \'Auto\''):
        adparm.paper_config().updated({"cost": {"input_bound": "Auto"}})
