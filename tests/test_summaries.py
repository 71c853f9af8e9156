"""What a run writes says what is true (issue 22, item 16): config.toml holds every value the run
used, matrices one row per line; no time beyond the run is quoted; summary.md has no stray
dashes; the weight axes carry units; the probing panel says why it dwarfs the torque."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import adparm
from adparm.cli import main
from adparm.config import tomllib
from adparm.summary import deviations, summary_markdown


def _configs() -> list[adparm.Config]:
    return [
        adparm.paper_config(),
        adparm.paper_config().updated({"extrapolation": {"points": 10}, "probe": {"until": 0}}),
        adparm.paper_config().updated({"controller": {"basis": "structured"}}),
        adparm.load_config("examples/planar_3link.toml"),
    ]


@pytest.fixture(autouse=True)
def _in_repository(monkeypatch, request) -> None:
    monkeypatch.chdir(request.config.rootpath)


@pytest.mark.parametrize("index", range(4))
def test_written_config_holds_every_resolved_value(index: int) -> None:
    config = _configs()[index]
    text = config.to_toml(resolved=True)
    data = tomllib.loads(text)
    # every value adparm resolved for a setting left out is written, marked as resolved
    for name, (value, _) in config.left_out_values().items():
        section, key = name.split(".")
        assert key in data[section], name
        assert np.allclose(data[section][key], value) if not isinstance(value, str) else True
    assert data["critic"]["epsilon_T"] == config.resolved_epsilon_T
    if config.critic.epsilon_T is None:
        assert re.search(r"# resolved \(left out\).*\nepsilon_T = ", text)
    for name in config.derived:  # and every derived one says so
        assert f"{name.split('.')[1]} = " in text
    assert ("# derived for this arm:" in text) == bool(config.derived)
    # the same run: every resolved value equal, the same deviations from the paper
    again = adparm.Config.from_dict(data)
    assert tomllib.loads(again.to_toml(resolved=True)) == data
    assert [(r["parameter"], r["used"]) for r in deviations(again)] == [
        (r["parameter"], r["used"]) for r in deviations(config)
    ]
    # without resolved=True, the same config back (nothing made explicit)
    assert adparm.Config.from_dict(tomllib.loads(config.to_toml())) == config


def test_written_matrices_have_one_row_per_line() -> None:
    text = adparm.paper_config().to_toml(resolved=True)
    assert "Q = [\n    [40.0, 2.0, -4.0, 4.0],\n    [2.0, 40.0, 4.0, -6.0],\n" in text
    assert "R = [\n    [0.25, 0.0],\n    [0.0, 0.25],\n]" in text
    assert "phases = [\n    [0.0, 1.0, 2.0, 3.0],\n    [0.0, 1.0, 2.0, 3.0],\n]" in text
    assert "disturbance = [0.1, 0.1]\n" in text
    assert not re.search(r"^\s*-?[\d.]+,?$", text, flags=re.MULTILINE)  # no number alone
    # a long vector is wrapped, not one number per line, and every line stays within 100
    long = adparm.load_config("examples/planar_3link.toml").to_toml(resolved=True)
    assert not re.search(r"^\s*-?[\d.e-]+,?$", long, flags=re.MULTILINE)
    assert max(len(line) for line in long.splitlines() if not line.startswith("urdf")) <= 100


def test_cli_writes_the_resolved_config(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    assert (
        main(["reproduce", "--out", str(out), "--T", "0.5", "--no-progress", "--no-figures"]) == 0
    )
    capsys.readouterr()
    text = (out / "config.toml").read_text()
    assert "epsilon_T = 1e-06" in text and "critic_weights = [1.0, 1.0," in text
    rerun = adparm.load_config(out / "config.toml")
    first = adparm.load_result(out / "result.npz")
    again = adparm.simulate(rerun, diagnose=False)
    np.testing.assert_array_equal(again.critic_weights, first.critic_weights)


def test_no_time_beyond_the_run_is_quoted(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    assert main(["reproduce", "--out", str(out), "--T", "3", "--no-progress", "--no-figures"]) == 0
    printed = capsys.readouterr().out.replace(str(tmp_path), "<tmp>")  # pytest-110 is a path
    assert "110" not in printed and "at t = 3 s" in printed
    summary = (out / "summary.md").read_text()
    assert "t = 110 s (the paper's claim) not reached: the run ends at t = 3 s" in summary
    assert "- at t = 110" not in summary and "-  at" not in summary
    for line in summary.splitlines():
        if "110 s" in line and line.startswith("- critic"):
            assert "not reached" in line


def test_the_claim_is_quoted_when_reached(tmp_path, capsys) -> None:
    config = adparm.paper_config().updated({"sim": {"T": 110.0}})
    summary = adparm.simulate(config, diagnose=False).summary()
    text = summary_markdown(summary)
    assert re.search(r"\d at t = 110 s; within 1 % from", text), text


def test_summary_has_no_stray_dashes() -> None:
    config = adparm.paper_config().updated({"sim": {"T": 1.0}})
    result = adparm.simulate(config, diagnose=False)
    text = summary_markdown(result.summary())
    assert "none over an extrapolation box (extrapolation.points = 0)" in text
    for line in text.splitlines():  # no "-" standing for a value outside the tables
        body = line[2:] if line.startswith("- ") else line
        if not body.startswith("|"):
            assert not re.search(r"(^|[:,;(=]) ?-( |$|[,;)])", body), line
    extrapolating = config.updated({"extrapolation": {"points": 10}})
    text = summary_markdown(adparm.simulate(extrapolating, diagnose=False).summary())
    assert re.search(r"\d over the extrapolation box", text)


def test_weight_axes_carry_units() -> None:
    pytest.importorskip("matplotlib")
    from adparm.plotting import WEIGHT_UNIT, plot_critic_weights

    result = adparm.simulate(adparm.paper_config().updated({"sim": {"T": 1.0}}), diagnose=False)
    figure = plot_critic_weights(result)
    label = figure.axes[0].get_ylabel()
    assert "(-)" not in label and WEIGHT_UNIT in label and "unit of V" in label


def test_probe_panel_says_why_it_dwarfs_the_torque() -> None:
    from adparm.plotting import plot_torques, probe_note

    result = adparm.simulate(adparm.paper_config(), diagnose=False)
    note = probe_note(result)
    assert note is not None and "RISE" in note and "feedforward" in note
    cancelled = re.search(r"cancel (\d+)-(\d+) % of it", note)
    assert cancelled and 90 <= int(cancelled[1]) <= int(cancelled[2]) <= 100, note
    # the numbers are the run's: RMS of the probe and of tau while probing
    on = result.t < result.config.probe.until
    rms = np.sqrt(np.mean(result.probe[on] ** 2, axis=0))
    assert f"probe {rms[0]:.3g}, {rms[1]:.3g} N m" in note
    probe_axes = plot_torques(result).axes[1]
    assert probe_axes.get_title(loc="left") == note
    # no probing: no note
    quiet = adparm.simulate(
        adparm.paper_config().updated({"probe": {"until": 0.0}, "sim": {"T": 1.0}}),
        diagnose=False,
    )
    assert probe_note(quiet) is None
    assert plot_torques(quiet).axes[1].get_title(loc="left") == ""
    # a short probing window: the RMS only, no share claimed
    short = adparm.simulate(
        adparm.paper_config().updated({"probe": {"until": 1.0}, "sim": {"T": 2.0}}),
        diagnose=False,
    )
    assert "cancel" not in probe_note(short) and "RMS while probing" in probe_note(short)


def test_summary_json_keeps_the_claim_fields() -> None:
    result = adparm.simulate(adparm.paper_config().updated({"sim": {"T": 1.0}}), diagnose=False)
    summary = json.loads(json.dumps(adparm.summary.summarize(result)))
    assert summary["critic_relative_error_at_claim"] is None
    assert summary["paper_claim_time"] == 110.0


def test_a_urdf_run_quotes_no_paper_claim() -> None:
    # the paper's 110 s is a claim about its two-link arm: a URDF arm's summary said "t = 110 s
    # (the paper's claim) not reached" for every run
    plant = {"urdf": "examples/arms/planar_3link.urdf"}
    config = adparm.Config.from_dict({"plant": plant, "sim": {"T": 0.2}})
    result = adparm.simulate(config, diagnose=False)
    summary = json.loads(json.dumps(adparm.summary.summarize(result)))
    assert summary["paper_claim_time"] is None
    assert summary["critic_relative_error_at_claim"] is None
    text = adparm.summary.summary_markdown(summary)
    assert "- critic: ||W - W*|| / ||W*|| = " in text and "the paper's claim" not in text


def test_the_urdf_default_basis_is_not_called_set_by_the_configuration() -> None:
    plant = {"urdf": "examples/arms/planar_3link.urdf"}
    for controller in ({}, {"basis": "structured"}):
        config = adparm.Config.from_dict({"plant": plant, "controller": controller})
        (row,) = [
            r for r in adparm.summary.deviations(config) if r["parameter"] == "controller.basis"
        ]
        assert row["reason"].startswith("A URDF arm's default"), row
    quadratic = adparm.Config.from_dict({"plant": plant, "controller": {"basis": "quadratic"}})
    (row,) = [
        r for r in adparm.summary.deviations(quadratic) if r["parameter"] == "controller.basis"
    ]
    assert row["reason"].startswith("Set by this configuration")
