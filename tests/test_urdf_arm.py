"""Arms from URDF (adparm.UrdfArm, the C++ PinocchioArm): the two-link URDF against the built-in
model, other arms against NumPy and Pinocchio's Python bindings, dM/dt - 2C skew, M > 0,
M = sum_k pi_k M_k(q), and the URDFs that must be refused."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.urdf import EXAMPLE_LOCKED_JOINTS

from numpy_reference import pinocchio_terms

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import every_arm  # noqa: E402

ARMS = Path(__file__).resolve().parents[1] / "examples" / "arms"
PAPER = {"p1": 5.0, "p2": 1.0, "p3": 1.0, "g1": 9.8 * 1.2, "g2": 9.8}


def builtin_terms(q, dq, coulomb: float, viscous: float) -> dict:
    p = _core.ArmParameters()
    for key, value in dict(PAPER, coulomb=coulomb, viscous=viscous).items():
        setattr(p, key, value)
    return _core.arm_terms(p, q, dq)


def random_states(rng: np.random.Generator, n: int, count: int = 20):
    for _ in range(count):
        yield rng.uniform(-np.pi, np.pi, n), rng.uniform(-3.0, 3.0, n)


def arm_paths() -> dict[str, Path]:
    paths = {
        "two_link": ARMS / "two_link.urdf",
        "planar_3link": ARMS / "planar_3link.urdf",
        "spatial_3dof": ARMS / "spatial_3dof.urdf",
    }
    try:
        paths["ur5"] = adparm.example_robot_urdf("ur5")
    except ModuleNotFoundError:  # example-robot-data is in the test extra; say so if missing
        pass
    return paths


ARM_PATHS = arm_paths()


def test_example_robot_data_is_installed() -> None:
    assert "ur5" in ARM_PATHS, "pip install example-robot-data (adparm's test extra)"


# --- the paper's arm -----------------------------------------------------------------------------


def test_two_link_urdf_matches_the_builtin_model(rng) -> None:
    coulomb, viscous = -0.1, 0.3
    arm = adparm.UrdfArm(
        ARMS / "two_link.urdf", gravity=[0, 0, -9.8], coulomb=coulomb, viscous=viscous
    )
    assert arm.dof == 2
    assert arm.joint_names == ["joint1", "joint2"]
    assert arm.joint_types == ["continuous", "continuous"]
    states = list(random_states(rng, 2, 200)) + [(np.zeros(2), np.zeros(2))]
    for q, dq in states:
        ours = arm.terms(q, dq)
        theirs = builtin_terms(q, dq, coulomb, viscous)
        for name in ("M", "C", "G", "F", "M_inv"):
            np.testing.assert_allclose(ours[name], theirs[name], rtol=0, atol=1e-12, err_msg=name)


def test_two_link_urdf_differs_from_a_different_builtin_arm(rng) -> None:
    # the comparison above can fail: the URDF is not the arm with p3 = 1.1
    arm = adparm.UrdfArm(ARMS / "two_link.urdf", gravity=[0, 0, -9.8])
    p = _core.ArmParameters()
    p.p3, p.coulomb = 1.1, 0.0
    q, dq = np.array([0.3, 0.4]), np.array([1.0, -1.0])
    assert np.abs(arm.terms(q, dq)["M"] - _core.arm_terms(p, q, dq)["M"]).max() > 0.05


# --- an independent NumPy model of the planar 3-link arm -----------------------------------------


def planar_3link_numpy(q: np.ndarray, g: float = 9.81) -> tuple[np.ndarray, np.ndarray]:
    """M(q) and G(q) of examples/arms/planar_3link.urdf from its link data: rods of length l,
    mass m, centre of mass at l/2, inertia m l^2 / 12 about the joint axis, and a 0.2 kg point
    mass at the tip of link 3. Arm in the x-z plane, angles from the horizontal."""
    lengths = np.array([0.5, 0.4, 0.3])
    bodies = [  # (link, distance of the mass along it, mass, inertia about its own centre)
        (0, 0.25, 2.0, 2.0 * 0.5**2 / 12),
        (1, 0.20, 1.5, 1.5 * 0.4**2 / 12),
        (2, 0.15, 1.0, 1.0 * 0.3**2 / 12),
        (2, 0.30, 0.2, 0.0),
    ]
    theta = np.cumsum(q)
    M = np.zeros((3, 3))
    G = np.zeros(3)
    for link, distance, mass, inertia in bodies:
        # position of the mass: sum of the previous links plus `distance` along this one
        reach = np.append(lengths[:link], distance)
        angles = theta[: link + 1]
        J = np.zeros((2, 3))  # d(x, z)/dq
        for j in range(link + 1):
            J[0, j] = -np.sum(reach[j:] * np.sin(angles[j:]))
            J[1, j] = np.sum(reach[j:] * np.cos(angles[j:]))
        spin = np.zeros(3)
        spin[: link + 1] = 1.0
        M += mass * J.T @ J + inertia * np.outer(spin, spin)
        G += mass * g * J[1]
    return M, G


def test_planar_3link_matches_numpy(rng) -> None:
    arm = adparm.UrdfArm(ARMS / "planar_3link.urdf")
    assert arm.joint_names == ["shoulder", "elbow", "wrist"]
    for q, dq in random_states(rng, 3):
        terms = arm.terms(q, dq)
        M, G = planar_3link_numpy(q)
        np.testing.assert_allclose(terms["M"], M, rtol=0, atol=1e-12)
        np.testing.assert_allclose(terms["G"], G, rtol=0, atol=1e-12)


# --- against Pinocchio's Python bindings ---------------------------------------------------------


@pytest.mark.parametrize("name", [n for n in ARM_PATHS if n != "two_link"])
def test_terms_match_pinocchio_python(name: str, rng) -> None:
    gravity = [0.3, -0.2, -9.81]
    arm = adparm.UrdfArm(ARM_PATHS[name], gravity=gravity)
    for q, dq in random_states(rng, arm.dof, 10):
        ours = arm.terms(q, dq)
        theirs = pinocchio_terms(ARM_PATHS[name], gravity, q, dq)
        scale = np.abs(theirs["M"]).max()
        for key in ("M", "C", "G"):
            np.testing.assert_allclose(ours[key], theirs[key], rtol=0, atol=1e-10 * max(1, scale))
        np.testing.assert_allclose(ours["M_inv"], theirs["M_inv"], rtol=1e-9, atol=1e-9)
    assert arm.joint_names == theirs["names"]
    np.testing.assert_array_equal(arm.inertial_parameters, theirs["pi"])


def tree_and_chain_paths(tmp_path_factory) -> dict[str, Path]:
    """Every example robot that reads without locked joints, the test tree (a prismatic branch)
    and three random chains of bench/every_arm.py."""
    paths = {"branched": Path(__file__).parent / "branched.urdf"}
    for name in adparm.EXAMPLE_ROBOTS:
        if name not in EXAMPLE_LOCKED_JOINTS:  # Panda and Baxter read only with locked joints
            paths[name] = adparm.example_robot_urdf(name)
    folder = tmp_path_factory.mktemp("chains")
    for seed, joints in ((3, 4), (11, 7), (29, 9)):
        path = folder / f"chain{joints}_{seed}.urdf"
        path.write_text(every_arm.random_chain_urdf(np.random.default_rng(seed), joints))
        paths[path.stem] = path
    return paths


def test_mass_and_gravity_from_the_coriolis_pass_are_pinocchios(tmp_path_factory, rng) -> None:
    """M and G come from the Coriolis pass's composite inertias (PinocchioArm::compute) in place
    of pinocchio::crba and computeGeneralizedGravity: the same to round-off on every example
    robot, a tree and random chains, with gravity off the vertical."""
    gravity = [0.7, -0.4, -9.81]
    paths = tree_and_chain_paths(tmp_path_factory)
    assert {"branched", "ur5", "kinova", "chain9_29"} <= set(paths)
    for name, path in paths.items():
        arm = adparm.UrdfArm(path, gravity=gravity)
        for q, dq in random_states(rng, arm.dof, 4):
            ours = arm.terms(q, dq)
            theirs = pinocchio_terms(path, gravity, q, dq)
            for key in ("M", "G", "C"):
                scale = max(1.0, np.abs(theirs[key]).max())
                np.testing.assert_allclose(
                    ours[key], theirs[key], rtol=0, atol=1e-13 * scale, err_msg=f"{name} {key}"
                )
            np.testing.assert_array_equal(ours["M"], ours["M"].T)


def test_ur5_has_six_revolute_joints_with_limits() -> None:
    arm = adparm.UrdfArm(adparm.example_robot_urdf("ur5"))
    assert arm.dof == 6
    assert arm.joint_types == ["revolute"] * 6
    assert arm.joint_names[0] == "shoulder_pan_joint"
    assert np.all(np.isfinite(arm.limits["lower"])) and np.all(arm.limits["upper"] > 0)


def test_prismatic_and_continuous_joints(tmp_path, rng) -> None:
    text = (ARMS / "spatial_3dof.urdf").read_text()
    text = text.replace('name="base_yaw" type="revolute"', 'name="base_yaw" type="continuous"')
    text = text.replace(
        'name="elbow_pitch" type="revolute">',
        'name="elbow_pitch" type="prismatic">',
    )
    path = tmp_path / "mixed.urdf"
    path.write_text(text)
    arm = adparm.UrdfArm(path)
    assert arm.joint_types == ["continuous", "revolute", "prismatic"]
    assert arm.limits["lower"][0] == -np.inf and arm.limits["upper"][0] == np.inf
    for q, dq in random_states(rng, 3, 5):
        ours = arm.terms(q, dq)
        theirs = pinocchio_terms(path, [0, 0, -9.81], q, dq)
        for key in ("M", "C", "G", "M_inv"):
            np.testing.assert_allclose(ours[key], theirs[key], rtol=1e-10, atol=1e-10)


# --- properties ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(ARM_PATHS))
def test_dM_dt_minus_2C_is_skew_symmetric(name: str, rng) -> None:
    arm = adparm.UrdfArm(ARM_PATHS[name])
    h = 1e-6
    for q, dq in random_states(rng, arm.dof, 10):
        dM = (arm.terms(q + h * dq, dq)["M"] - arm.terms(q - h * dq, dq)["M"]) / (2 * h)
        C = arm.terms(q, dq)["C"]
        N = dM - 2 * C
        assert np.abs(N + N.T).max() < 1e-6 * max(1.0, np.abs(dM).max())
        # and the test can fail: with C halved, dM/dt - C = C^T is not skew (C + C^T = dM/dt)
        wrong = dM - C
        assert np.abs(wrong + wrong.T).max() > 1e-4 * np.abs(dM).max()


@pytest.mark.parametrize("name", list(ARM_PATHS))
def test_mass_matrix_is_symmetric_positive_definite(name: str, rng) -> None:
    arm = adparm.UrdfArm(ARM_PATHS[name])
    for q, dq in random_states(rng, arm.dof, 10):
        terms = arm.terms(q, dq)
        M = terms["M"]
        np.testing.assert_array_equal(M, M.T)
        np.testing.assert_array_equal(terms["M_inv"], terms["M_inv"].T)
        assert np.linalg.eigvalsh(M).min() > 0
        np.testing.assert_allclose(terms["M_inv"] @ M, np.eye(arm.dof), rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", list(ARM_PATHS))
def test_mass_matrix_is_linear_in_the_inertial_parameters(name: str, rng) -> None:
    arm = adparm.UrdfArm(ARM_PATHS[name])
    pi = arm.inertial_parameters
    assert pi.shape == (10 * arm.dof,)
    for q, dq in random_states(rng, arm.dof, 5):
        Mk = arm.mass_regressor(q)
        assert Mk.shape == (10 * arm.dof, arm.dof, arm.dof)
        M = arm.terms(q, dq)["M"]
        np.testing.assert_allclose(np.einsum("k,kij->ij", pi, Mk), M, rtol=0, atol=1e-10)
        np.testing.assert_allclose(Mk, Mk.transpose(0, 2, 1), rtol=0, atol=1e-12)
        # each M_k is a derivative: the mass of body 1 moves M only through its own M_k
        changed = pi.copy()
        changed[0] += 1.0
        assert np.abs(np.einsum("k,kij->ij", changed, Mk) - M - Mk[0]).max() < 1e-10


@pytest.mark.parametrize(
    "name, count",
    # 7 and 13 as in issue 14's NumPy prototype; the two-link arm has p1, p2, p3 and the
    # coefficient of sin q2 (the first moment of link 2 across the link), which is 0 here
    [("two_link", 4), ("planar_3link", 7), ("spatial_3dof", 13), ("ur5", None)],
)
def test_base_parameters(name: str, count: int | None, rng) -> None:
    if name not in ARM_PATHS:
        pytest.fail("example-robot-data is missing")
    arm = adparm.UrdfArm(ARM_PATHS[name])
    values, columns, combination = arm.base_parameters()
    if count is not None:
        assert len(values) == count
    # the core's product (Eigen) and NumPy's may differ in the last bits
    np.testing.assert_allclose(
        combination @ arm.inertial_parameters, values, rtol=1e-13, atol=1e-15
    )
    for q, dq in random_states(rng, arm.dof, 5):  # poses other than the sampled ones
        Mk = arm.mass_regressor(q)
        M = np.einsum("i,ijk->jk", values, Mk[columns])
        np.testing.assert_allclose(M, arm.terms(q, dq)["M"], rtol=0, atol=1e-10)
    # minimal: no M_k of the chosen columns is a combination of the others
    stacked = np.stack(
        [
            arm.mass_regressor(q)[columns].reshape(len(columns), -1)
            for q, _ in random_states(rng, arm.dof, 10)
        ],
        axis=1,
    )
    assert np.linalg.matrix_rank(stacked.reshape(len(columns), -1)) == len(columns)


def test_two_link_mass_regressor_gives_p1_p2_p3(rng) -> None:
    # the built-in M = p1 M1 + p2 M2 + p3 M3: the same M from the URDF's parameters
    arm = adparm.UrdfArm(ARMS / "two_link.urdf", gravity=[0, 0, -9.8])
    q = rng.uniform(-np.pi, np.pi, 2)
    M = np.einsum("k,kij->ij", arm.inertial_parameters, arm.mass_regressor(q))
    np.testing.assert_allclose(M, builtin_terms(q, q, 0, 0)["M"], rtol=0, atol=1e-12)


def test_friction_per_joint() -> None:
    arm = adparm.UrdfArm(ARMS / "planar_3link.urdf", coulomb=[0.1, 0.2, 0.3], viscous=0.5)
    dq = np.array([1.0, -2.0, 0.0])
    F = arm.terms(np.zeros(3), dq)["F"]
    np.testing.assert_allclose(F, [0.1 + 0.5, -0.2 - 1.0, 0.0], rtol=0, atol=1e-15)


# --- refused input -------------------------------------------------------------------------------

JOINT = """
  <joint name="{name}" type="{type}">
    <parent link="{parent}"/><child link="{child}"/>
    <axis xyz="0 0 1"/>{extra}
  </joint>"""
LINK = """
  <link name="{name}"><inertial><mass value="1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>"""


def urdf_text(*joints: tuple[str, str, str]) -> str:
    links = ["base"] + [f"link{i}" for i in range(1, len(joints) + 1)]
    parts = [LINK.format(name=name) for name in links]
    for i, (name, kind, extra) in enumerate(joints):
        parts.append(
            JOINT.format(name=name, type=kind, parent=links[i], child=links[i + 1], extra=extra)
        )
    return '<?xml version="1.0"?>\n<robot name="test">' + "".join(parts) + "\n</robot>\n"


LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


@pytest.mark.parametrize(
    "text, message",
    [
        ("this is not XML", "not a valid URDF"),
        ('<?xml version="1.0"?><robot name="x"><link name="a"/>', "not a valid URDF"),
        (urdf_text(("weld", "fixed", "")), "no actuated joint"),
        (urdf_text(("free", "floating", "")), "joint 'free' is floating (a floating base)"),
        (urdf_text(("slide", "planar", "")), "joint 'slide' is planar"),
        (
            urdf_text(("a", "revolute", LIMIT), ("b", "revolute", LIMIT + '<mimic joint="a"/>')),
            "joint 'b' is a mimic joint (of 'a')",
        ),
        (urdf_text(("ball", "spherical", "")), "not a valid URDF"),
    ],
    ids=["not-xml", "truncated", "no-joint", "floating", "planar", "mimic", "spherical"],
)
def test_refused_urdf(tmp_path, text: str, message: str) -> None:
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    with pytest.raises(ValueError, match=re.escape(f"URDF {path}: ") + ".*" + re.escape(message)):
        adparm.UrdfArm(path)


def test_a_valid_test_urdf_is_accepted(tmp_path) -> None:
    # the refusals above are about the named problem, not the test URDF's form
    path = tmp_path / "arm.urdf"
    path.write_text(urdf_text(("a", "revolute", LIMIT), ("b", "continuous", "")))
    assert adparm.UrdfArm(path).joint_types == ["revolute", "continuous"]


def test_missing_file_is_refused(tmp_path) -> None:
    with pytest.raises(ValueError, match="no such file"):
        adparm.UrdfArm(tmp_path / "missing.urdf")
    with pytest.raises(ValueError, match="cannot open the file"):
        _core.UrdfArm(str(tmp_path / "missing.urdf"))


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda arm: arm.terms(np.zeros(2), np.zeros(3)), "q: expected shape (3,), got (2,)"),
        (lambda arm: arm.terms(np.zeros(3), np.zeros(4)), "dq: expected shape (3,), got (4,)"),
        (lambda arm: arm.mass_regressor(np.zeros((3, 1))), "q: expected shape (3,)"),
        (lambda arm: arm._arm.terms(np.zeros(2), np.zeros(3)), "q: expected shape (3, 1)"),
        (lambda arm: arm._arm.mass_regressor(np.zeros(4)), "q: expected shape (3, 1)"),
    ],
)
def test_sizes_are_checked(call, message: str) -> None:
    arm = adparm.UrdfArm(ARMS / "planar_3link.urdf")
    with pytest.raises(ValueError, match=re.escape(message)):
        call(arm)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"gravity": [0, -9.81]}, "gravity: expected shape (3,), got (2,)"),
        ({"coulomb": [0.1, 0.2]}, "coulomb: expected 3 values (one per joint of"),
        ({"viscous": [[0.1]]}, "viscous: expected one number or one per joint"),
        ({"gravity": [0, 0, np.nan]}, "gravity: must be finite"),
        ({"coulomb": np.inf}, "coulomb: must be finite"),
    ],
)
def test_bad_arguments_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        adparm.UrdfArm(ARMS / "planar_3link.urdf", **kwargs)


def test_example_robot_urdf() -> None:
    assert adparm.example_robot_urdf("ur5").name == "ur5_robot.urdf"
    assert adparm.example_robot_urdf("ur_description/urdf/ur3_robot.urdf").is_file()
    with pytest.raises(ValueError, match="no robot 'r2d2' .known names: "):
        adparm.example_robot_urdf("r2d2")


# --- the guide's examples ------------------------------------------------------------------------

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "urdf-arms.md"


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", path.read_text(), flags=re.S | re.M)


def test_guide_has_examples() -> None:
    assert len(python_blocks(GUIDE)) >= 4


@pytest.mark.parametrize("index", range(len(python_blocks(GUIDE))))
def test_guide_example_runs(index: int, tmp_path, monkeypatch, capsys) -> None:
    (tmp_path / "examples").symlink_to(ARMS.parent, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    exec(compile(python_blocks(GUIDE)[index], f"{GUIDE.name}[{index}]", "exec"), {})
    assert capsys.readouterr().out  # every example prints what it shows


def test_a_config_reads_its_urdf_once_per_file_version(monkeypatch, tmp_path) -> None:
    """Building a URDF config and simulating it read the file in Python once: its kinematics
    (joints, structured basis size, rates) and the arm with the config's gravity and friction
    share the parse (issue 23: it was read 19 times, then twice); a changed file is read
    again."""
    import shutil

    import adparm._core

    urdf = tmp_path / "arm.urdf"
    shutil.copy(ARMS / "planar_3link.urdf", urdf)
    reads = []
    real = adparm._core.UrdfArm

    def counting(*args, **kwargs):
        reads.append(args[0])
        return real(*args, **kwargs)

    monkeypatch.setattr(adparm._core, "UrdfArm", counting)
    plant = {"urdf": str(urdf), "coulomb": 0.05}
    config = adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.01}})
    adparm.simulate(config, diagnose=False)
    assert len(reads) == 1
    urdf.write_text(urdf.read_text() + "\n<!-- changed -->\n")
    adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.01}})
    assert len(reads) == 2
