"""An independent NumPy implementation of the paper's equations, written from the paper,
ERRATA.md and the closed loop's specification (not from the C++ sources), for checking the C++
core.

State layout (the core's), 87 entries:
[q (2), dq (2), Wc (8), Wa (8), Gamma (8x8, column-major), nu (2), J (1)], J the accumulated cost
int x^T Q x + u^T R u dt with u the controller's applied input.

Conventions: e1 = qd - q, e2 = (dqd - dq) + alpha1 e1, x = [e1; e2]; the error system is
dx = f(x) + g(x) u with g = [0; M^-1] (ERRATA), and the torque is tau = h + mu - u.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np

from adparm import Config, SampledTrajectory, SinusoidTrajectory

STATE_SIZE = 87
Q_SLICE, DQ_SLICE = slice(0, 2), slice(2, 4)
WC_SLICE, WA_SLICE = slice(4, 12), slice(12, 20)
GAMMA_SLICE, NU_SLICE, COST_INDEX = slice(20, 84), slice(84, 86), 86


# --- arm ------------------------------------------------------------------------------------------


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


def model_parameters(config: Config) -> dict:
    return config.model.resolve(config.plant)


# --- desired trajectory ---------------------------------------------------------------------------


@functools.lru_cache(maxsize=64)
def _spline(trajectory: SampledTrajectory):
    return trajectory.spline()


def desired(config: Config, t: float):
    """(qd, dqd, ddqd) at time t, each (2,)."""
    qd = config.task.qd
    if isinstance(qd, SinusoidTrajectory):
        a, w, p = (np.array(getattr(qd, k)) for k in ("amplitude", "frequency", "phase"))
        angle = w * t + p
        return (
            np.array(qd.offset) + (a * np.sin(angle)).sum(axis=1),
            (a * w * np.cos(angle)).sum(axis=1),
            -(a * w**2 * np.sin(angle)).sum(axis=1),
        )
    if isinstance(qd, SampledTrajectory):
        spline = _spline(qd)
        tc = min(max(float(t), qd.t[0]), qd.t[-1])
        return tuple(np.asarray(spline(tc, nu), dtype=float) for nu in range(3))
    return np.array(qd, dtype=float), np.zeros(2), np.zeros(2)


def error_state(config: Config, q, dq, qd, dqd) -> np.ndarray:
    """x = [e1; e2] of the joint state (q, dq) for the desired state (qd, dqd)."""
    alpha1 = np.array(config.control.alpha1)
    e1 = qd - q
    e2 = (dqd - dq) + alpha1 @ e1
    return np.concatenate([e1, e2])


def joint_state(config: Config, x, qd, dqd):
    """(q, dq) of the error state x for the desired state (qd, dqd)."""
    alpha1 = np.array(config.control.alpha1)
    e1, e2 = x[:2], x[2:]
    return qd - e1, dqd - e2 + alpha1 @ e1


# --- basis ----------------------------------------------------------------------------------------


def basis(kind: str, x, qd=(0.0, 0.0), dqd=(0.0, 0.0)):
    """phi, d phi / dx (8, 4) and the desired rate (d phi / d qd) dqd (8,).

    paper: phi(x) = [x1^2, x2^2, x1 x2, x3^2, x3^2 cos x2, x4^2, x3 x4, x3 x4 cos x2];
    augmented: the same with cos x2 replaced by cos(qd2 - x2) (= cos q2)."""
    x1, x2, x3, x4 = np.asarray(x, dtype=float)
    qd, dqd = np.asarray(qd, dtype=float), np.asarray(dqd, dtype=float)
    if kind == "structured":
        return structured_basis(x, qd, dqd)
    if kind == "paper":
        c, dc_dx2 = np.cos(x2), -np.sin(x2)
        dc_dqd2 = 0.0
    elif kind == "augmented":
        c = np.cos(qd[1] - x2)
        dc_dx2 = np.sin(qd[1] - x2)
        dc_dqd2 = -np.sin(qd[1] - x2)
    else:
        raise ValueError(kind)
    phi = np.array([x1**2, x2**2, x1 * x2, x3**2, x3**2 * c, x4**2, x3 * x4, x3 * x4 * c])
    J = np.zeros((8, 4))
    J[0, 0] = 2 * x1
    J[1, 1] = 2 * x2
    J[2, 0], J[2, 1] = x2, x1
    J[3, 2] = 2 * x3
    J[4, 1], J[4, 2] = x3**2 * dc_dx2, 2 * x3 * c
    J[5, 3] = 2 * x4
    J[6, 2], J[6, 3] = x4, x3
    J[7, 1], J[7, 2], J[7, 3] = x3 * x4 * dc_dx2, x4 * c, x3 * c
    rate = np.zeros(8)
    rate[4] = x3**2 * dc_dqd2 * dqd[1]
    rate[7] = x3 * x4 * dc_dqd2 * dqd[1]
    return phi, J, rate


def structured_basis(x, qd=(0.0, 0.0), dqd=(0.0, 0.0)):
    """phi (6,), d phi / dx (6, 4), (d phi / d qd) dqd (6,) of the structured basis, from its
    definition: [e1_i e1_j (i <= j); e2^T M_k(q) e2], q = qd - e1, M1 = [[1, 0], [0, 0]],
    M2 = [[0, 1], [1, 1]], M3 = cos q2 [[2, 1], [1, 0]] (matrix forms, not expanded)."""
    x = np.asarray(x, dtype=float)
    e1, e2 = x[:2], x[2:]
    q2 = qd[1] - e1[1]
    shape3 = np.array([[2.0, 1.0], [1.0, 0.0]])
    matrices = [np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 1.0], [1.0, 1.0]])]
    matrices.append(np.cos(q2) * shape3)
    pairs = [(0, 0), (0, 1), (1, 1)]
    phi = np.array([e1[i] * e1[j] for i, j in pairs] + [e2 @ Mk @ e2 for Mk in matrices])
    J = np.zeros((6, 4))
    for row, (i, j) in enumerate(pairs):
        J[row, i] += e1[j]
        J[row, j] += e1[i]
    for k, Mk in enumerate(matrices):
        J[3 + k, 2:] = 2.0 * Mk @ e2  # d (e2^T Mk e2) / d e2
    # M3 depends on q2 = qd2 - e1_2: d/d e1_2 = sin q2 e2^T shape3 e2, d/d qd2 = the negative
    J[5, 1] = np.sin(q2) * (e2 @ shape3 @ e2)
    rate = np.zeros(6)
    rate[5] = -np.sin(q2) * (e2 @ shape3 @ e2) * dqd[1]
    return phi, J, rate


# --- error system and HJB -------------------------------------------------------------------------


def error_model(config: Config, x, qd, dqd):
    """f(x), g(x) of eq. (9) (g = [0; M^-1]) on the believed model, at the joint state recovered
    from x and the desired state (qd, dqd)."""
    alpha1 = np.array(config.control.alpha1)
    q, dq = joint_state(config, x, qd, dqd)
    M, C, _, _ = arm_terms(model_parameters(config), q, dq)
    Minv = np.linalg.inv(M)
    e1, e2 = x[:2], x[2:]
    f = np.concatenate([-alpha1 @ e1 + e2, -Minv @ C @ e2])
    g = np.vstack([np.zeros((2, 2)), Minv])
    return f, g


def input_bound(config: Config) -> np.ndarray | None:
    """lambda per joint, or None without an input bound."""
    bound = config.cost.input_bound
    if bound is None:
        return None
    return np.broadcast_to(np.asarray(bound, dtype=float), (len(config.cost.R),)).copy()


def bounded_input_cost(u, R_diagonal, bound) -> float:
    """U(u) = sum_i R_i [2 lambda_i u_i atanh(u_i / lambda_i) + lambda_i^2 ln(1 - u_i^2 /
    lambda_i^2)] (Abu-Khalaf & Lewis 2005) = sum_i R_i lambda_i^2 [(1 + s) ln(1 + s) + (1 - s)
    ln(1 - s)], s = u_i / lambda_i, for |u_i| < lambda_i (test_input_bound checks the two forms
    agree); beyond the bound,
    U at the bound (R_i lambda_i^2 2 ln 2) plus R_i (|u_i| - lambda_i)^2."""
    u = np.asarray(u, dtype=float)
    total = 0.0
    for ui, r, lam in zip(u, R_diagonal, bound, strict=True):
        if abs(ui) < lam:  # the printed formula rewritten: it loses digits near the bound
            s = ui / lam
            total += r * lam**2 * ((1 + s) * np.log(1 + s) + (1 - s) * np.log(1 - s))
        else:
            total += r * lam**2 * 2 * np.log(2) + r * (abs(ui) - lam) ** 2
    return float(total)


def log_cosh(z):
    """ln cosh z = ln(e^z + e^-z) - ln 2 (NumPy's logaddexp: no overflow)."""
    return np.logaddexp(z, -z) - np.log(2.0)


def policy_input_cost(D, R_diagonal, bound) -> float:
    """U(u) at u = -lambda tanh(D): sum_i R_i lambda_i^2 [2 D_i tanh D_i - 2 ln cosh D_i] (the
    printed formula loses digits there as tanh D_i -> +-1; test_input_bound checks the two
    agree where both are accurate)."""
    D = np.asarray(D, dtype=float)
    return float(np.sum(R_diagonal * bound**2 * (2 * D * np.tanh(D) - 2 * log_cosh(D))))


def state_cost(config: Config, x) -> float:
    """x^T Q x, or with e2_cost = logcosh: e1^T Q11 e1 + 2 e1^T Q12 e2 + sum_i 2 lambda_i^2 R_i
    ln cosh(s_i e2_i / (R_i lambda_i)), s_i = sqrt(Q22_ii R_i)."""
    Q = np.array(config.cost.Q)
    x = np.asarray(x, dtype=float)
    if config.cost.e2_cost != "logcosh":
        return float(x @ Q @ x)
    n = len(x) // 2
    e1, e2 = x[:n], x[n:]
    r = np.diag(np.array(config.cost.R))
    lam = input_bound(config)
    s = np.sqrt(np.diag(Q[n:, n:]) * r)
    z = s * e2 / (r * lam)
    return float(
        e1 @ Q[:n, :n] @ e1 + 2 * e1 @ Q[:n, n:] @ e2 + np.sum(2 * lam**2 * r * log_cosh(z))
    )


def hjb(config: Config, x, qd, dqd, Wc, Wa) -> dict:
    """At state x: u_hat = -1/2 R^-1 g^T J^T Wa, omega = J (f + g u_hat) + desired_rate,
    eps = x^T Q x + u_hat^T R u_hat + Wc . omega and B = J g (8, 2). With an input bound:
    u_hat = -lambda tanh(D), D = (2 lambda)^-1 R^-1 B^T Wa, and U(u_hat) for u_hat^T R u_hat."""
    R = np.array(config.cost.R)
    x = np.asarray(x, dtype=float)
    f, g = error_model(config, x, qd, dqd)
    _, J, rate = basis(config.controller.basis, x, qd, dqd)
    bound = input_bound(config)
    if bound is None:
        u_hat = -0.5 * np.linalg.solve(R, g.T @ J.T @ Wa)
        input_cost = u_hat @ R @ u_hat
    else:
        D = np.linalg.solve(R, g.T @ J.T @ Wa) / (2 * bound)
        u_hat = -bound * np.tanh(D)
        input_cost = policy_input_cost(D, np.diag(R), bound)
    omega = J @ (f + g @ u_hat) + rate
    eps = state_cost(config, x) + input_cost + Wc @ omega
    return {"eps": eps, "omega": omega, "u_hat": u_hat, "B": J @ g}


def hjb_residual(config: Config, x, Wc, Wa, t: float = 0.0) -> float:
    """The HJB error at x with the desired state at time t."""
    qd, dqd, _ = desired(config, t)
    return hjb(config, np.asarray(x, dtype=float), qd, dqd, np.asarray(Wc), np.asarray(Wa))["eps"]


# --- extrapolation points -------------------------------------------------------------------------


def box_vector(config: Config) -> np.ndarray:
    return np.broadcast_to(np.array(config.extrapolation.box, dtype=float), (4,)).copy()


def centre_vector(config: Config) -> np.ndarray:
    return np.broadcast_to(np.array(config.extrapolation.centre, dtype=float), (4,)).copy()


def fixed_points(config: Config) -> np.ndarray:
    e = config.extrapolation
    draw = np.random.RandomState(e.seed).random_sample((e.points, 4))
    return centre_vector(config) + box_vector(config) * (2 * draw - 1)


def grid_points(config: Config) -> np.ndarray:
    e = config.extrapolation
    m = round(e.points**0.25)
    assert m**4 == e.points
    box = box_vector(config)
    axes = [box[k] * (2 * np.arange(m) / (m - 1) - 1) if m > 1 else np.zeros(1) for k in range(4)]
    axes = [centre + axis for centre, axis in zip(centre_vector(config), axes, strict=True)]
    return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, 4)


def extrapolation_points(config: Config) -> np.ndarray:
    """What adparm.extrapolation_points returns: fixed or grid points, zeros for local."""
    e = config.extrapolation
    if e.mode == "fixed":
        return fixed_points(config)
    if e.mode == "grid":
        return grid_points(config)
    return np.zeros((e.points, 4))


class LocalPoints:
    """The local mode's stream: points = x + centre + box (2 U - 1), U drawn from
    RandomState(seed)."""

    def __init__(self, config: Config) -> None:
        self.points = config.extrapolation.points
        self.box = box_vector(config)
        self.centre = centre_vector(config)
        self.stream = np.random.RandomState(config.extrapolation.seed)

    def draw(self, x: np.ndarray) -> np.ndarray:
        return (x + self.centre) + self.box * (2 * self.stream.random_sample((self.points, 4)) - 1)


def tracking_error(config: Config, t: float, state: np.ndarray) -> np.ndarray:
    qd, dqd, _ = desired(config, t)
    return error_state(config, state[Q_SLICE], state[DQ_SLICE], qd, dqd)


# --- closed loop ----------------------------------------------------------------------------------


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
            config.initial_weights("critic_weights"),
            config.initial_weights("actor_weights"),
            (config.critic.gamma0 * np.eye(8)).reshape(-1, order="F"),
            np.zeros(2),
            np.zeros(1),
        ]
    )


def e2_block(W: np.ndarray, c: float) -> np.ndarray:
    """P(c) of the e2 part e2^T P(c) e2 of V = W^T phi (paper/augmented basis), c = cos q2."""
    b = 0.5 * (W[6] + c * W[7])
    return np.array([[W[3] + c * W[4], b], [b, W[5]]])


#: positive_block.hpp's kE2Recovery (1/s)
E2_RECOVERY = 100.0


def keep_e2_block_positive(
    W: np.ndarray, rate: np.ndarray, margin: float, metric: np.ndarray | None = None
) -> np.ndarray:
    """The least change of ``rate`` (rate + metric N lambda, lambda >= 0) that gives
    d lambda_min(P(c)) / dt >= E2_RECOVERY (margin - lambda_min) at c = +-1 wherever
    lambda_min <= margin: eigh for the gradient of lambda_min, every active set tried by brute
    force, the candidate nearest to ``rate`` in the metric's inverse kept."""
    metric = np.eye(8) if metric is None else metric
    normals, floors = [], []
    for c in (1.0, -1.0):
        values, vectors = np.linalg.eigh(e2_block(W, c))
        if values[0] <= margin:
            v = vectors[:, 0]
            n = np.zeros(8)
            n[3:8] = [v[0] ** 2, c * v[0] ** 2, v[1] ** 2, v[0] * v[1], c * v[0] * v[1]]
            normals.append(n)
            floors.append(E2_RECOVERY * (margin - values[0]))
    if all(n @ rate >= f for n, f in zip(normals, floors, strict=True)):
        return rate
    candidates = []
    tolerance = 1e-9 * max(np.abs(rate).max(), max(floors), 1.0)
    for subset in ([0], [1], [0, 1]):
        if max(subset) >= len(normals):
            continue
        N = np.array([normals[i] for i in subset]).T
        lam = np.linalg.solve(N.T @ metric @ N, np.array([floors[i] for i in subset]) - N.T @ rate)
        projected = rate + metric @ N @ lam
        feasible = all(n @ projected >= f - tolerance for n, f in zip(normals, floors, strict=True))
        if np.all(lam >= -1e-12) and feasible:  # KKT
            candidates.append(projected)
    inverse = np.linalg.inv(metric)
    return min(candidates, key=lambda r: (r - rate) @ inverse @ (r - rate))


def rhs(config: Config, t: float, state: np.ndarray, points: np.ndarray | None = None):
    """The closed loop's right-hand side at (t, state) and its outputs (qd, e1, e2, tau, u, u_hat,
    mu, probe, hjb_error).

    ``points``: the extrapolation points (N, 4) in x. None takes the fixed or grid points of the
    config, or for mode local the first draw of a fresh stream around this state's x (what
    _core.closed_loop_derivative does)."""
    state = np.asarray(state, dtype=float)
    q, dq = state[Q_SLICE], state[DQ_SLICE]
    Wc, Wa = state[WC_SLICE], state[WA_SLICE]
    Gamma = state[GAMMA_SLICE].reshape(8, 8, order="F")
    nu = state[NU_SLICE]
    alpha1 = np.array(config.control.alpha1)
    Q = np.array(config.cost.Q)
    R = np.array(config.cost.R)
    Rinv = np.linalg.inv(R)
    qd, dqd, ddqd = desired(config, t)
    x = error_state(config, q, dq, qd, dqd)
    e1, e2 = x[:2], x[2:]
    if points is None:
        if config.extrapolation.mode == "local":
            points = LocalPoints(config).draw(x)
        else:
            points = extrapolation_points(config)

    sample = hjb(config, x, qd, dqd, Wc, Wa)
    u_hat = sample["u_hat"]

    # learning (adp only): critic eqs. (23)-(24) and actor eq. (26), averaged over the
    # extrapolation points (weight 1/N) on top of the trajectory's own sample (weight 1)
    kind = config.controller.kind
    dWc, dWa, dGamma = np.zeros(8), np.zeros(8), np.zeros((8, 8))
    if kind == "adp":
        c, a = config.critic, config.actor
        grad = np.zeros(8)
        samples = [(1.0, sample)]
        n = len(points)
        samples += [(1.0 / n, hjb(config, p, qd, dqd, Wc, Wa)) for p in points]
        for w, s in samples:
            omega, eps, B = s["omega"], s["eps"], s["B"]
            rho = 1.0 + c.nu * omega @ Gamma @ omega
            dWc += -w * c.eta_c * Gamma @ omega * eps / rho
            dGamma += -w * c.eta_c * Gamma @ np.outer(omega, omega) @ Gamma / rho
            # d eps / d Wa: with an input bound B R^-1 diag(1 - tanh^2 D) B^T (Wa - Wc)
            bound = input_bound(config)
            slope = np.eye(2) if bound is None else np.diag(1 - (s["u_hat"] / bound) ** 2)
            grad += (
                -w
                * a.eta_a1
                * eps
                / np.sqrt(1 + omega @ omega)
                * B
                @ Rinv
                @ slope
                @ B.T
                @ (Wa - Wc)
            )
        if a.positive_e2:
            dWc = keep_e2_block_positive(Wc, dWc, a.e2_margin, Gamma)
        dWa = grad - a.eta_a2 * (Wa - Wc)
        if a.positive_e2:
            dWa = keep_e2_block_positive(Wa, dWa, a.e2_margin)
        if Wa @ Wa >= a.weight_bound**2 and Wa @ dWa > 0:
            dWa = dWa - Wa * (Wa @ dWa) / (Wa @ Wa)

    # the controller's input u (to dx = f + g u)
    de1 = e2 - alpha1 @ e1
    p = probe(config, t) if kind == "adp" else np.zeros(2)
    if kind == "adp":
        u = u_hat + p
    elif kind == "rise":
        u = np.zeros(2)
    elif kind == "pd":
        u = -(config.controller.gain_matrix("kp") @ e1 + config.controller.gain_matrix("kd") @ de1)
    elif kind == "optimal":
        u = -Rinv @ e2
        if input_bound(config) is not None:
            u = -input_bound(config) * np.tanh(Rinv @ e2 / input_bound(config))
    else:
        raise ValueError(kind)

    # RISE, eqs. (27)-(28)
    ctl = config.control
    if config.controller.rise:
        qd0, dqd0, _ = desired(config, 0.0)
        e2_0 = error_state(config, np.array(config.task.q0), np.array(config.task.dq0), qd0, dqd0)[
            2:
        ]
        mu = (ctl.ks + 1) * (e2 - e2_0) + nu
        dnu = (ctl.ks + 1) * ctl.alpha2 * e2 + ctl.beta1 * np.sign(e2)
    else:
        mu, dnu = np.zeros(2), np.zeros(2)

    # torque tau = h + mu - u, h of eq. (5) in full on the believed model
    Mm, Cm, Gm, Fm = arm_terms(model_parameters(config), q, dq)
    h = Mm @ (ddqd + alpha1 @ (dqd - dq)) + Cm @ (dqd + alpha1 @ e1) + Gm + Fm
    tau_commanded = h + mu - u
    # the drive's clip to plant.torque_limits, and RISE's conditional integration meanwhile
    tau = tau_commanded
    limits = config.plant.limit_vector(2)
    if limits.size:
        tau = np.clip(tau_commanded, -limits, limits)
        if config.control.anti_windup and config.controller.rise:
            pushing = ((tau_commanded > limits) & (dnu > 0)) | (
                (tau_commanded < -limits) & (dnu < 0)
            )
            dnu = np.where(pushing, 0.0, dnu)

    # plant, eq. (1)
    Mp, Cp, Gp, Fp = arm_terms(plant_parameters(config), q, dq)
    d1, d2 = config.plant.disturbance
    tau_d = np.array([d1 * np.sin(t), d2 * np.cos(t)])
    ddq = np.linalg.solve(Mp, tau - Cp @ dq - Gp - Fp - tau_d)

    if input_bound(config) is None:
        dJ = x @ Q @ x + u @ R @ u
    else:
        dJ = state_cost(config, x) + bounded_input_cost(u, np.diag(R), input_bound(config))
    rate = np.concatenate([dq, ddq, dWc, dWa, dGamma.reshape(-1, order="F"), dnu, [dJ]])
    outputs = {
        "qd": qd,
        "e1": e1,
        "e2": e2,
        "tau": tau,
        "tau_commanded": tau_commanded,
        "u": u,
        "u_hat": u_hat,
        "mu": mu,
        "probe": p,
        "hjb_error": sample["eps"],
    }
    return rate, outputs


def reset_threshold(config: Config) -> float:
    """epsilon_T as core_settings passes it (critic.epsilon_T, or its default when left out)."""
    resolved = getattr(config, "resolved_epsilon_T", None)
    return config.critic.epsilon_T if resolved is None else resolved


def simulate(config: Config, steps: int, *, redraw: bool = True):
    """Classical RK4 (step config.sim.dt) with the covariance reset after each step and, in mode
    local, the extrapolation points redrawn around the state at the start of each step (drawn
    once, around x(0), if not ``redraw``). Returns the states (steps + 1, 87) and the reset
    times."""
    dt = config.sim.dt
    state = initial_state(config)
    local = LocalPoints(config) if config.extrapolation.mode == "local" else None
    points = extrapolation_points(config)
    if local is not None:
        points = local.draw(tracking_error(config, 0.0, state))
    states = [state.copy()]
    resets = []
    epsilon_T = reset_threshold(config)
    for k in range(steps):
        t = k * dt
        k1 = rhs(config, t, state, points)[0]
        k2 = rhs(config, t + dt / 2, state + dt / 2 * k1, points)[0]
        k3 = rhs(config, t + dt / 2, state + dt / 2 * k2, points)[0]
        k4 = rhs(config, t + dt, state + dt * k3, points)[0]
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        Gamma = state[GAMMA_SLICE].reshape(8, 8, order="F")
        if np.linalg.eigvalsh(0.5 * (Gamma + Gamma.T)).min() < epsilon_T:
            state[GAMMA_SLICE] = (config.critic.gamma0 * np.eye(8)).reshape(-1, order="F")
            resets.append((k + 1) * dt)
        if local is not None and redraw:
            points = local.draw(tracking_error(config, (k + 1) * dt, state))
        states.append(state.copy())
    return np.array(states), np.array(resets)


def pinocchio_model(path, gravity=(0.0, 0.0, -9.81)):
    # Pinocchio's Python bindings (the pin package, in the test extra): an independent caller
    import pinocchio

    model = pinocchio.buildModelFromUrdf(str(path))
    model.gravity.linear = np.asarray(gravity, dtype=float)
    return model


def pinocchio_configuration(model, q: np.ndarray) -> np.ndarray:
    config = np.zeros(model.nq)  # a continuous joint's q is (cos, sin) in Pinocchio
    for i in range(1, model.njoints):
        joint = model.joints[i]
        if joint.nq == 2:
            config[joint.idx_q : joint.idx_q + 2] = np.cos(q[joint.idx_v]), np.sin(q[joint.idx_v])
        else:
            config[joint.idx_q] = q[joint.idx_v]
    return config


def pinocchio_terms(path, gravity, q: np.ndarray, dq: np.ndarray) -> dict:
    import pinocchio

    model = pinocchio_model(path, gravity)
    data = model.createData()
    config = pinocchio_configuration(model, q)
    M = np.triu(pinocchio.crba(model, data, config))
    Minv = np.triu(pinocchio.computeMinverse(model, data, config))
    return {
        "M": M + np.triu(M, 1).T,
        "M_inv": Minv + np.triu(Minv, 1).T,
        "C": pinocchio.computeCoriolisMatrix(model, data, config, dq).copy(),
        "G": pinocchio.computeGeneralizedGravity(model, data, config).copy(),
        "names": list(model.names)[1:],
        "pi": np.concatenate(
            [model.inertias[i].toDynamicParameters() for i in range(1, model.njoints)]
        ),
    }
