"""An independent NumPy implementation of the paper's equations, written from the paper and
ERRATA.md (not from the C++ sources), for checking the C++ core.

State layout (the core's): [q (2), dq (2), Wc (8), Wa (8), Gamma (8x8, column-major), nu (2)].
"""

from __future__ import annotations

import numpy as np

from adparm import Config


def arm_terms(p: dict, q: np.ndarray, dq: np.ndarray):
    """M, C, G, F of Section 4 in the general two-link form."""
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    M = np.array(
        [[p["p1"] + 2 * p["p3"] * c2, p["p2"] + p["p3"] * c2], [p["p2"] + p["p3"] * c2, p["p2"]]]
    )
    C = p["p3"] * s2 * np.array([[-dq[1], -(dq[0] + dq[1])], [dq[0], 0.0]])
    G = np.array(
        [
            p["g1"] * np.cos(q[0]) + p["g2"] * np.cos(q[0] + q[1]),
            p["g2"] * np.cos(q[0] + q[1]),
        ]
    )
    F = p["coulomb"] * np.sign(dq) + p["viscous"] * dq
    return M, C, G, F


def plant_parameters(config: Config) -> dict:
    return {
        k: getattr(config.plant, k) for k in ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")
    }


def basis(x: np.ndarray):
    """phi(x) = [x1^2, x2^2, x1 x2, x3^2, x3^2 cos x2, x4^2, x3 x4, x3 x4 cos x2] and d phi / dx."""
    x1, x2, x3, x4 = x
    c, s = np.cos(x2), np.sin(x2)
    phi = np.array([x1**2, x2**2, x1 * x2, x3**2, x3**2 * c, x4**2, x3 * x4, x3 * x4 * c])
    J = np.zeros((8, 4))
    J[0, 0] = 2 * x1
    J[1, 1] = 2 * x2
    J[2, 0], J[2, 1] = x2, x1
    J[3, 2] = 2 * x3
    J[4, 1], J[4, 2] = -(x3**2) * s, 2 * x3 * c
    J[5, 3] = 2 * x4
    J[6, 2], J[6, 3] = x4, x3
    J[7, 1], J[7, 2], J[7, 3] = -x3 * x4 * s, x4 * c, x3 * c
    return phi, J


def error_model(config: Config, x: np.ndarray):
    """f(x), g(x) of eq. (9) (g = [0; M^-1]) for the set-point qd, on the believed model."""
    alpha1 = np.array(config.control.alpha1)
    qd = np.array(config.task.qd)
    e1, e2 = x[:2], x[2:]
    q = qd - e1
    dq = alpha1 @ e1 - e2
    M, C, _, _ = arm_terms(config.model.resolve(config.plant), q, dq)
    Minv = np.linalg.inv(M)
    f = np.concatenate([-alpha1 @ e1 + e2, -Minv @ C @ e2])
    g = np.vstack([np.zeros((2, 2)), Minv])
    return f, g


def hjb(config: Config, x, f, g, Wc, Wa):
    """eq. (22): returns (eps_hjb, omega, u_hat, G_phi)."""
    Q = np.array(config.cost.Q)
    R = np.array(config.cost.R)
    Rinv = np.linalg.inv(R)
    _, J = basis(x)
    G_phi = J @ (g @ Rinv @ g.T) @ J.T
    u_hat = -0.5 * Rinv @ g.T @ J.T @ Wa
    omega = J @ (f + g @ u_hat)
    eps = x @ Q @ x + 0.25 * Wa @ G_phi @ Wa + Wc @ J @ f - 0.5 * Wc @ G_phi @ Wa
    return eps, omega, u_hat, G_phi


def hjb_residual(config: Config, x, Wc, Wa) -> float:
    f, g = error_model(config, x)
    return hjb(config, x, f, g, np.asarray(Wc), np.asarray(Wa))[0]


def probe(config: Config, t: float) -> np.ndarray:
    if t >= config.probe.until:
        return np.zeros(2)
    w = np.array(config.probe.frequencies)
    phases = config.probe.phase_matrix()
    value = (config.probe.amplitude_matrix() * np.sin(w * t + phases)).sum(axis=1)
    ramp = config.probe.ramp
    return value * (t / ramp if t < ramp else 1.0)


def initial_state(config: Config) -> np.ndarray:
    return np.concatenate(
        [
            config.task.q0,
            config.task.dq0,
            config.init.critic_weights,
            config.init.actor_weights,
            (config.critic.gamma0 * np.eye(8)).reshape(-1, order="F"),
            np.zeros(2),
        ]
    )


def rhs(config: Config, t: float, state: np.ndarray):
    """The closed loop's right-hand side and its outputs (tau, u_hat, mu, hjb_error)."""
    q, dq = state[0:2], state[2:4]
    Wc, Wa = state[4:12], state[12:20]
    Gamma = state[20:84].reshape(8, 8, order="F")
    nu = state[84:86]
    alpha1 = np.array(config.control.alpha1)
    qd = np.array(config.task.qd)
    e1 = qd - q
    e2 = -dq + alpha1 @ e1
    x = np.concatenate([e1, e2])

    f, g = error_model(config, x)
    eps, omega, u_hat, G_phi = hjb(config, x, f, g, Wc, Wa)

    # critic, eqs. (23)-(24)
    rho = 1.0 + config.critic.nu * omega @ Gamma @ omega
    dWc = -config.critic.eta_c * Gamma @ omega * eps / rho
    dGamma = -config.critic.eta_c * Gamma @ np.outer(omega, omega) @ Gamma / rho
    # actor, eq. (26) with projection onto ||Wa|| <= bound
    a = config.actor
    dWa = -a.eta_a1 / np.sqrt(1 + omega @ omega) * G_phi @ (Wa - Wc) * eps - a.eta_a2 * (Wa - Wc)
    if Wa @ Wa >= a.weight_bound**2 and Wa @ dWa > 0:
        dWa = dWa - Wa * (Wa @ dWa) / (Wa @ Wa)

    # RISE, eqs. (27)-(28)
    c = config.control
    e2_0 = -np.array(config.task.dq0) + alpha1 @ (qd - np.array(config.task.q0))
    mu = (c.ks + 1) * e2 - (c.ks + 1) * e2_0 + nu
    dnu = (c.ks + 1) * c.alpha2 * e2 + c.beta1 * np.sign(e2)

    # torque: tau = h_hat + mu - (u_hat + probe), h of eq. (5) with the believed model
    Mm, Cm, Gm, Fm = arm_terms(config.model.resolve(config.plant), q, dq)
    h = Mm @ (alpha1 @ (-dq)) + Cm @ (alpha1 @ e1) + Gm + Fm
    tau = h + mu - (u_hat + probe(config, t))

    # plant, eq. (1)
    Mp, Cp, Gp, Fp = arm_terms(plant_parameters(config), q, dq)
    a1, a2 = config.plant.disturbance
    tau_d = np.array([a1 * np.sin(t), a2 * np.cos(t)])
    ddq = np.linalg.solve(Mp, tau - Cp @ dq - Gp - Fp - tau_d)

    rate = np.concatenate([dq, ddq, dWc, dWa, dGamma.reshape(-1, order="F"), dnu])
    outputs = {"e1": e1, "e2": e2, "tau": tau, "u_hat": u_hat, "mu": mu, "hjb_error": eps}
    return rate, outputs


def simulate(config: Config, steps: int):
    """RK4 with the covariance reset between steps; returns the states at each step."""
    dt = config.sim.dt
    state = initial_state(config)
    states = [state.copy()]
    for k in range(steps):
        t = k * dt
        k1 = rhs(config, t, state)[0]
        k2 = rhs(config, t + dt / 2, state + dt / 2 * k1)[0]
        k3 = rhs(config, t + dt / 2, state + dt / 2 * k2)[0]
        k4 = rhs(config, t + dt, state + dt * k3)[0]
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        Gamma = state[20:84].reshape(8, 8, order="F")
        if np.linalg.eigvalsh(Gamma).min() < config.critic.epsilon_T:
            state[20:84] = (config.critic.gamma0 * np.eye(8)).reshape(-1, order="F")
        states.append(state.copy())
    return np.array(states)
