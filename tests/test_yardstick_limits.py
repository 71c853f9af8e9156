"""adparm.optimal_cost with torque limits, the bounded input cost and the logcosh state cost,
and on URDF arms (M, C, G from adam-robotics, checked against Pinocchio's Python bindings)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import adparm

from numpy_reference import pinocchio_terms

ARMS = Path(__file__).resolve().parents[1] / "examples" / "arms"
SPATIAL = ARMS / "spatial_3dof.urdf"
#: A fixed horizon and discretisation: the same NLP with and without constraints, and each test
#: within seconds (the default refinement is tested in tests/test_optimal.py).
FAST = {"horizon": 12.0, "intervals": 200, "max_intervals": 400}

pytest.importorskip("adam.casadi", reason="adam-robotics builds a URDF arm's CasADi terms")


@pytest.mark.parametrize("name", ["two_link", "planar_3link", "spatial_3dof", "ur5"])
def test_urdf_terms_match_pinocchio(name: str, rng) -> None:
    import casadi

    from adparm.symbolic_arm import arm_expressions

    path = adparm.example_robot_urdf("ur5") if name == "ur5" else ARMS / f"{name}.urdf"
    gravity = [0.3, -0.2, -9.81]
    config = adparm.Config.from_dict(
        {"plant": {"urdf": str(path), "gravity": gravity, "coulomb": 0.2, "viscous": 0.5}}
    )
    n = config.dof
    q, dq = casadi.SX.sym("q", n), casadi.SX.sym("dq", n)
    terms = arm_expressions(config, q, dq)
    function = casadi.Function("terms", [q, dq], [terms[k] for k in ("M", "C", "G", "F")])
    for _ in range(10):
        qv, dqv = rng.uniform(-2.0, 2.0, n), rng.uniform(-2.0, 2.0, n)
        M, C, G, F = (np.array(v) for v in function(qv, dqv))
        terms = pinocchio_terms(path, gravity, qv, dqv)
        theirs = (terms["M"], terms["C"], terms["G"])
        scale = max(1.0, np.abs(theirs[0]).max())
        for ours, expected in zip((M, C, G.ravel()), theirs, strict=True):
            np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(F.ravel(), 0.2 * np.sign(dqv) + 0.5 * dqv, atol=1e-14)
    # and the comparison can fail: C halved is not Pinocchio's
    assert np.abs(0.5 * C - theirs[1]).max() > 1e-3 * np.abs(theirs[1]).max()


def test_torque_limits_raise_the_optimum_and_inactive_ones_change_nothing() -> None:
    config = adparm.paper_config()
    x0 = adparm.initial_error_state(config)
    free = adparm.optimal_cost(config, **FAST)
    limited = adparm.optimal_cost(config, torque_limits=[25.0, 12.0], **FAST)
    assert free.torque_limits is None and limited.torque_limits == (25.0, 12.0)
    assert limited.active_until > 0.0 and "torque limits active" in limited.note
    assert limited > free * (1.0 + 1e-3)  # the limits bind from this x0
    small = 0.02 * x0  # no limit is reached: the same optimum
    free_small = adparm.optimal_cost(config, small, **FAST)
    limited_small = adparm.optimal_cost(config, small, torque_limits=[25.0, 12.0], **FAST)
    assert limited_small.active_until == 0.0
    assert abs(limited_small / free_small - 1.0) < 1e-8


def test_exact_logcosh_family_on_the_paper_arm() -> None:
    # the paper's corrected instance is exact (Q22 = R^-1): with the bounded input cost and the
    # logcosh e2 cost, V* = e1^T K e1 + e2^T M e2 is still the optimum (issue 24)
    config = adparm.paper_config()
    x0 = adparm.initial_error_state(config)
    R = np.array(config.cost.R)
    bound = 2.0
    # the policy saturates at the start: |R^-1 e2(0)| / lambda > 1 (u* = -lambda tanh of it)
    assert np.abs(np.linalg.solve(R, x0[2:])).max() / bound > 1.0
    value = adparm.optimal_value(config)
    options = {"horizon": 30.0, "intervals": 400, "max_intervals": 800}
    best = adparm.optimal_cost(config, input_bound=bound, e2_cost="logcosh", **options)
    assert best.e2_cost == "logcosh" and best.input_bound == (2.0, 2.0)
    assert abs(best / value - 1.0) < 1e-4
    # and the test can fail: the bounded input cost with the quadratic state cost is another
    # problem, whose optimum is not V*
    other = adparm.optimal_cost(config, input_bound=bound, **options)
    assert abs(other / value - 1.0) > 1e-2


def spatial_exact_config() -> adparm.Config:
    K = np.array([[2.0, 0.3, 0.0], [0.3, 1.5, 0.2], [0.0, 0.2, 1.0]])
    alpha1 = 3.0 * np.eye(3)
    R = np.diag([0.5, 1.0, 2.0])
    return adparm.Config.from_dict(
        {
            "plant": {"urdf": str(SPATIAL), "coulomb": 0.0},
            "cost": {"Q": adparm.solvable_cost(K, alpha1, R), "R": R},
            "control": {"alpha1": alpha1},
            "task": {"q0": [0.4, -0.3, 0.5], "dq0": [0.5, 0.0, -0.5]},
        }
    )


def test_exact_logcosh_family_on_a_3_joint_urdf_arm() -> None:
    config = spatial_exact_config()
    x0 = adparm.initial_error_state(config)
    R = np.array(config.cost.R)
    assert np.abs(np.linalg.solve(R, x0[3:])).max() / 0.5 > 1.0  # the policy saturates
    value = adparm.optimal_value(config)
    # one solve of 100 intervals (a URDF arm's transcription costs about 10 times the built-in
    # arm's per interval): 3.7e-4 from V*, 6.7e-5 at 150 intervals
    options = {"horizon": 12.0, "intervals": 100, "max_intervals": 100}
    best = adparm.optimal_cost(config, input_bound=0.5, e2_cost="logcosh", **options)
    assert abs(best / value - 1.0) < 1e-3, best.note
    options = {"horizon": 12.0, "intervals": 40, "max_intervals": 40}
    quadratic = adparm.optimal_cost(config, input_bound=0.5, **options)
    assert abs(quadratic / value - 1.0) > 0.1


def test_the_two_link_urdf_transcribes_as_the_builtin_arm() -> None:
    # examples/arms/two_link.urdf with gravity [0, 0, -9.8] is the paper's arm (tests/
    # test_urdf_arm.py): the same J*, with torque limits (G and friction in tau) too
    builtin = adparm.paper_config()
    urdf = adparm.Config.from_dict(
        {
            "plant": {"urdf": str(ARMS / "two_link.urdf"), "gravity": [0.0, 0.0, -9.8]},
            "cost": {"Q": builtin.cost.Q, "R": builtin.cost.R},
            "control": {"alpha1": builtin.control.alpha1},
            "task": {"qd": list(builtin.task.qd), "q0": builtin.task.q0, "dq0": builtin.task.dq0},
        }
    )
    assert urdf.plant.coulomb == builtin.plant.coulomb
    np.testing.assert_array_equal(
        adparm.initial_error_state(urdf), adparm.initial_error_state(builtin)
    )
    options = {**FAST, "torque_limits": [25.0, 12.0]}
    a, b = adparm.optimal_cost(builtin, **options), adparm.optimal_cost(urdf, **options)
    assert a.active_until > 0.0
    assert abs(a / b - 1.0) < 1e-8


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"torque_limits": [25.0]}, r"torque_limits: expected one number or 2"),
        ({"torque_limits": -1.0}, r"torque_limits: expected one number or 2"),
        ({"torque_limits": [10.0, 5.0]}, r"torque_limits: .* cannot hold the set-point"),
        ({"input_bound": np.inf}, r"input_bound: expected one number or 2 numbers > 0, finite"),
        ({"e2_cost": "logcosh"}, r"e2_cost: 'logcosh' needs an input bound \(cost.input_bound\)"),
        ({"e2_cost": "cubic"}, r"e2_cost: expected 'quadratic' or 'logcosh'"),
    ],
)
def test_bad_arguments_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        adparm.optimal_cost(adparm.paper_config(), **kwargs)


def test_a_non_diagonal_R_is_refused_with_an_input_bound() -> None:
    config = adparm.paper_config()
    R = np.array([[1.0, 0.2], [0.2, 1.0]])
    config = config.updated({"cost": {"R": R, "Q": np.diag([40.0, 40.0, 1.0, 1.0])}})
    with pytest.raises(ValueError, match=r"cost\.R: an input bound needs it diagonal"):
        adparm.optimal_cost(config, input_bound=1.0)


def test_locked_joints_are_refused() -> None:
    config = adparm.Config.from_dict(
        {"plant": {"urdf": str(ARMS / "spatial_3dof.urdf"), "locked_joints": {"base_yaw": 0.3}}}
    )
    with pytest.raises(ValueError, match=r"plant\.locked_joints: optimal_cost does not"):
        adparm.optimal_cost(config)


def test_the_default_horizon_is_lengthened_past_the_active_limits() -> None:
    # the terminal cost x^T P x is the small-signal cost-to-go: the horizon leaves 12 LQR time
    # constants (default_horizon) after the last node where a limit is active
    config = adparm.paper_config()
    tail = adparm.truth.default_horizon(config)
    coarse = {"intervals": 100, "max_intervals": 100}
    best = adparm.optimal_cost(config, torque_limits=[25.0, 12.0], **coarse)
    assert best.active_until > 0.1
    assert best.horizon == pytest.approx(best.active_until + tail, rel=1e-6)
    assert best.terminal_share < 1e-9
    assert adparm.optimal_cost(config, **coarse).horizon == tail  # no limit: as before


def test_compare_widens_the_plant_limits_by_the_disturbance(monkeypatch) -> None:
    # plant.torque_limits comes with issue 24's plant limits; the comparison takes it where the
    # config has it, widened by |d|, so that J* bounds every row's J (u = h + tau_d - tau)
    from adparm import comparison, truth

    config = adparm.paper_config()
    calls = []
    monkeypatch.setattr(truth, "optimal_cost", lambda config, **kwargs: calls.append(kwargs))
    comparison._optimal_cost(config)
    assert "torque_limits" not in calls[-1] and calls[-1]["model"] is False
    object.__setattr__(config.plant, "torque_limits", (25.0, 12.0))
    comparison._optimal_cost(config)
    np.testing.assert_allclose(calls[-1]["torque_limits"], [25.1, 12.1])
