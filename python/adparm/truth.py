"""Runs that tell the truth: yardsticks for any cost and the diagnostics of a learning run.

- :func:`lqr_value`: P of the Riccati equation of the error system linearised at the set-point
  (python-control), the exact V* = x^T P x of a linear arm and the local V* of any other.
- :func:`optimal_cost`: the numerically optimal cost from x0 for the believed model (or the
  plant) without disturbance, by direct transcription (CasADi + IPOPT), for any cost, refined
  until it settles to a stated tolerance (:class:`OptimalCost`).
- :func:`diagnose`: after a run, the e2 block of the learned V (positive definite?), the distance
  to a known W*, the HJB residual of the final weights over the region the run explored (and over
  the extrapolation box) relative to x^T Q x, and the learned V against the best yardstick. It
  gives a verdict; :func:`adparm.simulate` warns with :class:`ApproximationWarning` when the basis
  cannot represent V* or learning has not converged.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .basis_family import PaperBasis, UrdfStructuredBasis, basis_for
from .config import Config
from .desired import desired_state
from .divergence import (
    divergence_causes,
    e2_block_min_eigenvalues,
    extrapolation_shortfall,
    initial_actor_e2_block,
    limits_advice,
    slow_actor_change,
    structured_e2_block_min_eigenvalue,
    torque_clipping,
)
from .identification import (
    estimate_advice,
    estimate_critic_error,
    identifier_diagnosis,
    judged_config,
    model_gap_text,
)
from .optimal import basis, lqr_value, optimal_weights, policy
from .progress import SETTLED_FALL, half_time_index, longer_run_advice, longer_run_estimate
from .residual import best_residual, relative_residual
from .result import ApproximationWarning, SimulationResult, register, warn_if_approximate
from .saturation import limits_below_task, position_limits_text, saturation_text
from .simulation import SimulationDiverged, simulate
from .yardstick import OptimalCost, default_horizon, optimal_cost

__all__ = [
    "RESIDUAL_TOLERANCE",
    "ApproximationWarning",
    "OptimalCost",
    "default_horizon",
    "diagnose",
    "check_step_size",
    "e2_block_min_eigenvalue",
    "expression_quadratic_form",
    "learned_matrix",
    "lqr_value",
    "optimal_cost",
    "warn_if_approximate",
]

#: Re-exported: the causes of a divergence (adparm.divergence), how much longer a run needs
#: (adparm.progress) and the approximation warning (adparm.result) are part of the truth about a
#: run.
REEXPORTED = (
    ApproximationWarning,
    divergence_causes,
    initial_actor_e2_block,
    longer_run_estimate,
    structured_e2_block_min_eigenvalue,
    warn_if_approximate,
)

#: The relative HJB residual rms(eps) / rms(x^T Q x) above which a run is flagged (a critic 2 %
#: off W* leaves a few per cent).
RESIDUAL_TOLERANCE = 0.05

# Samples of the explored region and of the extrapolation box (fixed seed: same verdict each time).
_SAMPLES = 200
_SEED = 20240


def _check_config(config: Any) -> Config:
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    return config


def learned_matrix(config: Config, weights: Any) -> np.ndarray:
    """The quadratic form of V = W^T phi at the set-point qd(0) (x -> 0, cos q2 -> cos qd2):
    blockdiag([[W1, W3/2], [W3/2, W2]], [[W4 + c W5, (W7 + c W8)/2], [., W6]]), to compare with
    :func:`lqr_value`."""
    W = np.asarray(weights, dtype=float)
    c = math.cos(desired_state(config, 0.0)[0][1])
    P = np.zeros((4, 4))
    P[:2, :2] = [[W[0], W[2] / 2], [W[2] / 2, W[1]]]
    b = 0.5 * (W[6] + c * W[7])
    P[2:, 2:] = [[W[3] + c * W[4], b], [b, W[5]]]
    return P


def expression_quadratic_form(config: Config, weights: Any, *, step: float = 1e-4) -> np.ndarray:
    """The quadratic form S of V = W^T phi at the set-point qd(0) for an expression basis
    (V(x) = x^T S x + O(|x|^3) near x = 0), from V at the states step e_i and step (e_i + e_j):
    S_ii = V(h e_i) / h^2, S_ij = (V(h (e_i + e_j)) - V(h e_i) - V(h e_j)) / (2 h^2); terms of
    degree 4 contribute h^2 relative. To compare with :func:`lqr_value`."""
    W = np.asarray(weights, dtype=float)
    n_x = 2 * config.dof
    unit = step * np.eye(n_x)
    pairs = [(i, j) for i in range(n_x) for j in range(i + 1, n_x)]
    states = np.vstack([unit] + [unit[i] + unit[j] for i, j in pairs])
    phi = basis(config, states, desired_state(config, 0.0)[0])[0]
    V = phi @ W / step**2
    S = np.diag(V[:n_x])
    for k, (i, j) in enumerate(pairs):
        S[i, j] = S[j, i] = 0.5 * (V[n_x + k] - V[i] - V[j])
    return S


def e2_block_min_eigenvalue(weights: Any) -> float:
    """min over cos q2 in [-1, 1] of lambda_min(P(cos q2)), P the e2 block of V = W^T phi in the
    paper/augmented basis (affine in cos q2, so the minimum is at cos q2 = +-1). Negative: V is
    not positive definite for some q, as at the anti-stabilising HJB solution."""
    W = np.asarray(weights, dtype=float)
    values = []
    for c in (1.0, -1.0):
        b = 0.5 * (W[6] + c * W[7])
        values.append(np.linalg.eigvalsh([[W[3] + c * W[4], b], [b, W[5]]])[0])
    return float(min(values))


def _explored_states(result: SimulationResult, rng: np.random.Generator) -> np.ndarray:
    x = np.hstack([result.e1, result.e2])
    low, high = x.min(axis=0), x.max(axis=0)
    return rng.uniform(low, high, size=(_SAMPLES, x.shape[1]))


def _policy_error(result: SimulationResult, target: np.ndarray) -> float:
    """rms |u_hat - u*| / rms |u*| over the last 10 % of the recorded rows (at most 200): u_hat
    as recorded (eq. 20 with the g the controller believed: beta_hat's while identifying), u* of
    W* and the judged arm's g, at the recorded states."""
    config = judged_config(result.config)
    tail = np.nonzero(result.t >= result.t[0] + 0.9 * (result.t[-1] - result.t[0]))[0]
    tail = tail[np.linspace(0, tail.size - 1, min(tail.size, 200)).round().astype(int)]
    u_hat, x = result.u_hat[tail], np.hstack([result.e1, result.e2])[tail]
    u_star = policy(config, x, result.t[tail], target)
    scale = math.sqrt(float(np.mean(u_star**2)))
    if scale == 0.0:  # at rest exactly: u* = 0 there, compare the weights alone
        return 0.0 if np.allclose(u_hat, 0.0) else math.inf
    return math.sqrt(float(np.mean((u_hat - u_star) ** 2))) / scale


def _exact_cost_advice(config: Config) -> str:
    """How to make W* known when the basis does not represent V* for the run's cost: a cost of
    the exact family (on a URDF arm with the structured basis, the only one with a known W*
    there; tests/test_truth.py runs it)."""
    bounded = config.cost.input_bound is not None
    name = "adparm.saturated_cost" if bounded else "adparm.solvable_cost"
    if config.plant.urdf is None:
        return (
            f"use a cost of the exact family ({name}; then W* is known), or a basis that can "
            "represent V* (controller.basis), and compare with adparm.lqr_value / "
            "adparm.optimal_cost"
        )
    structured = isinstance(basis_for(config), UrdfStructuredBasis)
    return (
        "for a known optimum use "
        + ("" if structured else 'controller.basis = "structured" (the default) with ')
        + f"a cost of the exact family: {'[cost]' if bounded else 'cost.Q'} = {name}(K, alpha1, "
        + ("R, input_bound)" if bounded else "R)")
        + " with this run's control.alpha1 and cost.R (then W* is known and the structured "
        "basis represents V*)"
    )


def _half_time_residual(
    result: SimulationResult, config: Config, X: np.ndarray, target: Any, t_end: float
) -> float | None:
    """Without a known W*: the HJB residual over X of the weights at half time (None with W*,
    whose own progress measures learning). A final residual not 2 % below it has settled: UR3,
    UR5 and a 6-joint chain with Q = I, R = I settle at 0.09-0.13 in 10 s and keep it at 30-40 s
    (the best weights: 0.046), the Kinova falls from 0.36 at 10 s to 0.22 at 40 s."""
    if target is not None or result.t.size < 4:
        return None
    middle = half_time_index(result.t)
    Wc, Wa = result.critic_weights[middle], result.actor_weights[middle]
    return relative_residual(config, X, Wc, Wa, t_end)


def diagnose(result: SimulationResult, *, tolerance: float | None = None) -> dict[str, Any]:
    """The truth about a run, with what the actuator limits did:
    ``saturated_time`` (seconds per joint) and ``saturation`` (:func:`saturation_text`, None when
    no torque was clipped), which the verdict ends with, and ``position_limits``
    (:func:`position_limits_text`: where a URDF arm's joints went past their position limits, None
    when none did), which it adds last."""
    out = _diagnose_learning(result, tolerance=tolerance)
    learned = out["verdict"] in ("ok", "not a learning run")
    identifier = identifier_diagnosis(result)
    out["identifier"] = identifier
    informative = identifier is not None and identifier["ever_informative"]
    if identifier is None or out["verdict"] == "no rows":
        pass  # below: a run that does not learn hears only of a stack never informative
    elif not informative and out["verdict"] == "ok":
        out["verdict"] = identifier["text"]
    elif not (informative and out["verdict"] == "not a learning run"):
        out["verdict"] += "; " + identifier["text"]
    out["model_gap"] = model_gap_text(result, out["verdict"])
    if out["model_gap"] is not None:
        out["verdict"] += "; " + out["model_gap"]
    out["saturated_time"] = [float(v) for v in result.saturated_time]
    out["saturation"] = saturation_text(result)
    if out["saturation"] is not None:
        out["verdict"] += "; " + out["saturation"]
        below = limits_below_task(result.config)
        if below is not None:  # no change of learning helps: the limits or the task must change
            out["verdict"] = below[0] + "; " + out["verdict"]  # the cause first
            out["advice"] = [below[1]]
        elif not learned:  # limits that hold the task, clipped through the transient
            clipping = torque_clipping(result)
            if clipping is not None and clipping[1] is not None:
                out["advice"] = [limits_advice(clipping[1]) + ": " + clipping[0]]
    out["position_limits"] = position_limits_text(result)
    if out["position_limits"] is not None:
        out["verdict"] += "; " + out["position_limits"]
    return out


def _estimate_optimum_learned(
    result: SimulationResult, out: dict[str, Any], target: np.ndarray | None = None
) -> str | None:
    """For an identifying run whose critic ended ten times closer to the optimum of its own
    estimate, W*(beta_hat), than to the plant's W* (estimate_critic_error): the distances, as
    the verdict says them; None otherwise (then learning itself has not converged)."""
    own = estimate_critic_error(result, target)
    plant = out.get("critic_relative_error")
    if own is None or plant is None or not own < 0.1 * plant:
        return None
    return f"||Wc - W*(beta_hat)|| / ||W*|| = {own:.2g}, from the plant's W* {plant:.3g}"


def _diagnose_learning(
    result: SimulationResult, *, tolerance: float | None = None
) -> dict[str, Any]:
    """The truth about a run (plain JSON-ready data; summary.json's ``diagnostics``):

    - e2_block_min_eigenvalue (critic, actor): min over q of lambda_min of V's e2 block (for
      the structured basis of a URDF arm: over the joint positions of the explored region); <= 0
      means the run ended at a non-stabilising solution;
    - critic_relative_error: ||Wc - W*|| / ||W*|| when W* is known (else None);
    - hjb_residual_explored: rms(eps) / rms(x^T Q x) of the HJB error (eq. 21) of the final
      weights over states drawn uniformly in the box the run's x explored; hjb_residual_box: the
      same over the extrapolation box (when extrapolation is on); hjb_residual_trajectory: the same
      along the last 10 % of the recorded rows; hjb_residual_best (when the explored residual is
      above RESIDUAL_TOLERANCE): the least residual any weights reach there (least squares), which
      tells a basis that cannot represent V* (large) from learning that has not converged (small);
    - value_yardstick ("W*" or "LQR") and value_error: the relative error of the learned V against
      V* (sampled states, W* known) or of its quadratic form at the set-point against the LQR P;
    - verdict: "ok", or the problems found, and advice: what to try.
    - actor_relative_error and policy_relative_error (W* known): ||Wa - W*|| / ||W*|| and
      rms |u_hat - u*| / rms |u*| over the last 10 % of the run. "ok" needs the critic, the actor
      and the policy each within ``tolerance`` (default: the config's diagnostics.tolerance, 1 %).
    The region learning fits (the extrapolation box with fixed or grid points, else the explored
    region) is where the basis's best residual is measured: a residual the basis can reach there
    is "not converged", one it cannot is "the basis cannot represent V*".
    Only learning (adp) runs with rows are diagnosed; others give verdict "not a learning run".
    An identifying run (``identifier.enabled``) is judged against the plant (judged_config)."""
    config = judged_config(result.config)
    if tolerance is None:
        tolerance = config.diagnostics.tolerance
    out: dict[str, Any] = {"verdict": "ok", "problems": [], "advice": []}
    if config.controller.kind != "adp" or result.t.size < 2:
        out["verdict"] = "not a learning run" if config.controller.kind != "adp" else "no rows"
        return out
    Wc, Wa = result.critic_weights[-1], result.actor_weights[-1]
    family = basis_for(config)
    paper_basis = isinstance(family, PaperBasis)  # the e2 block's layout is known
    out["e2_block_min_eigenvalue"] = e2_block_min_eigenvalue(Wc) if paper_basis else None
    out["actor_e2_block_min_eigenvalue"] = e2_block_min_eigenvalue(Wa) if paper_basis else None
    finite = bool(np.all(np.isfinite(Wc)) and np.all(np.isfinite(Wa)))
    urdf_structured = isinstance(family, UrdfStructuredBasis)
    if urdf_structured and finite and result.status != "diverged":
        # the e2 block sum_b W_b M_b(q) depends on every joint angle: its least eigenvalue over
        # the joint positions of the explored region (and qd)
        e1 = _explored_states(result, np.random.default_rng(_SEED))[:, : config.dof]
        e1 = np.vstack([np.zeros(config.dof), e1])
        out["e2_block_min_eigenvalue"], out["actor_e2_block_min_eigenvalue"] = (
            e2_block_min_eigenvalues(config, [Wc, Wa], e1)
        )
    if result.status == "diverged" or not finite:
        out["problems"].append("diverged")
        if (
            paper_basis
            and min(out["e2_block_min_eigenvalue"], out["actor_e2_block_min_eigenvalue"]) <= 0.0
        ):
            out["problems"].append("the e2 block of the learned V is not positive definite")
        out["problems"].extend(
            divergence_causes(config, result)
        )  # what the config shows beforehand
        out["verdict"] = "; ".join(out["problems"])
        return out
    try:
        target = optimal_weights(config)
    except ValueError:
        target = None
    rng = np.random.default_rng(_SEED)
    X = _explored_states(result, rng)
    t_end = float(result.t[-1])
    out["hjb_residual_explored"] = relative_residual(config, X, Wc, Wa, t_end)
    out["hjb_residual_box"] = None
    if config.extrapolation.points > 0:
        low, high = config.extrapolation.bounds(config.dof)
        out["hjb_residual_box"] = relative_residual(
            config, rng.uniform(low, high, size=(_SAMPLES, low.size)), Wc, Wa, t_end
        )
    tail = result.t >= result.t[0] + 0.9 * (result.t[-1] - result.t[0])
    x_tail = np.hstack([result.e1, result.e2])[tail]
    q_tail = np.einsum("ni,ij,nj->n", x_tail, np.array(config.cost.Q), x_tail)
    out["hjb_residual_trajectory"] = float(
        np.sqrt(np.mean(result.hjb_error[tail] ** 2)) / max(np.sqrt(np.mean(q_tail**2)), 1e-300)
    )
    out["tolerance"] = tolerance
    out["actor_relative_error"] = out["policy_relative_error"] = None
    if target is not None:
        out["critic_relative_error"] = float(np.linalg.norm(Wc - target) / np.linalg.norm(target))
        out["actor_relative_error"] = float(np.linalg.norm(Wa - target) / np.linalg.norm(target))
        out["policy_relative_error"] = _policy_error(result, target)
        out["value_yardstick"] = "W*"
        phi = basis(config, X, desired_state(config, 0.0)[0])[0]
        exact = phi @ target
        out["value_error"] = float(np.sqrt(np.mean((phi @ Wc - exact) ** 2) / np.mean(exact**2)))
    else:
        out["critic_relative_error"] = None
        if config.task.is_set_point and paper_basis:
            P = lqr_value(config)
            out["value_yardstick"] = "LQR"
            out["value_error"] = float(
                np.linalg.norm(learned_matrix(config, Wc) - P) / np.linalg.norm(P)
            )
        elif config.task.is_set_point and config.controller.is_expression:
            P = lqr_value(config)
            out["value_yardstick"] = "LQR"
            out["value_error"] = float(
                np.linalg.norm(expression_quadratic_form(config, Wc) - P) / np.linalg.norm(P)
            )
        else:
            out["value_yardstick"], out["value_error"] = None, None

    problems, advice = out["problems"], out["advice"]
    lowest = (
        min(out["e2_block_min_eigenvalue"], out["actor_e2_block_min_eigenvalue"])
        if paper_basis or urdf_structured
        else math.inf
    )
    chased = None  # set: the actor followed an unsettled critic (divergence.slow_actor_change)
    if lowest <= 0.0:
        problems.append(
            "ended at a non-stabilising solution: the e2 block of the learned V is not positive "
            f"definite (lambda_min = {lowest:.3g}"
            + (" over the explored joint positions)" if urdf_structured else ")")
        )
        if not urdf_structured:
            advice.append("keep actor.positive_e2 = true (the default)")
        elif chased := slow_actor_change(config):  # pulled by the critic's first, unsettled fits
            advice.append(f"{chased}: the actor followed the critic before it settled")
    short = []  # the parts that end outside the tolerance of the known optimum
    if target is not None:
        for key, text in (
            ("critic_relative_error", "critic ||Wc - W*|| / ||W*||"),
            ("actor_relative_error", "actor ||Wa - W*|| / ||W*||"),
            ("policy_relative_error", "policy rms|u_hat - u*| / rms|u*| over the last 10 %"),
        ):
            if not out[key] <= tolerance:
                short.append(f"{text} = {out[key]:.3g}")
    if short:
        problems.append(
            f"ended away from the known W* (tolerance {tolerance:g}): " + ", ".join(short)
        )
    # the region learning fits: the extrapolation box (fixed or grid points), else the explored
    fitted = config.extrapolation.points > 0 and config.extrapolation.mode != "local"
    X_fit = X
    if fitted:
        low, high = config.extrapolation.bounds(config.dof)
        X_fit = np.random.default_rng(_SEED + 1).uniform(low, high, size=(_SAMPLES, low.size))
    residual = (
        relative_residual(config, X_fit, Wc, Wa, t_end)
        if fitted
        else (out["hjb_residual_explored"])
    )
    region = "the extrapolation box" if fitted else "the explored region"
    on_trajectory = out["hjb_residual_trajectory"]
    out["hjb_residual_best"] = None
    if residual > RESIDUAL_TOLERANCE:
        if target is not None:  # the basis represents V* exactly: W* reaches round-off
            best = relative_residual(config, X_fit, target, target, t_end)
        else:
            best = best_residual(config, X_fit, Wc, t_end)
        out["hjb_residual_best"] = best
        if best > RESIDUAL_TOLERANCE:
            out["approximation"] = "basis"
            problems.append(
                f"the basis cannot represent V*: the HJB residual of the final weights is "
                f"{residual:.3g} of x^T Q x over {region} ({on_trajectory:.3g} along "
                f"the end of the trajectory), and no weights do better than {best:.3g} there"
            )
            advice.append(_exact_cost_advice(config))
        else:
            earlier = _half_time_residual(result, config, X_fit, target, t_end)
            settled = earlier is not None and residual >= (1.0 - SETTLED_FALL) * earlier
            if settled and best > 1e-6:  # not round-off: V* is not in the basis
                out["approximation"] = "basis"
                problems.append(
                    f"learning settled away from the basis' best fit: the HJB residual of the "
                    f"final weights is {residual:.3g} of x^T Q x over {region} ({earlier:.3g} at "
                    f"half time), where other weights reach {best:.3g}, not round-off: V* is not "
                    "in this basis for this cost, and learning settles elsewhere"
                )
                if not chased:  # a longer run at the same rate keeps the non-stabilising solution
                    advice.append("a longer run will not help; " + _exact_cost_advice(config))
            elif (own := _estimate_optimum_learned(result, out, target)) is not None:
                out["approximation"] = "identification"
                problems.append(
                    f"the critic learned the optimum of its estimate ({own}), and beta_hat's "
                    f"error leaves the plant's HJB residual at {residual:.3g} of x^T Q x over "
                    f"{region}, where the basis can reach {best:.3g}"
                )
                advice.append(estimate_advice(result))
            else:
                out["approximation"] = "not converged"
                problems.append(
                    f"learning has not converged: the HJB residual of the final weights is "
                    f"{residual:.3g} of x^T Q x over {region}"
                    + ("" if earlier is None else f" ({earlier:.3g} at half time)")
                    + f", where the basis can reach {best:.3g}"
                )
                if settled:
                    longer = "a longer run will not help: the residual did not fall over the "
                    longer += "second half of the run"
                elif target is None:  # the UR5, Q = I, R = I, 2 s: still falling, settles at 3 s
                    longer = "a longer run may lower the residual, but without a known W* "
                    longer += "nothing tells how far or how soon"
                else:
                    longer = longer_run_advice(
                        result, target, tolerance, out["policy_relative_error"]
                    )
                if not chased:
                    advice.append(
                        longer
                        + (
                            ", excite more (probe.amplitude) or add Bellman-error extrapolation "
                            "(extrapolation.points)"
                            if config.extrapolation.points == 0
                            else ""
                        )
                    )
                    if target is None and not settled:
                        advice.append(_exact_cost_advice(config))
    elif short:
        out["approximation"] = "not converged"
        if not chased:  # a longer run at the same rate keeps the non-stabilising solution
            advice.append(
                longer_run_advice(result, target, tolerance, out["policy_relative_error"])
                + (
                    ", or add Bellman-error extrapolation (extrapolation.points)"
                    if config.extrapolation.points == 0
                    else ""
                )
            )
    shortfall = extrapolation_shortfall(config)
    out["extrapolation_shortfall"] = shortfall
    if shortfall is not None and problems:  # a likely reason why learning fell short
        problems.append(shortfall)
        advice.append(f"use extrapolation.points >= {config.basis_size} (several times more helps)")
    unknown = target is None and config.plant.urdf is not None
    if problems:
        out["verdict"] = "; ".join(problems)
        if unknown:
            out["verdict"] += (
                "; the optimum is not known (no exact W* for this basis on a URDF arm)"
            )
    elif unknown:
        # nothing wrong was found, but nothing proves the optimum was reached either
        yardstick = (
            f"; its quadratic form is {out['value_error']:.3g} off the LQR value of the "
            "linearisation at the set-point"
            if out["value_error"] is not None
            else ""
        )
        out["verdict"] = (
            "ok, but the optimum is not known: no exact W* for this basis on a URDF arm "
            f"(HJB residual {residual:.3g} of x^T Q x over the explored region{yardstick})"
        )
    return out


#: check_step_size flags a transient whose dt and dt/2 runs differ by more than this (relative).
STEP_TOLERANCE = 0.01


def check_step_size(config: Config, *, transient: float = 1.0) -> dict[str, Any]:
    """The integration error of the early learning transient: runs ``config`` over the first
    ``transient`` seconds (at most sim.T) with sim.dt and with sim.dt / 2 and compares, on the rows
    both record (every ~10 ms), the critic weights and e1:

    - critic_max_difference: max_t ||Wc_dt - Wc_dt/2|| / max_t ||Wc_dt/2||;
    - critic_final_difference: the same at the end of the transient;
    - e1_max_difference: max_t |e1_dt - e1_dt/2| / max_t |e1_dt/2|;
    - verdict: "ok" when all are below STEP_TOLERANCE (1 %), else what was seen and what to try.
    RK4 is fourth order, so the difference is about 15/16 of the error of the dt run."""
    config = _check_config(config)
    if not (isinstance(transient, (int, float)) and math.isfinite(transient) and transient > 0):
        raise ValueError(f"transient: expected a finite number > 0, got {transient!r}")
    dt = config.sim.dt
    T = min(float(transient), config.sim.T)
    every = max(1, round(0.01 / dt))
    runs = []
    for step, record in ((dt, every), (dt / 2, 2 * every)):
        changed = config.updated({"sim": {"T": T, "dt": step, "record_every": record}})
        try:
            runs.append(simulate(changed, diagnose=False))
        except SimulationDiverged as error:
            runs.append(error.result)
    coarse, fine = runs
    n = min(coarse.t.size, fine.t.size) - 1  # the last row is at T in both
    out: dict[str, Any] = {"dt": dt, "transient": T}
    if coarse.status != "finished" or fine.status != "finished":
        out["verdict"] = (
            f"a run diverged (dt: {coarse.status}, dt/2: {fine.status}); try a smaller sim.dt"
        )
        return out
    rows = list(range(n)) + [-1]
    Wc, Wc_half = coarse.critic_weights[rows], fine.critic_weights[rows]
    e1, e1_half = coarse.e1[rows], fine.e1[rows]
    scale = max(np.linalg.norm(Wc_half, axis=1).max(), 1e-300)
    difference = np.linalg.norm(Wc - Wc_half, axis=1)
    out["critic_max_difference"] = float(difference.max() / scale)
    out["critic_final_difference"] = float(
        difference[-1] / max(np.linalg.norm(Wc_half[-1]), 1e-300)
    )
    out["e1_max_difference"] = float(
        np.linalg.norm(e1 - e1_half, axis=1).max()
        / max(np.linalg.norm(e1_half, axis=1).max(), 1e-300)
    )
    worst = max(out["critic_max_difference"], out["e1_max_difference"])
    out["verdict"] = (
        "ok"
        if worst <= STEP_TOLERANCE
        else f"sim.dt = {dt:g} s leaves {100 * worst:.2g} % of integration error in the first "
        f"{T:g} s (critic weights or e1 against a dt/2 run); try sim.dt = {dt / 2:g}"
    )
    return out


register("diagnose", lambda result: diagnose(result))
