"""The online identifier of the two-link arm's base parameters ([identifier], issue 25 stage 1):
its regressors against the arm's terms, the measurable (momentum) equation along a simulated
trajectory, and identification with learning from a model 30 % off."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import _core

from numpy_reference import arm_terms as reference_arm_terms
from numpy_reference import pinocchio_configuration, pinocchio_model

NAMES = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")


def random_parameters(rng: np.random.Generator) -> dict:
    while True:
        p = {
            "p1": rng.uniform(2.0, 8.0),
            "p2": rng.uniform(0.5, 2.0),
            "p3": rng.uniform(0.1, 1.0),
            "g1": rng.uniform(5.0, 15.0),
            "g2": rng.uniform(2.0, 10.0),
            "coulomb": rng.uniform(-0.5, 0.5),
            "viscous": rng.uniform(0.0, 1.0),
        }
        if p["p1"] * p["p2"] - p["p2"] ** 2 - p["p3"] ** 2 > 0.0:
            return p


def core_terms(p: dict, q: np.ndarray, dq: np.ndarray) -> dict:
    parameters = _core.ArmParameters()
    for key, value in p.items():
        setattr(parameters, key, value)
    return _core.arm_terms(parameters, q, dq)


@pytest.mark.parametrize("seed", range(20))
def test_regressors_times_beta_are_the_arm_terms(seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = random_parameters(rng)
    beta = np.array([p[name] for name in NAMES])
    q, dq, ddq, dq_r, ddq_r = (rng.uniform(-3.0, 3.0, 2) for _ in range(5))
    Y = _core.two_link_regressors(q, dq, ddq, dq_r, ddq_r)
    for terms in (
        core_terms(p, q, dq),
        dict(zip("MCGF", reference_arm_terms(p, q, dq), strict=True)),
    ):
        M, C, G, F = (np.asarray(terms[key]) for key in "MCGF")
        scale = 1.0 + np.abs(M @ ddq).max() + np.abs(C @ dq).max() + np.abs(G).max()
        # eq. (1): Y beta = M ddq + C dq + G + F
        np.testing.assert_allclose(
            Y["Y"] @ beta, M @ ddq + C @ dq + G + F, rtol=0, atol=1e-12 * scale
        )
        # eq. (5): Y_r beta = h = M ddq_r + C(q, dq) dq_r + G + F(dq)
        h = M @ ddq_r + C @ dq_r + G + F
        np.testing.assert_allclose(Y["Y_r"] @ beta, h, rtol=0, atol=1e-12 * (1.0 + np.abs(h).max()))
        # the momentum equation's regressors: M dq and G + F - C^T dq
        np.testing.assert_allclose(Y["Y_M"] @ beta, M @ dq, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(Y["Y_N"] @ beta, G + F - C.T @ dq, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("seed", range(10))
def test_slotine_li_identity_of_the_issue(seed: int) -> None:
    # C(q, a) b is symmetric bilinear in (a, b) (Christoffel symbols), so
    # C(q, dq) dq_r = [C(q, dq + dq_r)(dq + dq_r) - C(q, dq - dq_r)(dq - dq_r)] / 4, and Y_r is
    # Y(q, 0, ddq_r) + [Y(q, dq + dq_r, 0) - Y(q, dq - dq_r, 0)] / 4 on the inertial parameters
    rng = np.random.default_rng(100 + seed)
    p = random_parameters(rng)
    q, dq, dq_r, ddq_r = (rng.uniform(-3.0, 3.0, 2) for _ in range(4))
    C = np.asarray(core_terms(p, q, dq)["C"])
    s, d = dq + dq_r, dq - dq_r
    polar = (
        np.asarray(core_terms(p, q, s)["C"]) @ s - np.asarray(core_terms(p, q, d)["C"]) @ d
    ) / 4
    np.testing.assert_allclose(C @ dq_r, polar, rtol=0, atol=1e-12 * (1 + np.abs(polar).max()))

    def Y(v, a):
        return _core.two_link_regressors(q, v, a, v, a)["Y"]

    zero = np.zeros(2)
    formula = Y(zero, ddq_r) + (Y(s, zero) - Y(d, zero)) / 4
    Y_r = _core.two_link_regressors(q, dq, zero, dq_r, ddq_r)["Y_r"]
    np.testing.assert_allclose(Y_r[:, :3], formula[:, :3], rtol=0, atol=1e-12 * 100)
    # (the friction columns are F(dq), not the formula's [F(s) - F(d)] / 4)


def base(**changes) -> adparm.Config:
    config = adparm.paper_config().updated(
        {
            "controller": {"basis": "structured"},
            "plant": {"disturbance": [0.0, 0.0]},
            "extrapolation": {"points": 20, "mode": "fixed", "seed": 1},
            "sim": {"T": 20.0, "record_every": 100},
        }
    )
    return config.updated(changes) if changes else config


def model_off(config: adparm.Config, seed: int = 3) -> adparm.Config:
    """The model's p1, p2, p3, g1, g2 scaled by random factors in [0.7, 1.3] (M stays positive
    definite)."""
    rng = np.random.default_rng(seed)
    while True:
        factors = rng.uniform(0.7, 1.3, 5)
        values = {
            key: float(getattr(config.plant, key) * f)
            for key, f in zip(("p1", "p2", "p3", "g1", "g2"), factors, strict=True)
        }
        if values["p1"] * values["p2"] - values["p2"] ** 2 - values["p3"] ** 2 > 0.0:
            return config.updated({"model": values})


def momentum_residual(config: adparm.Config, beta: np.ndarray, window: float = 0.2) -> float:
    """The largest relative residual of int tau dt = Y_w beta over the run's windows, from the
    recorded q, dq and applied tau (every step recorded), integrated by the trapezoid rule."""
    result = adparm.simulate(config, diagnose=False)
    t, q, dq, tau = result.t, result.q, result.dq, result.tau
    regressors = [
        _core.two_link_regressors(q[i], dq[i], dq[i], dq[i], dq[i]) for i in range(t.size)
    ]
    Y_M = np.array([r["Y_M"] for r in regressors])
    Y_N = np.array([r["Y_N"] for r in regressors])
    steps = round(window / config.sim.dt)
    worst = 0.0
    for start in range(0, t.size - steps, steps):
        w = slice(start, start + steps + 1)
        b = np.trapezoid(tau[w], t[w], axis=0)
        Y = Y_M[start + steps] - Y_M[start] + np.trapezoid(Y_N[w], t[w], axis=0)
        worst = max(worst, np.abs(Y @ beta - b).max() / (1.0 + np.abs(b).max()))
    return worst


def test_measurable_equation_holds_along_a_simulated_trajectory() -> None:
    # int tau dt = [M dq] + int (G + F - C^T dq) dt over windows of a run (probing on, no
    # disturbance): to the trapezoid rule's accuracy, which halving dt improves about 4 times
    config = base(sim={"T": 2.0, "record_every": 1, "dt": 1e-3})
    beta = adparm.base_parameters(config, "plant")
    coarse = momentum_residual(config, beta)
    fine = momentum_residual(config.updated({"sim": {"dt": 5e-4}}), beta)
    assert coarse < 1e-3, coarse
    assert fine < coarse / 3.0, (coarse, fine)
    # a wrong beta does not satisfy it
    assert momentum_residual(config, beta * np.array([1.1, 1, 1, 1, 1, 1, 1])) > 1e-2


def critic_error(result: adparm.SimulationResult, W: np.ndarray) -> float:
    return float(np.linalg.norm(result.critic_weights[-1] - W) / np.linalg.norm(W))


def test_identification_reaches_the_plant_from_a_model_30_percent_off() -> None:
    config = model_off(base(identifier={"enabled": True}))
    beta_plant = adparm.base_parameters(config, "plant")
    beta_model = adparm.base_parameters(config, "model")
    assert np.abs(beta_model[:5] / beta_plant[:5] - 1).max() > 0.1
    result = adparm.simulate(config, diagnose=False)
    beta_hat = result.model_parameters
    assert beta_hat.shape == (result.t.size, 7)
    np.testing.assert_array_equal(beta_hat[0], beta_model)
    error = np.abs(beta_hat[-1, :5] / beta_plant[:5] - 1).max()
    assert error < 0.01, (error, beta_hat[-1], beta_plant)
    np.testing.assert_array_equal(beta_hat[:, 5:], np.tile(beta_model[5:], (result.t.size, 1)))
    W_plant = adparm.optimal_weights(adparm.identification.plant_model_config(config))
    assert critic_error(result, W_plant) < 0.01, critic_error(result, W_plant)
    assert result.stack_singular_value.shape == (result.t.size,)
    diagnostics = adparm.diagnose(result)
    assert diagnostics["identifier"]["ever_informative"]
    assert diagnostics["identifier"]["parameter_relative_error"] < 0.01
    assert "became informative" in diagnostics["verdict"]
    # identifier.stop_probe: the probe stopped for good once beta_hat settled (the stack
    # informative; measured 4.9 s), and the critic still reached the plant's W* (above)
    stopped = diagnostics["identifier"]["probe_stopped_time"]
    assert stopped is not None and diagnostics["identifier"]["informative_time"] < stopped < 10.0
    assert np.all(result.probe[result.t >= stopped] == 0.0)
    assert np.any(result.probe[result.t < stopped] != 0.0)
    assert "the probe stopped at" in diagnostics["verdict"]

    # the same run without identification ends at the model's W*, not the plant's
    plain = adparm.simulate(config.updated({"identifier": {"enabled": False}}), diagnose=False)
    assert plain.model_parameters is None and plain.stack_singular_value is None
    W_model = adparm.optimal_weights(config)
    assert critic_error(plain, W_model) < 0.01, critic_error(plain, W_model)
    assert critic_error(plain, W_plant) > 0.05


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_with_the_paper_disturbance_the_estimate_stays_within_five_percent(seed: int) -> None:
    # tau_d(t) (0.1 N m) enters each window's int tau dt unmodelled: a bias, documented as within
    # 5 % after 5 s (measured: 1.5-3 %); the critic still ends within 1 % of the plant's W*
    config = model_off(base(identifier={"enabled": True}, plant={"disturbance": [0.1, 0.1]}), seed)
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    beta = adparm.base_parameters(config, "plant")[:5]
    error = np.abs(result.model_parameters[:, :5] / beta - 1).max(axis=1)
    assert error[result.t >= 5.0].max() < 0.05, error[result.t >= 5.0].max()
    W_plant = adparm.optimal_weights(adparm.identification.plant_model_config(config))
    assert critic_error(result, W_plant) < 0.01


def test_without_excitation_the_stack_never_becomes_informative() -> None:
    # at rest at the set-point, no probe: only gravity is seen, the stack has rank 2 of 5
    config = model_off(
        base(
            identifier={"enabled": True},
            task={"q0": [0.0, 0.0]},
            probe={"until": 0.0},
            extrapolation={"points": 0},
            sim={"T": 5.0, "record_every": 100},
        )
    )
    result = adparm.simulate(config, diagnose=False)
    assert np.all(result.stack_singular_value < config.identifier.singular_value_threshold)
    beta_model = adparm.base_parameters(config, "model")
    assert np.all(np.isfinite(result.model_parameters))
    assert np.abs(result.model_parameters - beta_model).max() < 2.0 * np.abs(beta_model).max()
    diagnostics = adparm.diagnose(result)
    assert not diagnostics["identifier"]["ever_informative"]
    assert "never became informative" in diagnostics["verdict"]


def test_without_extrapolation_points_the_probe_is_not_stopped() -> None:
    # the probe is then the critic's only excitation: identifier.stop_probe leaves it on
    config = model_off(
        base(identifier={"enabled": True}, extrapolation={"points": 0}, sim={"T": 6.0})
    )
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    assert adparm.diagnose(result)["identifier"]["ever_informative"]
    assert np.any(result.probe[result.t >= 5.0] != 0.0)
    assert adparm.identification.identifier_diagnosis(result)["probe_stopped_time"] is None


def test_identification_off_is_the_default_and_changes_nothing() -> None:
    config = adparm.paper_config().updated({"sim": {"T": 0.2}})
    assert config.identifier.enabled is False
    a = adparm.simulate(config, diagnose=False)
    b = adparm.simulate(config.updated({"identifier": {"gain": 5.0}}), diagnose=False)
    for name in ("q", "dq", "tau", "critic_weights", "actor_weights", "cost"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.model_parameters is None


def test_base_parameters_of_the_two_link_arm() -> None:
    config = adparm.paper_config().updated({"model": {"p1": 6.0}})
    assert adparm.base_parameter_names(config) == NAMES
    np.testing.assert_array_equal(
        adparm.base_parameters(config), [5.0, 1.0, 1.0, 9.8 * 1.2, 9.8, -0.1, 0.0]
    )
    assert adparm.base_parameters(config, "model")[0] == 6.0
    with pytest.raises(ValueError, match="which"):
        adparm.base_parameters(config, "believed")


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"identifier": {"gain": 0.0}}, r"^identifier\.gain: must be > 0"),
        ({"identifier": {"window": -1.0}}, r"^identifier\.window: must be > 0"),
        ({"identifier": {"history_size": 0}}, r"^identifier\.history_size: "),
        ({"identifier": {"tolerance": 0.0}}, r"^identifier\.tolerance: must be > 0"),
        (
            {"identifier": {"inertia": False, "gravity": False}},
            r"^identifier\.inertia, identifier\.gravity, identifier\.friction: at least one",
        ),
    ],
)
def test_bad_identifier_settings_are_refused_naming_the_field(changes, message) -> None:
    with pytest.raises(ValueError, match=message):
        adparm.paper_config().updated(changes)


RECORDED = ("q", "dq", "tau", "critic_weights", "actor_weights", "model_parameters")


def assert_same_recordings(a, b, atol: float) -> None:
    for name in RECORDED:
        x, y = getattr(a, name), getattr(b, name)
        scale = max(np.abs(x).max(), 1.0)
        np.testing.assert_allclose(y, x, rtol=0, atol=atol * scale, err_msg=name)
    # sigma_min = sqrt(lambda_min): a singular stack's round-off in lambda_min (1e-16) is 1e-8
    # in sigma_min, so the squares are compared
    x, y = a.stack_singular_value**2, b.stack_singular_value**2
    scale = max(np.abs(x).max(), 1.0)
    np.testing.assert_allclose(y, x, rtol=0, atol=atol * scale, err_msg="stack_singular_value")
    # the predicted error: infinite at the same rows (undetermined), else close
    x, y = a.stack_uncertainty, b.stack_uncertainty
    np.testing.assert_array_equal(np.isinf(y), np.isinf(x), err_msg="stack_uncertainty")
    finite = np.isfinite(x)
    np.testing.assert_allclose(y[finite], x[finite], rtol=1e-6, err_msg="stack_uncertainty")


def test_an_expression_basis_identifies_as_the_built_in_basis() -> None:
    # the augmented basis written as terms runs the dynamic-size loop with an expression basis
    # (DynamicRegressor<TwoLinkRegressor>): the same laws as the fixed-size built-in basis, to
    # the round-off the learning laws amplify (tests/test_dynamic_sizes.py)
    ones = [1.0] * 8  # the built-in basis' default (an expression basis derives its own)
    config = model_off(
        base(
            identifier={"enabled": True},
            controller={"basis": "augmented"},
            init={"critic_weights": ones, "actor_weights": ones},
            actor={"positive_e2": False},  # the projection acts on the named bases only
            sim={"T": 4.0},
        )
    )
    built_in = adparm.simulate(config, diagnose=False)
    terms = adparm.simulate(
        config.updated({"controller": {"basis": ["augmented"]}}), diagnose=False
    )
    assert terms.model_parameters is not None
    beta_model = adparm.base_parameters(config, "model")
    assert np.abs(built_in.model_parameters[-1] - beta_model).max() > 0.1  # it identified
    assert_same_recordings(built_in, terms, atol=1e-8)


def test_the_dynamic_size_loop_identifies_as_the_fixed_size_one() -> None:
    # the fixed sizes prepare the 20 extrapolation points at every evaluation; the dynamic sizes
    # once, and again only after a step that changed beta_hat (held here until about 1.1 s, while
    # the stack is not informative; it changes at every step after): points left from an older
    # beta_hat would part the two runs
    from adparm.translate import core_settings

    config = model_off(base(identifier={"enabled": True}, sim={"T": 4.0, "record_every": 100}))
    recordings = []
    for dynamic in (False, True):
        settings = core_settings(config)
        settings.dynamic_sizes = dynamic
        simulation = _core.Simulation(settings)
        while simulation.status == "running":
            simulation.advance(997)
        recordings.append(simulation.recording())
    fixed, dynamic = recordings
    for name in ("q", "critic_weights", "model_parameters", "stack_singular_value"):
        scale = max(np.abs(fixed[name]).max(), 1.0)
        np.testing.assert_allclose(dynamic[name], fixed[name], rtol=0, atol=1e-9 * scale)
    assert np.abs(fixed["model_parameters"][-1] - fixed["model_parameters"][0]).max() > 0.1
    changed = np.any(fixed["model_parameters"] != fixed["model_parameters"][0], axis=1)
    assert 0.5 < np.ravel(fixed["t"])[np.argmax(changed)] < 2.0 and changed[-5:].all()
    finite = np.isfinite(fixed["stack_uncertainty"])
    np.testing.assert_array_equal(np.isfinite(dynamic["stack_uncertainty"]), finite)
    np.testing.assert_allclose(
        dynamic["stack_uncertainty"][finite], fixed["stack_uncertainty"][finite], rtol=1e-6
    )


def test_base_parameters_of_a_urdf_arm_are_the_structured_basis_ones() -> None:
    # the kinetic energy's base parameters: the tail of the structured basis' W* (s = 1 here)
    config = adparm.load_config(adparm.example_path("planar_3link.toml"))
    groups = adparm.dynamics.base_parameter_groups(config)
    r = groups.count("inertia")
    names = adparm.base_parameter_names(config)[:r]
    beta = adparm.base_parameters(config, "plant")[:r]
    assert len(names) == beta.size > 0
    assert adparm.basis_names(config)[-beta.size :] == tuple(f"e2'M_b e2 ({n})" for n in names)
    assert adparm.optimal.value_scale(config) == 1.0
    np.testing.assert_allclose(adparm.optimal_weights(config)[-beta.size :], beta, rtol=1e-12)


@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_save_and_load_keep_the_identifier_series(tmp_path, suffix) -> None:
    config = model_off(base(identifier={"enabled": True}, sim={"T": 0.2, "record_every": 10}))
    result = adparm.simulate(config, diagnose=False)
    assert result.model_parameters is not None
    path = result.save(tmp_path / ("run" + suffix))
    back = adparm.load_result(path)
    np.testing.assert_array_equal(back.model_parameters, result.model_parameters)
    np.testing.assert_array_equal(back.stack_singular_value, result.stack_singular_value)
    np.testing.assert_array_equal(back.stack_uncertainty, result.stack_uncertainty)
    if suffix == ".csv":
        names = adparm.storage.columns(6, 2, 7)
        assert names[-9:] == [f"beta_hat{p}" for p in range(1, 8)] + [
            "stack_singular_value",
            "stack_uncertainty",
        ]


def test_a_run_without_identification_saves_no_identifier_series(tmp_path) -> None:
    result = adparm.simulate(base(sim={"T": 0.05}), diagnose=False)
    back = adparm.load_result(result.save(tmp_path / "run.csv"))
    assert back.model_parameters is None and back.stack_singular_value is None
    assert back.stack_uncertainty is None


def _identifying_run() -> adparm.SimulationResult:
    config = model_off(base(identifier={"enabled": True}, sim={"T": 1.5, "record_every": 10}))
    return adparm.simulate(config, diagnose=False)


def test_the_model_parameters_figure_draws_the_estimate_over_the_plant() -> None:
    result = _identifying_run()
    config = result.config
    assert "model_parameters" in adparm.plotting.figure_names(result)
    figure = result.plot("model_parameters")
    top, bottom = figure.axes[:2]
    beta = adparm.base_parameters(config, "plant")
    names = adparm.base_parameter_names(config)
    identified = [names.index(name) for name in ("p1", "p2", "p3", "g1", "g2")]
    lines = [line for line in top.get_lines() if not line.get_label().startswith("_")]
    # one line per identified parameter, beta_hat_i / beta_i, then the plant's line at 1
    assert len(lines) == len(identified) + 1
    for line, i in zip(lines, identified, strict=False):
        np.testing.assert_array_equal(line.get_xdata(), result.t)
        np.testing.assert_array_equal(line.get_ydata(), result.model_parameters[:, i] / beta[i])
        assert f"plant {beta[i]:.4g}" in line.get_label()
    np.testing.assert_array_equal(lines[-1].get_ydata(), [1.0, 1.0])
    # the model starts 30 % off and the estimate ends on the plant
    start = np.array([line.get_ydata()[0] for line in lines[:-1]])
    end = np.array([line.get_ydata()[-1] for line in lines[:-1]])
    assert np.abs(start - 1.0).max() > 0.1
    assert np.abs(end - 1.0).max() < 0.01
    assert "coulomb, viscous" in top.get_title(loc="left")  # not identified: named, not drawn
    # the stack's minimum singular value (an empty stack, 0, not drawn), its threshold, and the
    # time it became informative
    sigma, threshold, informative = (
        line for line in bottom.get_lines() if not line.get_label().startswith("_")
    )
    expected = np.where(result.stack_singular_value > 0.0, result.stack_singular_value, np.nan)
    np.testing.assert_array_equal(sigma.get_ydata(), expected)
    assert bottom.get_yscale() == "log"
    assert threshold.get_ydata()[0] == config.identifier.singular_value_threshold
    time = adparm.diagnose(result)["identifier"]["informative_time"]
    assert time is not None and informative.get_xdata()[0] == time
    # the rank condition and the predicted error of the stack's estimate (max_uncertainty)
    agreed = result.stack_uncertainty <= config.identifier.max_uncertainty
    first = result.t[
        np.flatnonzero((result.stack_singular_value >= threshold.get_ydata()[0]) & agreed)[0]
    ]
    assert time == first
    # like the other figures: into given axes (the first panel alone) or a given figure
    from matplotlib.figure import Figure

    target = Figure()
    assert result.plot("model_parameters", ax=target.subplots()) is target
    assert len(target.axes) == 1
    target = Figure()
    assert result.plot("model_parameters", fig=target) is target and len(target.axes) == 2


def test_the_model_parameters_figure_only_for_an_identifying_run(tmp_path) -> None:
    plain = adparm.simulate(base(sim={"T": 0.1, "record_every": 10}), diagnose=False)
    assert "model_parameters" not in adparm.plotting.figure_names(plain)
    with pytest.raises(ValueError, match=r"^identifier\.enabled: .*identifying run"):
        plain.plot("model_parameters")
    written = adparm.write_report(plain, tmp_path / "plain", formats=("png",))
    assert not any(path.name.startswith("model_parameters") for path in written)
    identifying = _identifying_run()
    written = adparm.write_report(identifying, tmp_path / "identifying", formats=("png",))
    assert (tmp_path / "identifying" / "model_parameters.png") in written


def test_adparm_run_writes_the_model_parameters_figure_of_an_identifying_run(tmp_path) -> None:
    from adparm import cli

    config = model_off(base(identifier={"enabled": True}, sim={"T": 0.5, "record_every": 10}))
    for name, run in (("plain", base(sim={"T": 0.1, "record_every": 10})), ("ident", config)):
        path = tmp_path / f"{name}.toml"
        path.write_text(run.to_toml(), encoding="utf-8")
        out = tmp_path / name
        cli.main(["run", str(path), "--out", str(out), "--formats", "png", "--no-progress"])
        assert (out / "fig4_errors.png").is_file()
        assert (out / "model_parameters.png").is_file() == (name == "ident")


# URDF arms (issue 25 stage 2): Pinocchio's joint torque regressor reduced to the base
# parameters (cpp/include/adparm/urdf_regressor.hpp), checked against Pinocchio's Python
# bindings (an independent caller: rnea, crba, computeCoriolisMatrix, computeGeneralizedGravity).


def urdf_arm_paths() -> dict:
    paths = {
        "planar_3link": adparm.example_path("arms/planar_3link.urdf"),
        "spatial_3dof": adparm.example_path("arms/spatial_3dof.urdf"),
    }
    paths["ur5"] = adparm.example_robot_urdf("ur5")
    paths["branched"] = Path(__file__).parent / "branched.urdf"  # a tree: supporting joints only
    return paths


@pytest.mark.parametrize("name", ["planar_3link", "spatial_3dof", "ur5", "branched"])
@pytest.mark.parametrize("seed", range(5))
def test_urdf_regressors_times_beta_are_pinocchio_terms(name: str, seed: int) -> None:
    import pinocchio

    rng = np.random.default_rng(200 + seed)
    path = urdf_arm_paths()[name]
    n = adparm.UrdfArm(path).dof
    coulomb, viscous = rng.uniform(-0.5, 0.5, n), rng.uniform(0.0, 1.0, n)
    arm = adparm.UrdfArm(path, coulomb=coulomb, viscous=viscous)
    beta, names, groups = arm.identifier_parameters()
    assert len(names) == len(groups) == beta.size
    r = len(arm.base_parameters()[0])
    assert groups[:r] == ["inertia"] * r and groups[-2 * n :] == ["friction"] * (2 * n)
    np.testing.assert_array_equal(beta[:r], arm.base_parameters()[0])
    np.testing.assert_array_equal(beta[-2 * n :], np.concatenate([coulomb, viscous]))
    model = pinocchio_model(path)
    data = model.createData()
    q, dq, ddq, dq_r, ddq_r = (rng.uniform(-2.0, 2.0, n) for _ in range(5))
    config = pinocchio_configuration(model, q)
    M = np.triu(pinocchio.crba(model, data, config))
    M = M + np.triu(M, 1).T
    C = pinocchio.computeCoriolisMatrix(model, data, config, dq).copy()
    G = pinocchio.computeGeneralizedGravity(model, data, config).copy()
    F = coulomb * np.sign(dq) + viscous * dq
    Y = arm.identifier_regressors(q, dq, ddq, dq_r, ddq_r)
    tau = pinocchio.rnea(model, data, config, dq, ddq) + F
    scale = 1.0 + np.abs(tau).max() + np.abs(M).max() * (1 + np.abs(dq).max()) ** 2
    # eq. (1): Y beta = M ddq + C dq + G + F (Pinocchio's rnea)
    np.testing.assert_allclose(Y["Y"] @ beta, tau, rtol=0, atol=1e-12 * scale)
    # eq. (5): Y_r beta = h = M ddq_r + C(q, dq) dq_r + G + F(dq)
    h = M @ ddq_r + C @ dq_r + G + F
    np.testing.assert_allclose(Y["Y_r"] @ beta, h, rtol=0, atol=1e-12 * scale)
    # the momentum equation's regressors: M dq and G + F - C^T dq
    np.testing.assert_allclose(Y["Y_M"] @ beta, M @ dq, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(Y["Y_N"] @ beta, G + F - C.T @ dq, rtol=0, atol=1e-12 * scale)
    # the gravity columns see gravity alone: M dq does not depend on them
    gravity = [i for i, g in enumerate(groups) if g == "gravity"]
    np.testing.assert_allclose(Y["Y_M"][:, gravity], 0.0, rtol=0, atol=1e-12 * scale)


def scaled_urdf(path, factors: np.ndarray, out) -> None:
    """The URDF at ``path`` with each link's mass and inertia scaled by the next of ``factors``
    (the centres of mass kept): a model whose base parameters are off by up to the factors."""
    import xml.etree.ElementTree as ET

    tree = ET.parse(str(path))
    links = [link for link in tree.getroot().iter("link") if link.find("inertial") is not None]
    for link, factor in zip(links, factors, strict=False):
        inertial = link.find("inertial")
        mass = inertial.find("mass")
        mass.set("value", repr(float(mass.get("value")) * float(factor)))
        inertia = inertial.find("inertia")
        for key, value in inertia.attrib.items():
            inertia.set(key, repr(float(value) * float(factor)))
    tree.write(str(out))


def test_a_urdf_model_off_gives_beta_with_the_same_structure(tmp_path) -> None:
    path = urdf_arm_paths()["spatial_3dof"]
    scaled_urdf(path, np.array([1.2, 0.8, 1.1, 0.9]), tmp_path / "model.urdf")
    plant, model = adparm.UrdfArm(path), adparm.UrdfArm(tmp_path / "model.urdf")
    beta_plant, names, groups = plant.identifier_parameters()
    beta_model, model_names, model_groups = model.identifier_parameters()
    assert names == model_names and groups == model_groups
    assert np.abs(beta_model / np.where(beta_plant == 0, 1, beta_plant) - 1).max() > 0.05


def urdf_identifying_config(tmp_path, T: float) -> adparm.Config:
    """The planar 3-link arm (examples/planar_3link.toml: the exact cost family, 50 fixed
    extrapolation points) believing a model whose links' masses and inertias are scaled by
    random factors in [0.7, 1.3] (a model URDF written here), identifying it, with a probe of 5 N
    m per joint at random phases."""
    rng = np.random.default_rng(3)
    plant = adparm.example_path("arms/planar_3link.urdf")
    scaled_urdf(plant, rng.uniform(0.7, 1.3, 10), tmp_path / "model.urdf")
    config = adparm.load_config(adparm.example_path("planar_3link.toml"))
    n = config.dof
    return config.updated(
        {
            "model": {"urdf": str(tmp_path / "model.urdf")},
            "identifier": {"enabled": True},
            "probe": {
                "until": 100.0,
                "amplitude": [5.0] * n,
                "phases": rng.uniform(0.0, 2.0 * np.pi, (n, 4)).tolist(),
            },
            "sim": {"T": T, "record_every": 100},
        }
    )


def test_urdf_identification_reaches_the_plant_from_a_model_off(tmp_path) -> None:
    config = urdf_identifying_config(tmp_path, T=8.0)
    beta = adparm.base_parameters(config, "plant")
    beta_model = adparm.base_parameters(config, "model")
    identified = adparm.identification.identified_parameters(config)
    # ||beta_hat - beta|| / ||beta|| over the identified parameters: the small base parameters
    # (first moments off the links' axes, ~1e-3 kg m) end further off in relative terms (notes)

    def error(b: np.ndarray) -> float:
        return float(
            np.linalg.norm(b[identified] - beta[identified]) / np.linalg.norm(beta[identified])
        )

    assert error(beta_model) > 0.05
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    assert result.model_parameters.shape == (result.t.size, beta.size)
    np.testing.assert_allclose(result.model_parameters[0], beta_model, rtol=1e-12)
    assert error(result.model_parameters[-1]) < 0.01, error(result.model_parameters[-1])
    W_plant = adparm.optimal_weights(adparm.identification.plant_model_config(config))
    W_model = adparm.optimal_weights(config)
    assert critic_error(result, W_plant) < 0.01, critic_error(result, W_plant)
    assert np.linalg.norm(W_model - W_plant) / np.linalg.norm(W_plant) > 0.02
    # the policy applied (u_hat, with beta_hat's g) against the plant's u*, as the diagnostics
    # judge it (the actor's weights with the plant's g are not what the controller applies: on
    # the gallery's payload case that policy is 17.7 % off while u_hat is within 3e-7)
    tail = result.t >= 0.9 * result.t[-1]
    x = np.hstack([result.e1, result.e2])[tail]
    u_star = adparm.optimal.policy(
        adparm.identification.plant_model_config(config), x, result.t[tail], W_plant
    )
    u_error = np.sqrt(np.mean((result.u_hat[tail] - u_star) ** 2) / np.mean(u_star**2))
    assert u_error < 0.01, u_error
    assert adparm.diagnose(result)["policy_relative_error"] < 0.01
    # off: the same run ends at the model's W*, not the plant's
    plain = adparm.simulate(config.updated({"identifier": {"enabled": False}}), diagnose=False)
    assert critic_error(plain, W_model) < 0.01, critic_error(plain, W_model)
    assert critic_error(plain, W_plant) > 0.015, critic_error(plain, W_plant)


def test_the_parameter_figure_draws_round_off_zeros_as_zero() -> None:
    """A planar URDF arm's base parameters hold round-off zeros (mc_z of about 1e-17 beside
    2 kg m): the figure lists them as plant value 0 instead of drawing beta_hat / 1e-17."""
    from adparm.identifier_figure import ZERO_PARAMETER, relative_parameters

    config = adparm.load_config(adparm.example_path("planar_3link.toml")).updated(
        {"identifier": {"enabled": True}, "sim": {"T": 0.02}}
    )
    result = adparm.simulate(config, diagnose=False)
    beta = adparm.base_parameters(config, "plant")
    names = adparm.base_parameter_names(config)
    values, drawn, zero = relative_parameters(result)
    assert zero and all(names[i].startswith("mc_z") for i in zero)
    assert all(abs(beta[i]) > ZERO_PARAMETER * np.abs(beta).max() for i in drawn)
    assert np.abs(values).max() < 10.0  # ratios of real parameters, not of round-off


def test_a_urdf_arm_identifies_with_an_expression_basis(tmp_path) -> None:
    # the identifier is the arm's, whatever the basis: the quadratic basis cannot represent the
    # 3-link arm's V* (no W* known, and the verdict says so), but beta_hat still reaches beta
    config = urdf_identifying_config(tmp_path, T=8.0).updated(
        {"controller": {"basis": "quadratic"}}
    )
    beta = adparm.base_parameters(config, "plant")
    identified = adparm.identification.identified_parameters(config)

    def error(b: np.ndarray) -> float:
        return float(
            np.linalg.norm(b[identified] - beta[identified]) / np.linalg.norm(beta[identified])
        )

    assert error(adparm.base_parameters(config, "model")) > 0.05
    with pytest.warns(adparm.ApproximationWarning, match="the basis cannot represent V"):
        result = adparm.simulate(config)
    assert result.status == "finished"
    assert error(result.model_parameters[-1]) < 0.01, error(result.model_parameters[-1])
    diagnostics = result.diagnostics
    assert diagnostics["identifier"]["ever_informative"]
    assert "the optimum is not known" in diagnostics["verdict"]
    # the verdict gives beta_hat's error by norm and its worst parameter's (named)
    identifier = diagnostics["identifier"]
    assert identifier["parameter_norm_error"] == pytest.approx(error(result.model_parameters[-1]))
    names = adparm.base_parameter_names(config)
    largest = np.abs(beta).max()  # a zero parameter (to 1e-9) relative to the largest
    scale = np.where(np.abs(beta) > 1e-9 * largest, np.abs(beta), largest)
    worst = max(identified, key=lambda i: abs(result.model_parameters[-1, i] - beta[i]) / scale[i])
    assert identifier["worst_parameter"] == names[worst]
    assert (
        f"beta_hat ends {identifier['parameter_norm_error']:.3g} (relative, by norm) from the "
        f"plant's beta, its worst parameter ({names[worst]})" in diagnostics["verdict"]
    )


@pytest.mark.parametrize("kind", ["rise", "pd", "optimal"])
def test_controllers_that_do_not_learn_identify_too(kind: str) -> None:
    # the identifier feeds every controller's feedforward; the verdict of a run that does not
    # learn says nothing of the identifier unless its stack never became informative
    config = model_off(
        base(identifier={"enabled": True}, controller={"kind": kind}, sim={"T": 4.0})
    )
    beta, beta_model = (adparm.base_parameters(config, which) for which in ("plant", "model"))
    result = adparm.simulate(config)
    assert np.abs(beta_model[:5] / beta[:5] - 1).max() > 0.1
    assert np.abs(result.model_parameters[-1, :5] / beta[:5] - 1).max() < 0.01
    assert result.diagnostics["verdict"] == "not a learning run"
    still = config.updated({"task": {"q0": [0.0, 0.0]}, "probe": {"until": 0.0}, "sim": {"T": 1.0}})
    verdict = adparm.simulate(still).diagnostics["verdict"]
    assert verdict.startswith("not a learning run; the identifier's history stack never became")


def test_many_parameters_are_drawn_in_the_range_they_reach_once_informative() -> None:
    # a URDF arm's dozens of ratios swing far before the stack is informative (the UR5's reach
    # 20): the panel's y range is then the one from the informative time on, and the note says
    # how far the earlier values reach
    import matplotlib.pyplot as plt

    from adparm import identifier_figure

    result = _identifying_run()
    start = adparm.diagnose(result)["identifier"]["informative_time"]
    assert start is not None and start > result.t[1]
    values = 1.0 + 0.01 * np.sin(np.outer(result.t, np.arange(1, 13)))  # 12 parameters near 1
    figure, axes = plt.subplots()
    assert identifier_figure._focus(axes, result, values) is None  # nothing beyond the range
    values[result.t < start, 3] = 20.0
    note = identifier_figure._focus(axes, result, values)
    assert note is not None and "before, they reach 0.99 to 20" in note
    low, high = axes.get_ylim()
    assert 0.8 < low < 0.9 and 1.1 < high < 1.2
    plt.close(figure)


def test_a_divergence_after_beta_hat_jumped_says_so() -> None:
    # divergence_causes names a jump of beta_hat just before the end (a random 4-joint chain
    # diverged 2 ms after its estimate jumped when the stack became informative: notes), and
    # says nothing of it when the estimate stayed
    import dataclasses

    from adparm.divergence import divergence_causes, estimate_jump

    result = _identifying_run()
    assert estimate_jump(result) is None  # beta_hat moves slowly
    jumped = np.array(result.model_parameters)
    jumped[-1] *= 1.5
    moved = dataclasses.replace(result, model_parameters=jumped)
    text = estimate_jump(moved)
    assert text is not None and text.startswith("the identifier's estimate beta_hat moved by 0.5")
    assert divergence_causes(result.config, moved)[0] == text
    plain = adparm.simulate(
        result.config.updated({"identifier": {"enabled": False}}), diagnose=False
    )
    assert estimate_jump(plain) is None
