"""Locked joints (plant.locked_joints, model.locked_joints, UrdfArm(locked_joints=...)) through
Pinocchio's reduced model, the physical checks of a URDF before the run, and the arms of
example-robot-data (EXAMPLE_ROBOTS)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.urdf import EXAMPLE_LOCKED_JOINTS, EXAMPLE_ROBOTS

ARMS = Path(__file__).resolve().parents[1] / "examples" / "arms"
PLANAR = ARMS / "planar_3link.urdf"
FINGERS = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}


def example_robot(name: str) -> Path:
    try:
        return adparm.example_robot_urdf(name)
    except ModuleNotFoundError:
        pytest.skip("example-robot-data is not installed")


def panda_config(**plant) -> adparm.Config:
    example_robot("panda")
    return adparm.Config.from_dict(
        {"plant": {"urdf": "example-robot-data:panda", **plant}, "sim": {"T": 0.01, "dt": 1e-4}}
    )


# --- the Panda with its fingers locked ---------------------------------------------------------


def test_panda_with_fingers_locked_matches_pinocchio() -> None:
    pin = pytest.importorskip("pinocchio")
    path = example_robot("panda")
    arm = adparm.UrdfArm(path, locked_joints=FINGERS)
    assert arm.dof == 7
    assert arm.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    assert arm.locked_joints == FINGERS

    full = pin.buildModelFromUrdf(str(path))
    locked = [full.getJointId(name) for name in FINGERS]
    reduced = pin.buildReducedModel(full, locked, pin.neutral(full))
    data = reduced.createData()
    assert reduced.nv == 7
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = rng.uniform(arm.limits["lower"], arm.limits["upper"])
        expected = pin.crba(reduced, data, q)
        expected = np.triu(expected) + np.triu(expected, 1).T
        M = arm.terms(q, np.zeros(7))["M"]
        assert np.abs(M - expected).max() <= 1e-12 * max(1.0, np.abs(expected).max())


def test_a_locked_leader_locks_its_mimic_joint() -> None:
    path = example_robot("panda")
    arm = adparm.UrdfArm(path, locked_joints={"panda_finger_joint1": 0.02})
    assert arm.dof == 7
    assert arm.locked_joints == {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
    # the fingers' position moves the hand's centre of mass: M differs from the fingers at 0
    closed = adparm.UrdfArm(path, locked_joints=FINGERS)
    q = np.full(7, 0.3)
    assert not np.allclose(arm.terms(q, np.zeros(7))["M"], closed.terms(q, np.zeros(7))["M"])


def test_panda_config_dof_round_trip_and_run(tmp_path) -> None:
    config = panda_config(locked_joints=FINGERS)
    assert config.dof == 7
    assert config.plant.locked_joints == FINGERS
    assert config.model.resolve_urdf(config.plant)["locked_joints"] == FINGERS
    path = tmp_path / "panda.toml"
    path.write_text(config.to_toml())
    assert adparm.load_config(path) == config
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    assert result.q.shape[1] == 7
    assert np.isfinite(result.q).all()


def test_model_locked_joints_default_to_the_plant_and_may_differ() -> None:
    config = panda_config(locked_joints=FINGERS)
    wrong = config.updated({"model": {"locked_joints": {"panda_finger_joint1": 0.04}}})
    assert wrong.model.resolve_urdf(wrong.plant)["locked_joints"] == {"panda_finger_joint1": 0.04}
    q = np.full(7, 0.2)
    believed = adparm.arm_terms(wrong, q=q, dq=np.zeros(7), model=True)["M"]
    actual = adparm.arm_terms(wrong, q=q, dq=np.zeros(7))["M"]
    assert not np.allclose(believed, actual)
    with pytest.raises(ValueError, match=r"model\.locked_joints: the model has n = 6 joints"):
        config.updated({"model": {"locked_joints": {**FINGERS, "panda_joint7": 0.0}}})


# --- refusals, naming the field ------------------------------------------------------------------


def test_a_free_mimic_joint_is_refused_saying_what_to_lock() -> None:
    with pytest.raises(
        ValueError,
        match=re.escape("plant.locked_joints: URDF ")
        + ".*joint 'panda_finger_joint2' is a mimic joint \\(of 'panda_finger_joint1'\\).*"
        + re.escape(
            "lock it: [plant] locked_joints = {panda_finger_joint1 = 0.0, "
            "panda_finger_joint2 = 0.0}"
        ),
    ):
        panda_config()


def test_an_unknown_locked_joint_is_refused_listing_the_joints() -> None:
    with pytest.raises(
        ValueError,
        match=r"plant\.locked_joints: no joint 'finger' in .*panda\.urdf; its joints: "
        r"panda_joint1, .*panda_finger_joint2",
    ):
        panda_config(locked_joints={"finger": 0.0})
    with pytest.raises(ValueError, match=r"model\.locked_joints: no joint 'finger'"):
        panda_config(locked_joints=FINGERS).updated({"model": {"locked_joints": {"finger": 0.0}}})


def test_a_locked_position_outside_the_limits_is_refused() -> None:
    with pytest.raises(
        ValueError,
        match=r"plant\.locked_joints: joint 'panda_finger_joint1' locked at 0\.5, outside its "
        r"limits \[0\.0, 0\.04\]",
    ):
        panda_config(locked_joints={"panda_finger_joint1": 0.5})


def test_inconsistent_mimic_positions_are_refused() -> None:
    with pytest.raises(ValueError, match=r"plant\.locked_joints: .*'panda_finger_joint2' .*puts"):
        panda_config(locked_joints={"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.01})


@pytest.mark.parametrize(
    "value, error, message",
    [
        ([0.0], TypeError, r"plant\.locked_joints: expected a table"),
        ({"panda_finger_joint1": "x"}, TypeError, r"plant\.locked_joints\.panda_finger_joint1"),
        ({"panda_finger_joint1": float("nan")}, ValueError, r"must be finite"),
    ],
    ids=["not-a-table", "not-a-number", "nan"],
)
def test_bad_locked_joints_values_are_refused(value, error, message) -> None:
    with pytest.raises(error, match=message):
        panda_config(locked_joints=value)


def test_locked_joints_need_a_urdf_arm() -> None:
    with pytest.raises(ValueError, match=r"plant\.locked_joints: only with a URDF arm"):
        adparm.Config.from_dict({"plant": {"locked_joints": {"a": 0.0}}})
    with pytest.raises(ValueError, match=r"model\.locked_joints: only with a URDF plant"):
        adparm.Config.from_dict({"model": {"locked_joints": {"a": 0.0}}})


def test_urdf_arm_locked_joint_refusals() -> None:
    path = example_robot("panda")
    with pytest.raises(ValueError, match=r"^locked_joints: joint 'panda_joint8' .*is fixed"):
        adparm.UrdfArm(path, locked_joints={**FINGERS, "panda_joint8": 0.0})
    with pytest.raises(ValueError, match=r"lock it: locked_joints = \{panda_finger_joint1"):
        adparm.UrdfArm(path)


# --- physical checks of the URDF -----------------------------------------------------------------


def broken_planar(tmp_path: Path, old: str, new: str) -> Path:
    text = PLANAR.read_text()
    assert old in text
    path = tmp_path / "planar.urdf"
    path.write_text(text.replace(old, new, 1))
    return path


LINK1_INERTIA = (
    'ixx="0.001" ixy="0" ixz="0" iyy="0.0416666666666667" iyz="0" izz="0.0416666666666667"'
)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ('<mass value="2.0"/>', '<mass value="2,0"/>', "link 'link1': <mass value='2,0'>"),
        ('<mass value="2.0"/>', '<mass value="-2.0"/>', "link 'link1' has mass -2.0"),
        (
            LINK1_INERTIA,
            LINK1_INERTIA.replace('iyy="0.0416666666666667"', 'iyy="0.01"'),
            "link 'link1' has an inertia that breaks the triangle inequality",
        ),
        (
            LINK1_INERTIA,
            LINK1_INERTIA.replace('ixy="0"', 'ixy="0.05"'),
            "link 'link1' has an inertia that is not positive semi-definite",
        ),
        (
            '<axis xyz="0 -1 0"/>',
            '<axis xyz="0 0 0"/>',
            "joint 'shoulder' (which moves link 'link1') has a zero axis",
        ),
        (
            '<mass value="2.0"/>',
            '<mass value="0.0"/>',
            "link 'link1' (the body joint 'shoulder' moves, with the links fixed or locked to "
            "it) has mass 0.0",
        ),
    ],
    ids=["mass-2,0", "negative-mass", "triangle", "indefinite", "zero-axis", "massless-body"],
)
def test_physically_impossible_urdfs_are_refused(tmp_path, old, new, message) -> None:
    path = broken_planar(tmp_path, old, new)
    with pytest.raises(ValueError, match=re.escape(f"plant.urdf: URDF {path}: {message}")):
        adparm.Config.from_dict({"plant": {"urdf": str(path)}})
    with pytest.raises(ValueError, match=re.escape(message)):
        adparm.UrdfArm(path)
    with pytest.raises(ValueError, match=re.escape(f"model.urdf: URDF {path}: {message}")):
        adparm.Config.from_dict({"plant": {"urdf": str(PLANAR)}, "model": {"urdf": str(path)}})


def test_a_link_that_never_moves_is_not_checked(tmp_path) -> None:
    """A link fixed to the base (TIAGo's antennas), or beyond joints all locked, never moves and
    its inertia never enters the dynamics: a physically impossible one is not refused there,
    and is refused where a joint moves it."""
    antenna = (
        '<link name="antenna"><inertial><mass value="0.01"/><inertia ixx="-1e-8" ixy="0" '
        'ixz="0" iyy="3.5e-8" iyz="0" izz="9e-8"/></inertial></link>'
    )

    def mounted_on(parent: str) -> Path:
        mount = (
            f'<joint name="antenna_mount" type="fixed"><parent link="{parent}"/>'
            '<child link="antenna"/></joint>'
        )
        return broken_planar(
            tmp_path, '<link name="base_link"/>', f'<link name="base_link"/>{antenna}{mount}'
        )

    assert adparm.UrdfArm(mounted_on("base_link")).dof == 3
    message = "link 'antenna' has an inertia that is not positive semi-definite"
    with pytest.raises(ValueError, match=re.escape(message)):
        adparm.UrdfArm(mounted_on("link1"))
    assert adparm.UrdfArm(mounted_on("link1"), locked_joints={"shoulder": 0.5}).dof == 2


@pytest.mark.parametrize("declared", [True, False])
def test_a_xacro_file_is_told_to_be_expanded_first(tmp_path, declared) -> None:
    """A ROS package's arm.urdf.xacro given as the URDF: its ${m} would read as text (urdfdom:
    a massless link); the message names xacro, which expands it (checked by hand with PyPI's
    xacro 2.1.1: the arm.urdf it writes runs)."""
    namespace = ' xmlns:xacro="http://www.ros.org/wiki/xacro"' if declared else ""
    text = PLANAR.read_text().replace('<mass value="2.0"/>', '<mass value="${m}"/>', 1)
    text = text.replace("<robot ", f"<robot{namespace} ", 1)
    text = text.replace(
        '<link name="base_link"/>',
        '<xacro:property name="m" value="2"/><link name="base_link"/>',
        1,
    )
    path = tmp_path / "planar.urdf.xacro"
    path.write_text(text)
    message = f"URDF {path} is a xacro file"
    with pytest.raises(ValueError, match=re.escape(message)):
        adparm.Config.from_dict({"plant": {"urdf": str(path)}})
    with pytest.raises(ValueError, match=re.escape(f"xacro {path} > arm.urdf")):
        adparm.UrdfArm(path)


def test_an_arm_with_more_joints_than_the_core_supports_is_told_to_lock_some() -> None:
    """TIAGo with its hand: 48 joints (the core supports 12); the message names the field that
    makes it an arm the core can run."""
    try:
        urdf = adparm.example_robot_urdf("tiago_description/robots/tiago.urdf")
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")
    message = "has 48 joints; the core supports 1 to 12: lock joints (plant.locked_joints)"
    with pytest.raises(ValueError, match=re.escape(message)):
        adparm.Config.from_dict({"plant": {"urdf": str(urdf)}})


def test_the_shipped_arms_pass_the_physical_checks() -> None:
    for path in sorted(ARMS.glob("*.urdf")):
        assert adparm.UrdfArm(path).dof >= 2


# --- example-robot-data ------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(EXAMPLE_ROBOTS))
def test_every_example_robot_builds_an_arm(name: str) -> None:
    path = example_robot(name)
    arm = adparm.UrdfArm(path, locked_joints=EXAMPLE_LOCKED_JOINTS.get(name))
    assert 2 <= arm.dof <= 7
    M = arm.terms(np.zeros(arm.dof), np.zeros(arm.dof))["M"]
    assert np.linalg.eigvalsh(M).min() > 0.0
    config = adparm.Config.from_dict(
        {
            "plant": {
                "urdf": f"example-robot-data:{name}",
                "locked_joints": EXAMPLE_LOCKED_JOINTS.get(name),
            }
        }
    )
    assert config.dof == arm.dof


def test_example_robot_urdf_docstring_says_which_robots_need_locks() -> None:
    """Every robot of EXAMPLE_ROBOTS is a plant as it is except those of EXAMPLE_LOCKED_JOINTS,
    which are refused without their locks, naming plant.locked_joints; the docstring names
    exactly those (it once listed "panda" as if it worked alone)."""
    example_robot("ur5")
    doc = adparm.example_robot_urdf.__doc__
    for name in sorted(EXAMPLE_ROBOTS):
        plant = {"urdf": f"example-robot-data:{name}"}
        if name in EXAMPLE_LOCKED_JOINTS:
            assert f'"{name}"' in doc.split("except three")[1].split("Examples")[0], name
            with pytest.raises(ValueError, match="plant.locked_joints"):
                adparm.Config.from_dict({"plant": plant})
        else:
            assert adparm.Config.from_dict({"plant": plant}).dof >= 2, name
    assert "except three" in doc and len(EXAMPLE_LOCKED_JOINTS) == 3


@pytest.mark.parametrize("name", ["talos_arm", "baxter"])
def test_talos_and_baxter_arms_run(name: str) -> None:
    example_robot(name)
    config = adparm.Config.from_dict(
        {
            "plant": {
                "urdf": f"example-robot-data:{name}",
                "locked_joints": EXAMPLE_LOCKED_JOINTS.get(name),
            },
            "sim": {"T": 0.01, "dt": 1e-4},
        }
    )
    assert config.dof == 7
    assert adparm.simulate(config, diagnose=False).status == "finished"
