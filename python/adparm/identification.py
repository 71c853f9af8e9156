"""What an identifying run ([identifier], issue 25) did: the plant's base parameters against the
final estimate, whether the history stack became informative, and the config an identifying run's
learning is judged by (the plant's: its critic should reach the plant's W*). adparm.truth's
diagnose reports it."""

from __future__ import annotations

from typing import Any

import numpy as np

from .basis_family import UrdfStructuredBasis, basis_for
from .config import Config
from .dynamics import base_parameter_groups, base_parameter_names
from .optimal import base_parameters, optimal_weights
from .result import SimulationResult

__all__ = [
    "ESTIMATE_ADVICE",
    "estimate_advice",
    "estimate_critic_error",
    "identified_parameters",
    "identifier_diagnosis",
    "judged_config",
    "model_gap_text",
    "plant_critic_error",
    "plant_model_config",
]


def plant_model_config(config: Config) -> Config:
    """``config`` with the controller believing the plant (``[model]`` emptied): the config whose
    W* an identifying run's critic should reach."""
    return config.believing_the_plant()


def judged_config(config: Config) -> Config:
    """The config a run's learning is judged by: its own, or for an identifying run
    (``identifier.enabled``) the plant's (plant_model_config): its critic should reach the plant's
    W*, the optimum the identified model leads to."""
    return plant_model_config(config) if config.identifier.enabled else config


def identified_parameters(config: Config) -> list[int]:
    """The indices (in the order of base_parameter_names) of the parameters the identifier
    estimates: identifier.inertia, .gravity and .friction say which groups; the others stay at
    the model's values."""
    return [
        i
        for i, group in enumerate(base_parameter_groups(config))
        if getattr(config.identifier, group)
    ]


def _scale(beta: np.ndarray, i: int) -> float:
    """What beta_i's error is relative to: |beta_i|, or for a parameter that is zero (to 1e-9 of
    the largest: a URDF arm's base parameter can vanish on the plant, e.g. a planar arm's) the
    largest |beta_j|, or 1."""
    largest = float(np.max(np.abs(beta))) if beta.size else 0.0
    if abs(beta[i]) > 1e-9 * largest:
        return float(abs(beta[i]))
    return largest if largest > 0.0 else 1.0


def identifier_diagnosis(result: SimulationResult) -> dict[str, Any] | None:
    """The online identifier's truth (None without ``identifier.enabled``): the plant's beta
    (known in simulation) against the final estimate, and whether the history stack ever became
    informative (its minimum singular value at or above identifier.singular_value_threshold):

    - beta_plant, beta_hat: lists in the order of base_parameter_names;
    - parameter_relative_error: max over the identified parameters of |beta_hat - beta| / |beta|
      (a parameter with beta = 0, to 1e-9 of the largest: relative to the largest |beta|), and
      worst_parameter, its name;
    - parameter_norm_error: ||beta_hat - beta|| / ||beta|| over the identified parameters (a
      small parameter's relative error can be large while this is small: URDF arms);
    - ever_informative, informative_time (s, the first recorded row at the threshold and within
      identifier.max_uncertainty, or None), max_singular_value (the largest minimum singular
      value recorded), min_uncertainty (the smallest predicted error of the stack's estimate
      while at the threshold, inf if never);
    - probe_stopped_time: the first recorded row from which identifier.stop_probe switched the
      probe off (s), or None (not stopped, or no probe);
    - text: what the verdict says."""
    config = result.config
    if not config.identifier.enabled or result.model_parameters is None or result.t.size == 0:
        return None
    beta = base_parameters(config, "plant")
    beta_hat = np.asarray(result.model_parameters[-1], dtype=float)
    identified = identified_parameters(config)
    errors = [abs(beta_hat[i] - beta[i]) / _scale(beta, i) for i in identified]
    error = float(max(errors)) if errors else 0.0
    worst = base_parameter_names(config)[identified[int(np.argmax(errors))]] if errors else None
    difference, size = beta_hat[identified] - beta[identified], beta[identified]
    norm_error = float(np.linalg.norm(difference) / max(float(np.linalg.norm(size)), 1e-300))
    sigma = np.asarray(result.stack_singular_value, dtype=float)
    threshold = config.identifier.singular_value_threshold
    limit = config.identifier.max_uncertainty
    uncertainty = (
        np.full(sigma.shape, 0.0)  # a result saved before the uncertainty was recorded
        if result.stack_uncertainty is None
        else np.asarray(result.stack_uncertainty, dtype=float)
    )
    ranked = (sigma >= threshold) & (sigma > 0.0)
    informative = np.flatnonzero(ranked & (uncertainty <= limit))
    ever = bool(informative.size > 0)
    largest = float(np.max(sigma)) if sigma.size else 0.0
    least = float(np.min(uncertainty[ranked])) if ranked.any() else float("inf")
    stopped = _probe_stopped_time(result)
    if ever:
        text = (
            f"the identifier's history stack became informative at t = "
            f"{result.t[informative[0]]:.3g} s; beta_hat ends {norm_error:.3g} (relative, by "
            f"norm) from the plant's beta, its worst parameter ({worst}) {error:.3g}"
        )
        if stopped is not None:
            text += f"; the probe stopped at t = {stopped:.3g} s (identifier.stop_probe)"
    elif ranked.any():
        text = (
            "the identifier's history stack never became informative: its equations disagree "
            f"(the predicted error of its estimate was at best {least:.3g}, above "
            f"identifier.max_uncertainty = {limit:g}; an unmodelled torque such as the "
            "disturbance or friction not identified biases them), so the model is not "
            f"identified (beta_hat ends {error:.3g} from the plant's beta); "
            + _excitation_advice(config)
        )
    else:
        text = (
            "the identifier's history stack never became informative (its minimum singular value "
            f"peaked at {largest:.3g}, below identifier.singular_value_threshold = {threshold:g}): "
            f"the model is not identified (beta_hat ends {error:.3g} from the plant's beta); "
            + _excitation_advice(config)
        )
    return {
        "beta_plant": [float(v) for v in beta],
        "beta_hat": [float(v) for v in beta_hat],
        "parameter_relative_error": error,
        "worst_parameter": worst,
        "parameter_norm_error": norm_error,
        "ever_informative": ever,
        "informative_time": float(result.t[informative[0]]) if ever else None,
        "max_singular_value": largest,
        "min_uncertainty": least,
        "probe_stopped_time": stopped,
        "text": text,
    }


def _excitation_advice(config: Config) -> str:
    """What excites the arm more, for a run whose stack never became informative: the probe
    (on, or 10 times larger) for a learning controller, a moving desired trajectory for the
    others (the probe acts only while the controller learns). A URDF arm's derived probe (sized
    to move e2 by about 0.1 rad/s) left the stack uninformative on the UR5, the Panda and the
    Kinova with a model 20 % light (minimum singular value 4e-4 to 2e-3 of the 0.01 needed), so
    its probe is switched on at 10 times that, for 30 s: the UR5 is then informative at 3.0 s and
    ends "ok" (critic 0.12 % from the plant's W*), the Panda stops its probe at 12 s and ends
    within 0.12 % (docs: unknown dynamics)."""
    if config.controller.kind != "adp":  # only adp learns and probes
        return (
            f"a {config.controller.kind!r} controller applies no probe: excite the arm with a "
            "moving desired trajectory (task.qd, e.g. a sinusoid)"
        )
    if config.probe.until <= 0.0 and config.plant.urdf is None:
        return (
            "switch the probe on (probe.until = 100; identifier.stop_probe ends it once "
            "beta_hat settles)"
        )
    amplitude = np.asarray(config.probe.amplitude, dtype=float)
    if amplitude.ndim == 0:
        larger = f"probe.amplitude = {10.0 * float(amplitude):.3g}"
    elif amplitude.ndim == 1:
        larger = "probe.amplitude = [" + ", ".join(f"{10.0 * a:.3g}" for a in amplitude) + "]"
    else:
        larger = "probe.amplitude 10 times larger"
    if config.probe.until <= 0.0:
        longer = ", sim.T = 30" if config.sim.T < 30.0 else ""
        return (
            f"switch the probe on at 10 times its amplitude (probe.until = 100, "
            f"{larger}{longer}): identifier.stop_probe ends it once beta_hat "
            "settles, and the critic settles after it"
        )
    if amplitude.ndim > 1:
        return f"excite the arm more: a larger probe ({larger})"
    return f"excite the arm more: a larger probe (e.g. {larger}, 10 times)"


def _probe_stopped_time(result: SimulationResult) -> float | None:
    """The first recorded row from which the applied probe is zero for good, before probe.until
    (identifier.stop_probe, which acts only with extrapolation points); None otherwise."""
    config = result.config
    if not config.identifier.stop_probe or config.extrapolation.points == 0:
        return None
    probing = np.flatnonzero(np.any(np.asarray(result.probe) != 0.0, axis=1))
    if probing.size == 0 or probing[-1] + 1 >= result.t.size:
        return None
    stopped = float(result.t[probing[-1] + 1])
    return stopped if stopped < config.probe.until else None


def plant_critic_error(result: SimulationResult) -> float | None:
    """||Wc(T) - W*|| / ||W*|| with W* the *plant's* (the critic of the controller believing the
    plant: the true optimum's weights), at the last recorded row; None for a run that does not
    learn (kind other than adp), without rows, or where W* is not known (adparm.optimal_weights
    refuses the cost or the basis). A run without identification and with a wrong model ends
    at the model's W*, its distance from the plant's is this error; an identifying run's critic
    should reach the plant's."""
    if result.config.controller.kind != "adp" or result.t.size == 0:
        return None
    try:
        target = optimal_weights(plant_model_config(result.config))
    except ValueError:  # W* unknown for this cost, basis or task
        return None
    norm = float(np.linalg.norm(target))
    if norm == 0.0:  # pragma: no cover - W* holds K > 0
        return None
    return float(np.linalg.norm(result.critic_weights[-1] - target) / norm)


def estimate_critic_error(
    result: SimulationResult, plant_weights: np.ndarray | None = None
) -> float | None:
    """||Wc(T) - W*(beta_hat(T))|| / ||W*||: how far an identifying run's critic ends from the
    optimum of its own final estimate, for a URDF arm's structured basis, whose W* is [K terms;
    s beta] (adparm.optimal_weights): the plant's W* with s beta_hat's kinetic-energy parameters
    as its tail. Small where the critic learned what its estimate leads to and beta_hat's error is
    what is left. None otherwise (not identifying, another basis, W* not known).
    ``plant_weights``: the plant's W*, where the caller has it (adparm.truth)."""
    config = result.config
    if not config.identifier.enabled or result.model_parameters is None or result.t.size == 0:
        return None
    if not isinstance(basis_for(config), UrdfStructuredBasis):
        return None
    W = plant_weights
    if W is None:
        try:
            W = optimal_weights(plant_model_config(config))
        except ValueError:  # W* unknown for this cost or task
            return None
    beta = base_parameters(config, "plant")
    tail = W.size - config.dof * (config.dof + 1) // 2  # the kinetic-energy parameters
    s = float(W[-tail:] @ beta[:tail] / (beta[:tail] @ beta[:tail]))
    target = W.copy()
    target[-tail:] = s * np.asarray(result.model_parameters[-1], dtype=float)[:tail]
    return float(np.linalg.norm(result.critic_weights[-1] - target) / np.linalg.norm(W))


#: The advice to an identifying run whose critic learned the optimum of its estimate from an
#: informative stack, while the estimate's error leaves the plant's HJB residual large.
ESTIMATE_ADVICE = (
    "a longer run will not help: the critic follows beta_hat, whose error is what is left (an "
    "unmodelled torque, plant.disturbance or friction not identified, biases the parameters that "
    "move the arm least)"
)


def estimate_advice(result: SimulationResult) -> str:
    """What to do when the critic learned the optimum of its estimate (estimate_critic_error):
    ESTIMATE_ADVICE after an informative stack, else what excites the arm (the estimate stayed at
    the model)."""
    diagnosis = identifier_diagnosis(result)
    if diagnosis is not None and not diagnosis["ever_informative"]:
        return "the model is not identified: " + _excitation_advice(result.config)
    if np.any(np.asarray(result.probe)[-1] != 0.0):  # still probing: beta_hat may still move
        return (
            "the critic follows beta_hat, whose error is what is left: a longer run helps as far "
            "as the probe, still on, improves beta_hat"
        )
    return ESTIMATE_ADVICE


def model_gap_text(result: SimulationResult, verdict: str) -> str | None:
    """For a learning run that does not identify and believes a model other than the plant
    (``[model]``): its critic is judged against the believed model's W*, the optimum it can
    reach; say how far that lies from the plant's W* (:func:`plant_critic_error`). None
    otherwise, or where the plant's W* is not known."""
    config = result.config
    if (
        config.identifier.enabled
        or verdict in ("not a learning run", "no rows")
        or not config.model.differs(config.plant)
    ):
        return None
    gap = plant_critic_error(result)
    if gap is None:
        return None
    return (
        "the model differs from the plant: the critic is judged against the believed model's "
        f"W*, and ends {gap:.3g} (relative) from the plant's W*"
    )
