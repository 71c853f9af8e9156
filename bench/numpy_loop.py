"""The paper's closed loop written plainly in NumPy, to be timed against ``adparm.simulate``.

This is how a researcher would code the loop of ``adparm.paper_config()`` without the C++ core:
small ``np.array`` objects, ``@`` products, ``np.linalg.solve`` for the arm's acceleration and
``np.linalg.eigvalsh`` for the covariance-reset test, one Python call of the right-hand side per
RK4 stage. It is fair to NumPy: everything that depends only on the config (Q, R, R^-1, alpha1,
the RISE gains, the probe's amplitudes, frequencies and phases, the arm parameters, epsilon_T =
``config.resolved_epsilon_T``, e2(0), ...) is computed once in the constructor, not per call.

Covered: controller kind "adp" (critic eqs. 23-24 with the covariance reset, actor eq. 26 with
its projection) with the RISE term on or off (``controller.rise``), either basis
(``controller.basis`` "augmented", the default, or "paper"), any constant set-point qd, a model
that differs from the plant, the probing signal (with ramp and cut-off), the disturbance and the
accumulated cost, integrated by classical RK4 with step ``sim.dt``. Not covered, refused with a
ValueError naming the field: other controller kinds, Bellman-error extrapolation
(``extrapolation.points`` != 0) and time-varying desired trajectories (``task.qd``). There is no
divergence test (``sim.divergence_bound`` is ignored).

State layout (the core's), 87 entries: [q (2), dq (2), Wc (8), Wa (8), Gamma (8x8, column-major),
nu (2), J (1)]. ``NumpyPaperLoop(config).run(n)`` returns the states at t = 0, dt, ..., n dt;
``adparm.simulate`` records every ``sim.record_every``-th of them (``FIELDS`` maps the result's
arrays to the state's entries).
"""

from __future__ import annotations

import numpy as np

import adparm

#: SimulationResult array -> entries of the 87-entry state.
FIELDS = {
    "q": slice(0, 2),
    "dq": slice(2, 4),
    "critic_weights": slice(4, 12),
    "actor_weights": slice(12, 20),
    "cost": 86,
}
GAMMA = slice(20, 84)
NU = slice(84, 86)
STATE_SIZE = 87


def _arm(p: tuple[float, ...], q: np.ndarray, dq: np.ndarray):
    """Inertia M, Coriolis C, gravity G and friction F of the two-link arm with parameters
    p = (p1, p2, p3, g1, g2, coulomb, viscous)."""
    p1, p2, p3, g1, g2, coulomb, viscous = p
    cos2 = np.cos(q[1])
    h = p3 * np.sin(q[1])
    M = np.array([[p1 + 2.0 * p3 * cos2, p2 + p3 * cos2], [p2 + p3 * cos2, p2]])
    C = np.array([[-h * dq[1], -h * (dq[0] + dq[1])], [h * dq[0], 0.0]])
    cos12 = np.cos(q[0] + q[1])
    G = np.array([g1 * np.cos(q[0]) + g2 * cos12, g2 * cos12])
    F = coulomb * np.sign(dq) + viscous * dq
    return M, C, G, F


def keep_e2_block_positive(W, rate, margin, metric):
    """adparm's projection (positive_block.hpp): where lambda_min of the e2 block P(c) of W,
    c = +-1, is at or below margin, d lambda_min / dt >= 100 (margin - lambda_min), by
    rate + metric N mu over the active constraints (at most two)."""
    normals, floors = [], []
    for c in (1.0, -1.0):
        b = 0.5 * (W[6] + c * W[7])
        values, vectors = np.linalg.eigh(np.array([[W[3] + c * W[4], b], [b, W[5]]]))
        v = vectors[:, 0]
        n = np.zeros(8)
        n[3:8] = [v[0] ** 2, c * v[0] ** 2, v[1] ** 2, v[0] * v[1], c * v[0] * v[1]]
        if values[0] <= margin:
            normals.append(n)
            floors.append(100.0 * (margin - values[0]))
    pairs = list(zip(normals, floors, strict=True))
    if all(n @ rate >= f for n, f in pairs):
        return rate
    for n, f in pairs:  # one constraint
        if n @ rate < f:
            projected = rate + (f - n @ rate) / (n @ metric @ n) * (metric @ n)
            if all(m @ projected >= g for m, g in pairs if m is not n):
                return projected
    N = np.array(normals).T
    return rate + metric @ N @ np.linalg.solve(N.T @ metric @ N, np.array(floors) - N.T @ rate)


class NumpyPaperLoop:
    """The closed loop of ``config`` (see the module docstring for what is covered)."""

    def __init__(self, config: adparm.Config) -> None:
        if config.controller.kind != "adp":
            raise ValueError(
                f"controller.kind: NumpyPaperLoop covers 'adp' only, got {config.controller.kind!r}"
            )
        if config.extrapolation.points != 0:
            raise ValueError(
                "extrapolation.points: NumpyPaperLoop covers no extrapolation points (0), "
                f"got {config.extrapolation.points}"
            )
        if not config.task.is_set_point:
            raise ValueError(
                f"task.qd: NumpyPaperLoop covers a constant set-point only, got {config.task.qd!r}"
            )
        if config.cost.input_bound is not None:
            raise ValueError(
                "cost.input_bound: NumpyPaperLoop covers the quadratic input cost only "
                "(tests/numpy_reference.py covers the bound)"
            )
        self.config = config
        self.dt = config.sim.dt
        self.record_every = config.sim.record_every

        names = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")
        self.plant = tuple(getattr(config.plant, k) for k in names)
        resolved = config.model.resolve(config.plant)
        self.model = tuple(resolved[k] for k in names)
        self.exact_model = self.model == self.plant
        self.disturbance = np.array(config.plant.disturbance)

        self.qd = np.array(config.task.qd, dtype=float)
        self.paper_basis = config.controller.basis == "paper"
        self.alpha1 = np.array(config.control.alpha1)
        self.Q = np.array(config.cost.Q)
        self.R = np.array(config.cost.R)
        self.Rinv = np.linalg.inv(self.R)

        c, a = config.critic, config.actor
        self.eta_c, self.nu_c, self.gamma0 = c.eta_c, c.nu, c.gamma0
        self.epsilon_T = config.resolved_epsilon_T
        self.eta_a1, self.eta_a2 = a.eta_a1, a.eta_a2
        self.weight_bound_sq = a.weight_bound**2
        self.positive_e2, self.e2_margin = a.positive_e2, a.e2_margin

        ctl = config.control
        self.rise = config.controller.rise
        self.k_mu = ctl.ks + 1.0
        self.k_nu = (ctl.ks + 1.0) * ctl.alpha2
        self.beta1 = ctl.beta1
        e1_0 = self.qd - np.array(config.task.q0)
        self.e2_0 = -np.array(config.task.dq0) + self.alpha1 @ e1_0

        pr = config.probe
        self.probe_amplitude = pr.amplitude_matrix()
        self.probe_frequency = np.array(pr.frequencies)
        self.probe_phase = pr.phase_matrix()
        self.probe_until, self.probe_ramp = pr.until, pr.ramp

        self.gamma_reset = (c.gamma0 * np.eye(8)).reshape(-1, order="F")

    def initial_state(self) -> np.ndarray:
        cfg = self.config
        state = np.zeros(STATE_SIZE)
        state[0:2] = cfg.task.q0
        state[2:4] = cfg.task.dq0
        state[4:12] = cfg.initial_weights("critic_weights")
        state[12:20] = cfg.initial_weights("actor_weights")
        state[GAMMA] = self.gamma_reset
        return state

    def probe(self, t: float) -> np.ndarray:
        if t >= self.probe_until:
            return np.zeros(2)
        waves = self.probe_amplitude * np.sin(self.probe_frequency * t + self.probe_phase)
        scale = t / self.probe_ramp if t < self.probe_ramp else 1.0
        return scale * waves.sum(axis=1)

    def basis_jacobian(self, x: np.ndarray) -> np.ndarray:
        """d phi / dx (8, 4) of phi(x) = [x1^2, x2^2, x1 x2, x3^2, x3^2 c, x4^2, x3 x4, x3 x4 c],
        c = cos(qd2 - x2) (augmented) or cos x2 (paper). With qd constant, phi has no qd rate."""
        x1, x2, x3, x4 = x
        if self.paper_basis:
            c, dc = np.cos(x2), -np.sin(x2)
        else:
            c, dc = np.cos(self.qd[1] - x2), np.sin(self.qd[1] - x2)
        return np.array(
            [
                [2.0 * x1, 0.0, 0.0, 0.0],
                [0.0, 2.0 * x2, 0.0, 0.0],
                [x2, x1, 0.0, 0.0],
                [0.0, 0.0, 2.0 * x3, 0.0],
                [0.0, x3 * x3 * dc, 2.0 * x3 * c, 0.0],
                [0.0, 0.0, 0.0, 2.0 * x4],
                [0.0, 0.0, x4, x3],
                [0.0, x3 * x4 * dc, x4 * c, x3 * c],
            ]
        )

    def derivative(self, t: float, state: np.ndarray) -> np.ndarray:
        """d state / dt at time t."""
        q, dq = state[0:2], state[2:4]
        Wc, Wa = state[4:12], state[12:20]
        Gamma = state[GAMMA].reshape(8, 8, order="F")
        nu = state[NU]

        # tracking error x = [e1; e2], e1 = qd - q, e2 = de1 + alpha1 e1 (dqd = 0)
        e1 = self.qd - q
        e2 = -dq + self.alpha1 @ e1
        x = np.concatenate([e1, e2])

        # error system dx = f(x) + g(x) u on the believed model, g = [0; M^-1]
        Mm, Cm, Gm, Fm = _arm(self.model, q, dq)
        Minv = np.linalg.inv(Mm)
        dphi = self.basis_jacobian(x)
        B = dphi[:, 2:] @ Minv  # d phi / dx g (8, 2)

        # actor input (eq. 20), HJB error (eq. 21) and its regressor omega
        u_hat = -0.5 * self.Rinv @ (B.T @ Wa)
        omega = dphi[:, :2] @ (e2 - self.alpha1 @ e1) + B @ (u_hat - Cm @ e2)
        hjb = x @ self.Q @ x + u_hat @ self.R @ u_hat + Wc @ omega

        # critic, eqs. (23)-(24)
        Gw = Gamma @ omega
        gain = self.eta_c / (1.0 + self.nu_c * (omega @ Gw))  # eta_c / rho
        dWc = -(gain * hjb) * Gw
        dGamma = -gain * np.outer(Gw, Gw)
        if self.positive_e2:  # keep the e2 block positive definite (not in the paper)
            dWc = keep_e2_block_positive(Wc, dWc, self.e2_margin, Gamma)

        # actor, eq. (26), with the projection onto ||Wa|| <= weight_bound
        dW = Wa - Wc
        dWa = -self.eta_a1 * hjb / np.sqrt(1.0 + omega @ omega) * (B @ (self.Rinv @ (B.T @ dW)))
        dWa = dWa - self.eta_a2 * dW
        if self.positive_e2:
            dWa = keep_e2_block_positive(Wa, dWa, self.e2_margin, np.eye(8))
        WaWa = Wa @ Wa
        if WaWa >= self.weight_bound_sq and Wa @ dWa > 0.0:
            dWa = dWa - (Wa @ dWa) / WaWa * Wa

        u = u_hat + self.probe(t)

        # RISE, eqs. (27)-(28)
        if self.rise:
            mu = self.k_mu * (e2 - self.e2_0) + nu
            dnu = self.k_nu * e2 + self.beta1 * np.sign(e2)
        else:
            mu = np.zeros(2)
            dnu = np.zeros(2)

        # torque tau = h + mu - u with the feedforward h of eq. (5), then the plant, eq. (1)
        h = Mm @ (self.alpha1 @ (-dq)) + Cm @ (self.alpha1 @ e1) + Gm + Fm
        tau = h + mu - u
        if self.exact_model:
            Mp, Cp, Gp, Fp = Mm, Cm, Gm, Fm
        else:
            Mp, Cp, Gp, Fp = _arm(self.plant, q, dq)
        tau_d = self.disturbance * np.array([np.sin(t), np.cos(t)])
        ddq = np.linalg.solve(Mp, tau - Cp @ dq - Gp - Fp - tau_d)

        dJ = x @ self.Q @ x + u @ self.R @ u
        return np.concatenate(
            [dq, ddq, dWc, dWa, dGamma.reshape(-1, order="F"), dnu, np.array([dJ])]
        )

    def step(self, t: float, state: np.ndarray) -> np.ndarray:
        """One RK4 step from (t, state), then Gamma reset to gamma0 I if lambda_min < epsilon_T."""
        dt = self.dt
        k1 = self.derivative(t, state)
        k2 = self.derivative(t + 0.5 * dt, state + 0.5 * dt * k1)
        k3 = self.derivative(t + 0.5 * dt, state + 0.5 * dt * k2)
        k4 = self.derivative(t + dt, state + dt * k3)
        new = state + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        Gamma = new[GAMMA].reshape(8, 8, order="F")  # symmetric: its rates are outer(v, v)
        if np.linalg.eigvalsh(Gamma)[0] < self.epsilon_T:
            new[GAMMA] = self.gamma_reset
        return new

    def run(self, steps: int) -> np.ndarray:
        """The states (steps + 1, 87) at t = 0, dt, ..., steps dt."""
        states = np.empty((steps + 1, STATE_SIZE))
        states[0] = state = self.initial_state()
        for k in range(steps):
            state = self.step(k * self.dt, state)
            states[k + 1] = state
        return states


def recorded_pairs(
    config: adparm.Config, states: np.ndarray
) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The NumPy ``states`` (steps + 1, 87) of ``run(steps)`` beside ``adparm.simulate`` over the
    same horizon, at the core's recorded rows: the step index of each row, and for each array of
    ``FIELDS`` the pair (NumPy, core)."""
    steps = states.shape[0] - 1
    result = adparm.simulate(config.updated({"sim": {"T": steps * config.sim.dt}}))
    index = np.rint(np.asarray(result.t) / config.sim.dt).astype(int)
    pairs = {
        name: (states[index][:, entries], np.asarray(getattr(result, name)))
        for name, entries in FIELDS.items()
    }
    return index, pairs
