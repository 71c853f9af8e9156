"""A URDF arm's joint position limits: the default set-point lies inside them on every arm of
example-robot-data (adparm.joint_limits.rest_position), a URDF that leaves its limits out reads
no limit, and a run whose joints went past them says so in its verdict, naming the joint, and
whether the task or the transient took them there (adparm.saturation.position_limits_text)."""

from __future__ import annotations

import numpy as np
import pytest

import adparm
from adparm import dynamics
from adparm.joint_limits import HOME_MARGIN, rest_position
from adparm.saturation import POSITION_LIMIT_SLACK, limits_below_task
from adparm.urdf import EXAMPLE_LOCKED_JOINTS, EXAMPLE_ROBOTS

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


def _plant(name: str) -> dict:
    try:
        adparm.example_robot_urdf(name)
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")
    plant: dict = {"urdf": f"example-robot-data:{name}"}
    if name in EXAMPLE_LOCKED_JOINTS:
        plant["locked_joints"] = EXAMPLE_LOCKED_JOINTS[name]
    return plant


def test_the_rest_position_is_0_moved_inside_the_limits() -> None:
    inf = np.inf
    low = np.array([-inf, -3.0, -3.0718, 0.82, 0.0, -0.2])
    high = np.array([inf, 3.0, -0.0698, 5.46, 0.4, 2.0])
    qd = rest_position(low, high)
    # unlimited and wide: 0; the Panda's joint 4 and the Kinova's joint 2: HOME_MARGIN inside the
    # nearer limit; a 0.4 range: a quarter of it; a gripper's: HOME_MARGIN past its lower limit
    assert np.allclose(qd, [0.0, 0.0, -0.0698 - HOME_MARGIN, 0.82 + HOME_MARGIN, 0.1, 0.2])


def test_a_urdf_without_position_limits_reads_none() -> None:
    # the double pendulum's revolute joints give no lower and upper: urdfdom reads 0 and 0
    arm = adparm.UrdfArm(str(adparm.example_robot_urdf("double_pendulum")))
    assert np.all(arm.limits["lower"] == -np.inf) and np.all(arm.limits["upper"] == np.inf)
    config = adparm.Config.from_dict({"plant": _plant("double_pendulum")})
    assert config.task.qd == (0.0, 0.0) and config.task.q0 == (0.1, 0.1)


def test_a_joint_whose_lower_equals_its_upper_reads_unlimited_in_the_core(tmp_path) -> None:
    # <limit lower="0" upper="0" ...> (urdfdom's reading of limits left out; Pinocchio keeps
    # [0, 0]): the core's limits (not only UrdfArm.limits) are +-inf, so its sampled poses and
    # its locked-joint check see no point-sized range: locking the joint at 0.5 is accepted
    path = tmp_path / "zero_width.urdf"
    link = (
        '<link name="{0}"><inertial><origin xyz="0.2 0 0"/><mass value="1.0"/><inertia '
        'ixx="0.002" iyy="0.015" izz="0.015" ixy="0" ixz="0" iyz="0"/></inertial></link>'
    )
    joint = (
        '<joint name="{0}" type="revolute"><parent link="{1}"/><child link="{2}"/>'
        '<origin xyz="{3} 0 0"/><axis xyz="0 0 1"/>'
        '<limit lower="0" upper="0" effort="30" velocity="2"/></joint>'
    )
    path.write_text(
        '<?xml version="1.0"?><robot name="zero_width"><link name="base"/>'
        + link.format("a")
        + link.format("b")
        + joint.format("j1", "base", "a", 0.0)
        + joint.format("j2", "a", "b", 0.4)
        + "</robot>"
    )
    arm = adparm.UrdfArm(str(path))
    core = arm._arm.limits
    assert np.all(core["lower"] == -np.inf) and np.all(core["upper"] == np.inf)
    locked = adparm.UrdfArm(str(path), locked_joints={"j2": 0.5})
    assert locked.dof == 1


@pytest.mark.parametrize("name", sorted(EXAMPLE_ROBOTS))
def test_the_default_task_lies_within_the_joint_limits(name: str) -> None:
    # before: qd = 0 clipped into the limits, on a limit of the Kinova, Panda, SO-100, Talos arm
    # and Z1 (the transient then ran past it)
    config = adparm.Config.from_dict({"plant": _plant(name)})
    arm = adparm.urdf.config_arm(config)
    low, high = arm.limits["lower"], arm.limits["upper"]
    margin = np.minimum(HOME_MARGIN, (high - low) / 4.0)
    qd, q0 = np.array(config.task.qd), np.array(config.task.q0)
    assert np.all(qd >= low + margin - 1e-12) and np.all(qd <= high - margin + 1e-12)
    assert np.all(q0 >= low) and np.all(q0 <= high)


def _limits_text(plant: dict, **sections: dict) -> str | None:
    config = adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.5}, **sections})
    diagnostics = adparm.simulate(config).diagnostics
    text = diagnostics["position_limits"]
    assert (text is None) == ("position limits" not in diagnostics["verdict"])
    return text


def test_a_task_outside_the_limits_is_told_and_leaving_it_out_mends_it() -> None:
    plant = _plant("panda")
    # qd = 0: the Panda's joint 4 has limits [-3.07, -0.07] (before: "ok", the simulation having
    # no joint stops)
    text = _limits_text(plant, task={"qd": [0.0] * 7})
    assert text is not None and "joint 4 ('panda_joint4')" in text
    assert "task.qd lies outside the limits (left out, it is derived within them)" in text
    assert "task.q0" not in text  # derived from the qd given: -0.1 on joint 4, inside
    assert _limits_text(plant) is None  # the fix the text names
    text = _limits_text(plant, task={"q0": [0.1, 0.1, 0.1, 0.0, 0.1, 0.1, 0.1]})
    assert text is not None and "task.q0 lies outside the limits" in text
    assert "task.qd" not in text


def test_a_trajectory_leaving_the_limits_is_told() -> None:
    qd = {"kind": "sinusoid", "amplitude": [0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0]}
    qd["frequency"] = [1.0] * 7
    text = _limits_text(_plant("panda"), task={"qd": {**qd, "offset": [0, 0, 0, -0.2, 0, 0, 0]}})
    assert text is not None and "task.qd leaves the limits" in text and "joint 4" in text
    text = _limits_text(_plant("panda"), task={"qd": {**qd, "offset": [0, 0, 0, -1, 0, 0, 0]}})
    assert text is None


def test_a_sinusoid_without_an_offset_moves_about_the_rest_position() -> None:
    # before: about 0 on every joint, outside the Panda's joint 4 and its limits' verdict
    plant = _plant("panda")
    qd = {"kind": "sinusoid", "amplitude": [0.1] * 7, "frequency": [1.0] * 7}
    config = adparm.Config.from_dict({"plant": plant, "task": {"qd": qd}})
    rest = adparm.Config.from_dict({"plant": plant}).task.qd
    assert config.task.qd.offset == rest and rest[3] == pytest.approx(-0.0698 - HOME_MARGIN)
    assert "task.qd" in config.derived
    np.testing.assert_allclose(adparm.desired_state(config, 0.0)[0], rest)
    assert np.allclose(config.task.q0, np.array(rest) + 0.1)
    assert _limits_text(plant, task={"qd": qd}) is None
    two_link = adparm.paper_config().updated({"task": {"qd": {"kind": "sinusoid"}}})
    assert two_link.task.qd.offset == (0.0, 0.0)


def test_a_transient_past_the_limits_is_told_and_its_fix_works() -> None:
    # the SO-101's gripper (limits [-0.175, 1.75], M = 1.6e-5 kg m^2): the former default
    # disturbance, 0.1 N m on every joint, swings it about 0.5 rad before RISE takes it up, past
    # the lower limit from its default qd; the derived one (0.1 M_jj on it) does not
    plant = _plant("so101")
    derived = adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.5}})
    assert derived.plant.disturbance[5] < 1e-5
    assert adparm.simulate(derived).diagnostics["position_limits"] is None
    plant["disturbance"] = [0.1] * 6
    config = adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.5}})
    result = adparm.simulate(config)
    text = result.diagnostics["position_limits"]
    assert text is not None and "joint 6 ('gripper')" in text
    assert "the transient went past them: choose a task.qd at least that much farther" in text
    past = float(np.max(config_low(config)[5] - result.q[:, 5]))
    assert past > POSITION_LIMIT_SLACK
    qd = list(config.task.qd)
    qd[5] += 2.0 * past  # farther from the lower limit by twice what it went past
    assert _limits_text(plant, task={"qd": qd}) is None


def test_joints_past_the_limits_under_clipped_torques_are_not_told_to_move_qd() -> None:
    # the SO-101 with 0.05 N m on every joint cannot hold its arm: it falls past the position
    # limits wherever qd lies (here its rest position, and 0); the note said "choose a task.qd
    # farther from those limits", which does not help: the clipped torque is named instead
    plant = {**_plant("so101"), "torque_limits": [0.05] * 6}
    for task in ({}, {"qd": [0.0] * 6}):
        config = adparm.Config.from_dict({"plant": plant, "task": task, "sim": {"T": 0.5}})
        text = adparm.simulate(config).diagnostics["position_limits"]
        assert text is not None and "joint 2 ('shoulder_lift') reached" in text
        assert "the applied torque was clipped at plant.torque_limits before they went" in text
        assert "choose a task.qd" not in text


def config_low(config: adparm.Config) -> np.ndarray:
    return np.asarray(adparm.urdf.config_arm(config).limits["lower"])


def test_a_rest_position_the_arm_cannot_hold_gives_way_to_one_it_can() -> None:
    # Baxter's left arm at 0: its shoulder needs 56.4 N m against its 50 (before: the default
    # run was told "the torque limits cannot hold the task")
    plant = _plant("baxter")
    config = adparm.Config.from_dict({"plant": plant})
    assert "least loads the actuators against gravity" in config.derived["task.qd"]
    assert limits_below_task(config) is None
    held = dynamics.task_torque(config) + 0.1
    assert np.all(held <= 0.3 * np.asarray(config.plant.torque_limits))
    at_zero = config.updated({"task": {"qd": [0.0] * 7}})
    assert limits_below_task(at_zero) is not None
    arm = adparm.urdf.config_arm(config)
    low, high = arm.limits["lower"], arm.limits["upper"]
    margin = np.minimum(HOME_MARGIN, (high - low) / 4.0)
    qd = np.array(config.task.qd)
    assert np.all(qd >= low + margin - 1e-9) and np.all(qd <= high - margin + 1e-9)
    # believed 20 % light, the model holds 0 (45 N m) and the plant does not (55.3 N m): the
    # pose is chosen for both (it was 0, and the run was told "the torque limits cannot hold")
    light = adparm.Config.from_dict({"plant": plant, "model": {**plant, "scale": 0.8}})
    assert np.abs(np.array(light.task.qd) - qd).max() < 0.01
    assert limits_below_task(light) is None
    # an arm that holds its rest position keeps it
    assert adparm.Config.from_dict({"plant": _plant("ur5")}).task.qd == (0.0,) * 6


def test_a_probe_on_while_the_joints_went_past_is_named_as_their_cause() -> None:
    # the Panda identifying a 1 kg payload with the advised probe (10 times the derived one) went
    # 0.76 rad past joint 4's limit while the probe was on, and a qd farther from that limit sent
    # every joint past its limits: the cause is the probe, not the transient
    from types import SimpleNamespace

    plant = _plant("so101")
    config = adparm.Config.from_dict(
        {"plant": plant, "probe": {"until": 100.0}, "sim": {"T": 0.05}}
    )
    result = adparm.simulate(config, diagnose=False)
    high = np.asarray(adparm.urdf.config_arm(config).limits["upper"])
    q = np.array(result.q)
    q[-3:, 0] = high[0] + 0.1  # joint 1 past its upper limit over the last rows
    probed = SimpleNamespace(
        config=config,
        t=result.t,
        q=q,
        qd=result.qd,
        probe=result.probe,
        tau=result.tau,
        tau_commanded=result.tau_commanded,
    )
    assert np.any(np.asarray(result.probe)[-3:] != 0.0)
    text = adparm.saturation.position_limits_text(probed)
    assert "joint 1 ('shoulder_pan') reached" in text
    assert "the probe was on while they went past: it drove them" in text
    quiet = SimpleNamespace(**{**vars(probed), "probe": np.zeros_like(result.probe)})
    assert "the transient went past them" in adparm.saturation.position_limits_text(quiet)
