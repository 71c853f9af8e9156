"""Hostile inputs, round 2 (issue 22): a finished run is never lost to a step after it; basis
expressions are bounded before sympy works on them; deep nesting and thread failures are bad
input (exit 2), not a traceback; repeated figure formats are written once."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import cli

pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

SHORT = ["--T", "0.2", "--no-progress"]
# A generous bound for a loaded 2-core machine; each case takes about a second or less alone.
FAST = 10.0

# Q asymmetric by one ulp: passes the 1e-12 symmetry check, refused by python-control's care.
ULP_Q = [
    [10.0, 1.0, 0.0, 0.0],
    [1.0000000000000002, 10.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
]


def ulp_config(tmp_path: Path) -> Path:
    path = tmp_path / "ulp.toml"
    rows = ", ".join("[" + ", ".join(repr(v) for v in row) + "]" for row in ULP_Q)
    path.write_text(f"[cost]\nQ = [{rows}]\n[sim]\nT = 0.2\n")
    return path


# -- 1. the steps after a run never lose it ------------------------------------------------------


def test_a_matrix_asymmetric_by_round_off_is_stored_symmetric() -> None:
    config = adparm.paper_config().updated({"cost": {"Q": ULP_Q, "R": [[0.25, 1e-17], [0, 0.25]]}})
    Q, R = np.array(config.cost.Q), np.array(config.cost.R)
    assert np.array_equal(Q, Q.T) and np.array_equal(R, R.T)
    assert Q[0, 1] == pytest.approx(1.0, rel=1e-15)
    P = adparm.lqr_value(config)  # python-control's care refused the asymmetric Q
    assert np.all(np.isfinite(np.asarray(P)))
    bad = [[10, 1, 0, 0], [1.001, 10, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    with pytest.raises(ValueError, match="cost.Q: must be symmetric"):
        adparm.paper_config().updated({"cost": {"Q": bad}})


def test_run_with_a_round_off_asymmetric_q_finishes_and_writes(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    status = cli.main(["run", str(ulp_config(tmp_path)), "--out", str(out), "--no-figures", *SHORT])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["post_run_errors"] == []
    assert (out / "result.npz").is_file() and (out / "result.csv").is_file()


def raising(*args, **kwargs):
    raise RuntimeError("a yardstick broke\nsecond line")


@pytest.mark.parametrize("command", ["run", "reproduce"])
def test_a_failing_diagnosis_is_reported_and_every_file_is_written(
    command, tmp_path, monkeypatch, capsys
) -> None:
    from adparm import summary, truth

    monkeypatch.setattr(truth, "diagnose", raising)
    monkeypatch.setattr(summary, "diagnose", raising)
    out = tmp_path / "out"
    argv = [command] + ([str(ulp_config(tmp_path))] if command == "run" else [])
    status = cli.main([*argv, "--out", str(out), "--formats", "png", *SHORT])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "Traceback" not in captured.err
    assert "diagnosis" in captured.err and "a yardstick broke" in captured.err
    data = json.loads((out / "summary.json").read_text())
    assert len(data["post_run_errors"]) == 1
    assert "RuntimeError: a yardstick broke" in data["post_run_errors"][0]
    assert data["verdict"].startswith("unknown")
    assert "a yardstick broke" in (out / "summary.md").read_text()
    for name in ("result.npz", "result.csv", "config.toml", "fig2_critic_weights.png"):
        assert (out / name).is_file(), name


def test_a_figure_that_cannot_be_drawn_is_reported_and_the_rest_written(
    tmp_path, monkeypatch, capsys
) -> None:
    from adparm import simulation

    def plot(self, names=None, **kwargs):
        if names == ["fig3_actor_weights"]:
            raise ValueError("cannot draw this one")
        return original(self, names, **kwargs)

    original = simulation.SimulationResult.plot
    monkeypatch.setattr(simulation.SimulationResult, "plot", plot)
    out = tmp_path / "out"
    assert cli.main(["reproduce", "--out", str(out), "--formats", "png", *SHORT]) == 0
    data = json.loads((out / "summary.json").read_text())
    assert any("fig3_actor_weights" in line for line in data["post_run_errors"])
    assert (out / "fig2_critic_weights.png").is_file()
    assert not (out / "fig3_actor_weights.png").exists()
    assert (out / "result.npz").is_file()


def test_a_failing_summary_still_writes_the_run(tmp_path, monkeypatch, capsys) -> None:
    from adparm import summary

    monkeypatch.setattr(summary, "summarize", raising)
    out = tmp_path / "out"
    assert cli.main(["reproduce", "--out", str(out), "--no-figures", *SHORT]) == 0
    assert "a yardstick broke" in capsys.readouterr().err
    assert (out / "result.npz").is_file()
    assert "a yardstick broke" in (out / "summary.md").read_text()


def test_sweep_keeps_its_table_when_the_diagnosis_fails(tmp_path, monkeypatch, capsys) -> None:
    from adparm import summary, truth

    monkeypatch.setattr(truth, "diagnose", raising)
    monkeypatch.setattr(summary, "diagnose", raising)
    out = tmp_path / "sweep.csv"
    status = cli.main(
        ["sweep", "--grid", "critic.eta_c=100,200", "--threads", "1", "--out", str(out), *SHORT]
    )
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "Traceback" not in captured.err
    assert out.is_file() and "unknown" in out.read_text()


def test_compare_keeps_its_runs_when_j_star_fails(tmp_path, monkeypatch, capsys) -> None:
    from adparm import truth

    monkeypatch.setattr(truth, "optimal_cost", raising)
    out = tmp_path / "out"
    status = cli.main(
        ["compare", "--kinds", "pd,optimal", "--out", str(out), "--no-figures", *SHORT]
    )
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "J*" in captured.err and "a yardstick broke" in captured.err
    assert (out / "compare.csv").is_file()


# -- 10. a repeated figure format is written once ------------------------------------------------


def test_repeated_formats_are_written_once(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    assert cli.main(["reproduce", "--out", str(out), "--formats", "png,png", *SHORT]) == 0
    assert (out / "fig2_critic_weights.png").is_file()
    assert adparm.report.check_formats(["svg", "png", "svg"]) == ("svg", "png")


def test_compare_repeated_formats_are_written_once(tmp_path, capsys) -> None:
    out = tmp_path / "out"
    argv = ["compare", "--kinds", "pd", "--formats", "svg,svg", "--out", str(out), *SHORT]
    assert cli.main(argv) == 0
    assert (out / "compare.svg").is_file()
