"""Summary metrics of a run and the list of settings that differ from the paper's printed values.

:func:`summarize` returns plain JSON-ready data (the content of ``summary.json``);
:func:`summary_markdown` renders it as ``summary.md``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ._sections import SECTIONS
from .config import Config, paper_config
from .identification import judged_config
from .optimal import basis_names, optimal_weights
from .result import SimulationResult, post_run_failure, register, stop_time
from .saturation import torque_limit_values, torque_limits_text
from .truth import diagnose
from .units import effort_units, norm_unit, position_units

__all__ = [
    "PAPER_CLAIM_TIME",
    "accumulated_cost",
    "deviations",
    "relative_weight_error",
    "stop_time",
    "summarize",
    "summary_markdown",
]

#: The paper: "The value of Wc after 110 s is [...]" (Section 4).
PAPER_CLAIM_TIME = 110.0

# Values printed in Section 4 of the paper (corrected where the print is wrong).
_PAPER_PRINTED: dict[str, Any] = {
    "plant.p1": 5.0,
    "plant.p2": 1.0,
    "plant.p3": 1.0,
    "plant.g1": 9.8 * 1.2,
    "plant.g2": 9.8,
    "plant.coulomb": -0.1,
    "plant.disturbance": [0.1, 0.1],
    "task.q0": [0.1598, 0.2257],
    "task.qd": [0.0, 0.0],
    "cost.Q": [
        [40.0, 2.0, -4.0, 4.0],
        [2.0, 40.0, 4.0, -6.0],
        [-4.0, 4.0, 4.0, 0.0],
        [4.0, -6.0, 0.0, 4.0],
    ],
    "cost.R": [[0.25, 0.0], [0.0, 0.25]],
    "control.alpha1": [[15.6, 10.6], [10.6, 10.4]],
    "critic.eta_c": 800.0,
    "critic.nu": 1.0,
    "critic.gamma0": 100.0,
    "critic.epsilon_T": 0.001,
    "actor.eta_a1": 0.01,
    "actor.eta_a2": 1.0,
    "controller.kind": "adp",
    "controller.rise": True,
    "controller.basis": "paper",
    "extrapolation.points": 0,
}

# Why our defaults differ from the printed values, or what we chose where the paper is silent.
_REASONS: dict[str, str] = {
    "critic.epsilon_T": (
        "With the printed 1e-3, Gamma is reset every few tens of ms under strong excitation; each "
        "window is too short to inform the weakly excited e1 direction and the critic stalls "
        "10-40 % off W*. 1e-6 lets Gamma accumulate for seconds (about one reset per second)."
    ),
    "probe": (
        'Not printed ("a probing signal is added"). 4 sinusoids (1, 2.7, 5.3, 9.1 rad/s, phases '
        "0-3 rad) along the torque direction [71, 23] N m = 75 N m x M(qd) v_fast, v_fast the fast "
        "eigenvector of alpha1: the component of e1 along v_fast is filtered at 23.9 1/s and is "
        "the critic's least excited direction. Stops at t = 100 s."
    ),
    "control.ks": "Not printed; ks = 10, alpha2 = 1, beta1 = 0.5 satisfy condition (29).",
    "control.alpha2": "Not printed; see control.ks.",
    "control.beta1": "Not printed; beta1 = 0.5 > zeta1 + zeta2 / alpha2 = 0.2 (condition 29).",
    "init": (
        "Not printed; all ones. Zero weights are inadmissible: the critic diverges "
        "within milliseconds. The structured basis starts from K = I and the believed model's "
        "inertia."
    ),
    "task.dq0": "Not printed; the arm starts at rest.",
    "actor.weight_bound": "Not printed; the projection keeps ||Wa|| <= 100 (about 8 ||W*||).",
    "plant.viscous": "Not in the paper; 0 keeps its friction model.",
    "sim": "Not printed; RK4 with dt = 1 ms, horizon 150 s (past the 110 s claim).",
    "model": "Not in the paper; the controller's model defaults to the plant (exact model).",
    "actor.positive_e2": (
        "Not in the paper (its proj{} bounds only ||Wa||): the projection also keeps the e2 block "
        "of the critic's and the actor's V positive definite at cos q2 = +-1 (a URDF arm's "
        "structured basis: at qd(0), q(0) and joint positions of the extrapolation box). Without "
        "it about one run in four with other probe phases or q(0) ends at the anti-stabilising "
        "HJB solution (e2 block negated), reported as finished."
    ),
    "actor.e2_margin": "Not in the paper; see actor.positive_e2 (lambda_min >= 0.01 kg m^2).",
    "controller.basis": (
        "The paper's 8 functions over [x; qd] with cos x2 replaced by cos(qd2 - x2) = cos q2: "
        "identical to the printed basis while qd2 = 0, and exact for any desired trajectory."
    ),
}


def _flatten(config: Config, left_out: dict[str, tuple[Any, str]]) -> dict[str, Any]:
    """Every setting as "section.key": value, with the value adparm resolved for each one left
    out (Config.left_out_values; the model's keys only where given: left out, the model is the
    plant)."""
    import dataclasses

    given = config.to_dict()
    flat = {}
    for section, cls in SECTIONS.items():  # in the order of the sections and their fields
        for field in dataclasses.fields(cls):
            name = f"{section}.{field.name}"
            if field.name in given[section]:
                flat[name] = given[section][field.name]
            elif name in left_out and section != "model":
                flat[name] = left_out[name][0]
    return flat


def _equal(a: Any, b: Any) -> bool:
    try:
        return bool(a == b)
    except ValueError:  # arrays of different shapes
        return False


def _same(printed: Any, value: Any) -> bool:
    if isinstance(printed, (str, bool)) or isinstance(value, (str, bool, dict)):
        return printed == value
    if np.shape(printed) != np.shape(value):  # e.g. an arm of another joint count
        return False
    return bool(np.allclose(printed, value, rtol=1e-12, atol=0.0))


def deviations(config: Config) -> list[dict[str, Any]]:
    """Every setting that differs from the paper's printed value, and every setting the paper
    leaves open, as rows {parameter, paper, used, reason}."""
    left_out = config.left_out_values()
    used = _flatten(config, left_out)
    paper = paper_config()
    default = _flatten(paper, paper.left_out_values())
    rows = []
    first_of_section: dict[str, str] = {}
    for name, value in used.items():
        section = name.split(".")[0]
        printed = _PAPER_PRINTED.get(name)
        if printed is not None and _same(printed, value):
            continue
        # adparm's value when left out: the same run (a model key equal to the plant's: none)
        resolved = name in left_out and _equal(left_out[name][0], value)
        if resolved and name.startswith("model."):
            continue
        reason = _REASONS.get(name)
        if reason is None and section in _REASONS:
            reason = _REASONS[section]
            if section in first_of_section:
                reason = f"See {first_of_section[section]}."
            first_of_section.setdefault(section, name)
        if name in config.derived:  # left out, derived for this arm (rates.urdf_defaults)
            reason = f"Derived for this arm: {config.derived[name]}."
        elif name == "controller.basis" and config.plant.urdf and value == "structured":
            reason = "A URDF arm's default (its W* is known for a cost of the exact family)."
        elif not resolved and not _equal(value, default.get(name)):
            reason = "Set by this configuration (differs from adparm's default)."
        elif printed is None and reason is None:
            continue
        rows.append(
            {
                "parameter": name,
                "paper": printed if printed is not None else "not printed",
                "used": value,
                "reason": reason or "",
            }
        )
    return rows


def relative_weight_error(weights: np.ndarray, target: np.ndarray) -> np.ndarray:
    """||W(t) - W*|| / ||W*|| for each row of ``weights``."""
    return np.linalg.norm(np.asarray(weights) - target, axis=-1) / np.linalg.norm(target)


def _time_to_stay_within(
    t: np.ndarray, error: np.ndarray, tolerance: float, *, finished: bool = True
) -> float | None:
    """The time from which ``error`` stays within ``tolerance`` up to the end; None unless the
    run finished (a diverged or interrupted run's last row is not where it would have ended) and
    its last row is within."""
    if not finished or not t.size or not error[-1] <= tolerance:
        return None
    outside = np.nonzero(~(error <= tolerance))[0]
    if outside.size == 0:
        return float(t[0]) if t.size else None
    if outside[-1] + 1 >= t.size:
        return None
    return float(t[outside[-1] + 1])


def _value_at(t: np.ndarray, values: np.ndarray, time: float) -> Any:
    if not t.size or time > t[-1] + 1e-9:
        return None
    return values[min(int(np.searchsorted(t, time - 1e-9)), t.size - 1)]


def _number(value: Any) -> Any:
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def accumulated_cost(result: SimulationResult, *, include_probe: bool = True) -> float:
    """The integral of r = x^T Q x + u^T R u (eqs. 10-11) over the run. With the applied input u
    (default; adp: u_hat + probe) it is ``result.cost``, integrated by RK4 with the state. With
    ``include_probe=False`` u is the actor's u_hat alone, integrated by the trapezoidal rule on
    the recorded rows."""
    if include_probe:
        return float(result.cost[-1] - result.cost[0]) if result.t.size else 0.0
    Q = np.array(result.config.cost.Q)
    R = np.array(result.config.cost.R)
    x = np.hstack([result.e1, result.e2])
    u = result.u_hat
    r = np.einsum("ni,ij,nj->n", x, Q, x) + np.einsum("ni,ij,nj->n", u, R, u)
    if result.t.size < 2:
        return 0.0
    return float(np.sum(0.5 * (r[1:] + r[:-1]) * np.diff(result.t)))


def _cost_against_optimum(
    result: SimulationResult, options: Any, post_run_errors: list[str]
) -> dict[str, Any]:
    """applied_cost, optimal_cost and cost_vs_optimal_cost of summarize's ``optimal_cost``."""
    from .against_plant import applied_cost, run_optimal_cost

    if options is True:
        options = {}
    if not isinstance(options, dict):
        raise TypeError(
            f"optimal_cost: expected True or a dict of adparm.optimal_cost options, got {options!r}"
        )
    out: dict[str, Any] = {"applied_cost": None, "optimal_cost": None}
    out["cost_vs_optimal_cost"] = None
    try:
        cost = applied_cost(result)[0]
        out["applied_cost"] = _number(cost)
    except Exception as error:  # noqa: BLE001
        post_run_errors.append(post_run_failure("J (adparm.comparison.applied_cost)", error))
        return out
    best, problem = run_optimal_cost(result.config, **options)
    if problem is not None:
        post_run_errors.append(problem)
    if best is not None:
        out["optimal_cost"] = _number(float(best))
        if best > 0.0 and result.status == "finished" and math.isfinite(cost):
            out["cost_vs_optimal_cost"] = _number(cost / float(best) - 1.0)
    return out


def _against_the_plant(
    result: SimulationResult, diagnostics: dict[str, Any], post_run_errors: list[str]
) -> dict[str, Any]:
    """The run against the plant, whatever the controller believed (a sweep over model errors
    tabulates them): critic_relative_error_plant (||Wc(T) - W*|| / ||W*||, the plant's W*),
    parameter_relative_error (the believed base parameters' largest relative error at the end:
    beta_hat of an identifying run, else the model's) and stack_informative (whether the
    identifier's history stack ever became informative; None without identification)."""
    from .against_plant import believed_parameter_error, plant_critic_error

    identifier = diagnostics.get("identifier")
    out: dict[str, Any] = {
        "critic_relative_error_plant": None,
        "parameter_relative_error": None,
        "stack_informative": None if not identifier else identifier["ever_informative"],
    }
    try:
        out["critic_relative_error_plant"] = _number(plant_critic_error(result))
        out["parameter_relative_error"] = _number(believed_parameter_error(result))
    except Exception as error:  # noqa: BLE001 - any failure after the run is reported
        post_run_errors.append(
            post_run_failure("the run against the plant (critic, parameters)", error)
        )
    return out


def summarize(
    result: SimulationResult, *, tolerance: float | None = None, optimal_cost: Any = None
) -> dict[str, Any]:
    """The metrics of ``summary.json``: final weights beside W*, per-weight and relative errors,
    time to enter and stay within ``tolerance`` of W* (default: the config's
    diagnostics.tolerance, 1 %), the error at the paper's 110 s, final |e1|, accumulated cost,
    covariance resets, wall time and the deviations from the paper.

    ``optimal_cost`` (True, or a dict of options for adparm.optimal_cost such as
    ``{"intervals": 40}``; default None: not computed, it costs an IPOPT solve) adds compare's
    J / J* - 1: "applied_cost" (J of adparm.comparison.applied_cost, the quadratic cost of the
    input the error system received), "optimal_cost" (J*, adparm.comparison.run_optimal_cost,
    with the plant's torque limits) and "cost_vs_optimal_cost" (None unless the run finished
    and J* > 0)."""
    if tolerance is None:
        tolerance = result.config.diagnostics.tolerance
    if not 0.0 < tolerance < 1.0:
        raise ValueError(f"tolerance: expected a number in (0, 1), got {tolerance!r}")
    t = result.t
    # The steps after the run never lose it: a failure is in "post_run_errors", the rest is kept.
    post_run_errors: list[str] = []
    try:
        # an identifying run's critic is judged against the plant's W* (as its diagnosis)
        target = optimal_weights(judged_config(result.config))
    except ValueError as error:
        target, no_target = None, str(error)
    except Exception as error:  # noqa: BLE001 - any failure after the run is reported
        target, no_target = None, post_run_failure("W* (adparm.optimal_weights)", error)
        post_run_errors.append(no_target)
    try:
        deviation_rows = deviations(result.config)
    except Exception as error:  # noqa: BLE001
        deviation_rows = []
        post_run_errors.append(post_run_failure("the deviations from the paper", error))
    out: dict[str, Any] = {
        "status": result.status,
        "t_end": _number(t[-1]) if t.size else None,
        "stopped_at": stop_time(result),
        "T": result.config.sim.T,
        "divergence_bound": result.config.sim.divergence_bound,
        "basis": list(basis_names(result.config)),
        "critic_weights": result.critic_weights[-1].tolist() if t.size else None,
        "actor_weights": result.actor_weights[-1].tolist() if t.size else None,
        "optimal_weights": None if target is None else target.tolist(),
        "final_e1": result.e1[-1].tolist() if t.size else None,
        "final_e1_norm": _number(np.linalg.norm(result.e1[-1])) if t.size else None,
        "position_units": position_units(result.config),
        "accumulated_cost": accumulated_cost(result),
        "accumulated_cost_without_probe": accumulated_cost(result, include_probe=False),
        "covariance_resets": result.covariance_resets,
        "torque_limits": torque_limit_values(result.config),
        "torque_limit_units": effort_units(result.config),
        "saturated_time": result.saturated_time.tolist(),
        "wall_time": _number(result.wall_time),
        "tolerance": tolerance,
        "paper_claim_time": PAPER_CLAIM_TIME if result.config.plant.urdf is None else None,
        "deviations": deviation_rows,
    }
    try:
        diagnostics = (
            result.diagnostics
            if tolerance == result.config.diagnostics.tolerance
            else diagnose(result, tolerance=tolerance)
        )
    except Exception as error:  # noqa: BLE001
        message = post_run_failure("the diagnosis (adparm.truth.diagnose)", error)
        post_run_errors.append(message)
        diagnostics = {"verdict": f"unknown: {message}", "problems": [], "advice": []}
    out["verdict"] = diagnostics["verdict"]
    out["policy_relative_error"] = diagnostics.get("policy_relative_error")
    out["e2_block_min_eigenvalue"] = diagnostics.get("e2_block_min_eigenvalue")
    out["hjb_residual_explored"] = diagnostics.get("hjb_residual_explored")
    out["diagnostics"] = diagnostics
    out["post_run_errors"] = post_run_errors
    out.update(_against_the_plant(result, diagnostics, post_run_errors))
    if optimal_cost is not None and optimal_cost is not False:
        out.update(_cost_against_optimum(result, optimal_cost, post_run_errors))
    if target is None:
        out["optimal_weights_unavailable"] = no_target
        return out
    for name, weights in (("critic", result.critic_weights), ("actor", result.actor_weights)):
        error = relative_weight_error(weights, target)
        out[f"{name}_weight_error"] = (weights[-1] - target).tolist() if t.size else None
        out[f"{name}_relative_error"] = _number(error[-1]) if t.size else None
        claim = out["paper_claim_time"]  # the paper's arm only
        out[f"{name}_relative_error_at_claim"] = claim and _number(_value_at(t, error, claim))
        out[f"{name}_time_within_tolerance"] = _time_to_stay_within(
            t, error, tolerance, finished=result.status == "finished"
        )
    return out


def _fmt(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    return str(value)


def claim_text(summary: dict[str, Any], name: str = "critic", fmt: str = ".6g") -> str:
    """The relative error of ``name`` ("critic" or "actor") at the paper's 110 s, "<error> at
    t = 110 s", or that the run did not reach 110 s (never a value beyond the run's end); ""
    on a URDF arm (paper_claim_time None: the paper claims nothing of it)."""
    claim = summary.get("paper_claim_time", PAPER_CLAIM_TIME)
    value, end = summary.get(f"{name}_relative_error_at_claim"), summary.get("t_end")
    if claim is None:
        return ""
    if value is None or end is None or end < claim - 1e-9:
        ends = f"the run ends at t = {_fmt(end)} s" if end is not None else "nothing recorded"
        return f"t = {claim:g} s (the paper's claim) not reached: {ends}"
    return f"{format(value, fmt)} at t = {claim:g} s"


def _diagnostics_lines(d: dict[str, Any] | None) -> list[str]:
    if not d:
        return []
    lines = ["", f"**Verdict: {d['verdict']}**"]
    if d.get("advice"):
        lines.append(f"(try: {'; '.join(d['advice'])})")
    if "hjb_residual_explored" in d:
        lines += [
            "",
            f"- HJB residual of the final weights, rms(eps) / rms(x^T Q x): "
            f"{_fmt(d['hjb_residual_explored'])} over the explored region, "
            + (
                f"{_fmt(d['hjb_residual_box'])} over the extrapolation box, "
                if d.get("hjb_residual_box") is not None
                else "none over an extrapolation box (extrapolation.points = 0), "
            )
            + f"{_fmt(d['hjb_residual_trajectory'])} along the end of the trajectory"
            + (
                f"; the least any weights reach: {_fmt(d['hjb_residual_best'])}"
                if d.get("hjb_residual_best") is not None
                else ""
            ),
            (
                f"- learned V against {d['value_yardstick']}: relative error "
                f"{_fmt(d['value_error'])}"
                if d.get("value_yardstick")
                else "- learned V: no yardstick for this run (W* unknown, and no LQR value for "
                "its basis or task)"
            ),
            (
                f"- smallest eigenvalue of the e2 block of V (over q): critic "
                f"{_fmt(d['e2_block_min_eigenvalue'])}, actor "
                f"{_fmt(d['actor_e2_block_min_eigenvalue'])}"
                if d.get("e2_block_min_eigenvalue") is not None
                else "- smallest eigenvalue of the e2 block of V: not computed for this basis"
            ),
        ]
    return lines


def stop_line(summary: dict[str, Any]) -> str | None:
    """The first thing to say about a run that did not finish: where it diverged (or was
    interrupted) and its last |e1|, and that the weights reported are not a result. None for a
    finished run."""
    status = summary["status"]
    if status == "finished":
        return None
    stopped = summary.get("stopped_at")
    where = f"t = {_fmt(stopped)} s" if stopped is not None else "an unknown time"
    horizon = summary.get("T")
    of = f" of sim.T = {_fmt(horizon)} s" if horizon is not None else ""
    last = summary["t_end"]
    if last is None:
        return (
            f"**{status} at {where}**{of}: not even the first row was finite, nothing was "
            "recorded"
            + (
                " (the state or an output became non-finite or left sim.divergence_bound)"
                if status == "diverged"
                else ""
            )
        )
    unit = norm_unit(summary.get("position_units", ["rad"]))  # "(rad; m on joint 1)"
    e1 = (
        f"final |e1| = {_fmt(summary['final_e1_norm'])} {unit} at the last finite row "
        f"(t = {_fmt(last)} s)"
    )
    if status == "diverged":
        bound = summary.get("divergence_bound")
        cause = "the state or an output became non-finite or left sim.divergence_bound" + (
            f" = {_fmt(bound)}" if bound is not None else ""
        )
        return (
            f"**diverged at {where}**{of}: {cause}; {e1}. The weights and errors below are those "
            "of that row, before the divergence: not a result"
        )
    return (
        f"**{status} at {where}**{of}: {e1.replace('finite row', 'row')}. The weights and errors "
        "below are those of that row, not of a finished run"
    )


def summary_markdown(summary: dict[str, Any]) -> str:
    """``summary.md``: the W* table, the convergence figures and the deviations. A run that
    diverged or was interrupted says so first (:func:`stop_line`)."""
    lines = ["# adparm run summary", ""]
    stopped = stop_line(summary)
    if stopped is not None:
        lines += [stopped, ""]
    unit = norm_unit(summary.get("position_units", ["rad"]))
    lines += [
        f"- status: {summary['status']}, simulated to t = {_fmt(summary['t_end'])} s, "
        f"wall time {_fmt(summary['wall_time'])} s",
        f"- final |e1| = {_fmt(summary['final_e1_norm'])} {unit} "
        f"(e1 = {_fmt(summary['final_e1'])})",
        f"- accumulated cost of eq. (10): {_fmt(summary['accumulated_cost'])} with u = u_hat + "
        f"probe, {_fmt(summary['accumulated_cost_without_probe'])} with the actor's u_hat alone",
        f"- covariance resets: {summary['covariance_resets']}",
    ]
    parameter_error = summary.get("parameter_relative_error")
    if summary.get("stack_informative") is not None or parameter_error:
        believed = (
            "beta_hat at the end (identified)"
            if summary.get("stack_informative") is not None
            else "the model's (not identified)"
        )
        lines.append(
            f"- against the plant: the believed base parameters, {believed}, are "
            f"{_fmt(parameter_error)} (largest relative error) from the plant's; the critic "
            f"||Wc - W*|| / ||W*|| with the plant's W* = "
            f"{_fmt(summary.get('critic_relative_error_plant'))}"
        )
    limits = summary.get("torque_limits")
    if limits is not None:
        saturated = summary.get("saturated_time") or []
        lines.append(
            f"- torque limits {torque_limits_text(limits, summary.get('torque_limit_units'))}"
            + ": saturated "
            + ", ".join(f"joint {i + 1} {_fmt(v)} s" for i, v in enumerate(saturated))
        )
    for problem in summary.get("post_run_errors") or ():
        lines.append(f"- not computed: {problem} (the run and its files are complete)")
    lines += _diagnostics_lines(summary.get("diagnostics"))
    check = summary.get("step_size_check")
    if check is not None:
        lines.append(
            f"- step size: against a dt/2 run over the first {_fmt(check['transient'])} s, the "
            f"critic weights differ by {_fmt(check.get('critic_max_difference'))} (relative, "
            f"largest), e1 by {_fmt(check.get('e1_max_difference'))}: {check['verdict']}"
        )
    target = summary["optimal_weights"]
    if target is None:
        lines += [
            "",
            "W* is not known for this configuration (it is for a cost of the exact family, "
            f"adparm.solvable_cost): {summary['optimal_weights_unavailable']}",
        ]
    else:
        tol = 100 * summary["tolerance"]
        finished = summary["status"] == "finished"
        end = "at the end" if finished else f"at the last row (t = {_fmt(summary['t_end'])} s)"
        for name in ("critic", "actor"):
            within = summary[f"{name}_time_within_tolerance"]
            if within is not None:
                settled = f"within {tol:g} % from t = {within:.6g} s on"
            elif finished:
                settled = f"not within {tol:g} % at the end"
            else:
                settled = f"no time within {tol:g} %: the run {summary['status']}"
            lines.append(
                f"- {name}: ||W - W*|| / ||W*|| = {_fmt(summary[f'{name}_relative_error'])} {end}, "
                + "".join(f"{text}; " for text in [claim_text(summary, name)] if text)
                + settled
            )
        lines += [
            "",
            "| basis function | W* | critic Wc | Wc - W* | actor Wa | Wa - W* |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        # None for a run without rows (diverged at t = 0)
        columns = [
            summary[key] or [None] * len(target)
            for key in (
                "critic_weights",
                "critic_weight_error",
                "actor_weights",
                "actor_weight_error",
            )
        ]
        for i, name in enumerate(summary["basis"]):
            values = " | ".join(_fmt(column[i]) for column in columns)
            lines.append(f"| {name} | {_fmt(target[i])} | {values} |")
    lines += [
        "",
        "## Settings that differ from the paper's printed values or that it leaves open",
        "",
        "| parameter | paper | used | reason |",
        "|---|---|---|---|",
    ]
    for row in summary["deviations"]:
        lines.append(
            f"| {row['parameter']} | {_fmt(row['paper'])} | {_fmt(row['used'])} | {row['reason']} |"
        )
    return "\n".join(lines) + "\n"


register(
    "summary",
    lambda result, tolerance=None, optimal_cost=None: summarize(
        result, tolerance=tolerance, optimal_cost=optimal_cost
    ),
)
