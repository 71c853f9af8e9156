"""The structured basis of a URDF arm (UrdfArm.structured_basis, the C++ PinocchioStructuredBasis):
[e1_i e1_j (i <= j); e2^T M_b(q) e2 per base inertial parameter b], checked against Pinocchio's
Python bindings (CRBA, the kinetic-energy regressor, the Coriolis matrix) and NumPy: the e2 block
sums to e2^T M e2, W*^T phi is V*, the exact Jacobian and desired rate are derivatives, and the
HJB residual vanishes at W* under the exact-solution conditions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import qr as scipy_qr

import adparm
from adparm import _core
from adparm.simulation import core_settings

pin = pytest.importorskip("pinocchio")

ARMS = Path(__file__).resolve().parents[1] / "examples" / "arms"


def arm_path(name: str) -> Path:
    if name == "ur5":
        return adparm.example_robot_urdf("ur5")
    if name == "branched":  # tests/branched.urdf: a tree with a prismatic branch
        return Path(__file__).parent / "branched.urdf"
    return ARMS / f"{name}.urdf"


NAMES = ["planar_3link", "spatial_3dof", "ur5"]
# and, for the checks against Pinocchio's Python bindings, the two-link URDF (continuous joints:
# Pinocchio's cos, sin coordinates), an arm with a prismatic joint (written below) and a branched
# tree (tests/branched.urdf: the basis pairs each body's covectors with its supporting joints'
# columns only)
CHECKED = NAMES + ["two_link", "prismatic", "branched"]

PRISMATIC_URDF = """<robot name="prismatic">
  <link name="base"/>
  <link name="turret"><inertial><origin xyz="0.02 0.01 0.1"/><mass value="2"/>
    <inertia ixx="0.05" ixy="0.001" ixz="0.002" iyy="0.06" iyz="0.003" izz="0.04"/>
  </inertial></link>
  <link name="slider"><inertial><origin xyz="0.2 0.0 0.03"/><mass value="1.5"/>
    <inertia ixx="0.02" ixy="0.0" ixz="0.001" iyy="0.03" iyz="0.0" izz="0.025"/>
  </inertial></link>
  <link name="wrist"><inertial><origin xyz="0.05 0.02 0.0"/><mass value="0.5"/>
    <inertia ixx="0.004" ixy="0.0005" ixz="0.0" iyy="0.003" iyz="0.0002" izz="0.005"/>
  </inertial></link>
  <joint name="yaw" type="revolute"><parent link="base"/><child link="turret"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="reach" type="prismatic"><parent link="turret"/><child link="slider"/>
    <origin xyz="0 0 0.2"/><axis xyz="1 0 0"/>
    <limit lower="0.1" upper="0.8" effort="10" velocity="1"/></joint>
  <joint name="pitch" type="revolute"><parent link="slider"/><child link="wrist"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="2"/></joint>
</robot>
"""


class PinArm:
    """The same URDF through Pinocchio's Python bindings (an implementation independent of the
    core's C++ code), in adparm's coordinates (a continuous joint's q is its angle)."""

    def __init__(self, path: Path) -> None:
        self.model = pin.buildModelFromUrdf(str(path))
        self.data = self.model.createData()
        self.n = self.model.nv

    def configuration(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(self.model.nq)
        for i, joint in enumerate(self.model.joints[1:]):
            if joint.nq == 2:  # continuous: cos, sin
                out[joint.idx_q : joint.idx_q + 2] = np.cos(q[i]), np.sin(q[i])
            else:
                out[joint.idx_q] = q[i]
        return out

    def mass(self, q: np.ndarray) -> np.ndarray:
        M = pin.crba(self.model, self.data, self.configuration(q)).copy()
        return np.triu(M) + np.triu(M, 1).T

    def coriolis(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        return pin.computeCoriolisMatrix(self.model, self.data, self.configuration(q), dq).copy()

    def energy_regressor(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """T_k(q, v) for the 10 n inertial parameters (pinocchio.computeKineticEnergyRegressor)."""
        return pin.computeKineticEnergyRegressor(
            self.model, self.data, self.configuration(q), v
        ).copy()

    def e2_block(self, x: np.ndarray, qd: np.ndarray, columns: np.ndarray) -> np.ndarray:
        """e2^T M_b(q) e2 = 2 T_b(q, e2) at q = qd - e1."""
        n = self.n
        return 2.0 * self.energy_regressor(qd - x[:n], x[n:])[columns]


@pytest.fixture(scope="module", params=CHECKED)
def arm(request, tmp_path_factory) -> tuple[adparm.UrdfArm, PinArm]:
    if request.param == "prismatic":
        path = tmp_path_factory.mktemp("arms") / "prismatic.urdf"
        path.write_text(PRISMATIC_URDF)
    else:
        path = arm_path(request.param)
    return adparm.UrdfArm(path), PinArm(path)


def random_rows(rng: np.random.Generator, n: int, count: int):
    x = rng.uniform(-1.5, 1.5, size=(count, 2 * n))
    qd = rng.uniform(-np.pi, np.pi, size=(count, n))
    dqd = rng.uniform(-2.0, 2.0, size=(count, n))
    return x, qd, dqd


def e1_monomials(e1: np.ndarray) -> np.ndarray:
    n = e1.shape[-1]
    i, j = np.triu_indices(n)  # row by row: e1_1^2, e1_1 e1_2, ..., e1_n^2
    return e1[..., i] * e1[..., j]


def random_exact_instance(rng: np.random.Generator, n: int):
    """K, R SPD and alpha1 with K alpha1 + alpha1^T K = S, S - K R K > 0, so that
    Q = [[S, -K], [-K, R^-1]] > 0 (the exact-solution conditions with a positive definite Q)."""
    A = rng.normal(size=(n, n))
    K = A @ A.T + 0.5 * np.eye(n)
    B = rng.normal(size=(n, n))
    R = B @ B.T + 0.2 * np.eye(n)
    C = rng.normal(size=(n, n))
    S = K @ R @ K + C @ C.T + 0.1 * np.eye(n)
    skew = rng.normal(size=(n, n))
    alpha1 = np.linalg.solve(K, 0.5 * S + (skew - skew.T))
    assert np.linalg.norm(K @ alpha1 + alpha1.T @ K - S) < 1e-9 * np.linalg.norm(S)
    return K, alpha1, R, adparm.solvable_cost(K, alpha1, R)


# --- sizes, names, weights ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, joints, base", [("planar_3link", 3, 7), ("spatial_3dof", 3, 13), ("ur5", 6, None)]
)
def test_number_of_functions(name: str, joints: int, base: int | None) -> None:
    # 13 and 19 as issue 14's prototype found (7 and 13 base parameters)
    arm = adparm.UrdfArm(arm_path(name))
    names = arm.structured_names()
    values, columns, _ = arm.base_parameters()
    assert len(names) == joints * (joints + 1) // 2 + len(values)
    if base is not None:
        assert len(values) == base
    assert names[0] == "e1_1^2" and names[1] == "e1_1 e1_2"
    assert names[joints * (joints + 1) // 2 - 1] == f"e1_{joints}^2"
    parameter_names = arm.inertial_parameter_names
    assert len(parameter_names) == 10 * joints
    e2_names = names[joints * (joints + 1) // 2 :]
    assert e2_names == [f"e2'M_b e2 ({parameter_names[c]})" for c in columns]
    assert list(columns) == sorted(columns)


def test_ur5_size() -> None:
    arm = adparm.UrdfArm(arm_path("ur5"))
    phi, jacobian, rate = arm.structured_basis(np.zeros(12), np.zeros(6))
    assert phi.shape == (len(arm.structured_names()),) and jacobian.shape == (phi.size, 12)
    assert 21 < phi.size <= 128


def test_structured_weights(rng) -> None:
    arm = adparm.UrdfArm(arm_path("planar_3link"))
    K = rng.normal(size=(3, 3))
    W = arm.structured_weights(K)
    np.testing.assert_array_equal(
        W[:6], [K[0, 0], K[0, 1] + K[1, 0], K[0, 2] + K[2, 0], K[1, 1], K[1, 2] + K[2, 1], K[2, 2]]
    )
    np.testing.assert_array_equal(W[6:], arm.base_parameters()[0])
    with pytest.raises(ValueError, match=r"K: expected shape \(3, 3\)"):
        arm.structured_weights(np.eye(2))


def test_weights_of_another_arm_of_the_same_kinematics(rng, tmp_path) -> None:
    # the believed model's basis, the plant's W*: heavier and lighter links, the same geometry
    text = (ARMS / "planar_3link.urdf").read_text()
    heavier = text.replace('<mass value="2.0"/>', '<mass value="2.6"/>').replace(
        '<mass value="1.5"/>', '<mass value="1.2"/>'
    )
    heavier = heavier.replace('iyy="0.02" iyz="0" izz="0.02"', 'iyy="0.03" iyz="0" izz="0.03"')
    assert heavier != text
    (tmp_path / "heavier.urdf").write_text(heavier)
    model = adparm.UrdfArm(ARMS / "planar_3link.urdf")
    plant = adparm.UrdfArm(tmp_path / "heavier.urdf")
    K = np.diag([3.0, 2.0, 1.0])
    W = model.structured_weights(K, plant.inertial_parameters)
    assert np.abs(W - model.structured_weights(K)).max() > 0.05
    x, qd, _ = random_rows(rng, 3, 20)
    phi, _, _ = model.structured_basis(x, qd)
    for i in range(len(x)):
        e1, e2 = x[i, :3], x[i, 3:]
        M = plant.terms(qd[i] - e1, np.zeros(3))["M"]
        assert W @ phi[i] == pytest.approx(e1 @ K @ e1 + e2 @ M @ e2, rel=1e-12)
    with pytest.raises(ValueError, match=r"inertial_parameters: expected shape \(30,\)"):
        model.structured_weights(K, np.ones(20))


def test_bad_shapes_are_refused() -> None:
    arm = adparm.UrdfArm(arm_path("planar_3link"))
    with pytest.raises(ValueError, match=r"x: expected shape \(\.\.\., 6\)"):
        arm.structured_basis(np.zeros(4), np.zeros(3))
    with pytest.raises(ValueError, match=r"qd: expected shape \(\.\.\., 3\)"):
        arm.structured_basis(np.zeros(6), np.zeros(2))
    with pytest.raises(ValueError, match="dqd: shape"):
        arm.structured_basis(np.zeros((4, 6)), np.zeros(3), np.zeros((3, 3)))


# --- base parameters: the C++ choice against an independent SciPy computation ---------------------


def scipy_base_rank(arm: adparm.UrdfArm, rng: np.random.Generator) -> tuple[int, np.ndarray]:
    """Rank and an orthonormal basis of the row space of the stacked M_k entries (SciPy QR at
    other random poses), to compare with the C++ choice."""
    n = arm.dof
    rows = np.triu_indices(n)
    stacked = np.concatenate(
        [
            arm.mass_regressor(rng.uniform(-np.pi, np.pi, n))[:, rows[0], rows[1]].T
            for _ in range(60)
        ]
    )
    _, R, _ = scipy_qr(stacked, mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(R))
    rank = int(np.sum(diagonal > 1e-9 * diagonal[0]))
    _, _, Vt = np.linalg.svd(stacked)
    return rank, Vt[:rank]


def test_base_parameters_against_scipy(arm, rng) -> None:
    ours, reference = arm
    values, columns, combination = ours.base_parameters()
    rank, row_space = scipy_base_rank(ours, rng)
    assert len(values) == len(columns) == rank
    np.testing.assert_allclose(
        combination @ ours.inertial_parameters, values, rtol=1e-13, atol=1e-15
    )
    np.testing.assert_array_equal(combination[:, columns], np.eye(rank))
    for _ in range(5):  # M(q) = sum_b beta_b M_{col b}(q) at poses other than the sampled ones
        q = rng.uniform(-np.pi, np.pi, ours.dof)
        M = np.einsum("b,bij->ij", values, ours.mass_regressor(q)[columns])
        np.testing.assert_allclose(M, reference.mass(q), rtol=0, atol=1e-10)
    # span: every identifiable direction of the parameters is a combination of the chosen
    # columns' rows (the combination's rows span SciPy's row space, and nothing else)
    projection = row_space.T @ row_space
    np.testing.assert_allclose(combination @ projection, combination, atol=1e-8)
    assert np.linalg.matrix_rank(combination @ row_space.T) == rank
    # and the Python method is the C++ choice (one source)
    basis_values, basis_columns, _ = _core.UrdfStructuredBasis(ours._arm).base_parameters
    np.testing.assert_array_equal(basis_values, values)
    np.testing.assert_array_equal(basis_columns, columns)


def test_base_parameters_are_deterministic() -> None:
    first = adparm.UrdfArm(arm_path("spatial_3dof")).base_parameters()
    second = adparm.UrdfArm(arm_path("spatial_3dof")).base_parameters()
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="samples"):
        adparm.UrdfArm(arm_path("spatial_3dof")).base_parameters(samples=0)


# --- the basis against Pinocchio's Python bindings -----------------------------------------------


def test_e2_block_sums_to_the_kinetic_energy(arm, rng) -> None:
    ours, reference = arm
    n = ours.dof
    values, columns, _ = ours.base_parameters()
    x, qd, dqd = random_rows(rng, n, 30)
    phi, _, _ = ours.structured_basis(x, qd, dqd)
    e = n * (n + 1) // 2
    np.testing.assert_allclose(phi[:, :e], e1_monomials(x[:, :n]), rtol=1e-15, atol=0)
    for i in range(len(x)):
        e2 = x[i, n:]
        M = reference.mass(qd[i] - x[i, :n])
        assert values @ phi[i, e:] == pytest.approx(e2 @ M @ e2, rel=1e-12, abs=1e-12)
        # each function on its own: 2 T_b from pin's kinetic-energy regressor
        np.testing.assert_allclose(
            phi[i, e:], reference.e2_block(x[i], qd[i], columns), rtol=1e-12, atol=1e-12
        )


def test_optimal_weights_give_the_value_function(arm, rng) -> None:
    ours, reference = arm
    n = ours.dof
    A = rng.normal(size=(n, n))
    K = A @ A.T + np.eye(n)
    W = ours.structured_weights(K)
    x, qd, _ = random_rows(rng, n, 30)
    phi, _, _ = ours.structured_basis(x, qd)
    value = np.array(
        [
            x[i, :n] @ K @ x[i, :n] + x[i, n:] @ reference.mass(qd[i] - x[i, :n]) @ x[i, n:]
            for i in range(len(x))
        ]
    )
    np.testing.assert_allclose(phi @ W, value, rtol=1e-12)
    # a perturbed inertial weight is not V*
    W[-1] += 0.1 * max(1.0, abs(W[-1]))
    assert np.abs(phi @ W - value).max() > 1e-6 * np.abs(value).max()


def test_jacobian_and_desired_rate_are_derivatives(arm, rng) -> None:
    # against central differences of the independent pin-Python evaluation (and of our own)
    ours, reference = arm
    n = ours.dof
    _, columns, _ = ours.base_parameters()
    e = n * (n + 1) // 2
    x, qd, dqd = random_rows(rng, n, 8)
    phi, jacobian, rate = ours.structured_basis(x, qd, dqd)
    h = 1e-6

    def reference_phi(xi: np.ndarray, qdi: np.ndarray) -> np.ndarray:
        return np.concatenate([e1_monomials(xi[:n]), reference.e2_block(xi, qdi, columns)])

    for i in range(len(x)):
        step = h * np.eye(2 * n)
        numeric = np.stack(
            [
                (reference_phi(x[i] + s, qd[i]) - reference_phi(x[i] - s, qd[i])) / (2 * h)
                for s in step
            ],
            axis=1,
        )
        scale = np.abs(numeric).max()
        np.testing.assert_allclose(jacobian[i], numeric, rtol=0, atol=1e-7 * scale)
        # desired rate: d phi / dt along qd(t) = qd + t dqd
        along = (
            reference_phi(x[i], qd[i] + h * dqd[i]) - reference_phi(x[i], qd[i] - h * dqd[i])
        ) / (2 * h)
        np.testing.assert_allclose(rate[i], along, rtol=0, atol=1e-7 * scale)
        assert np.all(rate[i, :e] == 0.0)
        # our own phi, differenced, agrees too
        upper, _, _ = ours.structured_basis(x[i] + step[0], qd[i])
        lower, _, _ = ours.structured_basis(x[i] - step[0], qd[i])
        np.testing.assert_allclose(jacobian[i, :, 0], (upper - lower) / (2 * h), atol=1e-7 * scale)
    # the e2 block's Jacobian in e1 is not zero (q = qd - e1 enters through M_b(q))
    assert np.abs(jacobian[:, e:, :n]).max() > 1e-3
    # dqd = None is zero: no desired rate
    _, _, still = ours.structured_basis(x, qd)
    assert np.all(still == 0.0)


def test_batch_shapes_broadcast(rng) -> None:
    arm = adparm.UrdfArm(arm_path("spatial_3dof"))
    x = rng.uniform(-1, 1, size=(2, 5, 6))
    qd = rng.uniform(-1, 1, size=3)
    phi, jacobian, rate = arm.structured_basis(x, qd, np.ones(3))
    N = len(arm.structured_names())
    assert phi.shape == (2, 5, N) and jacobian.shape == (2, 5, N, 6) and rate.shape == (2, 5, N)
    one, one_jacobian, one_rate = arm.structured_basis(x[1, 3], qd, np.ones(3))
    np.testing.assert_array_equal(one, phi[1, 3])
    np.testing.assert_array_equal(one_jacobian, jacobian[1, 3])
    np.testing.assert_array_equal(one_rate, rate[1, 3])


# --- the HJB equation holds exactly at W* --------------------------------------------------------


def hjb_residual(ours, reference, x, qd, dqd, alpha1, Q, R, Wc, Wa) -> float:
    """eps = x^T Q x + u^T R u + Wc . (J (f + g u) + rate), u = -1/2 R^-1 g^T J^T Wa, with the
    error system's f(x) = [-alpha1 e1 + e2; -M^-1 C e2], g = [0; M^-1] at q = qd - e1,
    dq = dqd - (e2 - alpha1 e1), M and C from Pinocchio's Python bindings."""
    n = ours.dof
    e1, e2 = x[:n], x[n:]
    q, dq = qd - e1, dqd - (e2 - alpha1 @ e1)
    M, C = reference.mass(q), reference.coriolis(q, dq)
    Minv = np.linalg.inv(M)
    f = np.concatenate([-alpha1 @ e1 + e2, -Minv @ C @ e2])
    g = np.vstack([np.zeros((n, n)), Minv])
    _, J, rate = ours.structured_basis(x, qd, dqd)
    u = -0.5 * np.linalg.solve(R, g.T @ J.T @ Wa)
    return x @ Q @ x + u @ R @ u + Wc @ (J @ (f + g @ u) + rate)


@pytest.mark.parametrize("seed", range(3))
def test_hjb_residual_vanishes_at_optimal_weights(arm, seed: int) -> None:
    ours, reference = arm
    rng = np.random.default_rng(900 + seed)
    n = ours.dof
    K, alpha1, R, Q = random_exact_instance(rng, n)
    W = ours.structured_weights(K)
    x, qd, dqd = random_rows(rng, n, 25)
    worst = 0.0
    for i in range(len(x)):
        scale = x[i] @ Q @ x[i]
        args = (ours, reference, x[i], qd[i], dqd[i], alpha1, Q, R)
        worst = max(worst, abs(hjb_residual(*args, W, W)) / scale)
    assert worst < 1e-10, worst
    # and it can fail: a critic off W* in one inertial weight, or the e1 block
    for index in (n * (n + 1) // 2, len(W) - 1, 0):
        perturbed = W.copy()
        perturbed[index] += 0.05 * max(1.0, abs(W[index]))
        errors = [
            abs(hjb_residual(ours, reference, x[i], qd[i], dqd[i], alpha1, Q, R, perturbed, W))
            / (x[i] @ Q @ x[i])
            for i in range(len(x))
        ]
        assert max(errors) > 1e-6


def test_the_loops_basis_reuses_the_arms_kinematics_to_round_off(arm) -> None:
    """In the loop the basis gets the model's terms at the same q and reuses the joints'
    placements and world motion subspaces of the arm's Coriolis pass (with v and dJ of v = e2
    formed from them) instead of its own forward pass: the core's HJB residual
    (_core.hjb_residual, the loop's path) equals the residual above, whose basis runs its own
    pass (UrdfArm.structured_basis) and whose dynamics are Pinocchio's Python bindings, for weights
    off W*, on every checked arm (a prismatic joint, a branched tree, continuous joints)."""
    ours, reference = arm
    n = ours.dof
    rng = np.random.default_rng(17)
    K, alpha1, R, Q = random_exact_instance(rng, n)
    qd = rng.uniform(-1.0, 1.0, n)
    config = adparm.Config.from_dict(
        {
            "plant": {"urdf": str(ours.path)},
            "controller": {"basis": "structured"},
            "cost": {"Q": Q.tolist(), "R": R.tolist()},
            "control": {"alpha1": alpha1.tolist()},
            "task": {"qd": qd.tolist(), "q0": qd.tolist()},
        }
    )
    W = ours.structured_weights(K)
    x = rng.uniform(-1.0, 1.0, size=(12, 2 * n))
    for Wc, Wa in ((W, W), (W + 0.3 * rng.normal(size=W.size), W + 0.2 * rng.normal(size=W.size))):
        loop = _core.hjb_residual(core_settings(config), x, Wc, Wa, 0.0)
        own = [hjb_residual(ours, reference, xi, qd, np.zeros(n), alpha1, Q, R, Wc, Wa) for xi in x]
        scale = 1.0 + np.einsum("ni,ij,nj->n", x, Q, x)
        np.testing.assert_allclose(loop / scale, np.array(own) / scale, rtol=0, atol=1e-10)


# --- the two-link URDF against the two-link structured basis -------------------------------------


def test_two_link_urdf_spans_the_two_link_structured_basis(rng) -> None:
    # The two-link StructuredBasis' e2 block is [e2^T M1 e2, e2^T M2 e2, e2^T M3(q) e2] with
    # W* = (p1, p2, p3) = (5, 1, 1). The URDF's base parameters add one direction, the first
    # moment of link 2 across the link (a sin q2 term), whose value is 0 for this arm.
    arm = adparm.UrdfArm(ARMS / "two_link.urdf")
    values, _, _ = arm.base_parameters()
    assert len(values) == 4
    x = rng.uniform(-1.5, 1.5, size=(200, 4))
    qd = rng.uniform(-np.pi, np.pi, size=(200, 2))
    phi, _, _ = arm.structured_basis(x, qd)
    assert len(arm.structured_names()) == 7
    urdf_e2 = phi[:, 3:]
    two_link = np.stack(
        [
            _core.basis(_core.BasisKind.structured, x[i], qd[i], np.zeros(2))[0][3:]
            for i in range(len(x))
        ]
    )
    # each two-link function is a fixed combination of the URDF's functions
    coefficients, *_ = np.linalg.lstsq(urdf_e2, two_link, rcond=None)
    np.testing.assert_allclose(urdf_e2 @ coefficients, two_link, atol=1e-12)
    # the URDF block has exactly one more direction, and V*'s e2 part is in the common span
    assert np.linalg.matrix_rank(urdf_e2, tol=1e-9) == 4
    assert np.linalg.matrix_rank(np.hstack([urdf_e2, two_link]), tol=1e-9) == 4
    # p1, p2, p3 recovered from beta: the same e2^T M e2 at every point
    p, *_ = np.linalg.lstsq(two_link, urdf_e2 @ values, rcond=None)
    np.testing.assert_allclose(p, [5.0, 1.0, 1.0], rtol=1e-12)
    np.testing.assert_allclose(two_link @ p, urdf_e2 @ values, atol=1e-12)
    # the e1 block is the two-link one (x1^2, x1 x2, x2^2)
    np.testing.assert_allclose(
        phi[:, :3], np.stack([x[:, 0] ** 2, x[:, 0] * x[:, 1], x[:, 1] ** 2], axis=1), rtol=1e-15
    )


# --- the dynamic path's bounds -------------------------------------------------------------------


def chain_urdf(joints: int) -> str:
    """A serial chain of `joints` revolute joints with axes turning x, y, z (a spatial arm)."""
    link = (
        '<link name="l{i}"><inertial><origin xyz="0.1 0.02 0.05"/><mass value="1"/>'
        '<inertia ixx="0.2" ixy="0.01" ixz="0.02" iyy="0.25" iyz="0.03" izz="0.3"/>'
        "</inertial></link>"
    )
    joint = (
        '<joint name="j{i}" type="revolute"><parent link="l{parent}"/><child link="l{i}"/>'
        '<origin xyz="0.3 0 0.1"/><axis xyz="{axis}"/>'
        '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
    )
    axes = ["0 0 1", "0 1 0", "1 0 0"]
    parts = [link.format(i=0)]
    for i in range(1, joints + 1):
        parts += [link.format(i=i), joint.format(i=i, parent=i - 1, axis=axes[i % 3])]
    return '<robot name="chain">' + "".join(parts) + "</robot>"


def test_arms_beyond_the_dynamic_bounds_are_refused() -> None:
    # at most 12 joints and 128 functions (types.hpp); the message names the field and the count
    arm = _core.UrdfArm.from_xml(chain_urdf(13), name="chain13")
    with pytest.raises(ValueError, match="controller.basis: .*chain13 has 13 joints"):
        _core.UrdfStructuredBasis(arm)
    arm = _core.UrdfArm.from_xml(chain_urdf(12), name="chain12")
    with pytest.raises(ValueError, match=r"chain12 has \d+ functions \(78 for e1 and \d+ base"):
        _core.UrdfStructuredBasis(arm)
    # a chain within the bounds is accepted
    assert _core.UrdfStructuredBasis(_core.UrdfArm.from_xml(chain_urdf(5))).size <= 128


def test_a_basis_beyond_the_core_names_locking_joints_and_that_works(tmp_path) -> None:
    # a random 12-joint chain: 78 e1 functions and 78 base parameters, beyond the core's 128; the
    # message names plant.locked_joints, and with the last two joints locked (119 functions) the
    # arm runs
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    import every_arm

    path = tmp_path / "chain12.urdf"
    path.write_text(every_arm.random_chain_urdf(np.random.default_rng(5), 12))
    with pytest.raises(ValueError, match=r"at most 128: lock joints \(plant\.locked_joints\)"):
        adparm.Config.from_dict({"plant": {"urdf": str(path)}})
    locked = {"joint11": 0.0, "joint12": 0.0}
    plant = {"urdf": str(path), "locked_joints": locked}
    config = adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.01}})
    assert (config.dof, config.basis_size) == (10, 119)
    assert adparm.simulate(config, diagnose=False).status == "finished"
