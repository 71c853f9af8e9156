"""Bellman-error extrapolation: the critic reaches W* without probing (issue 4, part 1)."""

from __future__ import annotations

import numpy as np
import pytest

import adparm

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


def other_instance() -> adparm.Config:
    """An instance unlike the paper's whose W* is known: other K, alpha1, R and arm, with Q from
    the ERRATA conditions."""
    K = [[2.0, 0.5], [0.5, 1.0]]
    alpha1 = [[5.0, 1.0], [1.0, 3.0]]
    R = [[0.5, 0.0], [0.0, 0.5]]
    return adparm.paper_config().updated(
        {
            "cost": {"Q": adparm.solvable_cost(K, alpha1, R), "R": R},
            "control": {"alpha1": alpha1},
            "plant": {"p1": 3.0, "p2": 0.8, "p3": 0.5},
            "task": {"q0": [-0.4, 0.6]},
        }
    )


INSTANCES = {"paper": adparm.paper_config, "other": other_instance}


def without_probing(base: adparm.Config, **extrapolation) -> adparm.Config:
    return base.updated(
        {"probe": {"until": 0.0}, "sim": {"T": 12.0}, "extrapolation": extrapolation}
    )


def critic_error(result: adparm.SimulationResult) -> np.ndarray:
    target = adparm.optimal_weights(result.config)
    return np.linalg.norm(result.critic_weights - target, axis=1) / np.linalg.norm(target)


def test_the_other_instance_has_a_known_solution() -> None:
    config = other_instance()
    target = adparm.optimal_weights(config)
    np.testing.assert_array_equal(target, [2.0, 1.0, 1.0, 3.0, 1.0, 0.8, 1.6, 1.0])
    x = np.random.default_rng(1).uniform(-1, 1, (50, 4))
    assert np.abs(adparm.hjb_residual(config, x, target, target)).max() < 1e-9


@pytest.mark.parametrize("instance", INSTANCES)
@pytest.mark.parametrize(
    "extrapolation",
    [
        {"points": 10, "mode": "fixed", "seed": 0},
        {"points": 10, "mode": "fixed", "seed": 1},
        {"points": 16, "mode": "grid"},
        {"points": 10, "mode": "local", "box": 0.5},
        {"points": 50, "mode": "fixed", "seed": 2},
    ],
)
def test_critic_reaches_W_star_within_one_percent_by_10_s_without_probing(
    instance, extrapolation
) -> None:
    result = adparm.simulate(without_probing(INSTANCES[instance](), **extrapolation))
    assert not result.probe.any()
    error = critic_error(result)
    after = result.t >= 10.0
    assert error[after].max() < 0.01, (instance, extrapolation, error[after].max())
    actor = adparm.optimal_weights(result.config)
    actor_error = np.linalg.norm(result.actor_weights[-1] - actor) / np.linalg.norm(actor)
    assert actor_error < 0.01


@pytest.mark.parametrize("instance", INSTANCES)
@pytest.mark.parametrize("seed", [0, 1])
def test_five_fixed_points_are_too_few(instance, seed) -> None:
    """5 regressors cannot pin down 8 weights: the critic stays far from W*."""
    result = adparm.simulate(without_probing(INSTANCES[instance](), points=5, seed=seed))
    assert critic_error(result)[-1] > 0.05


@pytest.mark.parametrize("instance", INSTANCES)
def test_without_extrapolation_or_probing_the_critic_does_not_learn_W_star(instance) -> None:
    result = adparm.simulate(without_probing(INSTANCES[instance](), points=0))
    assert critic_error(result)[-1] > 0.05


def test_fixed_points_are_uniform_in_the_box_and_follow_the_seed() -> None:
    config = adparm.paper_config().updated(
        {"extrapolation": {"points": 200, "box": [1.0, 0.5, 2.0, 3.0], "seed": 7}}
    )
    points = adparm.extrapolation_points(config)
    assert points.shape == (200, 4)
    box = np.array([1.0, 0.5, 2.0, 3.0])
    assert np.all(np.abs(points) <= box)
    assert np.all(np.abs(points).max(axis=0) > 0.9 * box)  # they fill the box
    again = adparm.extrapolation_points(config)
    np.testing.assert_array_equal(points, again)
    other = adparm.extrapolation_points(config.updated({"extrapolation": {"seed": 8}}))
    assert not np.allclose(points, other)


def test_the_centre_moves_the_box_and_zero_changes_nothing() -> None:
    box = [1.0, 0.5, 2.0, 3.0]
    centre = [-0.5, 0.25, 0.0, 1.0]
    config = adparm.paper_config().updated(
        {"extrapolation": {"points": 200, "box": box, "seed": 7}}
    )
    points = adparm.extrapolation_points(config)
    moved = adparm.extrapolation_points(config.updated({"extrapolation": {"centre": centre}}))
    np.testing.assert_allclose(moved, points + np.array(centre), rtol=0, atol=1e-15)
    zero = adparm.extrapolation_points(config.updated({"extrapolation": {"centre": 0.0}}))
    np.testing.assert_array_equal(zero, points)
    grid = config.updated({"extrapolation": {"points": 81, "mode": "grid", "centre": centre}})
    grid_points = adparm.extrapolation_points(grid)
    for axis in range(4):
        np.testing.assert_allclose(
            np.unique(grid_points[:, axis]), centre[axis] + np.array([-1, 0, 1]) * box[axis]
        )
    with pytest.raises(ValueError, match="extrapolation.centre"):
        adparm.paper_config().updated({"extrapolation": {"centre": [0.0, 1.0]}})


def test_grid_points_span_the_box() -> None:
    config = adparm.paper_config().updated(
        {"extrapolation": {"points": 81, "mode": "grid", "box": 2.0}}
    )
    points = adparm.extrapolation_points(config)
    assert points.shape == (81, 4)
    for axis in range(4):
        np.testing.assert_array_equal(np.unique(points[:, axis]), [-2.0, 0.0, 2.0])
    assert len({tuple(p) for p in points}) == 81


def test_local_points_are_redrawn_and_runs_are_reproducible() -> None:
    config = without_probing(adparm.paper_config(), points=10, mode="local", seed=3).updated(
        {"sim": {"T": 2.0}}
    )
    first, second = adparm.simulate(config), adparm.simulate(config)
    for name in ("critic_weights", "actor_weights", "q", "cost"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    reseeded = adparm.simulate(config.updated({"extrapolation": {"seed": 4}}))
    assert not np.array_equal(first.critic_weights, reseeded.critic_weights)
