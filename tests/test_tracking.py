"""Time-varying trajectory tracking with the augmented basis (issue 4, part 2)."""

from __future__ import annotations

import numpy as np
import pytest

import adparm

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

SINUSOID = {"kind": "sinusoid", "amplitude": [0.5, 0.3], "frequency": [1.0, 2.0]}


def tracking(qd, *, basis: str = "augmented", T: float = 30.0) -> adparm.Config:
    """Learning while tracking, with extrapolation instead of probing."""
    return adparm.paper_config().updated(
        {
            "task": {"qd": qd},
            "controller": {"basis": basis},
            "probe": {"until": 0.0},
            "extrapolation": {"points": 10},
            "sim": {"T": T},
        }
    )


def windowed_max(result: adparm.SimulationResult, start: float, stop: float) -> float:
    inside = (result.t >= start) & (result.t <= stop)
    return float(np.linalg.norm(result.e1[inside], axis=1).max())


def test_hjb_residual_vanishes_at_W_star_on_a_moving_trajectory() -> None:
    config = tracking(SINUSOID)
    target = adparm.optimal_weights(config)
    rng = np.random.default_rng(0)
    for t in rng.uniform(0, 20, 5):
        x = rng.uniform(-1, 1, (20, 4))
        assert np.abs(adparm.hjb_residual(config, x, target, target, t=t)).max() < 1e-9
    # the paper's phi(x) cannot represent V* once qd2 moves
    paper = config.updated({"controller": {"basis": "paper"}})
    x = rng.uniform(-1, 1, (20, 4))
    assert np.abs(adparm.hjb_residual(paper, x, target, target, t=0.3)).max() > 1e-3


def test_tracking_error_is_bounded_and_shrinks_while_learning() -> None:
    result = adparm.simulate(tracking(SINUSOID))
    np.testing.assert_allclose(result.qd, adparm.desired_state(result.config, result.t)[:, 0])
    assert windowed_max(result, 0.0, 30.0) < 1.0  # bounded
    early, middle, late = (windowed_max(result, a, a + 5.0) for a in (0.0, 10.0, 25.0))
    assert late < 1e-3 * early and late <= middle
    assert late < 1e-5


def test_critic_learns_W_star_while_tracking_with_the_augmented_basis() -> None:
    result = adparm.simulate(tracking(SINUSOID))
    target = adparm.optimal_weights(result.config)
    error = np.linalg.norm(result.critic_weights - target, axis=1) / np.linalg.norm(target)
    assert error[result.t >= 10.0].max() < 0.01


def test_the_paper_basis_does_not_learn_W_star_while_tracking() -> None:
    result = adparm.simulate(tracking(SINUSOID, basis="paper"))
    target = adparm.optimal_weights(adparm.paper_config())
    error = np.linalg.norm(result.critic_weights - target, axis=1) / np.linalg.norm(target)
    assert error[result.t >= 10.0].max() > 0.1  # the weights keep wandering


def test_the_feedforward_uses_the_full_desired_state() -> None:
    """Starting on the trajectory with an exact model, no disturbance and no RISE, the optimal
    input is zero and the arm stays on qd(t): only h with qd, dqd and ddqd (eq. 5 in full) does
    that."""
    base = tracking(SINUSOID, T=10.0).updated(
        {
            "plant": {"disturbance": [0.0, 0.0], "coulomb": 0.0},
            "controller": {"kind": "optimal", "rise": False},
        }
    )
    qd0, dqd0, _ = adparm.desired_state(base, 0.0)
    config = base.updated({"task": {"q0": qd0, "dq0": dqd0}})
    result = adparm.simulate(config)
    assert np.abs(result.e1).max() < 1e-9 and np.abs(result.e2).max() < 1e-9
    # a wrong model of the arm (believed p1 off by 20 %) does leave the trajectory
    wrong = adparm.simulate(config.updated({"model": {"p1": 6.0}}))
    assert np.abs(wrong.e1).max() > 1e-4


def test_tracking_samples_from_a_file(tmp_path) -> None:
    t = np.linspace(0.0, 25.0, 101)
    q = np.column_stack([0.4 * np.sin(0.8 * t), 0.2 * (1 - np.cos(0.5 * t))])
    path = tmp_path / "qd.csv"
    np.savetxt(path, np.column_stack([t, q]), delimiter=",", header="t,qd1,qd2", comments="")
    (tmp_path / "run.toml").write_text(
        '[task.qd]\nkind = "samples"\nfile = "qd.csv"\n\n[probe]\nuntil = 0.0\n\n'
        "[extrapolation]\npoints = 10\n\n[sim]\nT = 25.0\n"
    )
    config = adparm.load_config(tmp_path / "run.toml")
    result = adparm.simulate(config)
    spline = config.task.qd.spline()
    np.testing.assert_allclose(result.qd, spline(result.t), atol=1e-12)
    assert windowed_max(result, 20.0, 25.0) < 1e-3 * windowed_max(result, 0.0, 5.0)
    target = adparm.optimal_weights(config)
    error = np.linalg.norm(result.critic_weights[-1] - target) / np.linalg.norm(target)
    assert error < 0.01


def test_samples_must_cover_the_horizon() -> None:
    with pytest.raises(ValueError, match="task.qd: the samples end at t = 5 s, before sim.T"):
        tracking({"kind": "samples", "t": [0.0, 5.0], "q": [[0, 0], [1, 1]]})


def test_a_sinusoid_on_a_urdf_arm_needs_no_offset_or_phase() -> None:
    # amplitude and frequency alone on a 3-joint arm: offset and phase are 0 on every joint (the
    # offset's default was the two-link arm's pair: "task.qd.offset: expected shape (3,)")
    qd = {"kind": "sinusoid", "amplitude": [0.3, 0.2, 0.1], "frequency": [1.0, 2.0, 3.0]}
    config = adparm.Config.from_dict(
        {
            "plant": {"urdf": "examples/arms/planar_3link.urdf"},
            "task": {"qd": qd},
            "sim": {"T": 0.05},
        }
    )
    assert config.task.qd.offset == (0.0, 0.0, 0.0)
    assert config.task.qd.phase == ((0.0,), (0.0,), (0.0,))
    np.testing.assert_allclose(
        adparm.desired_state(config, 0.5)[0], np.sin([0.5, 1.0, 1.5]) * [0.3, 0.2, 0.1]
    )
    assert adparm.simulate(config, diagnose=False).status == "finished"
    paper = adparm.paper_config().updated({"task": {"qd": {"kind": "sinusoid"}}})
    assert paper.task.qd.offset == (0.0, 0.0)


def test_samples_on_a_urdf_arm(tmp_path) -> None:
    # a 3-joint arm's samples, inline and from a CSV file: the core's spline equals SciPy's
    # CubicSpline (it raised "cannot reshape array of size 264 into shape (22,8)": the
    # coefficients were laid out for two joints)
    from scipy.interpolate import CubicSpline

    t = np.linspace(-0.1, 2.1, 23)
    q = np.stack([0.2 * np.sin(t), 0.1 * np.sin(2 * t), 0.05 * np.cos(t)], axis=1)
    plant = {"urdf": "examples/arms/planar_3link.urdf"}
    inline = {"kind": "samples", "t": t.tolist(), "q": q.tolist()}
    config = adparm.Config.from_dict({"plant": plant, "task": {"qd": inline}, "sim": {"T": 2.0}})
    spline, times = CubicSpline(t, q), np.array([0.03, 0.77, 1.95])
    expected = np.stack([spline(times), spline(times, 1), spline(times, 2)], axis=1)
    np.testing.assert_allclose(adparm.desired_state(config, times), expected, rtol=0, atol=1e-12)
    assert adparm.simulate(config, diagnose=False).status == "finished"
    path = tmp_path / "qd.csv"
    path.write_text(
        "t,qd1,qd2,qd3\n"
        + "\n".join(",".join(repr(float(v)) for v in row) for row in np.column_stack([t, q]))
    )
    from_file = config.updated({"task": {"qd": {"kind": "samples", "file": str(path)}}})
    np.testing.assert_array_equal(
        adparm.desired_state(from_file, times), adparm.desired_state(config, times)
    )
