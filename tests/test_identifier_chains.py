"""Identification on arms the other identifier tests do not use (issue 25): a light random chain
(bench/every_arm.py's random_chain_urdf), the config an identifying URDF run is judged by when
its settings are derived from the believed model, the probe an identifying URDF run gets by
default (none), and the advice of a verdict whose history stack never became informative."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.identification import _excitation_advice, identified_parameters, plant_model_config

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import every_arm  # noqa: E402
from test_identifier import base, critic_error, model_off, scaled_urdf  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


def chain_config(tmp_path: Path, seed: int | list[int], joints: int, **sections) -> adparm.Config:
    """A random chain of every_arm.random_chain_urdf (rng seed) believing a model whose links'
    masses and inertias are scaled by random factors in [0.7, 1.3] (the same rng), identifying,
    no disturbance; the cost, gains and dt derived from the model."""
    rng = np.random.default_rng(seed)
    name = f"chain{joints}_{np.ravel(seed)[0]}"
    plant = tmp_path / f"{name}.urdf"
    plant.write_text(every_arm.random_chain_urdf(rng, joints))
    model = tmp_path / f"{name}_model.urdf"
    scaled_urdf(plant, rng.uniform(0.7, 1.3, 12), model)
    data = {
        "plant": {"urdf": str(plant), "disturbance": [0.0] * joints},
        "model": {"urdf": str(model)},
        "identifier": {"enabled": True},
        "sim": {"record_every": 50},
    }
    for section, values in sections.items():
        data.setdefault(section, {}).update(values)
    return adparm.Config.from_dict(data)


def light_chain(tmp_path: Path, **sections) -> adparm.Config:
    """The random 4-joint chain (seed 7) whose M(q) has a smallest eigenvalue of 0.0026 beside
    1.5, with a 3 N m probe at random phases, 10 s: the case on which the gradient term made the
    identifying run diverge (docs: Unknown dynamics)."""
    phases = np.random.default_rng(7).uniform(0.0, 6.28, (4, 4)).tolist()
    probe = {"until": 100.0, "amplitude": [3.0] * 4, "phases": phases}
    return chain_config(tmp_path, 7, 4, probe=probe, sim={"T": 10.0}, **sections)


def test_a_light_random_chain_identifies_without_the_gradient_term(tmp_path) -> None:
    config = light_chain(tmp_path)
    assert config.identifier.gradient_term is False  # the default
    beta = adparm.base_parameters(config, "plant")
    identified = identified_parameters(config)
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    error = np.linalg.norm(result.model_parameters[-1, identified] - beta[identified])
    assert error / np.linalg.norm(beta[identified]) < 1e-3
    W_plant = adparm.optimal_weights(plant_model_config(config))
    assert critic_error(result, W_plant) < 0.01, critic_error(result, W_plant)
    # held at the model until the stack is informative (no term drives it before)
    informative = result.stack_singular_value >= config.identifier.singular_value_threshold
    before = result.t < result.t[np.argmax(informative)]
    beta_model = adparm.base_parameters(config, "model")
    assert before.any() and np.all(result.model_parameters[before] == beta_model)
    # with the gradient term (the law) the same run diverges or ends off
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            gradient = adparm.simulate(
                config.updated({"identifier": {"gradient_term": True}}), diagnose=False
            )
        except adparm.SimulationDiverged as diverged:
            assert "beta_hat moved" in str(diverged)
        else:
            assert critic_error(gradient, W_plant) > 0.01


def test_the_judged_config_keeps_the_settings_derived_from_the_model(tmp_path) -> None:
    # a URDF arm's cost, gains and dt are derived from the believed model: the plant's W* an
    # identifying run is judged by is that of the same cost, not of the plant's own defaults
    config = chain_config(tmp_path, 2, 3)
    assert "cost.R" in config.derived and "cost.Q" in config.derived
    judged = plant_model_config(config)
    assert judged.model == adparm.config.ModelConfig()
    for section, key in [("cost", "Q"), ("cost", "R"), ("control", "ks"), ("sim", "dt")]:
        assert getattr(getattr(judged, section), key) == getattr(getattr(config, section), key)
    own = adparm.Config.from_dict({"plant": {"urdf": config.plant.urdf}})
    assert not np.allclose(own.cost.R, config.cost.R)  # the plant's defaults pose another cost
    assert adparm.yardstick.plant_config(config).cost == config.cost


def test_an_identifying_urdf_run_leaves_the_probe_off_by_default(tmp_path) -> None:
    # the derived probe alone can break a large arm's critic (docs: URDF arms, the UR10): the
    # verdict suggests it instead (below)
    config = chain_config(tmp_path, 2, 3)
    assert config.probe.until == 0.0 and "probe.until" in config.derived
    given = config.updated({"probe": {"until": 3.0}})
    assert given.probe.until == 3.0 and "probe.until" not in given.derived


def test_the_advice_for_an_uninformative_stack_works(tmp_path) -> None:
    # the two-link arm at rest at its set-point with the probe off sees gravity only
    rest = model_off(
        base(
            identifier={"enabled": True},
            task={"q0": [0.0, 0.0]},
            probe={"until": 0.0},
            extrapolation={"points": 0},
            sim={"T": 3.0, "record_every": 100},
        )
    )
    verdict = adparm.simulate(rest).diagnostics["verdict"]
    assert "never became informative" in verdict
    assert "switch the probe on (probe.until = 100;" in verdict
    probed = adparm.simulate(rest.updated({"probe": {"until": 100.0}}))
    assert probed.diagnostics["identifier"]["ever_informative"]
    # a 4-joint chain whose derived probe is too weak: ten times larger fills the stack
    weak = chain_config(tmp_path, 2, 4, probe={"until": 100.0}, sim={"T": 4.0})
    verdict = adparm.simulate(weak).diagnostics["verdict"]
    larger = [10.0 * a for a in weak.probe.amplitude]  # per joint (derived)
    text = ", ".join(f"{a:.3g}" for a in larger)
    assert f"a larger probe (e.g. probe.amplitude = [{text}], 10 times)" in verdict
    stronger = adparm.simulate(weak.updated({"probe": {"amplitude": larger}}))
    assert stronger.diagnostics["identifier"]["ever_informative"]
    # a URDF arm with its probe off (the derived default): on at 10 times its derived amplitude
    # at once (the derived amplitude alone left the UR5's, the Panda's and the Kinova's stacks
    # uninformative)
    off = chain_config(tmp_path, 2, 4, sim={"T": 4.0})
    assert off.probe.until == 0.0
    verdict = adparm.simulate(off).diagnostics["verdict"]
    assert (
        f"switch the probe on at 10 times its amplitude (probe.until = 100, probe.amplitude = "
        f"[{text}], sim.T = 30)" in verdict
    )
    on = off.updated({"probe": {"until": 100.0, "amplitude": larger}})
    assert adparm.simulate(on).diagnostics["identifier"]["ever_informative"]
    # a controller that does not learn applies no probe: the advice is a moving trajectory
    pd = adparm.simulate(rest.updated({"controller": {"kind": "pd"}, "sim": {"T": 1.0}}))
    assert "excite the arm with a moving desired trajectory (task.qd" in pd.diagnostics["verdict"]
    sinusoid = {
        "kind": "sinusoid",
        "offset": [0.0, 0.0],
        "amplitude": [[0.5], [0.5]],
        "frequency": [[1.0], [2.0]],
    }
    sinusoid["phase"] = [[0.0], [0.0]]
    moving = adparm.simulate(pd.config.updated({"task": {"qd": sinusoid}, "sim": {"T": 3.0}}))
    assert moving.diagnostics["identifier"]["ever_informative"]


def test_the_stack_uncertainty_is_the_least_squares_formula() -> None:
    # (I3) in NumPy from the recorded q, dq and applied tau: the first windows all enter the
    # stack (it is not full before history_size of them), so after window w the stack is
    # windows 1..w; the paper's disturbance makes the equations disagree (r > 0)
    config = model_off(
        base(
            identifier={"enabled": True},
            plant={"disturbance": [0.1, 0.1]},
            sim={"T": 2.1, "record_every": 1},
        )
    )
    result = adparm.simulate(config, diagnose=False)
    identified = identified_parameters(config)
    held = [i for i in range(7) if i not in identified]
    beta_model = adparm.base_parameters(config, "model")
    zero = np.zeros(2)
    Y_M, Y_N = [], []
    for q, dq in zip(result.q, result.dq, strict=True):
        terms = adparm._core.two_link_regressors(q, dq, zero, zero, zero)
        Y_M.append(terms["Y_M"])
        Y_N.append(terms["Y_N"])
    Y_M, Y_N = np.array(Y_M), np.array(Y_N)
    steps = round(config.identifier.window / config.sim.dt)
    rows, torques, expected = [], [], []
    for w in range(1, 11):
        a, b = (w - 1) * steps, w * steps
        weights = np.full(steps + 1, config.sim.dt)
        weights[[0, -1]] *= 0.5  # the trapezoid rule over the window's steps
        rows.append(Y_M[b] - Y_M[a] + np.einsum("k,kij->ij", weights, Y_N[a : b + 1]))
        torques.append(weights @ result.tau[a : b + 1])
        Y, tau = np.vstack(rows), np.concatenate(torques)
        m, P = Y.shape[0], len(identified)
        if m < 2 * P:
            expected.append(np.inf)
            continue
        misfit_target = tau - Y[:, held] @ beta_model[held]
        solution, *_ = np.linalg.lstsq(Y[:, identified], misfit_target, rcond=None)
        r = np.sum((Y[:, identified] @ solution - misfit_target) ** 2)
        S = Y[:, identified].T @ Y[:, identified]
        expected.append(
            np.sqrt(r / (m - P) * np.trace(np.linalg.inv(S))) / np.linalg.norm(solution)
        )
    # each window's value is recorded from the row after it closed, until the next one closes
    recorded = [result.stack_uncertainty[w * steps + 1] for w in range(1, 11)]
    assert np.isinf(recorded[:4]).all() and np.isinf(expected[:4]).all()  # m < 2 P = 10
    np.testing.assert_allclose(recorded[4:], expected[4:], rtol=1e-6)
    assert 0.0 < min(recorded[4:]) < config.identifier.max_uncertainty, recorded


def test_a_stack_whose_equations_disagree_is_not_used(tmp_path) -> None:
    # a light random 3-joint chain with the paper's disturbance and a weak probe (0.759 N m on
    # every joint, the amplitude derived before it was per joint):
    # the stack reaches full rank at 4.6 s, but the disturbance biases it (its estimate would be
    # 2.1 times off by norm, and beta_hat jumped there before max_uncertainty): beta_hat stays
    # at the model and the verdict says why
    config = chain_config(
        tmp_path,
        [1, 99],
        3,
        plant={"disturbance": [0.1] * 3},
        probe={"until": 100.0, "amplitude": 0.759},
        sim={"T": 6.0},
    )
    result = adparm.simulate(config)
    threshold = config.identifier.singular_value_threshold
    assert (result.stack_singular_value >= threshold).any()
    ranked = result.stack_singular_value >= threshold
    assert (result.stack_uncertainty[ranked] > config.identifier.max_uncertainty).all()
    assert np.all(result.model_parameters == adparm.base_parameters(config, "model"))
    verdict = result.diagnostics["verdict"]
    assert "never became informative: its equations disagree" in verdict
    assert "above identifier.max_uncertainty = 0.05" in verdict


def test_a_model_of_other_kinematics_is_refused_when_identifying(tmp_path) -> None:
    # the identifier estimates masses and inertias on the model's kinematics: two random 3-joint
    # chains (other axes and link frames) ended at a non-stabilising solution with a stack that
    # "never became informative"; now refused before the run, naming model.urdf. The same model
    # without identification runs (judged against its own W*), and a model of the plant's
    # kinematics with other inertia identifies as before
    paths = []
    for seed in (1, 2):
        paths.append(tmp_path / f"chain3_{seed}.urdf")
        paths[-1].write_text(every_arm.random_chain_urdf(np.random.default_rng(seed), 3))
    data = {"plant": {"urdf": str(paths[0])}, "model": {"urdf": str(paths[1])}}
    with pytest.raises(ValueError, match=r"^model\.urdf: its kinematics .* differ from the plant"):
        adparm.Config.from_dict({**data, "identifier": {"enabled": True}})
    assert adparm.Config.from_dict(data).model.urdf == str(paths[1])
    scaled = adparm.urdf_with_scaled_inertia(paths[0], 1.2, path=tmp_path / "scaled.urdf")
    same = {"plant": {"urdf": str(paths[0])}, "model": {"urdf": str(scaled)}}
    assert adparm.Config.from_dict({**same, "identifier": {"enabled": True}}).identifier.enabled


def test_the_advice_names_a_matrix_probe_amplitude_plainly(tmp_path) -> None:
    # a joints x k amplitude is not spelled out: "probe.amplitude 10 times larger", probe on or off
    off = chain_config(tmp_path, 2, 4, probe={"amplitude": [[0.1, 0.2, 0.3, 0.4]] * 4})
    assert off.probe.until == 0.0
    advice = _excitation_advice(off)
    assert "(probe.until = 100, probe.amplitude 10 times larger, sim.T = 30)" in advice
    on = off.updated({"probe": {"until": 100.0}})
    assert _excitation_advice(on) == (
        "excite the arm more: a larger probe (probe.amplitude 10 times larger)"
    )


def test_a_critic_at_its_estimate_s_optimum_is_told_the_estimate_is_what_is_left(
    tmp_path, monkeypatch
) -> None:
    # W*(beta_hat): the structured basis' W* is [K terms; s beta] with Q22 = s^2 R^-1, so the
    # optimum of the estimate is the plant's W* with s beta_hat's kinetic-energy parameters
    from types import SimpleNamespace

    from adparm.identification import ESTIMATE_ADVICE, estimate_advice, estimate_critic_error
    from adparm.truth import _estimate_optimum_learned

    config = chain_config(tmp_path, 2, 3, sim={"T": 0.2})
    result = adparm.simulate(config, diagnose=False)
    plant = plant_model_config(config)
    W = adparm.optimal_weights(plant)
    beta = adparm.base_parameters(config, "plant")
    kinetic = W.size - 6  # after the 6 e1 products of a 3-joint arm
    Q22, R = np.array(config.cost.Q)[3:, 3:], np.array(config.cost.R)
    s = np.sqrt(Q22[0, 0] * R[0, 0])  # Q22 = s^2 R^-1 (R diagonal here)
    np.testing.assert_allclose(W[-kinetic:], s * beta[:kinetic], rtol=1e-9, atol=1e-12)
    beta_hat = np.asarray(result.model_parameters[-1])
    own = W.copy()
    own[-kinetic:] = s * beta_hat[:kinetic]
    gap = np.linalg.norm(own - W) / np.linalg.norm(W)
    assert gap > 0.01  # the model is 0.7-1.3 off and barely identified after 0.2 s

    def at(weights: np.ndarray) -> SimpleNamespace:
        rows = np.tile(weights, (result.t.size, 1))
        return SimpleNamespace(
            config=config,
            t=result.t,
            model_parameters=result.model_parameters,
            critic_weights=rows,
        )

    assert estimate_critic_error(at(own)) < 1e-12
    assert estimate_critic_error(at(W)) == pytest.approx(gap, rel=1e-9)
    # the verdict's part: only a critic ten times closer to its estimate's optimum than to W*
    text = _estimate_optimum_learned(at(own), {"critic_relative_error": gap})
    assert text is not None and text.startswith("||Wc - W*(beta_hat)|| / ||W*|| = ")
    assert _estimate_optimum_learned(at(W), {"critic_relative_error": 0.0}) is None
    # its advice: the estimate's error is what is left, or with a stack never informative (0.2 s
    # of a derived probe that is off) what excites the arm
    assert "a longer run will not help" in ESTIMATE_ADVICE
    assert not result.diagnostics["identifier"]["ever_informative"]
    assert estimate_advice(result).startswith("the model is not identified: switch the probe on")
    # an informative stack: the estimate is what is left, and a probe still on may still move it
    informative = {"ever_informative": True}
    monkeypatch.setattr(adparm.identification, "identifier_diagnosis", lambda _: informative)
    quiet = SimpleNamespace(config=config, probe=np.zeros((2, 3)))
    assert estimate_advice(quiet) == ESTIMATE_ADVICE
    probing = SimpleNamespace(config=config, probe=np.ones((2, 3)))
    assert "as far as the probe, still on, improves beta_hat" in estimate_advice(probing)
    # not identifying: nothing to say
    assert (
        estimate_critic_error(
            SimpleNamespace(
                **{**vars(at(own)), "config": config.updated({"identifier": {"enabled": False}})}
            )
        )
        is None
    )
