"""URDF arms with their structured basis in the closed loop (the default basis of a URDF arm).

Under the exact-solution conditions (Q11 = K alpha1 + alpha1^T K, Q12 = -K, Q22 = R^-1) the value
V* = e1^T K e1 + e2^T M(q) e2 solves the HJB exactly on any arm, so its weights W* = [K entries;
the arm's base inertial parameters] are known: the HJB error of the core's loop vanishes there
to round-off, and a run that learns must reach them. A run that cannot (too few extrapolation
points, a policy too fast for the step) says why."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import adparm
from adparm.truth import (
    divergence_causes,
    extrapolation_shortfall,
    structured_e2_block_min_eigenvalue,
)

ROOT = Path(__file__).resolve().parents[1]
ARMS = ROOT / "examples" / "arms"
PLANAR = ARMS / "planar_3link.urdf"
SPATIAL = ARMS / "spatial_3dof.urdf"
TWO_LINK = ARMS / "two_link.urdf"


def _ur5() -> Path:
    try:
        return adparm.example_robot_urdf("ur5")
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")


def _arm(name: str) -> Path:
    return {"planar": PLANAR, "spatial": SPATIAL}.get(name) or _ur5()


def _random_cost(rng: np.random.Generator, n: int) -> dict:
    """A random cost of the exact family: K and R symmetric positive definite, alpha1 = K^-1 N
    with N + N^T positive definite (so -alpha1 is Hurwitz and Q11 = N + N^T), R small enough
    that Q = [[Q11, -K], [-K, R^-1]] is positive semidefinite."""
    A = rng.normal(size=(n, n))
    K = A @ A.T / n + 0.5 * np.eye(n)
    B = rng.normal(size=(n, n))
    N = B @ B.T / n + np.eye(n) + 0.3 * (B - B.T)
    alpha1 = np.linalg.solve(K, N)
    Q11 = N + N.T
    r = 0.5 * np.linalg.eigvalsh(Q11).min() / np.linalg.eigvalsh(K).max() ** 2
    R = r * (np.eye(n) + 0.1 * np.diag(rng.uniform(0.0, 1.0, n)))
    Q = adparm.solvable_cost(K, alpha1, R)
    assert np.linalg.eigvalsh(Q).min() >= -1e-12
    return {"K": K, "alpha1": alpha1, "R": R, "Q": Q}


def _config(urdf: Path, cost: dict, **sections: dict) -> adparm.Config:
    data = {
        "plant": {"urdf": str(urdf)},
        "cost": {"Q": cost["Q"].tolist(), "R": cost["R"].tolist()},
        "control": {"alpha1": cost["alpha1"].tolist()},
    }
    for name, values in sections.items():
        data[name] = {**data.get(name, {}), **values}
    return adparm.Config.from_dict(data)


@pytest.mark.parametrize("arm", ["planar", "spatial", "ur5"])
def test_hjb_error_of_the_loop_vanishes_at_W_star(arm: str, rng) -> None:
    urdf = _arm(arm)
    n = adparm.UrdfArm(urdf).dof
    cost = _random_cost(rng, n)
    qd = {
        "kind": "sinusoid",  # a moving qd: the basis' desired rate enters the HJB error
        "amplitude": rng.uniform(0.2, 0.6, n).tolist(),
        "frequency": rng.uniform(0.5, 2.0, n).tolist(),
        "offset": rng.uniform(-0.5, 0.5, n).tolist(),
    }
    config = _config(urdf, cost, task={"q0": [0.0] * n, "qd": qd})
    assert config.controller.basis == "structured"
    W = adparm.optimal_weights(config)
    assert W.size == len(adparm.basis_names(config)) == config.basis_size
    x = rng.uniform(-1.0, 1.0, (40, 2 * n))
    scale = np.einsum("mi,ij,mj->m", x, cost["Q"], x)
    for t in (0.0, 0.7):
        residual = adparm.hjb_residual(config, x, W, W, t=t)
        assert np.abs(residual / scale).max() < 1e-10
    # the check can fail: 1 % off W* in one weight leaves a residual far above round-off
    off = W.copy()
    off[-1] += 0.01 * np.abs(W).max()
    assert np.abs(adparm.hjb_residual(config, x, off, off, t=0.7) / scale).max() > 1e-6


@pytest.mark.parametrize("arm", ["planar", "spatial", "ur5"])
def test_optimal_value_is_e1_K_e1_plus_e2_M_e2(arm: str, rng) -> None:
    urdf = _arm(arm)
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    n = model.nv
    cost = _random_cost(rng, n)
    qd = rng.uniform(-1.0, 1.0, n)
    config = _config(urdf, cost, task={"q0": [0.0] * n, "qd": qd.tolist()})
    for _ in range(5):
        x = rng.uniform(-1.0, 1.0, 2 * n)
        e1, e2 = x[:n], x[n:]
        q = qd - e1
        configuration = pin.neutral(model)
        for j in range(1, model.njoints):  # continuous joints store (cos, sin)
            i = model.joints[j].idx_q
            if model.joints[j].nq == 2:
                configuration[i : i + 2] = np.cos(q[j - 1]), np.sin(q[j - 1])
            else:
                configuration[i] = q[j - 1]
        M = pin.crba(model, data, configuration)
        M = np.triu(M) + np.triu(M, 1).T
        expected = e1 @ cost["K"] @ e1 + e2 @ M @ e2
        assert adparm.optimal_value(config, x) == pytest.approx(expected, rel=1e-12)


def _learning_run(urdf: Path, cost: dict, init: np.ndarray | None, T: float) -> tuple:
    n = adparm.UrdfArm(urdf).dof
    sections = {
        "task": {"q0": [0.2, -0.3, 0.1][:n], "qd": [0.5, 0.1, -0.2][:n]},
        "probe": {"until": 0.0},  # no probing: Bellman-error extrapolation only
        "extrapolation": {"points": 50, "box": 1.0, "mode": "fixed"},
        "sim": {"T": T},
    }
    if init is not None:
        sections["init"] = {"critic_weights": init.tolist(), "actor_weights": init.tolist()}
    config = _config(urdf, cost, **sections)
    result = adparm.simulate(config)
    W = adparm.optimal_weights(config)
    error = np.linalg.norm(result.critic_weights - W, axis=1) / np.linalg.norm(W)
    return result, error


def test_planar_3link_learns_W_star_from_the_default_weights(rng) -> None:
    """Default initial weights: K = I and the believed model's base parameters; the cost's K is
    random, so the critic has the e1 block to learn; within 1 % of W* by t = 20 s."""
    result, error = _learning_run(PLANAR, _random_cost(rng, 3), None, 20.0)
    assert result.status == "finished"
    assert error[0] > 0.05  # there is something to learn
    assert error[-1] < 0.01
    assert result.diagnostics["verdict"] == "ok"
    assert result.diagnostics["critic_relative_error"] < 0.01
    assert result.diagnostics["e2_block_min_eigenvalue"] > 0.0  # a stabilising solution


def test_the_e2_block_of_structured_weights_is_the_inertia(rng) -> None:
    """At W* the e2 block sum_b W_b M_b(q) is M(q): its least eigenvalue over the sampled
    positions is that of M; the negated weights give a negative one (not stabilising)."""
    config = _config(PLANAR, _random_cost(rng, 3), task={"qd": [0.5, 0.1, -0.2]})
    W = adparm.optimal_weights(config)
    e1 = rng.uniform(-1.0, 1.0, (20, 3))
    arm = adparm.UrdfArm(PLANAR)
    expected = min(
        np.linalg.eigvalsh(arm.terms(np.array([0.5, 0.1, -0.2]) - row, np.zeros(3))["M"]).min()
        for row in e1
    )
    assert structured_e2_block_min_eigenvalue(config, W, e1) == pytest.approx(expected, rel=1e-9)
    assert structured_e2_block_min_eigenvalue(config, -W, e1) < 0.0


@pytest.mark.parametrize("seed", [0, 1])
def test_planar_3link_learns_W_star_from_20_percent_off(seed: int) -> None:
    rng = np.random.default_rng(seed)
    cost = _random_cost(rng, 3)
    W = adparm.optimal_weights(_config(PLANAR, cost))
    init = W * (1.0 + rng.uniform(-0.2, 0.2, W.size))
    result, error = _learning_run(PLANAR, cost, init, 20.0)
    assert result.status == "finished"
    assert error[0] > 0.02 and error[-1] < 0.01


def test_spatial_3_joint_arm_learns_W_star_from_20_percent_off(rng) -> None:
    cost = _random_cost(rng, 3)
    W = adparm.optimal_weights(_config(SPATIAL, cost))
    assert W.size == 19  # 6 products e1_i e1_j and 13 base parameters
    init = W * (1.0 + rng.uniform(-0.2, 0.2, W.size))
    result, error = _learning_run(SPATIAL, cost, init, 10.0)
    assert result.status == "finished" and error[-1] < 0.01


def _paper_on_the_two_link_urdf(**sections: dict) -> adparm.Config:
    """The paper's instance with its plant read from examples/arms/two_link.urdf (gravity 9.8
    as printed, F = -0.1 sgn(dq))."""
    data = adparm.paper_config().to_dict()
    data["plant"] = {
        "urdf": str(TWO_LINK),
        "gravity": [0.0, 0.0, -9.8],
        "coulomb": -0.1,
        "disturbance": list(data["plant"]["disturbance"]),
    }
    data.pop("model", None)
    data.get("controller", {}).pop("basis", None)
    data.pop("init", None)
    for name, values in sections.items():
        data[name] = {**data.get(name, {}), **values}
    return adparm.Config.from_dict(data)


def test_the_paper_instance_on_the_two_link_urdf_has_the_paper_s_V_star(rng) -> None:
    """The structured basis of the two-link URDF represents the paper's V* (the same values as
    the built-in arm's W*), and a learning run from the default weights reaches it by 10 s."""
    config = _paper_on_the_two_link_urdf()
    paper = adparm.paper_config()
    assert config.dof == 2 and config.controller.basis == "structured"
    for _ in range(5):
        x = rng.uniform(-1.0, 1.0, 4)
        assert adparm.optimal_value(config, x) == pytest.approx(
            adparm.optimal_value(paper, x), rel=1e-12
        )
    run = _paper_on_the_two_link_urdf(
        probe={"until": 0.0},
        extrapolation={"points": 50, "box": 1.0, "mode": "fixed"},
        sim={"T": 10.0},
    )
    W = adparm.optimal_weights(run)
    init = W * (1.0 + np.random.default_rng(5).uniform(-0.2, 0.2, W.size))
    result = adparm.simulate(
        run.updated({"init": {"critic_weights": init.tolist(), "actor_weights": init.tolist()}})
    )
    error = np.linalg.norm(result.critic_weights - W, axis=1) / np.linalg.norm(W)
    assert error[0] > 0.02 and error[-1] < 0.01


def test_too_few_extrapolation_points_are_named_in_the_verdict() -> None:
    """N = 8 points for 13 functions: learning stalls away from W*, and the verdict says why."""
    rng = np.random.default_rng(3)
    K, eye = np.diag([2.0, 1.0, 0.5]), np.eye(3)
    cost = {"K": K, "alpha1": 2.0 * eye, "R": eye, "Q": adparm.solvable_cost(K, 2.0 * eye, eye)}
    W = adparm.optimal_weights(_config(PLANAR, cost))
    init = W * (1.0 + rng.uniform(-0.2, 0.2, W.size))
    config = _config(
        PLANAR,
        cost,
        probe={"amplitude": 0.0},
        extrapolation={"points": 8},
        sim={"T": 20.0},
        init={"critic_weights": init.tolist(), "actor_weights": init.tolist()},
    )
    assert "extrapolation.points = 8 is below the 13 basis functions" in (
        extrapolation_shortfall(config) or ""
    )
    with pytest.warns(adparm.ApproximationWarning, match="extrapolation.points = 8"):
        result = adparm.simulate(config)
    assert result.diagnostics["critic_relative_error"] > 0.02
    assert "extrapolation.points = 8 is below" in result.summary()["verdict"]
    # with as many points as functions and more, no such note
    assert extrapolation_shortfall(config.updated({"extrapolation": {"points": 13}})) is None


def test_a_policy_too_fast_for_the_step_is_refused_saying_why() -> None:
    """All-ones weights on the planar 3-link arm: the actor's policy makes e2 decay at about
    4600/s, beyond RK4's limit 2.785/dt at dt = 1 ms. An explicit dt = 1 ms is refused before the
    run, naming the policy and a step that works; sim.dt = "auto" (the default) picks that step,
    and the run finishes."""
    ones = [1.0] * 13
    config = adparm.Config.from_dict(
        {
            "plant": {"urdf": str(PLANAR)},
            "probe": {"until": 0.0},
            "extrapolation": {"points": 50},
            "init": {"critic_weights": ones, "actor_weights": ones},
            "cost": {"R": np.eye(3).tolist()},
            "sim": {"T": 0.05, "dt": 1e-3},
        }
    )
    with pytest.raises(ValueError, match=r"^sim\.dt: .*policy.*beyond RK4's stability limit"):
        adparm.simulate(config)
    auto = config.updated({"sim": {"dt": "auto"}})
    assert auto.sim.dt < 1e-3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", adparm.ApproximationWarning)
        fine = adparm.simulate(auto)
    assert fine.status == "finished"
    # the causes a divergence would list suggest no step: the one in effect is inside the limit
    assert not any("use sim.dt" in cause for cause in divergence_causes(auto))


def test_the_structured_e2_block_is_kept_positive_at_the_check_positions() -> None:
    # weights whose e2 block starts far below the margin (5 % of the arm's inertia; margin
    # lambda_min(M) / 2): the projection lifts it to the margin at every check position within a
    # fraction of a second and keeps it there, and learning still ends at W* (without the
    # projection this run ends at a non-stabilising solution, lambda_min = -0.012)
    from adparm.rates import check_positions, inertia_range

    base = adparm.Config.from_dict({"plant": {"urdf": "examples/arms/planar_3link.urdf"}})
    smallest, _ = inertia_range(base.plant.urdf)
    margin = 0.5 * smallest
    n = base.dof
    W = adparm.optimal_weights(base)
    start = W.copy()
    start[n * (n + 1) // 2 :] *= 0.05
    config = base.updated(
        {
            "actor": {"e2_margin": margin},
            "init": {"critic_weights": start.tolist(), "actor_weights": start.tolist()},
        }
    )
    positions = check_positions(config)
    e1 = positions[0] - positions  # q = qd - e1 at each check position
    assert structured_e2_block_min_eigenvalue(config, start, e1) < 0.1 * margin
    result = adparm.simulate(config, progress=False)
    later = result.t >= 0.2
    for weights in (result.critic_weights, result.actor_weights):
        lowest = min(
            structured_e2_block_min_eigenvalue(config, w, e1) for w in weights[later][::50]
        )
        assert lowest >= 0.99 * margin
    assert result.diagnostics["verdict"] == "ok", result.diagnostics["verdict"]


def test_a_Q_alone_on_a_urdf_arm_says_R_was_derived() -> None:
    """config.updated with cost.Q alone re-derives cost.R (I, since Q is given): a Q built with
    the R the config had before is then not of the exact family with the new R, and the error
    says that R was derived, its value and how to pin it; given with its R, W* is known."""
    config = adparm.Config.from_dict({"plant": {"urdf": str(PLANAR)}})
    R = np.array(config.cost.R)
    assert not np.allclose(R, np.eye(3))  # diag(1 / (10 M_ii(qd))), derived
    Q = adparm.solvable_cost(np.diag([2.0, 1.0, 0.5]), np.array(config.control.alpha1), R)
    alone = config.updated({"cost": {"Q": Q.tolist()}})
    with pytest.raises(ValueError, match=r"^cost\.Q: Q22 must equal s\^2 R\^-1") as error:
        adparm.optimal_weights(alone)
    message = str(error.value)
    assert "cost.R was not given but derived for this arm" in message
    assert "R = [[1.0, 0.0, 0.0]" in message and '"R": R' in message
    pinned = config.updated({"cost": {"Q": Q.tolist(), "R": R.tolist()}})
    assert adparm.optimal_weights(pinned)[0] == pytest.approx(2.0)
    # an explicit R that does not fit Q: the error does not blame a derivation
    wrong = pinned.updated({"cost": {"R": np.eye(3).tolist()}})
    with pytest.raises(ValueError, match="Q22 must equal") as error:
        adparm.optimal_weights(wrong)
    assert "derived" not in str(error.value)
