"""Issue 21's targets on every arm: given only [plant] urdf (the Panda: and its fingers locked), a
random cost of the exact family and weights 20 % off W*, a run learns W* (critic, actor and
policy within 1 %, verdict "ok"); an explicit step too coarse for the arm is refused before the
run, and every step a refusal or a divergence message suggests runs. The arms, costs and
configs are those of bench/every_arm.py, which measures the whole table (docs: URDF arms,
"Every arm, measured")."""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.rates import RK4_STABILITY_LIMIT, closed_loop_rates
from adparm.truth import divergence_causes

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import every_arm  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("every_arm")


def _target(name: str, folder: Path, index: int, **options) -> adparm.Config:
    if name not in every_arm.CHAINS:
        try:
            adparm.example_robot_urdf(name)
        except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
            pytest.skip("example-robot-data is not installed")
    rng = np.random.default_rng([0, index])
    return every_arm.target_config(every_arm.arm_plant(name, folder), rng, **options)


def _run_briefly(config: adparm.Config, dt: float) -> str:
    """200 steps: some 100 time constants of the fastest rate at a step "auto" would take."""
    brief = config.updated({"sim": {"dt": dt, "T": 200 * dt}})
    return adparm.simulate(brief, diagnose=False).status


def test_the_random_chains_are_physical_and_of_the_size_asked(folder: Path) -> None:
    for name, joints in every_arm.CHAINS.items():
        arm = adparm.UrdfArm(every_arm.arm_plant(name, folder)["urdf"])  # the physical checks
        assert arm.dof == joints
        rng = np.random.default_rng(joints)
        for _ in range(5):
            M = arm.terms(rng.uniform(-np.pi, np.pi, joints), np.zeros(joints))["M"]
            assert np.linalg.eigvalsh(M).min() > 0.0


def test_the_random_cost_is_of_the_exact_family_and_the_start_20_percent_off(folder) -> None:
    config = _target("chain4", folder, 0)
    W = adparm.optimal_weights(config)  # raises unless Q is of the exact family
    for key in ("critic_weights", "actor_weights"):
        start = np.asarray(getattr(config.init, key))
        assert np.linalg.norm(start - W) / np.linalg.norm(W) == pytest.approx(0.2)
    assert np.linalg.eigvalsh(np.array(config.cost.Q)).min() >= -1e-9
    assert not np.allclose(np.array(config.control.alpha1), 2.0 * np.eye(4))  # not the default
    assert config.sim.T == 10.0 and config.sim.dt <= 1e-3  # "auto"


@pytest.mark.parametrize("index", range(len(every_arm.ARMS)))
def test_a_too_coarse_step_is_refused_on_every_arm_and_the_suggestions_run(
    folder: Path, index: int
) -> None:
    """Before the run: a step at which the fastest rate is twice RK4's limit is refused naming
    sim.dt and a step that works; a step inside the limit but beyond the margin of "auto" is run,
    and the causes a divergence would list suggest a step: both suggested steps run."""
    name = every_arm.ARMS[index]
    config = _target(name, folder, index)
    fastest = max(entry["rate"] for entry in closed_loop_rates(config))
    coarse = config.updated({"sim": {"dt": 2.0 * RK4_STABILITY_LIMIT / fastest}})
    with pytest.raises(ValueError, match=r"^sim\.dt: .* too coarse") as error:
        adparm.simulate(coarse)
    suggested = float(re.search(r"Use sim\.dt = ([0-9.e-]+)", str(error.value)).group(1))
    assert suggested == config.sim.dt  # what "auto" picks
    assert _run_briefly(config, suggested) == "finished"
    near = config.updated({"sim": {"dt": 0.9 * RK4_STABILITY_LIMIT / fastest}})
    advice = next(cause for cause in divergence_causes(near) if "use sim.dt" in cause)
    step = float(re.search(r"use sim\.dt = ([0-9.e-]+)", advice).group(1))
    assert step < near.sim.dt
    assert _run_briefly(config, step) == "finished"


#: The arms whose full target run is in the suite (the table in the docs has them all), with the
#: simulated time: light and quick ones at the target's 10 s; the 6- and 7-joint arms take
#: 30-100 s each (bench/every_arm.py). The 5-joint chain ended 106 % off W* with the former
#: extrapolation box of 1 rad, the Z1 5.2 % off with the box that reached past its joint limits
#: (the symmetric box to the farther limit); with the derived range within its limits
#: (rates.extrapolation_range) it is within 1 % from 2.8 s, so 4 s prove it.
REPRESENTATIVE = {"chain3": 10.0, "chain4": 10.0, "chain5": 10.0, "finger_edu": 10.0, "z1": 4.0}


@pytest.mark.parametrize("name", REPRESENTATIVE)
def test_the_arm_learns_W_star_from_20_percent_off(folder: Path, name: str) -> None:
    T = REPRESENTATIVE[name]
    config = _target(name, folder, every_arm.ARMS.index(name), T=T)
    row = every_arm.measure(config)
    assert row["status"] == "finished", row["verdict"]
    assert row["verdict"] == "ok", row["verdict"]
    assert max(row["critic"], row["actor"], row["policy"]) < 0.01
    assert row["within"] is not None and row["within"] < T


def test_a_run_stopped_before_W_star_says_so(folder: Path) -> None:
    """The same run stopped at 0.2 s (it is within 1 % from about 0.5 s) is outside 1 %, and its
    verdict says which parts are."""
    config = _target("chain3", folder, every_arm.ARMS.index("chain3"), T=0.2)
    row = every_arm.measure(config)
    assert row["status"] == "finished" and not row["ok"]
    assert row["verdict"].startswith("ended away from the known W* (tolerance 0.01)")
    assert "critic ||Wc - W*|| / ||W*|| = " in row["verdict"]


def test_the_learning_defaults_of_a_urdf_arm_and_the_paper_s() -> None:
    """With extrapolation points a URDF arm derives critic.epsilon_T = 1e-5, actor.eta_a1 = 0 and
    actor.eta_a2 = 5 (rates.EPSILON_T_URDF, ETA_A2_URDF; the measurements of bench/every_arm.py),
    again on updated, and the probing values without points; given values are kept; the paper's
    config is untouched."""
    from adparm.rates import EPSILON_T_URDF, ETA_A2_URDF

    config = adparm.Config.from_dict({"plant": {"urdf": "examples/arms/planar_3link.urdf"}})
    learning = (config.critic.epsilon_T, config.actor.eta_a1, config.actor.eta_a2)
    assert learning == (EPSILON_T_URDF, 0.0, ETA_A2_URDF) == (1e-5, 0.0, 5.0)
    assert {"critic.epsilon_T", "actor.eta_a1", "actor.eta_a2"} <= set(config.derived)
    assert config.left_out_values()["critic.epsilon_T"][0] == EPSILON_T_URDF
    probing = config.updated({"extrapolation": {"points": 0}})
    assert (probing.resolved_epsilon_T, probing.actor.eta_a1, probing.actor.eta_a2) == (
        1e-6,
        0.01,
        1.0,
    )
    again = probing.updated({"extrapolation": {"points": 30}})
    assert (again.critic.epsilon_T, again.actor.eta_a1, again.actor.eta_a2) == (1e-5, 0.0, 5.0)
    given = config.updated(
        {"critic": {"epsilon_T": 1e-3}, "actor": {"eta_a1": 0.01, "eta_a2": 2.0}}
    )
    assert (given.critic.epsilon_T, given.actor.eta_a1, given.actor.eta_a2) == (1e-3, 0.01, 2.0)
    paper = adparm.paper_config()
    assert (paper.critic.epsilon_T, paper.actor.eta_a1, paper.actor.eta_a2) == (None, 0.01, 1.0)
    assert "actor.eta_a1" not in paper.derived and "actor.eta_a2" not in paper.derived


def _own_cost(name: str, seed: int, folder: Path) -> adparm.Config:
    """A user's first run with their own cost: the bench's random cost of the exact family for
    the seed (bench/every_arm.py --from-defaults), the default weights, sim.dt = "auto"."""
    rng = np.random.default_rng([seed, every_arm.ARMS.index(name)])
    return every_arm.target_config(every_arm.arm_plant(name, folder, seed), rng, off=None)


def _reset_window_change(text: str) -> dict:
    """The change reset_window_advice names: critic.epsilon_T = a and extrapolation.points = b."""
    found = re.search(
        r"lower critic\.epsilon_T to ([0-9.e+-]+) and extrapolation\.points to ([0-9]+): Gamma "
        r"was reset",
        text,
    )
    assert found, text
    return {"critic": {"epsilon_T": float(found[1])}, "extrapolation": {"points": int(found[2])}}


def _suggested(text: str) -> dict:
    """The change a message names: actor.eta_a2 = a and sim.T = b s, as an update."""
    found = re.search(
        r"actor\.eta_a2 = ([0-9.e+-]+) \(not [0-9.e+-]+\) and sim\.T = ([0-9.e+-]+) s", text
    )
    assert found, text
    return {"actor": {"eta_a2": float(found[1])}, "sim": {"T": float(found[2])}}


def test_a_divergence_from_an_actor_that_follows_an_unsettled_critic_names_a_change_that_works(
    folder: Path,
) -> None:
    """A random 6-joint chain with its own cost diverges at about 0.2 s from the default weights
    (its actor's policy, stable at every frozen instant, follows the critic's first, unsettled
    fits at 5/s); the message says so and names actor.eta_a2 = 0.5 with sim.T = 20 s, with which
    the same run ends "ok"."""
    config = _own_cost("chain6", 40, folder)
    assert config.actor.eta_a2 == 5.0 and config.sim.T == 10.0
    with pytest.raises(adparm.SimulationDiverged) as caught:
        adparm.simulate(config, diagnose=False)
    message = str(caught.value)
    assert "the actor followed the critic at actor.eta_a2 = 5/s before the critic's" in message
    change = _suggested(message)
    assert change == {"actor": {"eta_a2": 0.5}, "sim": {"T": 20.0}}
    result = adparm.simulate(config.updated(change))
    assert result.diagnostics["verdict"] == "ok", result.diagnostics["verdict"]
    # a slow actor is not told to be slower
    assert divergence_causes(config.updated(change), caught.value.result)[0].startswith(
        "the closed loop's rates"
    )


def test_a_non_stabilising_e2_block_names_a_change_that_works(folder: Path) -> None:
    """A random 7-joint chain with its own cost ends at a non-stabilising e2 block from the
    default weights; the advice (no longer "start from the default weights", which it did) names
    actor.eta_a2 = 0.5 with sim.T = 20 s and no longer run at the same rate, and that run ends
    "ok"."""
    config = _own_cost("chain7", 43, folder)
    diagnostics = adparm.simulate(config).diagnostics
    assert diagnostics["verdict"].startswith("ended at a non-stabilising solution")
    assert len(diagnostics["advice"]) == 1, diagnostics["advice"]
    assert diagnostics["advice"][0].endswith("the actor followed the critic before it settled")
    result = adparm.simulate(config.updated(_suggested(diagnostics["advice"][0])))
    assert result.diagnostics["verdict"] == "ok", result.diagnostics["verdict"]


def test_a_policy_taken_before_the_weights_settled_is_told_a_run_long_enough(folder) -> None:
    """The UR10 with its own cost (seed 46) from the default weights: at 10 s the weights are
    within 0.1 % of W*, but the policy's error, taken over the last second while they were still
    settling (within 1 % only from 8.9 s), is 1.2 %; the advice named sim.T = 10 s (the weights'
    own estimate) and now names 20 s, with which the run ends "ok"."""
    config = _own_cost("ur10", 46, folder)
    diagnostics = adparm.simulate(config, diagnose=False).diagnostics
    assert diagnostics["critic_relative_error"] < 0.01 > diagnostics["actor_relative_error"]
    assert diagnostics["policy_relative_error"] > 0.01
    found = re.search(
        r"the policy's error is taken over the last 10 % of the run \(from 9 s\)"
        r", while they were still settling: sim\.T = ([0-9.]+) s takes it after",
        " ".join(diagnostics["advice"]),
    )
    assert found, diagnostics["advice"]
    longer = adparm.simulate(config.updated({"sim": {"T": float(found[1])}}), diagnose=False)
    assert longer.diagnostics["verdict"] == "ok", longer.diagnostics["verdict"]


def test_learning_that_levels_off_while_gamma_is_reset_is_told_a_lower_epsilon_t(folder) -> None:
    """The Kinova with its own cost (seed 42) from the default weights: at 10 s it is told to run
    20 s (the two-point estimate cannot see that it levels off), and at 20 s its weights are still
    1.15 % from W* (under 2 % progress over the second half) while Gamma was reset about every
    0.55 s: the advice says that a longer run will not help and names critic.epsilon_T 10 times
    lower (1e-6: longer least-squares windows between resets), with which the run ends "ok"."""
    config = _own_cost("kinova", 42, folder).updated({"sim": {"T": 20.0}})
    assert config.critic.epsilon_T == 1e-5
    diagnostics = adparm.simulate(config, diagnose=False).diagnostics
    assert 0.01 < diagnostics["critic_relative_error"] < 0.02
    advice = " ".join(diagnostics["advice"])
    assert advice.startswith("a longer run will not help"), advice
    change = _reset_window_change(advice)
    assert change["critic"]["epsilon_T"] == pytest.approx(1e-6)
    assert change["extrapolation"]["points"] == 2 * config.extrapolation.points
    lower = adparm.simulate(config.updated(change))
    assert lower.diagnostics["verdict"] == "ok", lower.diagnostics["verdict"]


def test_a_lower_epsilon_t_alone_is_not_what_is_told(folder) -> None:
    """The Kinova with its own cost (seed 95) from the default weights levels off 1.6 % from W*
    while Gamma is reset over the second half. A lower critic.epsilon_T alone (the advice before)
    leaves it 1.68 % off with 1e-6 and with 1e-7 (and was then told 1e-7, then 1e-8); the advice
    now also doubles the extrapolation points, and with both the run ends "ok"."""
    config = _own_cost("kinova", 95, folder)
    diagnostics = adparm.simulate(config, diagnose=False).diagnostics
    assert 0.01 < diagnostics["critic_relative_error"] < 0.02
    advice = " ".join(diagnostics["advice"])
    assert advice.startswith("a longer run will not help"), advice
    lower = adparm.simulate(config.updated(_reset_window_change(advice)))
    assert lower.diagnostics["verdict"] == "ok", lower.diagnostics["verdict"]


def test_learning_that_crawls_while_gamma_is_reset_often_is_told_a_lower_epsilon_t(folder) -> None:
    """The xArm7 with its own cost (seed 58) from the default weights: Gamma is reset every 29 ms
    over the second half and the weights crawl (1.05 -> 1.02 relative to W*): besides "learning
    is slow", the advice names critic.epsilon_T = 1e-6, with which the run ends "ok"."""
    config = _own_cost("xarm7", 58, folder)
    diagnostics = adparm.simulate(config, diagnose=False).diagnostics
    advice = " ".join(diagnostics["advice"])
    assert advice.startswith("learning is slow"), advice
    lower = adparm.simulate(config.updated(_reset_window_change(advice)))
    assert lower.diagnostics["verdict"] == "ok", lower.diagnostics["verdict"]


def _tiago(file: str, locked: Callable[[Path], dict[str, float]]) -> adparm.Config:
    """TIAGo's arm from example-robot-data's `file`, the joints locked(urdf) held, run for 1 s."""
    try:
        urdf = adparm.example_robot_urdf(f"tiago_description/robots/{file}")
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")
    config = adparm.Config.from_dict(
        {"plant": {"urdf": str(urdf), "locked_joints": locked(urdf)}, "sim": {"T": 1.0}}
    )
    assert config.dof == 7
    return config


def _told_horizon(config: adparm.Config, start: str, pattern: str) -> float:
    """The sim.T the advice of `config`'s run names (its advice starts with `start`, the
    horizon is pattern's group); that horizon's run must end "ok"."""
    with pytest.warns(adparm.ApproximationWarning):
        advice = " ".join(adparm.simulate(config).diagnostics["advice"])
    assert advice.startswith(start), advice
    horizon = float(re.search(pattern, advice).group(1))
    longer = adparm.simulate(config.updated({"sim": {"T": horizon}}))
    assert longer.diagnostics["verdict"] == "ok", longer.diagnostics["verdict"]
    return horizon


def test_a_short_run_is_told_the_horizon_it_needs_not_a_change_of_learning() -> None:
    """TIAGo's arm (its base, torso and head locked) from its defaults, run for 1 s: its weights'
    error falls 0.88 -> 0.77 over the second half, so the tolerance needs sim.T = 50 s, more than
    20 times the run's. That is no sign of slow learning in a 1 s run (its 4 s and 10 s runs are
    told the same 50 s): it was told to change critic.epsilon_T and extrapolation.points; it is
    told to run longer (progress.LONGER_RUN_FLOOR), and with that horizon it ends "ok"."""
    joints = ("torso_lift_joint", "head_1_joint", "head_2_joint", "wheel_left_joint")
    locked = dict.fromkeys((*joints, "wheel_right_joint"), 0.0)
    config = _tiago("tiago_no_hand.urdf", lambda urdf: locked)
    assert _told_horizon(config, "run longer:", r"sim\.T = ([0-9.]+) s reaches") == 50.0


def test_a_run_that_ended_before_learning_started_is_told_a_longer_one() -> None:
    """TIAGo's arm with its hand (every other joint locked, 43 of 50): over its first second Gamma
    is reset 21 times and the weights' error barely moves (0.95 -> 0.94: under SETTLED_FALL, as
    a settled run's), then falls (0.03 at 6 s). A 1 s run was told "a longer run will not help";
    it is told "no progress yet" and ten times the horizon, with which it ends "ok"."""
    pin = pytest.importorskip("pinocchio")

    def all_but_the_arm(urdf: Path) -> dict[str, float]:  # at 0, or the limit nearest to it
        model = pin.buildModelFromUrdf(str(urdf))
        locked = {}
        for joint in range(1, model.njoints):
            name, iq = model.names[joint], model.idx_qs[joint]
            if not name.startswith("arm_"):
                low, high = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
                locked[name] = float(min(max(0.0, low), high)) if model.nqs[joint] == 1 else 0.0
        return locked

    config = _tiago("tiago.urdf", all_but_the_arm)
    start, pattern = "run longer: no progress yet", r"sim\.T = ([0-9.]+) s shows"
    assert _told_horizon(config, start, pattern) == 10.0
