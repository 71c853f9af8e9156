"""Config sized by the arm's joint count n (Config.dof): for an arm of n != 2 joints, settings
left out take the n-joint defaults, and a setting of the wrong size is refused naming the field
and n. No n-joint arm is wired to the config yet (a URDF arm will set dof); a Config whose dof is
3 stands in for one here."""

from __future__ import annotations

import numpy as np
import pytest

import adparm

# Short learning runs here have not converged and say so; that warning is not what is tested.
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


class ThreeJointConfig(adparm.Config):
    @property
    def dof(self) -> int:
        return 3


def test_settings_left_out_take_the_n_joint_defaults() -> None:
    config = ThreeJointConfig()
    eye = np.eye(3)
    assert config.task.q0 == (0.1,) * 3 and config.task.dq0 == (0.0,) * 3
    assert config.task.qd == (0.0,) * 3 and config.plant.disturbance == (0.1,) * 3
    np.testing.assert_array_equal(config.cost.R, eye)
    np.testing.assert_array_equal(config.control.alpha1, 2 * eye)
    # Q from the ERRATA conditions with K = I: V* = e1^T e1 + e2^T M e2 is exact
    np.testing.assert_array_equal(config.cost.Q, adparm.solvable_cost(eye, 2 * eye, eye))
    np.testing.assert_array_equal(config.probe.amplitude_matrix(3), np.ones((3, 4)))
    np.testing.assert_array_equal(config.probe.phase_matrix(3)[2], [0, 1, 2, 3])
    np.testing.assert_array_equal(config.controller.gain_matrix("kp", 3), 50 * eye)
    assert config.extrapolation.box_vector(3).shape == (6,)
    # and the two-link arm keeps the paper's values
    assert adparm.Config().cost.Q[0] == (40.0, 2.0, -4.0, 4.0)


def test_given_n_joint_settings_are_kept() -> None:
    config = ThreeJointConfig.from_dict(
        {
            "task": {
                "q0": [0.3, -0.2, 0.1],
                "qd": {
                    "kind": "sinusoid",
                    "amplitude": [1, 2, 3],
                    "frequency": [1, 1, 1],
                    "offset": [0, 0, 0],
                },
            },
            "cost": {"R": 2 * np.eye(3)},
            "control": {"alpha1": 5 * np.eye(3)},
            "extrapolation": {"box": [1, 2, 3, 4, 5, 6]},
            "probe": {"amplitude": [1.0, 2.0, 3.0]},
        },
        base=ThreeJointConfig(),
    )
    assert config.task.q0 == (0.3, -0.2, 0.1)
    np.testing.assert_array_equal(config.cost.R, 2 * np.eye(3))
    np.testing.assert_array_equal(config.probe.amplitude_matrix(3)[:, 0], [1, 2, 3])


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"cost": {"R": np.eye(2)}}, r"cost.R: expected shape \(3, 3\), got \(2, 2\)"),
        ({"cost": {"Q": 2 * np.eye(4)}}, r"cost.Q: expected shape \(6, 6\), got \(4, 4\)"),
        ({"control": {"alpha1": np.eye(4)}}, r"control.alpha1: expected shape \(3, 3\)"),
        ({"task": {"q0": [0.1, 0.2]}}, r"task.q0: expected shape \(3,\), got \(2,\)"),
        ({"task": {"qd": [0.1, 0.2]}}, r"task.qd: expected shape \(3,\)"),
        ({"plant": {"disturbance": [0.1] * 4}}, r"plant.disturbance: expected shape \(3,\)"),
        ({"extrapolation": {"box": [1.0] * 4}}, r"extrapolation.box: expected shape \(6,\)"),
        ({"probe": {"amplitude": [1.0, 2.0]}}, r"probe.amplitude: expected shape \(3,\)"),
        ({"controller": {"kp": np.eye(2)}}, r"controller.kp: expected shape \(3, 3\)"),
        (
            {"task": {"qd": {"kind": "samples", "t": [0, 200], "q": [[0, 0], [1, 1]]}}},
            r"task.qd.q: expected shape \(2, 3\)",
        ),
    ],
)
def test_wrong_sizes_name_the_field_and_n(changes: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message + r".*n = 3 joints"):
        ThreeJointConfig.from_dict(changes, base=ThreeJointConfig())
