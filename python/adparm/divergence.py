"""Why a run diverged, from its config (and its partial result): divergence_causes, and the checks
of the structured basis' e2 block and of an expression basis that it uses (adparm.truth uses them
too)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .basis_family import UrdfStructuredBasis, basis_for
from .config import Config
from .desired import desired_state
from .rates import (
    AUTO_MARGIN,
    ETA_A2_SLOW,
    RK4_STABILITY_LIMIT,
    SLOW_ACTOR_T,
    auto_step,
    closed_loop_rates,
    rates_text,
)
from .result import SimulationResult
from .transient import ADVISED_LIMITS_RULE, advised_torque_limits, clipped, limits_text
from .translate import extrapolation_points
from .urdf import config_arm

__all__ = [
    "actor_followed_critic",
    "divergence_causes",
    "estimate_jump",
    "extrapolation_shortfall",
    "initial_actor_e2_block",
    "limits_advice",
    "slow_actor_change",
    "torque_clipping",
]

#: The share of a run's recorded rows with a joint's torque clipped at plant.torque_limits from
#: which the clipping is named as a diverged run's cause (the SO-101 with 0.05 N m on its wrist
#: roll and gripper: 93-99 % on every joint before it diverged).
CLIPPED_SHARE = 0.1


def extrapolation_shortfall(config: Config) -> str | None:
    """What is wrong when Bellman-error extrapolation has fewer points than the basis has
    functions (``extrapolation.points`` < K): the points' regressors span at most N of the K
    directions, so they cannot determine the weights alone (the issue's prototype stalled 2-6 %
    off W* or drifted into divergence). None when N = 0 or N >= K."""
    points, size = config.extrapolation.points, config.basis_size
    if 0 < points < size:
        return (
            f"extrapolation.points = {points} is below the {size} basis functions: the points "
            "alone cannot determine the weights"
        )
    return None


def initial_actor_e2_block(config: Config) -> dict[str, float] | None:
    """The e2 block M_w = sum_b Wa_b M_b(qd(0)) of the initial actor weights of the structured
    basis of a URDF arm, seen through its policy u_hat = -R^-1 M^-1 M_w e2, which makes e2 decay
    as de2 = -A e2 with A = M^-1 R^-1 M^-1 M_w (believed model's M at qd(0)):
    {"min_eigenvalue": lambda_min(M_w), "rate": max |eig(A)| (1/s)}; None for other bases.
    lambda_min <= 0 pushes e2 away; rate * sim.dt above RK4_STABILITY_LIMIT makes the first steps
    of RK4 unstable (the weights all ones on the planar 3-link arm: 4600/s)."""
    if not isinstance(basis_for(config), UrdfStructuredBasis):
        return None
    n = config.dof
    qd = desired_state(config, 0.0)[0]
    arm, blocks = structured_e2_blocks(config, [config.initial_weights("actor_weights")], [qd])
    M_w = blocks[0, 0]
    M_inverse = np.linalg.inv(arm.terms(qd, np.zeros(n))["M"])
    A = M_inverse @ np.linalg.inv(np.array(config.cost.R)) @ M_inverse @ M_w
    return {
        "min_eigenvalue": float(np.linalg.eigvalsh(0.5 * (M_w + M_w.T)).min()),
        "rate": float(np.abs(np.linalg.eigvals(A)).max()),
    }


def structured_e2_blocks(config: Config, weight_sets: Any, positions: Any) -> tuple[Any, Any]:
    """The believed model's arm and the e2 blocks M_w(q) = sum_b W_b M_b(q) of each set of
    weights of the structured basis of a URDF arm (rows of weight_sets) at each joint position
    (rows of positions): an array (sets, positions, n, n). M_b are the arm's base-parameter
    directions (UrdfArm.base_parameters), computed once per position."""
    arm = config_arm(config, model=True)
    n = config.dof
    _, columns, _ = arm.base_parameters()
    W = np.atleast_2d(np.asarray(weight_sets, dtype=float))[:, n * (n + 1) // 2 :]
    M_b = np.array([arm.mass_regressor(q)[columns] for q in np.atleast_2d(positions)])
    return arm, np.einsum("wb,mbij->wmij", W, M_b)


def e2_block_min_eigenvalues(config: Config, weight_sets: Any, e1: Any) -> list[float]:
    """For each set of weights, min over the rows of e1 of lambda_min of its e2 block at
    q = qd(0) - e1 (structured_e2_block_min_eigenvalue)."""
    positions = desired_state(config, 0.0)[0] - np.atleast_2d(e1)
    _, blocks = structured_e2_blocks(config, weight_sets, positions)
    symmetric = 0.5 * (blocks + np.swapaxes(blocks, -1, -2))
    return [float(value) for value in np.linalg.eigvalsh(symmetric).min(axis=(1, 2))]


def structured_e2_block_min_eigenvalue(config: Config, weights: Any, e1: Any) -> float:
    """min over the rows of e1 (m, n) of lambda_min of the e2 block sum_b W_b M_b(q),
    q = qd(0) - e1, of weights W of the structured basis of a URDF arm (the believed model's
    base-parameter directions M_b). At or below 0 the learned V is not positive definite in e2
    there: not a stabilising solution."""
    return e2_block_min_eigenvalues(config, [weights], e1)[0]


def basis_problem_at_points(config: Config) -> str | None:
    """The first term of an expression basis that is not finite (or whose d phi / dx is not) at
    a fixed or grid extrapolation point, named with the point; None otherwise (the initial
    state is checked by Config)."""
    extrapolation = config.extrapolation
    family = basis_for(config)
    if family.finite_everywhere or not extrapolation.points:
        return None
    if extrapolation.mode == "local":  # drawn anew at each step
        return None
    qd = desired_state(config, 0.0)[0]
    problem = family.nonfinite(config, extrapolation_points(config), qd)
    return None if problem is None else f"at an extrapolation point, {problem}"


def basis_problem_near_end(result: SimulationResult) -> str | None:
    """The first term of an expression basis that is not finite (or whose d phi / dx is not)
    just after the last recorded row of a diverged run: x extrapolated along its last recorded
    velocity over two recording intervals."""
    config = result.config
    family = basis_for(config)
    if family.finite_everywhere or result.t.size < 2:
        return None
    t = result.t
    x = np.hstack([result.e1[-2:], result.e2[-2:]])
    step = t[-1] - t[-2]
    if not step > 0.0:
        return None
    states = x[-1] + np.linspace(0.0, 2.0, 41)[:, None] * (x[-1] - x[-2])
    problem = family.nonfinite(config, states, result.qd[-1])
    return None if problem is None else f"just after t = {t[-1]:.6g} s, {problem}"


def estimate_jump(result: SimulationResult, window: float = 0.1) -> str | None:
    """For an identifying run that diverged: how far beta_hat moved (relative, by norm) over
    the last ``window`` s of its rows (at least the last two), when by more than 5 %. The
    believed model then changed under the actor's weights, learnt for the former estimate; on a
    random 4-joint chain a jump of beta_hat when the stack became informative made the policy's
    gain through M_hat^-1 about 30 times larger and the run diverged within 2 ms (guide: Unknown
    dynamics). None otherwise."""
    estimate = result.model_parameters
    t = result.t
    if estimate is None or t.size < 2:
        return None
    first = min(int(np.searchsorted(t, t[-1] - window)), t.size - 2)
    before, after = np.asarray(estimate[first]), np.asarray(estimate[-1])
    moved = float(np.linalg.norm(after - before) / max(float(np.linalg.norm(before)), 1e-300))
    if not moved > 0.05:
        return None
    return (
        f"the identifier's estimate beta_hat moved by {moved:.3g} (relative, by norm) from "
        f"t = {t[first]:.6g} s to {t[-1]:.6g} s, just before the divergence: the believed model "
        "changed under the actor's weights, learnt for the former estimate"
    )


def slow_actor_change(config: Config) -> str | None:
    """The change that keeps the actor of a URDF arm's structured basis from following its critic
    before the critic's least squares has settled: actor.eta_a2 = rates.ETA_A2_SLOW with sim.T at
    least rates.SLOW_ACTOR_T (the actor's lag e^(-eta_a2 T) then ends below 5e-5 of its start).
    Random 6- and 7-joint chains with their own cost that diverged or ended at a non-stabilising
    e2 block at the derived 5/s end within 1 % of W* with it (docs: URDF arms, "Your own cost").
    None for other bases, without learning, or when the actor is that slow already."""
    if not isinstance(basis_for(config), UrdfStructuredBasis):
        return None
    if not (config.actor.eta_a2 > ETA_A2_SLOW and config.critic.eta_c > 0.0):
        return None
    T = max(config.sim.T, SLOW_ACTOR_T)
    return f"actor.eta_a2 = {ETA_A2_SLOW:g} (not {config.actor.eta_a2:g}) and sim.T = {T:g} s"


def actor_followed_critic(config: Config, result: SimulationResult) -> str | None:
    """For a diverged run of a URDF arm's structured basis whose actor's weights moved by more
    than 5 % (relative, by norm) before the divergence: the actor followed the critic at
    actor.eta_a2 while the critic's least squares was still far from settled (on a random 6-joint
    chain with its own cost the critic's e2 weights swung to 10 times their start within 0.2 s,
    and the actor's policy, stable at every frozen instant, diverged with them), with the change
    that avoids it (slow_actor_change). None otherwise."""
    change = slow_actor_change(config)
    weights = result.actor_weights
    finite = np.nonzero(np.all(np.isfinite(weights), axis=1))[0]
    if change is None or finite.size < 2:
        return None
    start = np.linalg.norm(weights[0])
    if not start > 0.0:
        return None
    last = finite[-1]
    moved = float(np.linalg.norm(weights[last] - weights[0]) / start)
    if not moved > 0.05:
        return None
    return (
        f"the actor's weights moved by {moved:.3g} (relative, by norm) by t = "
        f"{result.t[last]:.6g} s: the actor followed the critic at actor.eta_a2 = "
        f"{config.actor.eta_a2:g}/s before the critic's least squares settled (use {change})"
    )


def torque_clipping(result: SimulationResult) -> tuple[str, list[float] | None] | None:
    """When the applied torque was clipped at plant.torque_limits on some joint over at least
    CLIPPED_SHARE of the recorded rows: what to say (those joints and shares) and the limits that
    let the arm through (transient.advised_torque_limits; None where they are the given ones);
    else None. The theory assumes the commanded torque is applied: no change of the learning
    helps then."""
    if np.asarray(result.tau).size == 0:
        return None
    share = np.mean(clipped(result), axis=0)
    joints = np.flatnonzero(share >= CLIPPED_SHARE)
    if joints.size == 0:
        return None
    text = (
        "the applied torque was clipped at plant.torque_limits on "
        + ", ".join(f"joint {i + 1} in {100.0 * share[i]:.3g} %" for i in joints)
        + " of the recorded rows: the limits let the arm go, and no change of the learning helps"
    )
    config = result.config
    advised = advised_torque_limits(config)
    given = [float(v) for v in config.plant.limit_vector(config.dof)]
    return text, (advised if advised != given else None)


def limits_advice(advised: list[float]) -> str:
    """The advice of torque_clipping's limits."""
    return f"raise plant.torque_limits to {limits_text(advised)} ({ADVISED_LIMITS_RULE})"


def divergence_causes(config: Config, result: SimulationResult | None = None) -> list[str]:
    """Likely causes of a divergence that the config shows before any run, each with a change
    that is not already in effect: the measured fast rates of the closed loop against RK4's limit
    at sim.dt (rates.closed_loop_rates; a smaller sim.dt that keeps them inside it), given the
    partial result torques clipped at plant.torque_limits over much of it (torque_clipping) or
    else an actor that followed an unsettled critic (actor_followed_critic), initial
    actor weights of the structured basis of a URDF arm whose e2 block is not positive definite
    (only when init.actor_weights is set), fewer extrapolation points than basis functions, and
    first an expression basis term that is not finite at a fixed extrapolation point or (given
    the diverged run's partial ``result``) just after its last recorded row."""
    causes = []
    for problem in (
        basis_problem_at_points(config),
        None if result is None else basis_problem_near_end(result),
    ):
        if problem is not None:  # the first thing to fix: no step size helps
            causes.append(problem)
    clipping = None if result is None else torque_clipping(result)
    if clipping is not None:  # the learning ran on torques it did not command
        text, advised = clipping
        causes.append(text + ("" if advised is None else f" ({limits_advice(advised)})"))
    jump = None if result is None else estimate_jump(result)
    if jump is not None:
        causes.append(jump)
    rates = closed_loop_rates(config)
    dt = config.sim.dt
    fast = [entry for entry in rates if entry["rate"] * dt > AUTO_MARGIN * RK4_STABILITY_LIMIT]
    if fast:
        worst = max(fast, key=lambda entry: entry["rate"])
        causes.append(
            f"{worst['term']} acts at {worst['rate']:.4g}/s, near or beyond RK4's stability "
            f"limit {RK4_STABILITY_LIMIT}/sim.dt = {RK4_STABILITY_LIMIT / dt:.4g}/s (use "
            f'sim.dt = {auto_step(rates, config.sim.T):g}, which sim.dt = "auto" picks)'
        )
    chase = (
        None
        if result is None or jump is not None or clipping is not None
        else actor_followed_critic(config, result)
    )
    if chase is not None:
        causes.append(chase)
    block = initial_actor_e2_block(config)
    if block is not None and block["min_eigenvalue"] <= 0.0:
        causes.append(
            "the initial actor weights' e2 block M_w = sum_b Wa_b M_b(qd) is not positive "
            f"definite (lambda_min = {block['min_eigenvalue']:.3g}), so u_hat = -R^-1 M^-1 M_w e2 "
            "pushes e2 away"
            + (
                " (leave init.actor_weights out: the believed model's inertia)"
                if config.init.actor_weights is not None
                else ""
            )
        )
    for key in ("critic_weights", "actor_weights"):
        given = getattr(config.init, key)
        if given is not None and not np.any(np.asarray(given)):
            causes.append(
                f"init.{key} are all zero: at rest omega = 0 while the HJB error is x^T Q x > 0, "
                f"so the weights cannot settle (leave init.{key} out: the basis' default)"
            )
    shortfall = extrapolation_shortfall(config)
    if shortfall is not None:
        causes.append(shortfall + f" (use extrapolation.points >= {config.basis_size})")
    causes.append(
        f"the closed loop's rates at the start (RK4's limit 2.785/sim.dt = "
        f"{RK4_STABILITY_LIMIT / dt:.4g}/s): " + rates_text(rates)
    )
    return causes
