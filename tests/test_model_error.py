"""A model that differs from the plant (issue 25): model.scale, the summary's and a sweep's columns
against the plant (the critic against the plant's W*, the believed parameters against the
plant's, whether the identifier's stack became informative) and ``adparm sweep`` over them."""

from __future__ import annotations

import csv
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import adparm
from adparm.cli import main
from adparm.config import tomllib
from adparm.summary import summary_markdown
from adparm.sweep import SWEEP_METRICS, SWEEP_MODEL_METRICS
from adparm.translate import core_settings

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

#: The plant's W* of the structured basis by hand: [K11, 2 K12, K22, p1, p2, p3] (s = 1).
PLANT_W_STAR = np.array([4.0, -8.0, 6.0, 5.0, 1.0, 1.0])
PLANT = {"p1": 5.0, "p2": 1.0, "p3": 1.0, "g1": 11.76, "g2": 9.8}


def base(T: float = 20.0) -> adparm.Config:
    return adparm.paper_config().updated(
        {
            "controller": {"basis": "structured"},
            "plant": {"disturbance": [0.0, 0.0]},
            "extrapolation": {"points": 20, "mode": "fixed", "seed": 1},
            "sim": {"T": T, "record_every": 100},
        }
    )


def test_model_scale_scales_the_believed_two_link_model() -> None:
    config = adparm.paper_config().updated({"model": {"scale": 0.7}})
    expected = [0.7 * PLANT[key] for key in PLANT] + [-0.1, 0.0]  # friction left alone
    np.testing.assert_allclose(adparm.base_parameters(config, "model"), expected, rtol=1e-15)
    np.testing.assert_array_equal(
        adparm.base_parameters(config, "plant"), [*PLANT.values(), -0.1, 0.0]
    )
    # the believed model's W* is the scaled one: [K; s p] with p times 0.7
    structured = config.updated({"controller": {"basis": "structured"}})
    np.testing.assert_allclose(
        adparm.optimal_weights(structured), [4.0, -8.0, 6.0, 3.5, 0.7, 0.7], rtol=1e-14
    )
    # a given key is scaled too; the core believes the same (its M of the model)
    given = adparm.paper_config().updated({"model": {"p1": 4.0, "scale": 1.5}})
    assert adparm.base_parameters(given, "model")[0] == 6.0
    settings = core_settings(given)
    believed = [getattr(settings.model, key) for key in PLANT]
    assert believed == [6.0, 1.5, 1.5, 1.5 * 11.76, 1.5 * 9.8]
    assert settings.model.coulomb == -0.1  # friction left alone
    identifying = adparm.simulate(
        given.updated({"identifier": {"enabled": True}, "sim": {"T": 0.01}}), diagnose=False
    )
    np.testing.assert_array_equal(identifying.model_parameters[0, :5], believed)
    assert adparm.paper_config().model.scale is None  # left out: 1
    assert "scale" not in adparm.paper_config().to_toml()  # the paper's [model] stays empty
    text = config.to_toml()
    assert "scale = 0.7" in text and adparm.Config.from_dict(tomllib.loads(text)) == config


@pytest.mark.parametrize(
    ("value", "error", "message"),
    [
        (0.05, ValueError, "model.scale: must be >= 0.1, got 0.05"),
        (11.0, ValueError, "model.scale: must be <= 10, got 11"),
        (float("nan"), ValueError, "model.scale: must be finite"),
        ("0.7", TypeError, "model.scale: expected a number"),
        (True, TypeError, "model.scale: expected a number"),
        (0.0, ValueError, "model.scale: must be >= 0.1"),
    ],
)
def test_bad_model_scales_are_refused_naming_the_field(value, error, message) -> None:
    with pytest.raises(error, match=message):
        adparm.paper_config().updated({"model": {"scale": value}})


def _urdf_scaled(tmp_path, scale: float) -> tuple[adparm.Config, adparm.Config]:
    """A URDF arm with model.scale, and the same with model.urdf = the URDF written with every
    link's mass and inertia times scale (adparm.urdf_with_scaled_inertia, tested against
    Pinocchio's crba and gravity)."""
    plant = {"urdf": adparm.example_path("arms/planar_3link.urdf")}
    written = adparm.urdf_with_scaled_inertia(plant["urdf"], scale, path=tmp_path / "model.urdf")
    T = {"sim": {"T": 0.3}}
    return (
        adparm.Config.from_dict({"plant": plant, "model": {"scale": scale}, **T}),
        adparm.Config.from_dict({"plant": plant, "model": {"urdf": str(written)}, **T}),
    )


@pytest.mark.parametrize("scale", [0.7, 1.3])
def test_model_scale_on_a_urdf_arm_is_the_urdf_with_scaled_inertia(tmp_path, scale) -> None:
    # before: refused ("the two-link arm only"; write the model with urdf_with_scaled_inertia)
    by_key, by_file = _urdf_scaled(tmp_path, scale)
    rng = np.random.default_rng(5)
    for _ in range(3):
        q, dq = rng.uniform(-2, 2, 3), rng.uniform(-1, 1, 3)
        believed = adparm.arm_terms(by_key, q, dq, model=True)
        plant = adparm.arm_terms(by_key, q, dq)
        for term in ("M", "C", "G"):
            np.testing.assert_allclose(believed[term], scale * plant[term], rtol=1e-12, atol=1e-12)
    # the settings derived from the believed inertia, W* and the run itself: those of the file
    assert by_key.derived.keys() == by_file.derived.keys()
    for key in by_key.derived:
        section, name = key.split(".")
        np.testing.assert_allclose(
            np.asarray(getattr(getattr(by_key, section), name), dtype=float),
            np.asarray(getattr(getattr(by_file, section), name), dtype=float),
            rtol=1e-12,
            err_msg=key,
        )
    np.testing.assert_allclose(
        adparm.optimal_weights(by_key), adparm.optimal_weights(by_file), rtol=1e-12
    )
    first = adparm.simulate(by_key, diagnose=False)
    second = adparm.simulate(by_file, diagnose=False)
    np.testing.assert_allclose(first.critic_weights, second.critic_weights, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(first.q, second.q, rtol=1e-9, atol=1e-12)
    assert by_key.model.differs(by_key.plant)
    assert not by_key.updated({"model": {"scale": 1.0}}).model.differs(by_key.plant)


@pytest.mark.parametrize("scale", [0.0, -1.0, float("nan"), float("inf")])
def test_the_cores_inertia_scale_is_checked_naming_it(scale) -> None:
    arm = adparm.UrdfArm(adparm.example_path("arms/planar_3link.urdf"))
    with pytest.raises(ValueError, match="^inertia_scale: must be finite and > 0"):
        arm.with_inertia_scaled(scale)


def test_an_identifying_runs_summary_judges_the_critic_against_the_plant() -> None:
    config = base().updated({"model": {"scale": 0.7}, "identifier": {"enabled": True}})
    result = adparm.simulate(config, diagnose=False)
    summary = result.summary()
    np.testing.assert_allclose(summary["optimal_weights"], PLANT_W_STAR, rtol=1e-14)
    error = np.linalg.norm(result.critic_weights[-1] - PLANT_W_STAR) / np.linalg.norm(PLANT_W_STAR)
    assert summary["critic_relative_error"] == pytest.approx(error, rel=1e-12)
    assert summary["critic_relative_error_plant"] == pytest.approx(error, rel=1e-12)
    assert error < 0.01
    assert summary["stack_informative"] is True
    beta = np.array(list(PLANT.values()))
    assert summary["parameter_relative_error"] == pytest.approx(
        np.abs(result.model_parameters[-1, :5] / beta - 1.0).max(), rel=1e-12
    )
    assert summary["parameter_relative_error"] < 0.01
    assert summary["diagnostics"]["critic_relative_error"] == pytest.approx(error, rel=1e-12)
    assert "- against the plant: the believed base parameters, beta_hat at the end" in (
        summary_markdown(summary)
    )


def expected_gap(scale: float) -> float:
    """||W*_model - W*_plant|| / ||W*_plant|| of the structured basis: the p block times scale."""
    return abs(scale - 1.0) * np.linalg.norm([5.0, 1.0, 1.0]) / np.linalg.norm(PLANT_W_STAR)


@pytest.fixture(scope="module")
def model_sweep() -> adparm.SweepResult:
    grid = {"model.scale": [0.7, 1.3], "identifier.enabled": [False, True]}
    return adparm.sweep(base(), grid, threads=2)


def test_a_sweep_over_the_model_error_carries_the_identifier_columns(model_sweep) -> None:
    table = model_sweep
    assert table.columns == (
        "model.scale",
        "identifier.enabled",
        *SWEEP_METRICS,
        *SWEEP_MODEL_METRICS,
    )
    assert len(table) == 4 and all(row["status"] == "finished" for row in table)
    for row in table:
        if row["identifier.enabled"]:
            # identified: beta_hat within 1 % of the plant's, the critic at the plant's W*
            assert row["stack_informative"] is True
            assert row["parameter_relative_error"] < 0.01
            assert row["critic_relative_error_plant"] < 0.01
            assert "the model differs from the plant" not in row["verdict"]
        else:
            # not identified: the model's 30 % throughout, the critic at the model's W*
            assert row["stack_informative"] is None
            assert row["parameter_relative_error"] == pytest.approx(0.3, rel=1e-12)
            assert row["critic_relative_error"] < 0.01  # against the model's W* it believes
            assert row["critic_relative_error_plant"] == pytest.approx(
                expected_gap(row["model.scale"]), rel=0.01
            )
            # the verdict says what it was judged against, and how far the plant's W* is
            gap = f"{row['critic_relative_error_plant']:.3g}"
            assert row["verdict"].startswith("ok; the model differs from the plant: the critic")
            assert f"ends {gap} (relative) from the plant's W*" in row["verdict"]


def test_a_model_sweep_on_an_executor_gives_the_same_rows(model_sweep) -> None:
    grid = {"model.scale": [0.7, 1.3], "identifier.enabled": [False, True]}
    with ThreadPoolExecutor(2) as pool:
        table = adparm.sweep(base(), grid, executor=pool)
    assert table.columns == model_sweep.columns
    for a, b in zip(table, model_sweep, strict=True):
        for name in (
            "parameter_relative_error",
            "critic_relative_error_plant",
            "stack_informative",
        ):
            assert a[name] == b[name], name


def test_a_sweep_without_a_model_error_has_no_model_columns() -> None:
    table = adparm.sweep(base(T=0.2), {"critic.eta_c": [100.0]}, threads=1)
    assert table.columns == ("critic.eta_c", *SWEEP_METRICS)
    # one point with a wrong model is enough to add them (the exact one's are 0 and None)
    table = adparm.sweep(base(T=0.2), {"model.scale": [1.0, 0.9]}, threads=1)
    assert table.columns == ("model.scale", *SWEEP_METRICS, *SWEEP_MODEL_METRICS)
    assert table.rows[0]["parameter_relative_error"] == 0.0
    assert table.rows[1]["parameter_relative_error"] == pytest.approx(0.1, rel=1e-12)


def test_cli_sweep_over_the_model_error(tmp_path, capsys) -> None:
    config = tmp_path / "base.toml"
    config.write_text(base().to_toml())
    out = tmp_path / "model.csv"
    argv = [
        "sweep",
        str(config),
        "--grid",
        "model.scale=0.7,1.3",
        "--grid",
        "identifier.enabled=false,true",
    ]
    assert main([*argv, "--threads", "2", "--out", str(out), "--no-progress"]) == 0
    with open(out, newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert [row["model.scale"] for row in rows] == ["0.7", "0.7", "1.3", "1.3"]
    identified = [row for row in rows if row["identifier.enabled"] == "True"]
    assert len(identified) == 2
    assert all(float(row["critic_relative_error_plant"]) < 0.01 for row in identified)
    assert all(row["stack_informative"] == "True" for row in identified)
    assert "critic_relative_error_plant" in capsys.readouterr().out
