"""The fast rates of the closed loop, the RK4 step they allow, and the arm-aware defaults.

RK4 is stable on a decay exp(-lambda t) only while lambda dt <= RK4_STABILITY_LIMIT = 2.785. The
closed loop of adparm has several fast terms, each a rate in 1/s:

- the RISE feedback of eq. (27), (ks + 1) e2 acting through M^-1: (ks + 1) / lambda_min(M);
- the policy: u = -(G1 e1 + G2 e2) near x = 0 acts through M^-1 (the actor's initial weights
  for adp, u* = -R^-1 e2 for the optimal controller, kp and kd for pd);
- the error dynamics as a whole: the eigenvalues of the linearised loop
  [[-alpha1, I], [-M^-1 G1, -M^-1 (G2 + (ks + 1) I)]];
- the critic of eqs. (23)-(24): eta_c Gamma omega omega^T / rho with rho = 1 + nu omega^T Gamma
  omega has eigenvalues below eta_c / nu, and Bellman-error extrapolation adds the same bound
  again (the average over the points): eta_c / nu (1 + [points > 0]).

M is the plant's inertia (the policy's gain is computed from the believed model's, as the
controller does), sampled at qd(0), q(0) and (with extrapolation) at joint positions within
max(1, 2 |e1(0)|) rad of qd(0) inside the extrapolation box (:func:`rate_positions`).
:func:`closed_loop_rates` lists them, :func:`auto_step` picks sim.dt = "auto" and
:func:`check_step` refuses an explicit sim.dt beyond the limit.

:func:`urdf_defaults` derives the settings a URDF arm's config leaves out from the believed
model's inertia over its joint-limit box (docs: URDF arms, "Defaults derived from the arm").
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ._sections import EPSILON_T_PROBING
from .extrapolation_region import extrapolation_box, extrapolation_range  # re-exported
from .joint_limits import default_disturbance, default_set_point, effort_limits, limits_box

if TYPE_CHECKING:  # pragma: no cover
    from ._schema import ConfigSchema

__all__ = [
    "AUTO_MARGIN",
    "RK4_STABILITY_LIMIT",
    "UNLIMITED_BOUND",
    "auto_input_bound",
    "auto_step",
    "check_step",
    "extrapolation_box",
    "extrapolation_range",
    "closed_loop_rates",
    "inertia_range",
    "rise_ks",
    "urdf_defaults",
]

#: RK4's stability limit on the negative real axis: |lambda| dt <= 2.785.
RK4_STABILITY_LIMIT = 2.785
#: sim.dt = "auto" keeps every rate * dt at or below AUTO_MARGIN * RK4_STABILITY_LIMIT.
AUTO_MARGIN = 0.6
#: The largest step "auto" chooses (the paper loop's step).
AUTO_MAX_STEP = 1e-3

#: The e2 rates the derived defaults aim at (1/s): RISE's (ks + 1) / lambda_min(M) on the
#: lightest direction of the arm and the optimal policy's 1 / (r_i M_ii) on every joint. On the
#: paper's arm (lambda_min(M) = 0.39 kg m^2, ks = 10, R = 0.25 I) they are 28/s and 10/s.
RISE_RATE = 30.0
POLICY_RATE = 10.0
#: RISE's rate cap (1/s) where a gain of 1 is faster (rise_ks); RK4 resolves it at 1 ms.
RISE_RATE_MAX = 1000.0
#: alpha1 of a URDF arm (1/s), as the n-joint default before.
ALPHA1 = 2.0
#: critic.epsilon_T of a URDF arm with Bellman-error extrapolation. Gamma is reset to gamma0 I
#: when its least eigenvalue, that of the best-informed direction, falls below epsilon_T; the
#: weights of light joints (a wrist's inertia, 1e-4 kg m^2 next to a shoulder's 10) are informed
#: orders of magnitude more slowly, and with the two-link arm's 1e-3 (gamma0 / epsilon_T = 1e5)
#: each reset discards their information before they learn: the UR10 ends 5 % off W* after
#: 10 s (104 resets), the Kinova 6 %. With 1e-5 both are within 1 % by 3-4 s
#: (bench/every_arm.py, docs: URDF arms, "Every arm, measured").
EPSILON_T_URDF = 1e-5
#: actor.eta_a1 of the paper (and of a URDF arm learning from the probing signal alone); with
#: Bellman-error extrapolation a URDF arm's is 0: the gradient term of the actor law (26),
#: eta_a1 / sqrt(1 + omega^T omega) B R^-1 B^T (Wa - Wc) eps with B = dphi/dx M^-1, grows as
#: M^-1 and, on the Kinova (lambda_min(M) = 1.2e-4 kg m^2), holds actor and critic 7 % off W*
#: from 1 s on; without it the actor follows the critic at eta_a2 and both reach W*.
ETA_A1_PAPER = 0.01
#: actor.eta_a2 of a URDF arm with extrapolation (paper: 1), the rate at which the actor follows
#: the critic (a 7-joint chain: with 1, actor 1.7 % off after 10 s; with 5, 1e-9; docs).
ETA_A2_URDF = 5.0
#: actor.eta_a2 and sim.T (at least) that messages suggest when the actor followed an unsettled
#: critic (divergence.slow_actor_change).
ETA_A2_SLOW = 0.5
SLOW_ACTOR_T = 20.0

_SAMPLES = 64
_SEED = 20241202


@functools.lru_cache(maxsize=64)
def _inertia_range(
    urdf: str, mtime_ns: int, size: int, locked: tuple[tuple[str, float], ...]
) -> tuple[float, float]:
    from .urdf import shared_arm

    arm = shared_arm(urdf, locked_joints=dict(locked) or None)
    n = arm.dof
    low, high = limits_box(arm)
    rng = np.random.default_rng(_SEED)
    positions = np.vstack([np.clip(np.zeros(n), low, high), rng.uniform(low, high, (_SAMPLES, n))])
    smallest, largest = math.inf, 0.0
    for q in positions:
        eigenvalues = np.linalg.eigvalsh(arm.terms(q, np.zeros(n))["M"])
        smallest, largest = min(smallest, eigenvalues[0]), max(largest, eigenvalues[-1])
    return float(smallest), float(largest)


def rise_ks(smallest: float) -> float:
    """control.ks for lambda_min(M) = ``smallest``: ks + 1 = max(30 lambda_min, min(1, 1000
    lambda_min)); below 0 (the paper: ks >= 0) only where a gain of 1 acts beyond 1000/s."""
    gain = max(RISE_RATE * smallest, min(1.0, RISE_RATE_MAX * smallest))
    return float(gain - 1.0)


def inertia_range(urdf: str, locked_joints: dict[str, float] | None = None) -> tuple[float, float]:
    """(lambda_min, lambda_max) of M(q) of a URDF arm (with its locked joints held) over q at 0
    (clipped into the limits) and 64 seeded samples of its joint-limit box (limits clipped to
    [-pi, pi]); cached per file."""
    from pathlib import Path

    stat = Path(urdf).stat()
    locked = tuple(sorted((locked_joints or {}).items()))
    return _inertia_range(str(urdf), stat.st_mtime_ns, stat.st_size, locked)


def urdf_defaults(config: ConfigSchema) -> tuple[dict[tuple[str, str], Any], dict[str, str]]:
    """The settings of a URDF arm derived from its believed model (``[model]``, by default the
    plant), for the keys the config leaves out, and the reason for each (for the summary).

    With lambda_min, lambda_max = :func:`inertia_range` of the model's URDF (the rules and their
    reasons: docs, URDF arms, "Defaults derived from the arm"): the task (qd =
    joint_limits.default_set_point, q0 = qd + 0.1 rad), plant.disturbance (the plant's M_jj),
    plant.torque_limits (``<limit effort>``), control.alpha1 = 2 I, control.ks (:func:`rise_ks`),
    the cost (R = diag(1 / (POLICY_RATE M_ii(qd))), Q = solvable_cost(alpha / 2 R^-1, alpha1,
    R)), actor.e2_margin, .weight_bound, the learning (extrapolation points and
    :func:`extrapolation_box`, no probing, epsilon_T, eta_a1, eta_a2), sim.T = 10 s, dt "auto".
    """
    from .optimal import solvable_cost

    believed = config.model.resolve_urdf(config.plant)
    smallest, largest = inertia_range(believed["urdf"], believed["locked_joints"])
    if believed["scale"] is not None:  # M times scale (model.scale)
        smallest, largest = believed["scale"] * smallest, believed["scale"] * largest
    explicit = config.explicit_keys
    n = config.dof
    eye = np.eye(n)
    values: dict[tuple[str, str], Any] = {}
    inertia = (
        f"the believed model's inertia: lambda_min(M) = {smallest:.3g}, lambda_max(M) = "
        f"{largest:.3g} kg m^2 over the joint-limit box"
    )
    reasons: dict[str, str] = {}

    def put(key: str, value: Any, reason: str) -> None:
        if key not in explicit:
            section, name = key.split(".")
            values[(section, name)] = value
            reasons[key] = reason

    from .urdf import config_arm

    limits = config_arm(config).limits  # the plant's: the real arm's joint stops
    low, high = np.asarray(limits["lower"], dtype=float), np.asarray(limits["upper"], dtype=float)
    qd, reason = default_set_point(config)
    put("task.qd", tuple(float(v) for v in qd), reason)
    if "task.qd" in explicit:
        from ._arm_sections import SinusoidTrajectory
        from .desired import desired_state

        given = config.task.qd
        if isinstance(given, SinusoidTrajectory) and given.offset is None:
            rest = tuple(float(v) for v in qd)  # the sinusoids about the rest position
            values[("task", "qd")] = dataclasses.replace(given, offset=rest)
            reasons["task.qd"] = "the sinusoids' offset: the rest position (as a set-point's qd)"
            qd = qd + np.sum(np.asarray(given.amplitude) * np.sin(given.phase), axis=1)
        else:
            qd = desired_state(config, 0.0)[0]
    q0 = np.where(qd + 0.1 <= high, qd + 0.1, qd - 0.1)
    put("task.q0", tuple(q0), "qd(0) + 0.1 (rad, or m on a prismatic joint)")
    if "task.q0" in explicit:
        q0 = np.array(config.task.q0, dtype=float)
    put("task.dq0", (0.0,) * n, "at rest")
    effort = effort_limits(config_arm(config))  # 0 or none given: no limit
    if np.all(np.isinf(effort)):
        put("plant.torque_limits", "none", "the URDF gives no <limit effort> (or 0)")
    else:
        put(
            "plant.torque_limits",
            tuple(float(v) for v in effort),
            "the URDF's <limit effort> (0 or none given: no limit on that joint)",
        )
    alpha1 = ALPHA1 * eye if "control.alpha1" not in explicit else np.array(config.control.alpha1)
    put("control.alpha1", tuple(map(tuple, alpha1)), "2 I: e1 decays at 2/s")
    ks = rise_ks(smallest)
    put(
        "control.ks",
        ks,
        f"RISE acts at (ks + 1) / lambda_min(M) = {(ks + 1) / smallest:.3g}/s"
        + (
            " (ks < 0, below the paper's ks >= 0: a gain of 1 would act faster than 1000/s)"
            if ks < 0.0
            else ""
        )
        + f"; {inertia}",
    )
    from .optimal import inertia_matrices

    joint_inertia = np.diag(inertia_matrices(config, qd[None, :], model=True)[0]).copy()
    plant_inertia = np.diag(inertia_matrices(config, qd[None, :])[0])  # the plant's own joints
    put("plant.disturbance", *default_disturbance(plant_inertia))
    if "cost.R" in explicit:
        R = np.array(config.cost.R)
    elif "cost.Q" in explicit:
        R = eye
        put("cost.R", tuple(map(tuple, R)), "I (cost.Q is given)")
    else:
        R = np.diag(1.0 / (POLICY_RATE * joint_inertia))
        put(
            "cost.R",
            tuple(map(tuple, R)),
            "diag(1 / (10 M_ii(qd))): u* = -R^-1 e2 acts at about 10/s on every joint",
        )
    kd = POLICY_RATE * joint_inertia  # the pd baseline acts at about the policy's rate
    put("controller.kd", tuple(map(tuple, np.diag(kd))), "diag(10 M_ii(qd)): about 10/s")
    put("controller.kp", tuple(map(tuple, np.diag(5.0 * kd))), "5 kd (the two-link 50 to 10)")
    if "cost.Q" not in explicit:
        alpha = float(np.linalg.eigvals(alpha1).real.min())
        if "cost.R" in explicit:  # a K that keeps Q positive definite for any R
            r_max = float(np.linalg.eigvalsh(0.5 * (R + R.T)).max())
            K = alpha / (2.0 * r_max) * eye
        else:
            K = alpha / 2.0 * np.linalg.inv(R)
        put(
            "cost.Q",
            tuple(map(tuple, solvable_cost(K, alpha1, R))),
            f"solvable_cost(K = diag({', '.join(f'{k:.3g}' for k in np.diag(K))}), alpha1, R): "
            "W* is known",
        )
    policy_gain = np.diag(np.linalg.inv(0.5 * (R + R.T)))  # (R^-1)_jj of u* = -R^-1 e2
    put(
        "probe.amplitude",
        tuple(float(a) for a in 0.1 * (ks + 1.0 + policy_gain)),
        "0.1 (ks + 1 + (R^-1)_jj) N m on joint j: moves each e2_j by about 0.1 rad/s",
    )
    put("probe.until", 0.0, "no probing: Bellman-error extrapolation excites the critic")
    # the actor's ball ||Wa|| <= weight_bound must hold W*: about [K; beta] (K = -Q12 of the
    # exact family, beta the model's base parameters), and the initial weights
    Q = np.array(values.get(("cost", "Q"), config.cost.Q), dtype=float)
    K = -Q[:n, n:]
    rows, cols = np.triu_indices(n)
    k_entries = np.where(rows == cols, K[rows, cols], (K + K.T)[rows, cols])
    beta = np.asarray(config_arm(config, model=True).base_parameters()[0], dtype=float)
    size = math.sqrt(float(np.sum(k_entries**2) + np.sum(beta**2)))
    for key in ("critic_weights", "actor_weights"):
        given = getattr(config.init, key)
        if given is not None:
            size = max(size, float(np.linalg.norm(np.asarray(given, dtype=float))))
    put(
        "actor.weight_bound",
        max(100.0, 10.0 * size),
        f"10 times ||[K; beta]|| = {size:.3g} (K = -Q12, beta the base parameters: W* for a "
        "cost of the exact family), at least 100",
    )
    put("extrapolation.points", 2 * config.basis_size, "twice the basis functions")
    points = values.get(("extrapolation", "points"), config.extrapolation.points)
    if points > 0:
        put(
            "critic.epsilon_T",
            EPSILON_T_URDF,
            "Gamma reset when lambda_min(Gamma) < 1e-5 (the two-link arm's 1e-3 resets so often "
            "that the weakly excited weights of an arm with light and heavy joints never learn)",
        )
        put(
            "actor.eta_a1",
            0.0,
            "the actor follows the critic (eta_a2) alone: the gradient term eta_a1 B R^-1 B^T "
            "acts through M^-1 and on arms with light joints holds the actor, and the critic "
            "that evaluates its policy, away from W* (Kinova: 7 % off after 5 s)",
        )
        put(
            "actor.eta_a2",
            ETA_A2_URDF,
            "the actor follows the critic at 5/s (the paper's 1/s left the actor of a 7-joint "
            "chain 1.7 % off W* after 10 s with its critic within 0.1 %)",
        )
    else:
        put("critic.epsilon_T", EPSILON_T_PROBING, "learning from the probing signal alone")
        put("actor.eta_a1", ETA_A1_PAPER, "the paper's, learning from the probing signal")
        put("actor.eta_a2", 1.0, "the paper's, learning from the probing signal")
    put(
        "actor.e2_margin",
        0.1 * smallest,
        "a tenth of lambda_min(M): the e2 block of the learned V stays positive definite, "
        "well below the arm's own",
    )
    if "extrapolation.box" not in explicit and "extrapolation.centre" not in explicit:
        centre, box = extrapolation_range(qd, q0, low, high, alpha1)
        put(
            "extrapolation.centre",
            tuple(float(v) for v in centre),
            "e1: the middle of the joint's range within its limits, at most pi rad each way from "
            "qd(0); e2: 0 (rates.extrapolation_range)",
        )
        put(
            "extrapolation.box",
            tuple(float(v) for v in box),
            "e1: half the joint's range within its limits, at most pi rad each way from qd(0), "
            "holding e1(0), at least 1 rad wide; e2: alpha1 times the farther end "
            "(rates.extrapolation_range)",
        )
    else:
        b1, b2 = extrapolation_box(qd, q0, low, high, alpha1)
        put(
            "extrapolation.box",
            tuple(float(v) for v in np.concatenate([b1, b2])),
            "e1: the distance from qd(0) to the joint's nearer limit (the box stays within the "
            "limits), capped at pi rad, at least max(1, 2 |e1(0)|); e2: alpha1 times that "
            "(rates.extrapolation_box; extrapolation.centre is given)",
        )
    put("sim.T", 10.0, "learning from extrapolation reaches W* within seconds")
    return values, reasons


# --- cost.input_bound = "auto" ------------------------------------------------------------

#: cost.input_bound = "auto" on a joint without a torque limit (N m): so large that the bounded
#: input cost and policy equal the unbounded ones there (lambda = 1e6 reproduces the unbounded
#: run to 1e-9, tests/test_input_bound.py).
UNLIMITED_BOUND = 1e6


def auto_input_bound(config: ConfigSchema) -> tuple[tuple[float, ...], str]:
    """lambda of cost.input_bound = "auto", one per joint, and the reason (for config.derived).

    The controller commands tau = h_hat + mu - (u_hat + probe) and the drive clips it at the
    limit tau_bar_i (plant.torque_limits). The ADP input |u_hat_i| <= lambda_i then leaves the
    commanded torque inside the limit while |h_hat_i| + |mu_i| + |probe_i| + lambda_i <= tau_bar_i.
    With

        headroom_i = tau_bar_i - max_t |h_i(qd, dqd, ddqd)| - d_i - sum_k |amplitude_ik|,

    h = M ddqd + C dqd + G + F of the believed model along the desired trajectory
    (dynamics.task_torque: 200 samples over [0, sim.T]; a set-point: one), d_i the amplitude of
    the disturbance (plant.disturbance: RISE's mu cancels it, so the commanded torque carries
    it) and the probe's largest value on
    joint i (while it probes: probe.until > 0), "auto" takes lambda_i = headroom_i / 2: the other
    half is left to the rest of RISE's mu (its transient, model error) and to h away from the
    desired trajectory, which are not bounded a priori. A heuristic margin, conservative while
    that rest of |mu_i| stays below headroom_i / 2; the torque panel and result.saturated_time
    show whether the drive clipped. A joint without a limit (inf) gets
    UNLIMITED_BOUND (unbounded in practice). Refused, naming the fields, when no joint is limited
    or a limit does not hold the task's feedforward and the probe."""
    from .dynamics import task_torque

    n = config.dof
    limits = config.plant.limit_vector(n)
    if limits.size == 0 or np.all(np.isinf(limits)):
        raise ValueError(
            'cost.input_bound: "auto" derives lambda from plant.torque_limits, and no joint is '
            'limited (plant.torque_limits is left out, "none" or inf); give cost.input_bound '
            "numbers, or set plant.torque_limits"
        )
    feedforward = task_torque(config, model=True)
    disturbance = np.abs(np.asarray(config.plant.disturbance, dtype=float))
    probing = config.probe.until > 0.0
    probe = np.abs(config.probe.amplitude_matrix(n)).sum(axis=1) if probing else np.zeros(n)
    headroom = limits - feedforward - disturbance - probe
    short = np.flatnonzero(np.isfinite(limits) & (headroom <= 0.0))
    if short.size:
        i = int(short[0])
        raise ValueError(
            f'cost.input_bound: "auto": on joint {i + 1} the torque limit does not hold the '
            f"task's feedforward and the probe: plant.torque_limits = {limits[i]:.4g} N m, "
            f"max |h| over the desired trajectory = {feedforward[i]:.4g} N m, "
            f"plant.disturbance = {disturbance[i]:.4g} N m"
            + (f", probe.amplitude summed = {probe[i]:.4g} N m" if probing else "")
            + "; give cost.input_bound numbers, raise the limit or change the task"
        )
    bound = np.where(np.isfinite(limits), headroom / 2.0, UNLIMITED_BOUND)
    reason = (
        "auto: (plant.torque_limits - max |h| of the believed model over the desired trajectory"
        " - |plant.disturbance|"
        + (" - the probe's amplitude" if probing else "")
        + ") / 2, half the headroom left to RISE"
        + (f"; {UNLIMITED_BOUND:g} on the joints without a limit" if np.isinf(limits).any() else "")
    )
    return tuple(float(v) for v in bound), reason


# --- rates ----------------------------------------------------------------------------------


def check_positions(config: ConfigSchema) -> np.ndarray:
    """The joint positions (S, n) where actor.positive_e2 keeps the structured basis' e2 block
    sum_b W_b M_b(q) of a URDF arm positive definite: qd(0), q(0) and, with extrapolation,
    qd(0) - e1 at 32 seeded samples of its e1 box (the points are evaluated there)."""
    from .desired import desired_state

    n = config.dof
    qd = desired_state(config, 0.0)[0]
    rows = [qd, np.array(config.task.q0, dtype=float)]
    if config.extrapolation.points > 0:
        low, high = (bound[:n] for bound in config.extrapolation.bounds(n))
        rng = np.random.default_rng(_SEED)
        rows += list(qd - rng.uniform(low, high, size=(32, n)))
    return np.array(rows)


def rate_positions(config: ConfigSchema) -> np.ndarray:
    """Where :func:`closed_loop_rates` takes M: qd(0), q(0) and, with extrapolation, qd(0) - e1 at
    32 seeded samples of the e1 box clipped to max(1, 2 max|e1(0)|) rad, where the plant moves:
    the points elsewhere are evaluated, not integrated (a 7-joint chain's initial policy: 7,600/s
    over its joint range, 3,300/s within 1 rad of qd)."""
    from .desired import desired_state

    n = config.dof
    qd = desired_state(config, 0.0)[0]
    q0 = np.array(config.task.q0, dtype=float)
    rows = [qd, q0]
    if config.extrapolation.points > 0:
        reach = max(1.0, 2.0 * float(np.abs(qd - q0).max()))
        low, high = (np.clip(bound[:n], -reach, reach) for bound in config.extrapolation.bounds(n))
        rng = np.random.default_rng(_SEED)
        rows += list(qd - rng.uniform(low, high, size=(32, n)))
    return np.array(rows)


def _value_hessians(config: ConfigSchema, positions: np.ndarray) -> np.ndarray:
    """d(dV/de2)/dx (positions, n, 2n) of the actor's initial V = Wa^T phi at x = 0 with
    qd = each position, by central differences of the basis' exact Jacobian (exact for the
    quadratic bases)."""
    from .optimal import basis

    n = config.dof
    config.initial_weights("critic_weights")  # a basis without a default: named as before
    W = config.initial_weights("actor_weights")
    h = 1e-4
    steps = np.vstack([np.eye(2 * n) * h, -np.eye(2 * n) * h])  # (4n, 2n)
    X = np.broadcast_to(steps, (len(positions), 4 * n, 2 * n))
    qd = np.broadcast_to(positions[:, None, :], (len(positions), 4 * n, n))
    _, jacobian = basis(config, X, qd)
    gradient_e2 = np.einsum("pskx,k->psx", jacobian, W)[..., n:]  # (P, 4n, n)
    difference = (gradient_e2[:, : 2 * n] - gradient_e2[:, 2 * n :]) / (2 * h)  # (P, 2n, n)
    return np.swapaxes(difference, 1, 2)


def _policy_gains(config: ConfigSchema, positions: np.ndarray, masses: np.ndarray) -> np.ndarray:
    """G (positions, n, 2n) of the policy u = -G x linearised at x = 0 at each joint position."""
    n = config.dof
    kind = config.controller.kind
    count = len(positions)
    R_inverse = np.linalg.inv(np.array(config.cost.R))
    if kind == "pd":
        kp, kd = (config.controller.gain_matrix(key, n) for key in ("kp", "kd"))
        gain = np.hstack([kp - kd @ np.array(config.control.alpha1), kd])
        return np.broadcast_to(gain, (count, n, 2 * n))
    if kind == "optimal":
        return np.broadcast_to(np.hstack([np.zeros((n, n)), R_inverse]), (count, n, 2 * n))
    if kind != "adp":
        return np.zeros((count, n, 2 * n))
    # u_hat = -1/2 R^-1 g^T dV/dx = -1/2 R^-1 M^-1 dV/de2
    return 0.5 * R_inverse @ np.linalg.solve(masses, _value_hessians(config, positions))


def _spectral_radius(matrices: np.ndarray) -> float:
    """max |eigenvalue| over a stack of matrices; inf when an entry is not finite."""
    if not np.all(np.isfinite(matrices)):
        return math.inf
    return float(np.abs(np.linalg.eigvals(matrices)).max())


def closed_loop_rates(config: ConfigSchema) -> list[dict[str, Any]]:
    """The fast rates (1/s) of the closed loop of ``config`` before it runs: a list of
    ``{"term", "rate", "fields"}`` (fields: the settings that set the rate), the largest over the
    sampled joint positions (module docstring)."""
    n = config.dof
    eye = np.eye(n)
    alpha1 = np.array(config.control.alpha1, dtype=float)
    rise_gain = (config.control.ks + 1.0) if config.controller.rise else 0.0
    positions = rate_positions(config)
    # the controller computes its policy from the believed model; every torque acts through the
    # plant's M^-1, whose rates the step must resolve
    from .optimal import inertia_matrices

    gains = _policy_gains(config, positions, inertia_matrices(config, positions, model=True))
    masses = inertia_matrices(config, positions)
    inverses = np.linalg.inv(masses)
    rise = rise_gain / float(np.linalg.eigvalsh(masses)[:, 0].min())
    policy = _spectral_radius(inverses @ gains[:, :, n:])
    loop = 0.0
    for M_inverse, G in zip(inverses, gains, strict=True):
        A = np.block(
            [[-alpha1, eye], [-M_inverse @ G[:, :n], -M_inverse @ (G[:, n:] + rise_gain * eye)]]
        )
        loop = max(loop, _spectral_radius(A))
    policy_fields = {
        "adp": "init.actor_weights, cost.R",
        "optimal": "cost.R",
        "pd": "controller.kp, controller.kd",
    }.get(config.controller.kind, "")
    out = [
        {
            "term": "the error dynamics (RISE, policy and alpha1 together)",
            "rate": loop,
            "fields": "control.ks, cost.R, control.alpha1",
        },
        {"term": "the RISE feedback (ks + 1) M^-1", "rate": rise, "fields": "control.ks"},
        {"term": "the initial policy through M^-1", "rate": policy, "fields": policy_fields},
        {
            "term": "e1 = -alpha1 e1 + e2",
            "rate": float(np.abs(np.linalg.eigvals(alpha1)).max()),
            "fields": "control.alpha1",
        },
    ]
    # the bound eta_c / nu of the normalised law; for nu near 0 (unnormalised) it says nothing
    if config.controller.kind == "adp" and config.critic.nu >= 1e-6:
        factor = 2.0 if config.extrapolation.points > 0 else 1.0
        out.append(
            {
                "term": "the critic eta_c Gamma omega omega^T / rho"
                + (" (trajectory and extrapolation points)" if factor > 1 else ""),
                "rate": factor * config.critic.eta_c / config.critic.nu,
                "fields": "critic.eta_c",
            }
        )
    return out


def _nice_floor(value: float) -> float:
    """The largest 1, 2 or 5 times a power of ten at or below value."""
    exponent = math.floor(math.log10(value))
    for mantissa in (5.0, 2.0, 1.0):
        candidate = mantissa * 10.0**exponent
        if candidate <= value * (1.0 + 1e-12):
            return float(f"{candidate:.1g}")
    return float(f"{10.0 ** (exponent - 1) * 5:.1g}")  # pragma: no cover


def nice_ceil(value: float) -> float:
    """The smallest 1, 2 or 5 times a power of ten at or above value (a horizon to suggest)."""
    exponent = math.floor(math.log10(value))
    for mantissa in (1.0, 2.0, 5.0, 10.0):
        candidate = mantissa * 10.0**exponent
        if candidate >= value * (1.0 - 1e-12):
            return float(f"{candidate:.1g}")
    return float(f"{10.0 ** (exponent + 1):.1g}")  # pragma: no cover


def auto_step(rates: list[dict[str, Any]], T: float = math.inf) -> float:
    """sim.dt = "auto": the largest 1, 2 or 5 x 10^k s with every rate * dt <= AUTO_MARGIN *
    RK4_STABILITY_LIMIT, at most AUTO_MAX_STEP (1 ms) and sim.T."""
    fastest = max((entry["rate"] for entry in rates if math.isfinite(entry["rate"])), default=0.0)
    step = AUTO_MAX_STEP
    if fastest > 0.0:
        step = min(step, _nice_floor(AUTO_MARGIN * RK4_STABILITY_LIMIT / fastest))
    return min(step, T)


def too_fast(rates: list[dict[str, Any]], dt: float) -> list[dict[str, Any]]:
    """The (finite) rates beyond RK4's stability limit at step dt. A non-finite rate (weights
    that overflow) has no step to suggest: that run diverges and says so."""
    return [
        entry
        for entry in rates
        if math.isfinite(entry["rate"]) and entry["rate"] * dt > RK4_STABILITY_LIMIT
    ]


def rates_text(rates: list[dict[str, Any]]) -> str:
    return "; ".join(f"{entry['term']}: {entry['rate']:.4g}/s" for entry in rates)


def check_step(config: ConfigSchema) -> None:
    """Refuses (ValueError naming sim.dt) a step at which a fast rate of the closed loop is beyond
    RK4's stability limit, naming the term, its rate and a dt that works."""
    rates = closed_loop_rates(config)
    dt = config.sim.dt
    fast = too_fast(rates, dt)
    if not fast:
        return
    worst = max(fast, key=lambda entry: entry["rate"])
    works = auto_step(rates, config.sim.T)
    raise ValueError(
        f"sim.dt: {dt:g} s is too coarse for this closed loop: {worst['term']} acts at "
        f"{worst['rate']:.4g}/s, beyond RK4's stability limit {RK4_STABILITY_LIMIT}/sim.dt = "
        f"{RK4_STABILITY_LIMIT / dt:.4g}/s (set by {worst['fields']}). Use sim.dt = {works:g} "
        '(or sim.dt = "auto", which picks it). Rates: ' + rates_text(rates)
    )
