"""The closed loop of an n-joint URDF arm written plainly in NumPy + Pinocchio's Python bindings,
to be timed against the C++ core (bench/urdf_speed.py).

This is how a researcher would code the loop for their own arm without adparm's core: the arm's
M(q), C(q, dq) and G(q) from ``pinocchio`` (``pin.crba``, ``pin.computeCoriolisMatrix``,
``pin.computeGeneralizedGravity``), small ``np.array`` objects and ``@`` products, the
extrapolation points handled together by batched products (``np.einsum``), one Python call of the
right-hand side per RK4 stage. It is fair to NumPy: everything that depends only on the settings
(R^-1, the points, their weight-free HJB parts for the set-point, ...) is computed once.

The laws are the core's (closed_loop.hpp), for a constant set-point qd:
  e1 = qd - q, e2 = -dq + alpha1 e1, x = [e1; e2]; dx = f(x) + g(x) u, f = [-alpha1 e1 + e2;
  -M^-1 C e2], g = [0; M^-1]; u_hat = -1/2 R^-1 B^T Wa with B = (dphi/dx) g (eq. 20);
  omega = (dphi/dx) f + B u_hat, eps = x^T Q x + u_hat^T R u_hat + Wc^T omega (eq. 21);
  critic eqs. (23)-(24) with rho = 1 + nu omega^T Gamma omega and covariance resetting
  (Gamma = gamma0 I after a step that leaves lambda_min(Gamma) < epsilon_T); actor eq. (26) with
  the projection onto ||Wa|| <= weight_bound; Bellman-error extrapolation: each law gains the
  average of its term over N fixed points in x (drawn as the core draws them: NumPy's
  RandomState(seed).random_sample((N, 2n)) mapped to box (2 u - 1)); the input u = u_hat (no
  probing signal, no RISE), the torque tau = h - u with the feedforward
  h = M alpha1 (-dq) + C alpha1 e1 + G + F, the plant M ddq + C dq + G + F + tau_d = tau with
  tau_d,j = a_j sin t (odd j, from 1) or a_j cos t (even j); the accumulated cost
  dJ = x^T Q x + u^T R u; classical RK4 with step dt. The believed model is the plant.

A basis is a small object with ``size``, ``phi(x)`` and ``jacobian(x)`` (d phi / dx, size x 2n);
``QuadraticBasis`` is every x_i x_j (i <= j) in the order of ``adparm.bases.quadratic_terms``;
``StructuredBasis`` is the structured basis of a URDF arm (e1_i e1_j, then e2^T M_b(q) e2 per base
inertial parameter b: cpp/src/pinocchio_structured_basis.cpp) from Pinocchio's kinetic-energy
regressor and kinematics derivatives, for a constant set-point qd.

State layout (the core's): [q (n), dq (n), Wc (K), Wa (K), Gamma (K x K, column-major), nu (n,
zero without RISE), J (1)]. ``NumpyPinocchioLoop(...).run(steps)`` returns the states at
t = 0, dt, ..., steps dt.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin


class QuadraticBasis:
    """phi(x) = [x_i x_j for i <= j] (2n (2n + 1) / 2 functions of x, 2n) and its exact
    Jacobian."""

    def __init__(self, joints: int) -> None:
        self.state_dim = 2 * joints
        self.i, self.j = np.triu_indices(self.state_dim)  # (0, 0), (0, 1), ..., (1, 1), ...
        self.size = len(self.i)
        self.rows = np.arange(self.size)

    def phi(self, x: np.ndarray) -> np.ndarray:
        return x[self.i] * x[self.j]

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        J = np.zeros((self.size, self.state_dim))
        J[self.rows, self.i] = x[self.j]
        J[self.rows, self.j] += x[self.i]  # x_i^2: 2 x_i
        return J


def _cross(a: np.ndarray) -> np.ndarray:
    """[a]x, the matrix of a x . (3 x 3)."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def energy_gradient_matrices() -> np.ndarray:
    """A_k (10, 6, 6): the gradient of 2 T_k with respect to a body's local spatial velocity
    (v, w) is A_k (v, w), for Pinocchio's parameter order m, mc_x, mc_y, mc_z, I_xx, I_xy, I_yy,
    I_xz, I_yz, I_zz (2 T_k is a quadratic form: 2 T_k = 1/2 (v, w) . A_k (v, w))."""
    A = np.zeros((10, 6, 6))
    A[0, :3, :3] = 2.0 * np.eye(3)  # 2 T = |v|^2
    for a in range(3):  # 2 T = 2 (v x w)_a: d/dv = 2 w x e_a, d/dw = 2 e_a x v
        e = np.eye(3)[a]
        A[1 + a, :3, 3:] = -2.0 * _cross(e)
        A[1 + a, 3:, :3] = 2.0 * _cross(e)
    pairs = [(0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)]
    for k, (a, b) in enumerate(pairs, start=4):
        A[k, 3 + a, 3 + b] = A[k, 3 + b, 3 + a] = 2.0  # 2 T = w_a^2 or 2 w_a w_b
    return A


class StructuredBasis:
    """phi(x) = [e1_i e1_j (i <= j, row by row); e2^T M_b(q) e2 for each base inertial parameter
    b], q = qd - e1, with its exact Jacobian, at a constant set-point qd (the desired rate is
    zero). ``values``, ``columns``: the base parameters and their indices into the arm's 10 n
    inertial parameters (``adparm.UrdfArm(path).base_parameters()[:2]``, the core's choice).

    e2^T M_k(q) e2 = 2 T_k(q, v = e2), T_k the kinetic-energy regressor's column k
    (``pin.computeKineticEnergyRegressor``); its gradient with respect to the body's local
    velocity V = (v, w) is A_k V, and d phi_b / d e1 = -A_k V dV/dq, d phi_b / d e2 = A_k V dV/dv
    with dV/dq, dV/dv from ``pin.computeForwardKinematicsDerivatives`` and
    ``pin.getJointVelocityDerivatives`` (LOCAL frame)."""

    def __init__(self, arm: PinocchioArm, values, columns, qd) -> None:
        n = arm.dof
        self.arm, self.n = arm, n
        self.qd = np.asarray(qd, dtype=float)
        self.values = np.asarray(values, dtype=float)
        self.columns = np.asarray(columns, dtype=int)
        self.i, self.j = np.triu_indices(n)
        self.e1_size = len(self.i)
        self.size = self.e1_size + len(self.columns)
        self.rows = np.arange(self.e1_size)
        self.bodies = self.columns // 10 + 1  # Pinocchio's joint index of each base parameter
        self.joints = sorted(set(self.bodies.tolist()))
        self.A = energy_gradient_matrices()[self.columns % 10]  # (r, 6, 6)
        self.zero = np.zeros(n)

    def optimal_weights(self, K: np.ndarray) -> np.ndarray:
        """W* = [K_ii on squares, K_ij + K_ji on cross terms; the base parameters]."""
        K = np.asarray(K, dtype=float)
        e1 = np.where(self.i == self.j, K[self.i, self.j], K[self.i, self.j] + K[self.j, self.i])
        return np.concatenate([e1, self.values])

    def _kinematics(self, x: np.ndarray):
        e1, e2 = x[: self.n], x[self.n :]
        c = self.arm.configuration(self.qd - e1)
        return c, e2

    def phi(self, x: np.ndarray) -> np.ndarray:
        c, e2 = self._kinematics(x)
        e1 = x[: self.n]
        T = pin.computeKineticEnergyRegressor(self.arm.model, self.arm.data, c, e2)
        return np.concatenate([e1[self.i] * e1[self.j], 2.0 * np.asarray(T).ravel()[self.columns]])

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        n = self.n
        model, data = self.arm.model, self.arm.data
        c, e2 = self._kinematics(x)
        pin.computeForwardKinematicsDerivatives(model, data, c, e2, self.zero)
        V = np.zeros((model.njoints, 6))
        dV = np.zeros((model.njoints, 6, 2 * n))  # [d V / d e1, d V / d e2] = [-dV/dq, dV/dv]
        for joint in self.joints:
            V[joint] = data.v[joint].vector
            dq, dv = pin.getJointVelocityDerivatives(model, data, joint, pin.LOCAL)
            dV[joint, :, :n] = -dq
            dV[joint, :, n:] = dv
        gradients = np.einsum("bkl,bl->bk", self.A, V[self.bodies])  # (r, 6)
        J = np.zeros((self.size, 2 * n))
        J[self.rows, self.i] = x[self.j]
        J[self.rows, self.j] += x[self.i]
        J[self.e1_size :] = np.einsum("bk,bkm->bm", gradients, dV[self.bodies])
        return J


class PinocchioArm:
    """M, C, G, F of a URDF arm through Pinocchio's Python bindings; the joints are the URDF's
    in Pinocchio's model order, a continuous joint's q its angle."""

    def __init__(self, urdf: str | Path, gravity, coulomb=0.0, viscous=0.0) -> None:
        self.model = pin.buildModelFromUrdf(str(urdf))
        self.model.gravity.linear = np.asarray(gravity, dtype=float)
        self.data = self.model.createData()
        self.dof = self.model.nv
        self.coulomb = np.broadcast_to(np.asarray(coulomb, dtype=float), (self.dof,)).copy()
        self.viscous = np.broadcast_to(np.asarray(viscous, dtype=float), (self.dof,)).copy()
        # continuous joints store (cos q, sin q)
        self.continuous = [
            (joint.idx_q, joint.idx_v) for joint in self.model.joints[1:] if joint.nq == 2
        ]
        self.angle = [
            (joint.idx_q, joint.idx_v) for joint in self.model.joints[1:] if joint.nq == 1
        ]

    def configuration(self, q: np.ndarray) -> np.ndarray:
        if not self.continuous:
            return q
        c = np.empty(self.model.nq)
        for iq, iv in self.angle:
            c[iq] = q[iv]
        for iq, iv in self.continuous:
            c[iq], c[iq + 1] = np.cos(q[iv]), np.sin(q[iv])
        return c

    def terms(self, q: np.ndarray, dq: np.ndarray):
        c = self.configuration(q)
        M = pin.crba(self.model, self.data, c)
        M = np.triu(M) + np.triu(M, 1).T  # CRBA fills the upper triangle
        C = pin.computeCoriolisMatrix(self.model, self.data, c, dq).copy()
        G = pin.computeGeneralizedGravity(self.model, self.data, c).copy()
        F = self.coulomb * np.sign(dq) + self.viscous * dq
        return M, C, G, F


@dataclass
class LoopSettings:
    """The settings of one run (n joints, K basis functions); the defaults are those of the
    URDF loop cases of the C++ bench (bench_closed_loop.cpp, urdf_settings)."""

    q0: np.ndarray
    qd: np.ndarray
    critic_weights: np.ndarray
    actor_weights: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    alpha1: np.ndarray
    dq0: np.ndarray | None = None
    disturbance: np.ndarray | None = None
    eta_c: float = 800.0
    nu: float = 1.0
    gamma0: float = 100.0
    epsilon_T: float = 1e-3
    eta_a1: float = 0.01
    eta_a2: float = 1.0
    weight_bound: float = 100.0
    points: int = 0
    box: np.ndarray | None = None
    seed: int = 0
    dt: float = 1e-3


def bench_settings(arm: PinocchioArm, basis, points: int) -> LoopSettings:
    """The C++ bench's URDF loop case (bench_closed_loop.cpp, urdf_settings): qd = 0 from
    q0 = 0.2 rad at rest, K = I, alpha1 = 2 I, R = I, Q = [[K alpha1 + alpha1^T K, -K],
    [-K, R^-1]], no disturbance, eta_c = 1 (the quadratic basis diverges with the paper's 800),
    initial weights of x^T blockdiag(I, M(0)) x (quadratic basis) or W* = [entries of K = I; the
    base parameters] (structured basis, Python's default)."""
    n = arm.dof
    identity = np.eye(n)
    if isinstance(basis, StructuredBasis):
        weights = basis.optimal_weights(identity)
    else:
        M0 = arm.terms(np.zeros(n), np.zeros(n))[0]
        P = np.block([[identity, np.zeros((n, n))], [np.zeros((n, n)), M0]])
        weights = np.where(basis.i == basis.j, P[basis.i, basis.j], 2.0 * P[basis.i, basis.j])
    return LoopSettings(
        q0=np.full(n, 0.2),
        qd=np.zeros(n),
        critic_weights=weights,
        actor_weights=weights.copy(),
        Q=np.block([[4.0 * identity, -identity], [-identity, identity]]),
        R=identity,
        alpha1=2.0 * identity,
        eta_c=1.0,
        points=points,
    )


class NumpyPinocchioLoop:
    """The closed loop of ``arm`` (plant and believed model) with ``basis`` and ``settings`` (see
    the module docstring for the laws)."""

    def __init__(self, arm: PinocchioArm, basis, settings: LoopSettings) -> None:
        self.arm, self.basis, self.s = arm, basis, settings
        n, K = arm.dof, basis.size
        self.n, self.K = n, K
        self.qd = np.asarray(settings.qd, dtype=float)
        self.alpha1 = np.asarray(settings.alpha1, dtype=float)
        self.Q = np.asarray(settings.Q, dtype=float)
        self.R = np.asarray(settings.R, dtype=float)
        self.Rinv = np.linalg.inv(self.R)
        self.disturbance = (
            np.zeros(n) if settings.disturbance is None else np.asarray(settings.disturbance)
        )
        self.odd = np.arange(n) % 2 == 0  # joints 1, 3, ...: sin t
        self.dq0 = np.zeros(n) if settings.dq0 is None else np.asarray(settings.dq0)
        self.gamma_reset = (settings.gamma0 * np.eye(K)).reshape(-1, order="F")
        # offsets of the state
        self.o_wc = 2 * n
        self.o_wa = self.o_wc + K
        self.o_gamma = self.o_wa + K
        self.o_nu = self.o_gamma + K * K
        self.size = self.o_nu + n + 1
        self._prepare_points()

    def _prepare_points(self) -> None:
        """The fixed points and, for the set-point, their weight-free HJB parts: (dphi/dx) f,
        B = (dphi/dx) g and x^T Q x."""
        s, n = self.s, self.n
        N = s.points
        if N == 0:
            self.point_drift = self.point_B = self.point_cost = None
            return
        box = np.ones(2 * n) if s.box is None else np.asarray(s.box, dtype=float)
        u = np.random.RandomState(s.seed).random_sample((N, 2 * n))
        X = box * (2.0 * u - 1.0)
        drift, B, cost = [], [], []
        for x in X:
            e1, e2 = x[:n], x[n:]
            q = self.qd - e1
            dq = self.alpha1 @ e1 - e2  # dqd = 0
            M, C, _, _ = self.arm.terms(q, dq)
            Minv = np.linalg.inv(M)
            J = self.basis.jacobian(x)
            f = np.concatenate([-self.alpha1 @ e1 + e2, -Minv @ (C @ e2)])
            drift.append(J @ f)
            B.append(J[:, n:] @ Minv)
            cost.append(x @ self.Q @ x)
        self.point_drift = np.array(drift)  # (N, K)
        self.point_B = np.array(B)  # (N, K, n)
        self.point_cost = np.array(cost)  # (N,)

    def initial_state(self) -> np.ndarray:
        n, K = self.n, self.K
        state = np.zeros(self.size)
        state[:n] = self.s.q0
        state[n : 2 * n] = self.dq0
        state[self.o_wc : self.o_wc + K] = self.s.critic_weights
        state[self.o_wa : self.o_wa + K] = self.s.actor_weights
        state[self.o_gamma : self.o_nu] = self.gamma_reset
        return state

    def derivative(self, t: float, state: np.ndarray) -> np.ndarray:
        s, n, K = self.s, self.n, self.K
        q, dq = state[:n], state[n : 2 * n]
        Wc = state[self.o_wc : self.o_wc + K]
        Wa = state[self.o_wa : self.o_wa + K]
        Gamma = state[self.o_gamma : self.o_nu].reshape(K, K, order="F")

        e1 = self.qd - q
        e2 = -dq + self.alpha1 @ e1
        x = np.concatenate([e1, e2])
        M, C, G, F = self.arm.terms(q, dq)
        Minv = np.linalg.inv(M)
        J = self.basis.jacobian(x)
        B = J[:, n:] @ Minv
        f = np.concatenate([-self.alpha1 @ e1 + e2, -Minv @ (C @ e2)])
        state_cost = x @ self.Q @ x

        # eqs. (20)-(21) on the trajectory
        u_hat = -0.5 * self.Rinv @ (B.T @ Wa)
        omega = J @ f + B @ u_hat
        eps = state_cost + u_hat @ self.R @ u_hat + Wc @ omega

        # critic, eqs. (23)-(24), and the gradient term of the actor, eq. (26)
        difference = Wa - Wc
        Gw = Gamma @ omega
        gain = s.eta_c / (1.0 + s.nu * (omega @ Gw))
        dWc = -(gain * eps) * Gw
        dGamma = -gain * np.outer(Gw, Gw)
        gradient = -(s.eta_a1 * eps / np.sqrt(1.0 + omega @ omega)) * (
            B @ (self.Rinv @ (B.T @ difference))
        )

        if s.points:  # Bellman-error extrapolation: the average over the fixed points
            Bp = self.point_B
            w = 1.0 / s.points
            U = -0.5 * np.einsum("pkn,k->pn", Bp, Wa) @ self.Rinv.T
            Omega = self.point_drift + np.einsum("pkn,pn->pk", Bp, U)
            E = self.point_cost + np.einsum("pn,nm,pm->p", U, self.R, U) + Omega @ Wc
            GO = Omega @ Gamma.T  # rows Gamma omega_i
            gains = w * s.eta_c / (1.0 + s.nu * np.einsum("pk,pk->p", Omega, GO))
            dWc -= (gains * E) @ GO
            dGamma -= GO.T @ (gains[:, None] * GO)
            projected = np.einsum("pkn,k->pn", Bp, difference) @ self.Rinv.T
            coefficients = w * s.eta_a1 * E / np.sqrt(1.0 + np.einsum("pk,pk->p", Omega, Omega))
            gradient -= np.einsum("p,pkn,pn->k", coefficients, Bp, projected)

        # eq. (26) with the projection onto ||Wa|| <= weight_bound
        dWa = gradient - s.eta_a2 * difference
        WaWa = Wa @ Wa
        outward = Wa @ dWa
        if WaWa >= s.weight_bound**2 and outward > 0.0:
            dWa = dWa - outward / WaWa * Wa

        # u = u_hat, tau = h - u, the plant (eq. 1)
        u = u_hat
        h = M @ (self.alpha1 @ (-dq)) + C @ (self.alpha1 @ e1) + G + F
        tau = h - u
        tau_d = self.disturbance * np.where(self.odd, np.sin(t), np.cos(t))
        ddq = Minv @ (tau - C @ dq - G - F - tau_d)

        rate = np.empty(self.size)
        rate[:n] = dq
        rate[n : 2 * n] = ddq
        rate[self.o_wc : self.o_wc + K] = dWc
        rate[self.o_wa : self.o_wa + K] = dWa
        rate[self.o_gamma : self.o_nu] = dGamma.reshape(-1, order="F")
        rate[self.o_nu : self.o_nu + n] = 0.0
        rate[-1] = state_cost + u @ self.R @ u
        return rate

    def step(self, t: float, state: np.ndarray) -> np.ndarray:
        """One RK4 step from (t, state), then Gamma = gamma0 I if lambda_min < epsilon_T."""
        dt = self.s.dt
        k1 = self.derivative(t, state)
        k2 = self.derivative(t + 0.5 * dt, state + 0.5 * dt * k1)
        k3 = self.derivative(t + 0.5 * dt, state + 0.5 * dt * k2)
        k4 = self.derivative(t + dt, state + dt * k3)
        new = state + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        Gamma = new[self.o_gamma : self.o_nu].reshape(self.K, self.K, order="F")
        if np.linalg.eigvalsh(Gamma)[0] < self.s.epsilon_T:
            new[self.o_gamma : self.o_nu] = self.gamma_reset
        return new

    def run(self, steps: int) -> np.ndarray:
        """The states (steps + 1, size) at t = 0, dt, ..., steps dt."""
        states = np.empty((steps + 1, self.size))
        states[0] = state = self.initial_state()
        for k in range(steps):
            state = self.step(k * self.s.dt, state)
            states[k + 1] = state
        return states
