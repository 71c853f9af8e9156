"""Arm-aware defaults, sim.dt = "auto" and the stiffness check before the run (adparm.rates)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.rates import AUTO_MARGIN, RK4_STABILITY_LIMIT, closed_loop_rates, inertia_range

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

PLANAR = "examples/arms/planar_3link.urdf"


def _example(name: str) -> str:
    try:
        adparm.example_robot_urdf(name)
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")
    return f"example-robot-data:{name}"


def _bare(urdf: str, **sections: dict) -> adparm.Config:
    return adparm.Config.from_dict({"plant": {"urdf": urdf}, **sections})


@pytest.mark.parametrize("name", ["ur3", "ur10", "double_pendulum"])
def test_a_bare_urdf_arm_runs_from_the_defaults(name: str) -> None:
    # before: the UR3, UR10 and double pendulum diverged within 1-5 ms with only plant.urdf set
    config = _bare(_example(name), sim={"T": 0.3})
    for entry in closed_loop_rates(config):
        assert entry["rate"] * config.sim.dt <= AUTO_MARGIN * RK4_STABILITY_LIMIT + 1e-12
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    assert np.all(np.isfinite(result.critic_weights))


def test_defaults_follow_the_rule_of_the_docs() -> None:
    config = _bare(PLANAR)
    smallest, _ = inertia_range(config.plant.urdf)
    n = config.dof
    gain = max(30.0 * smallest, min(1.0, 1000.0 * smallest))
    assert config.control.ks == pytest.approx(gain - 1.0)
    # no cost given: R = diag(1 / (10 M_ii(qd))), K = alpha / 2 R^-1, Q of the exact family
    M = adparm.optimal.inertia_matrices(config, [config.task.qd], model=True)[0]
    assert np.allclose(config.cost.R, np.diag(1.0 / (10.0 * np.diag(M))))
    Q = np.array(config.cost.Q)
    assert np.allclose(-Q[:n, n:], np.linalg.inv(config.cost.R))  # alpha = 2
    adparm.optimal_weights(config)
    # the actor's ball holds W*, and the e2 margin lies well below the arm's inertia
    assert config.actor.weight_bound >= 10.0 * np.linalg.norm(adparm.optimal_weights(config))
    assert config.actor.e2_margin == pytest.approx(0.1 * smallest)
    assert config.extrapolation.points == 2 * config.basis_size
    assert config.probe.until == 0.0
    assert config.sim.T == 10.0
    for key in ("control.ks", "cost.R", "cost.Q", "sim.dt", "extrapolation.points"):
        assert key in config.derived
    # the written config holds the derived values and reads back to the same run
    again = adparm.Config.from_dict(tomllib.loads(config.to_toml()))
    assert again == config
    assert "ks" in config.to_dict()["control"]


def test_the_derived_box_spans_the_joint_range() -> None:
    """extrapolation.centre and .box (rates.extrapolation_range): per joint, e1 = qd - q spans the
    joint's range within its limits, at most pi each way from qd, at least 1 rad wide; e2 centred
    at 0, alpha1 times the farther end; derived again for a new alpha1; a given box is kept (and
    then centred on qd unless a centre is given too). The rates are taken where the plant moves
    (within max(1, 2 |e1(0)|) of qd), not over the whole box."""
    from adparm.rates import extrapolation_range, rate_positions

    config = _bare(PLANAR)
    n = config.dof
    limits = adparm.urdf.config_arm(config).limits
    low, high = np.asarray(limits["lower"]), np.asarray(limits["upper"])
    qd = np.asarray(config.task.qd, dtype=float)
    lower = np.maximum(qd - high, -np.pi)
    upper = np.minimum(qd - low, np.pi)
    centre, box = config.extrapolation.centre_vector(n), config.extrapolation.box_vector(n)
    assert np.allclose(centre[:n], (lower + upper) / 2) and np.all(centre[n:] == 0.0)
    assert np.allclose(box[:n], (upper - lower) / 2)
    reach = np.maximum(np.abs(lower), np.abs(upper))
    assert np.allclose(box[n:], 2.0 * reach)  # alpha1 = 2 I
    # the points' joint positions qd - e1 stay within the limits
    assert np.all(qd - (centre[:n] + box[:n]) >= low - 1e-12)
    assert np.all(qd - (centre[:n] - box[:n]) <= high + 1e-12)
    assert "extrapolation.box" in config.derived and "extrapolation.centre" in config.derived
    assert "extrapolation_range" in config.derived["extrapolation.box"]
    faster = config.updated({"control": {"alpha1": (3.0 * np.eye(n)).tolist()}})
    assert np.allclose(faster.extrapolation.box_vector(n)[n:], 3.0 * reach)
    given = config.updated({"extrapolation": {"box": 0.5}})
    assert np.allclose(given.extrapolation.box_vector(n), 0.5)
    assert np.all(given.extrapolation.centre_vector(n) == 0.0)
    positions = rate_positions(config)
    assert np.abs(positions - qd).max() <= max(1.0, 2 * np.abs(qd - config.task.q0).max())
    # a joint with qd on a limit, one in the middle, an unlimited one, a narrow one
    qd, q0 = np.zeros(4), np.array([0.1, 0.0, 0.0, 0.0])
    low, high = np.array([0.0, -1.5, -np.inf, -0.2]), np.array([3.0, 1.5, np.inf, 0.3])
    centre, box = extrapolation_range(qd, q0, low, high, 2.0 * np.eye(4))
    lo, hi = centre[:4] - box[:4], centre[:4] + box[:4]
    # e1 = qd - q: joint 0 spans q in [0, 3] (e1 in [-3, 0.1]: e1(0) = -0.1... held, and 0)
    assert np.allclose(lo, [-3.0, -1.5, -np.pi, -0.55]) and np.allclose(hi, [0.0, 1.5, np.pi, 0.45])


def test_the_box_rule_stays_within_the_limits() -> None:
    """rates.extrapolation_box: b1_i = max(1, 2 max|qd - q0|, min(pi, qd_i - low_i, high_i - qd_i))
    (the nearer limit, not the farther: the Z1's qd sits on three limits), b2 = max|alpha1| b1."""
    from adparm.rates import extrapolation_box

    qd, q0 = np.array([0.0, 0.5, 0.0, 0.0, 0.0, 0.0]), np.array([0.1, 0.5, 0.0, 0.0, 0.0, 0.0])
    low = np.array([0.0, -1.0, -2.0, -np.inf, np.nan, -0.2])
    high = np.array([3.0, 2.0, 5.0, np.inf, 1.5, 0.3])
    alpha1 = np.diag([2.0, 3.0, 1.0, 1.0, 1.0, 1.0])
    b1, b2 = extrapolation_box(qd, q0, low, high, alpha1)
    # qd on a limit: the floor 1 (not the 3 rad to the far limit); qd in the middle: 1.5 to
    # either limit; 2 rad to the nearer of 2 and 5; unlimited (inf or nan): pi; one limit
    # missing: the other's 1.5; a short range: the floor
    assert np.allclose(b1, [1.0, 1.5, 2.0, np.pi, 1.5, 1.0])
    assert np.allclose(b2, 3.0 * b1)
    # the floor grows with the initial error: 2 max|qd - q0| = 2 x 0.9 = 1.8 rad
    b1, _ = extrapolation_box(qd, q0 + np.array([0.8, 0, 0, 0, 0, 0]), low, high, alpha1)
    assert np.allclose(b1, [1.8, 1.8, 2.0, np.pi, 1.8, 1.8])
    # far limits on both sides: capped at pi
    far = np.full(1, 9.0)
    b1, _ = extrapolation_box(np.zeros(1), np.zeros(1), -far, far, np.eye(1))
    assert np.allclose(b1, [np.pi])
    # the Z1 with qd = 0 (on the limit of three joints; its default qd is 0.4 rad inside): the
    # symmetric box stays within the limits, but on those three joints, which get the floor
    # (its derived box is extrapolation_range's)
    z1 = _bare(_example("z1"), task={"qd": [0.0] * 7})
    limits = adparm.urdf.config_arm(z1).limits
    low, high = np.asarray(limits["lower"]), np.asarray(limits["upper"])
    qd, q0 = np.asarray(z1.task.qd, dtype=float), np.asarray(z1.task.q0, dtype=float)
    b1, _ = extrapolation_box(qd, q0, low, high, np.asarray(z1.control.alpha1, dtype=float))
    on_a_limit = (qd == low) | (qd == high)
    assert on_a_limit.sum() == 3 and np.all(b1[on_a_limit] == 1.0)
    inside = (qd - b1 >= low - 1e-12) & (qd + b1 <= high + 1e-12)
    assert np.all(inside[~on_a_limit])


def test_ks_below_zero_only_for_arms_so_light_that_a_gain_of_1_is_stiff() -> None:
    """control.ks = max(30 lambda_min, min(1, 1000 lambda_min)) - 1: the SO-101's wrist
    (lambda_min ~ 1.3e-5 kg m^2) gets -1 < ks < 0 and RISE acting at 1000/s (the step 1 ms); an
    arm with lambda_min >= 1e-3 keeps ks >= 0. ks > -1 is accepted by the schema and the core,
    -1 refused by both, naming control.ks."""
    from adparm.rates import rise_ks

    assert rise_ks(1.0) == pytest.approx(29.0)
    assert rise_ks(0.01) == 0.0 and rise_ks(1e-3) == 0.0
    assert rise_ks(1e-5) == pytest.approx(-0.99)
    so101 = _bare(_example("so101"))
    smallest, _ = inertia_range(adparm.example_robot_urdf("so101"))
    assert -1.0 < so101.control.ks < 0.0
    assert (so101.control.ks + 1.0) / smallest == pytest.approx(1000.0)
    assert "below the paper's ks >= 0" in so101.derived["control.ks"]
    assert so101.sim.dt == 1e-3
    brief = so101.updated({"sim": {"T": 0.2}})
    assert adparm.simulate(brief, diagnose=False).status == "finished"
    with pytest.raises(ValueError, match=r"^control\.ks: must be > -1"):
        so101.updated({"control": {"ks": -1.0}})
    from adparm.simulation import core_settings

    settings = core_settings(brief)
    control = settings.control  # pybind11 copies nested structs: change and assign back
    rise = control.rise
    rise.ks = -1.0
    control.rise = rise
    settings.control = control
    with pytest.raises(ValueError, match=r"^control\.ks: must be a finite number > -1"):
        adparm._core.Simulation(settings)


def test_the_paper_keeps_its_values() -> None:
    config = adparm.paper_config()
    assert config.sim.dt == 1e-3 and config.control.ks == 10.0 and config.sim.T == 150.0
    assert config.derived == {}
    assert np.allclose(config.cost.R, 0.25 * np.eye(2))


def test_a_two_joint_urdf_arm_is_not_given_the_papers_values() -> None:
    config = _bare(_example("double_pendulum"))
    assert not np.allclose(config.cost.R, 0.25 * np.eye(2))
    assert config.probe.amplitude != (71.0, 23.0)
    assert config.control.ks != 10.0 or "control.ks" in config.derived
    adparm.optimal_weights(config)  # an exact-family cost, consistent with its own R


def test_explicit_values_are_kept_and_a_given_q_keeps_r_at_identity() -> None:
    n = 3
    Q = adparm.solvable_cost(np.eye(n), 2.0 * np.eye(n), np.eye(n))
    config = _bare(PLANAR, control={"ks": 10.0}, cost={"Q": Q.tolist()}, sim={"dt": 2e-4})
    assert config.control.ks == 10.0 and config.sim.dt == 2e-4
    assert np.allclose(config.cost.R, np.eye(n))
    assert "control.ks" not in config.derived and "sim.dt" not in config.derived
    # a later update keeps them; "auto" hands the step back to the rule
    later = config.updated({"critic": {"eta_c": 400.0}})
    assert later.control.ks == 10.0 and later.sim.dt == 2e-4
    assert "sim.dt" in later.updated({"sim": {"dt": "auto"}}).derived


def test_auto_on_the_two_link_arm() -> None:
    config = adparm.paper_config().updated({"sim": {"dt": "auto"}})
    assert config.sim.dt == 1e-3  # the paper's loop is well inside RK4's region
    stiff = config.updated({"control": {"ks": 2000.0}, "sim": {"dt": "auto"}})
    assert stiff.sim.dt < 1e-3
    for entry in closed_loop_rates(stiff):
        assert entry["rate"] * stiff.sim.dt <= AUTO_MARGIN * RK4_STABILITY_LIMIT


def _suggested_dt(message: str) -> float:
    match = re.search(r"Use sim\.dt = ([0-9.e-]+)", message)
    assert match, message
    return float(match.group(1))


@pytest.mark.parametrize(
    ("urdf", "changes", "term"),
    [
        (PLANAR, {"critic": {"eta_c": 800.0}, "sim": {"dt": 2.5e-3}}, "critic"),
        ("ur10", {"sim": {"dt": 2e-3}}, "RISE"),
        (None, {"control": {"ks": 3000.0}, "sim": {"dt": 1e-3}}, "RISE"),
    ],
)
def test_a_too_coarse_step_is_refused_and_the_suggestion_runs(
    urdf: str | None, changes: dict, term: str
) -> None:
    if urdf is None:
        config = adparm.paper_config().updated(changes)
    else:
        config = _bare(urdf if urdf == PLANAR else _example(urdf), **changes)
    with pytest.raises(ValueError, match=r"^sim\.dt: .* too coarse") as error:
        adparm.simulate(config)
    message = str(error.value)
    assert term in message and "/s" in message
    fixed = config.updated({"sim": {"dt": _suggested_dt(message), "T": 0.2}})
    assert adparm.simulate(fixed, diagnose=False).status == "finished"


def test_the_refusal_comes_before_the_run_in_the_cli(tmp_path) -> None:
    from adparm.cli import main

    path = tmp_path / "run.toml"
    path.write_text(f'[plant]\nurdf = "{Path(PLANAR).resolve()}"\n[sim]\ndt = 0.01\n')
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    assert not (tmp_path / "out" / "result.npz").exists()


def test_the_verdict_covers_the_policy() -> None:
    # the critic starts at W* and stays there; the actor is frozen 20 % off: not "ok"
    config = adparm.paper_config().updated({"sim": {"T": 2.0}})
    w_star = adparm.optimal_weights(config)
    frozen = config.updated(
        {
            "init": {"critic_weights": w_star.tolist(), "actor_weights": (1.2 * w_star).tolist()},
            "actor": {"eta_a1": 0.0, "eta_a2": 0.0},
            "probe": {"until": 0.0},
            "extrapolation": {"points": 16},
        }
    )
    diagnostics = adparm.simulate(frozen).diagnostics
    assert diagnostics["critic_relative_error"] < 0.01
    assert diagnostics["actor_relative_error"] == pytest.approx(0.2)
    assert diagnostics["policy_relative_error"] > 0.01
    assert diagnostics["verdict"] != "ok"
    assert "actor" in diagnostics["verdict"] and "policy" in diagnostics["verdict"]


def test_the_policy_error_uses_the_recorded_input() -> None:
    from adparm.optimal import policy

    config = adparm.load_config("examples/planar_3link.toml").updated({"sim": {"T": 0.5}})
    result = adparm.simulate(config, diagnose=False)
    x = np.hstack([result.e1, result.e2])
    u = policy(config, x, result.t, result.actor_weights)
    assert np.allclose(u, result.u_hat, rtol=1e-10, atol=1e-10 * np.abs(result.u_hat).max())


def test_the_default_tolerance_is_one_percent() -> None:
    assert adparm.Config().diagnostics.tolerance == 0.01
    with pytest.raises(ValueError, match=r"diagnostics\.tolerance"):
        adparm.Config.from_dict({"diagnostics": {"tolerance": 1.5}})


def _random_exact_cost(urdf: str, seed: int) -> tuple[adparm.Config, np.random.Generator]:
    """Only plant.urdf and a random cost of the exact family (random K, alpha1, R)."""
    rng = np.random.default_rng(seed)
    n = _bare(urdf).dof
    A = rng.normal(size=(n, n))
    K = 0.2 * (A @ A.T / n + 0.5 * np.eye(n))
    alpha1, R = np.diag(rng.uniform(1, 3, n)), np.diag(rng.uniform(0.5, 2, n))
    config = _bare(
        urdf,
        cost={"Q": adparm.solvable_cost(K, alpha1, R).tolist(), "R": R.tolist()},
        control={"alpha1": alpha1.tolist()},
    )
    return config, rng


@pytest.mark.parametrize("seed", [0, 4])
def test_a_random_cost_is_learned_from_weights_20_percent_off(seed: int) -> None:
    # initial weights 20 % off W* (random signs) whose e2 block is positive definite: an
    # admissible first policy (the theory's assumption); verdict "ok" needs critic, actor and
    # policy within 1 % after the default T = 10 s
    from adparm.truth import initial_actor_e2_block

    config, rng = _random_exact_cost(PLANAR, seed)
    w_star = adparm.optimal_weights(config)
    start = (w_star * (1 + 0.2 * rng.choice([-1, 1], size=w_star.size))).tolist()
    config = config.updated({"init": {"critic_weights": start, "actor_weights": start}})
    assert initial_actor_e2_block(config)["min_eigenvalue"] > 0.0
    diagnostics = adparm.simulate(config).diagnostics
    assert diagnostics["verdict"] == "ok", diagnostics["verdict"]


def test_an_inadmissible_start_is_lifted_by_the_projection_or_named() -> None:
    # seed 3 draws 20 %-off weights whose e2 block is indefinite at qd: actor.positive_e2 (the
    # default) lifts the block back to the margin and learning ends at W*; without it the run
    # ends at a non-stabilising solution, and the verdict says so
    from adparm.truth import initial_actor_e2_block

    config, rng = _random_exact_cost(PLANAR, 3)
    w_star = adparm.optimal_weights(config)
    start = (w_star * (1 + 0.2 * rng.choice([-1, 1], size=w_star.size))).tolist()
    # the learning of the former defaults (actor.eta_a2 = 1, a box of 1 rad on e1): with the
    # derived ones (eta_a2 = 5, the box over the joint range) this run reaches W* even unprojected
    alpha = float(np.abs(np.linalg.eigvals(np.array(config.control.alpha1))).max())
    config = config.updated(
        {
            "init": {"critic_weights": start, "actor_weights": start},
            "actor": {"eta_a2": 1.0},
            "extrapolation": {"box": [1.0] * config.dof + [alpha] * config.dof},
        }
    )
    assert initial_actor_e2_block(config)["min_eigenvalue"] < 0.0
    assert adparm.simulate(config).diagnostics["verdict"] == "ok"
    unprojected = config.updated({"actor": {"positive_e2": False}})
    try:
        verdict = adparm.simulate(unprojected).diagnostics["verdict"]
    except adparm.SimulationDiverged as error:
        verdict = str(error)
    assert "not positive definite" in verdict


def test_a_divergence_suggests_only_what_works_and_is_not_in_effect() -> None:
    from adparm.truth import divergence_causes

    # the critic at 1600/s (extrapolation) with dt = 1.5 ms: inside RK4's limit (not refused) but
    # near it, so a divergence would name the step; the step it names finishes
    near = adparm.paper_config().updated(
        {"extrapolation": {"points": 10}, "sim": {"dt": 1.5e-3, "T": 0.5}}
    )
    causes = divergence_causes(near)
    suggestion = next(cause for cause in causes if "use sim.dt" in cause)
    dt = float(re.search(r"use sim\.dt = ([0-9.e-]+)", suggestion).group(1))
    assert dt < 1.5e-3
    assert adparm.simulate(near.updated({"sim": {"dt": dt}}), diagnose=False).status == "finished"
    # at the paper's step nothing is suggested for the step, and weights left out are not
    # suggested to be left out
    causes = divergence_causes(adparm.paper_config())
    assert not any("use sim.dt" in cause or "leave init" in cause for cause in causes)
    assert any("rates at the start" in cause for cause in causes)


def test_the_asymmetric_range_spans_the_joint_range_within_the_limits() -> None:
    """rates.extrapolation_range: with e1 = qd - q, e1_i in [max(qd_i - high_i, -pi),
    min(qd_i - low_i, pi)], holding 0 and e1_i(0), at least 1 rad wide; e2 symmetric,
    max|alpha1| max(|lo_i|, |hi_i|)."""
    from adparm.rates import extrapolation_range

    qd, q0 = np.array([0.0, 0.5, 0.0, 0.0, 0.0, 0.0]), np.array([0.1, 0.5, 0.0, 0.0, 0.0, 0.0])
    low = np.array([0.0, -1.0, -2.0, -np.inf, np.nan, -0.2])
    high = np.array([3.0, 2.0, 5.0, np.inf, 1.5, 0.3])
    alpha1 = np.diag([2.0, 3.0, 1.0, 1.0, 1.0, 1.0])
    centre, box = extrapolation_range(qd, q0, low, high, alpha1)
    lower, upper = centre[:6] - box[:6], centre[:6] + box[:6]
    # qd on the lower limit: q in [0, 3] is e1 in [-3, 0] (e1(0) = -0.1 inside); qd in the
    # middle: [-1.5, 1.5]; 5 rad away capped at pi; unlimited (inf or nan): pi each way; a
    # 0.5 rad range widened about its middle to 1 rad
    assert np.allclose(lower, [-3.0, -1.5, -np.pi, -np.pi, -1.5, -0.55])
    assert np.allclose(upper, [0.0, 1.5, 2.0, np.pi, np.pi, 0.45])
    assert np.allclose(centre[6:], 0.0)
    assert np.allclose(box[6:], 3.0 * np.maximum(np.abs(lower), np.abs(upper)))
    # the points' joint positions q = qd - e1 stay within the limits where the range allows
    q_low, q_high = qd - upper, qd - lower
    assert np.all(q_low[:5] >= np.nan_to_num(low[:5], nan=-np.inf) - 1e-12)
    assert np.all(q_high[:5] <= np.nan_to_num(high[:5], nan=np.inf) + 1e-12)
    # an initial error outside the range widens it to hold e1(0) = qd - q0
    start = q0 + np.array([4.0, 0, 0, 0, 0, 0])
    centre, box = extrapolation_range(qd, start, low, high, alpha1)
    assert np.isclose(centre[0] - box[0], -4.1) and np.isclose(centre[0] + box[0], 0.0)


def test_the_pd_baseline_of_a_urdf_arm_acts_at_the_policys_rate() -> None:
    # kd = diag(10 M_ii(qd)), kp = 5 kd: the two-link 50 and 10 acted through M^-1 at 35,700/s
    # on the Z1's wrist (sim.dt = "auto" chose 2e-5 s); derived, the step is 1 ms and the arm
    # settles (|e1| from 0.1 to about 0.002 rad in 2 s)
    try:
        adparm.example_robot_urdf("z1")
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")
    plant = {"urdf": "example-robot-data:z1"}
    config = adparm.Config.from_dict(
        {"plant": plant, "controller": {"kind": "pd"}, "sim": {"T": 2}}
    )
    M = adparm.dynamics.inertia_matrices(config, np.array([config.task.qd]), model=True)[0]
    np.testing.assert_array_equal(np.array(config.controller.kd), np.diag(10.0 * np.diag(M)))
    np.testing.assert_array_equal(
        np.array(config.controller.kp), 5.0 * np.array(config.controller.kd)
    )
    assert {"controller.kd", "controller.kp"} <= set(config.derived)
    assert config.sim.dt == 1e-3
    result = adparm.simulate(config)
    assert np.abs(result.e1[0]).max() == pytest.approx(0.1) and np.abs(result.e1[-1]).max() < 0.01
    given = config.updated({"controller": {"kp": 50.0, "kd": 10.0}, "sim": {"dt": "auto"}})
    assert given.controller.kd == 10.0 and given.sim.dt < 1e-4  # as the user asks
