"""adparm.compare: controllers side by side, its table, files, figure and ``adparm compare``."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.cli import main
from adparm.comparison import (
    COMPARE_COLUMNS,
    IDENTIFYING_LABEL,
    LEARNED_LABEL,
    applied_cost,
    applied_input,
)
from adparm.config import tomllib

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

LABELS = ["adp", LEARNED_LABEL, "rise", "pd", "optimal"]
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def paper_comparison() -> adparm.Comparison:
    return adparm.compare(adparm.paper_config())  # T = 150 s, about 0.6 s


@pytest.fixture(scope="module")
def short_comparison() -> adparm.Comparison:
    return adparm.compare(adparm.paper_config().updated({"sim": {"T": 3.0}}))


def _zero_weights(T: float) -> adparm.Config:
    """Zero initial weights: the adp run diverges within milliseconds (ERRATA)."""
    zeros = [0.0] * 8
    return adparm.paper_config().updated(
        {"init": {"critic_weights": zeros, "actor_weights": zeros}, "sim": {"T": T}}
    )


@pytest.mark.slow
def test_learned_policy_costs_within_one_percent_of_the_optimal_one(paper_comparison) -> None:
    c = paper_comparison
    assert list(c.results) == LABELS and [row["controller"] for row in c.rows] == LABELS
    rows = {row["controller"]: row for row in c.rows}
    assert all(row["status"] == "finished" for row in c.rows)
    learned = rows[LEARNED_LABEL]
    assert abs(learned["cost_vs_optimal"]) < 0.01
    assert learned["accumulated_cost"] == pytest.approx(rows["optimal"]["accumulated_cost"], 0.01)
    assert rows["optimal"]["cost_vs_optimal"] == 0.0
    # the learning run pays for its probe; the learned run is a fresh run from its final weights
    assert rows["adp"]["accumulated_cost"] > 100.0 * rows["optimal"]["accumulated_cost"]
    adp, second = c.results["adp"], c.results[LEARNED_LABEL]
    np.testing.assert_array_equal(second.config.init.critic_weights, adp.critic_weights[-1])
    np.testing.assert_array_equal(second.config.init.actor_weights, adp.actor_weights[-1])
    np.testing.assert_array_equal(second.critic_weights[0], adp.critic_weights[-1])
    assert second.config.probe.until == 0.0 and not np.any(second.probe)
    assert adp.config == adparm.paper_config()  # the learning run exactly as configured
    assert second.config.controller.kind == "adp" and second.t[-1] == pytest.approx(150.0)
    # every run starts from the same state on the same arm and task
    for label, result in c.results.items():
        np.testing.assert_array_equal(result.q[0], adp.q[0], err_msg=label)
        assert result.config.plant == adp.config.plant and result.config.task == adp.config.task
        assert result.config.controller.kind == ("adp" if "adp" in label else label)


def test_optimal_baseline_costs_the_optimal_value() -> None:
    """Without disturbance and RISE, u* = -R^-1 e2 accumulates exactly V*(x0) (ERRATA)."""
    config = adparm.paper_config().updated(
        {"plant": {"disturbance": [0.0, 0.0]}, "controller": {"rise": False}, "sim": {"T": 60.0}}
    )
    comparison = adparm.compare(config, kinds=["optimal"])
    result = comparison.results["optimal"]
    assert list(comparison.results) == ["optimal"] and result.status == "finished"
    x_end = np.hstack([result.e1[-1], result.e2[-1]])
    assert np.linalg.norm(x_end) < 1e-10  # V*(x(T)) is negligible
    value = adparm.optimal_value(config)
    assert value > 100.0
    # measured: relative difference 8e-13 (RK4 at dt = 1 ms)
    assert comparison.rows[0]["accumulated_cost"] == pytest.approx(value, rel=1e-10, abs=0.0)
    # with the disturbance and RISE on, the same policy's cost is clearly not V*
    disturbed = adparm.compare(adparm.paper_config().updated({"sim": {"T": 60.0}}), ["optimal"])
    assert abs(disturbed.rows[0]["accumulated_cost"] / value - 1.0) > 0.1


def test_no_controller_beats_the_optimum_on_the_compare_example() -> None:
    """Issue 22, item 13: rise and pd read J/J* - 1 = -0.5 and optimal itself -0.29 when RISE's
    effort was free. J now charges the applied input u = h + tau_d - tau, on which J* of the
    plant's error system is a lower bound."""
    config = adparm.load_config("examples/compare.toml")
    c = adparm.compare(config)
    best = c.optimal_cost
    assert best.converged and best.terminal and best.error <= best.rtol == 1e-4
    slack = best.error + c.quadrature_error
    rows = {row["controller"]: row for row in c.rows}
    for label, row in rows.items():
        assert row["status"] == "finished"
        assert row["cost_vs_optimal_cost"] >= -slack, label
    # RISE's mu adds to every input: even u* with mu is above J*, and rise and pd more so
    assert rows["pd"]["cost_vs_optimal_cost"] > rows["optimal"]["cost_vs_optimal_cost"] > 0.1
    assert rows["rise"]["cost_vs_optimal_cost"] > rows["optimal"]["cost_vs_optimal_cost"]
    assert "J (eq. 10, applied u)" in c.table_markdown() and best.note in c.table_markdown()
    assert c.to_json()["optimal_cost"]["intervals"] == best.intervals
    # without RISE and disturbance the optimal controller is the optimum: J / J* - 1 ~ 0
    exact = adparm.compare(
        config.updated({"controller": {"rise": False}, "plant": {"disturbance": [0.0, 0.0]}}),
        ["pd", "optimal"],
    )
    rows = {row["controller"]: row for row in exact.rows}
    assert abs(rows["optimal"]["cost_vs_optimal_cost"]) <= exact.optimal_cost.error
    assert rows["pd"]["cost_vs_optimal_cost"] > 0.1 and exact.quadrature_error == 0.0


def test_a_run_shorter_than_the_horizon_meets_the_optimum_over_its_own_time(
    short_comparison,
) -> None:
    """T = 3 s is shorter than J*'s default horizon (23 s): J* is then the optimum over [0, T]
    without a terminal cost, and no row is below it."""
    best = short_comparison.optimal_cost
    assert not best.terminal and best.horizon == 3.0 and best.converged
    assert "over [0, 3 s]" in short_comparison.table_markdown()
    slack = best.error + short_comparison.quadrature_error
    assert min(row["cost_vs_optimal_cost"] for row in short_comparison.rows) >= -slack


def test_applied_input_obeys_the_plant_error_system() -> None:
    """M de2 = -C e2 + u along the run (plant's M, C) for u = applied_input, with a model error
    (h - h_hat enters u), RISE and the disturbance."""
    config = adparm.paper_config().updated(
        {
            "sim": {"T": 1.0, "record_every": 1},
            "plant": {"coulomb": 0.0},  # de2 jumps where dq changes sign
            "model": {"p1": 6.0, "p3": 0.8},
            "controller": {"kind": "pd"},
        }
    )
    r = adparm.simulate(config, diagnose=False)
    u = applied_input(r)
    de2 = np.gradient(r.e2, r.t, axis=0)  # central differences at dt = 1 ms
    for i in range(1, r.t.size - 1, 50):
        terms = adparm.arm_terms(config, r.q[i], r.dq[i])
        np.testing.assert_allclose(
            terms["M"] @ de2[i] + terms["C"] @ r.e2[i], u[i], rtol=1e-3, atol=1e-4
        )
    # the model's error is part of u: an exact model gives a different u
    exact = config.updated({"model": {"p1": None, "p3": None}})
    assert np.abs(applied_input(adparm.simulate(exact, diagnose=False)) - u).max() > 0.1


def test_rows_agree_with_the_arrays(short_comparison) -> None:
    c = short_comparison
    assert list(c.results) == LABELS
    optimal = applied_cost(c.results["optimal"])[0]
    trapezoid = getattr(np, "trapezoid", None) or np.trapz  # noqa: NPY201 (NumPy < 2)
    for row in c.rows:
        r = c.results[row["controller"]]
        assert list(row) == list(COMPARE_COLUMNS)
        assert row["accumulated_cost"] == applied_cost(r)[0]
        assert row["cost_vs_optimal"] == pytest.approx(
            row["accumulated_cost"] / optimal - 1.0, rel=1e-14
        )
        e1_norm = np.linalg.norm(r.e1, axis=1)
        rms = np.sqrt(trapezoid(e1_norm**2, r.t) / (r.t[-1] - r.t[0]))
        assert row["rms_e1"] == pytest.approx(rms, rel=1e-12)
        assert min(e1_norm) < row["rms_e1"] < max(e1_norm)
        assert row["final_e1"] == pytest.approx(np.linalg.norm(r.e1[-1]), rel=1e-15)
        assert row["peak_torque"] == np.abs(r.tau).max()
        assert row["t_end"] == r.t[-1] == pytest.approx(3.0)
        assert row["wall_time"] == r.wall_time > 0.0 and row["status"] == r.status == "finished"
    assert c.diverged == []
    # both joints count: a stiff joint-2 gain makes joint 2 carry the peak torque
    stiff = adparm.paper_config().updated(
        {"sim": {"T": 1.0}, "controller": {"kp": [[0.0, 0.0], [0.0, 2000.0]]}}
    )
    pd = adparm.compare(stiff, ["pd"])
    tau = pd.results["pd"].tau
    assert np.abs(tau[:, 1]).max() > 1.1 * np.abs(tau[:, 0]).max()
    assert pd.rows[0]["peak_torque"] == np.abs(tau[:, 1]).max()
    assert pd.rows[0]["cost_vs_optimal"] is None  # optimal did not run


def test_table_dataframe_and_files_hold_the_rows(short_comparison, tmp_path) -> None:
    c = short_comparison
    text = c.table_markdown()
    lines = text.splitlines()
    assert (
        lines[0].startswith("| controller | J (eq. 10, applied u) |")
        and len(lines[0].split("|")) == len(COMPARE_COLUMNS) + 2
    )
    for row, line in zip(c.rows, lines[2:7], strict=True):
        assert line.startswith(f"| {row['controller']} | {row['accumulated_cost']:.6g} |")
        assert f"| {row['rms_e1']:.3g} |" in line and line.endswith("| finished |")
    assert "less the RISE term mu" in text and "lower bound of every J" in text

    frame = c.to_dataframe()
    assert list(frame.index) == LABELS and list(frame.columns) == list(COMPARE_COLUMNS[1:])
    assert frame.loc["pd", "peak_torque"] == c.rows[3]["peak_torque"]

    paths = c.save(tmp_path / "out")
    assert [p.name for p in paths] == ["compare.csv", "compare.json", "compare.md"]
    with paths[0].open() as stream:
        records = list(csv.DictReader(stream))
    assert [r["controller"] for r in records] == LABELS
    for record, row in zip(records, c.rows, strict=True):
        for column in ("accumulated_cost", "cost_vs_optimal", "rms_e1", "peak_torque"):
            assert float(record[column]) == row[column]  # repr round trip
    data = json.loads(paths[1].read_text())
    assert data["columns"] == list(COMPARE_COLUMNS) and data["rows"] == c.rows
    assert c.table_markdown() in paths[2].read_text()


def test_diverged_run_is_a_row_not_an_exception() -> None:
    c = adparm.compare(_zero_weights(0.5), ["adp", "optimal"])
    rows = {row["controller"]: row for row in c.rows}
    assert rows["adp"]["status"] == "diverged" and rows["adp"]["t_end"] < 0.01
    assert rows["adp"]["cost_vs_optimal"] is None  # its J covers 1 ms
    assert rows["optimal"]["status"] == "finished" and rows["optimal"]["t_end"] == 0.5
    assert "adp" in c.diverged and "optimal" not in c.diverged
    assert rows["adp"]["accumulated_cost"] == applied_cost(c.results["adp"])[0]


def test_kinds_are_validated() -> None:
    config = adparm.paper_config().updated({"sim": {"T": 0.1}})
    with pytest.raises(ValueError, match=r"unknown controller kind 'pid' \(did you mean 'pd'\?\)"):
        adparm.compare(config, ["adp", "pid"])
    with pytest.raises(ValueError, match="unknown controller kind 'lqr'; known kinds: adp") as info:
        adparm.compare(config, ["lqr"])
    assert "did you mean" not in str(info.value)
    with pytest.raises(ValueError, match="got 'optimal' more than once"):
        adparm.compare(config, ["optimal", "pd", "optimal"])
    with pytest.raises(ValueError, match="at least one"):
        adparm.compare(config, [])
    with pytest.raises(TypeError, match="kinds"):
        adparm.compare(config, [1])
    no_rise = config.updated({"controller": {"rise": False}})
    with pytest.raises(ValueError, match="'rise' .* needs controller.rise = true"):
        adparm.compare(no_rise)
    assert list(adparm.compare(no_rise, ["pd", "optimal"]).results) == ["pd", "optimal"]
    assert list(adparm.compare(config, "rise").results) == ["rise"]  # one kind as a string


def test_figure_sets_the_learning_run_apart_and_styles_each_controller(short_comparison) -> None:
    figure = short_comparison.plot()
    assert len(figure.axes) == 8  # 4 rows: e1 and tau of each joint; 2 columns
    learning, others = figure.axes[0::2], figure.axes[1::2]
    for column, labels in ((learning, LABELS[:1]), (others, LABELS[1:])):
        for axes in column:
            lines = [line for line in axes.get_lines() if not line.get_label().startswith("_")]
            assert [line.get_label() for line in lines] == labels
        legend = [text.get_text() for text in column[0].get_legend().get_texts()]
        assert legend == labels
        assert column[0].get_shared_x_axes().joined(column[0], column[3])
    assert "(rad)" in learning[0].get_ylabel() and "(N m)" in learning[3].get_ylabel()
    # each fixed controller has its own colour and its own line style; optimal on top
    lines = others[0].get_lines()
    assert len({line.get_color() for line in lines}) == len(lines)
    assert len({(line.get_linestyle(), line.get_linewidth()) for line in lines}) == len(lines)
    assert lines[-1].get_label() == "optimal" and lines[-1].get_zorder() == max(
        line.get_zorder() for line in lines
    )
    np.testing.assert_array_equal(
        others[0].get_lines()[2].get_ydata(), short_comparison.results["pd"].e1[:, 0]
    )
    np.testing.assert_array_equal(
        learning[3].get_lines()[0].get_ydata(), short_comparison.results["adp"].tau[:, 1]
    )
    assert "(s" in others[-1].get_xlabel() and others[-1].get_xscale() == "symlog"
    assert learning[-1].get_xscale() == "linear"
    assert short_comparison.plot(time_scale="linear").axes[-1].get_xscale() == "linear"
    with pytest.raises(ValueError, match="time_scale"):
        short_comparison.plot(time_scale="log")


def test_comparison_draws_into_given_axes(short_comparison) -> None:
    from matplotlib.figure import Figure

    figure = Figure()
    grid = figure.subplots(4, 2)
    assert short_comparison.plot(ax=grid) is figure
    with pytest.raises(ValueError, match="ax: expected 4 x 2"):
        short_comparison.plot(ax=Figure().subplots(4, 1))


def test_comparison_without_a_learning_run_has_one_column() -> None:
    config = adparm.paper_config().updated({"sim": {"T": 0.5}})
    figure = adparm.compare(config, kinds=["pd", "optimal"]).plot()
    assert len(figure.axes) == 4
    assert [line.get_label() for line in figure.axes[0].get_lines()] == ["pd", "optimal"]


def test_cli_compare_writes_the_table_and_files(tmp_path, capsys) -> None:
    out = tmp_path / "cmp"
    args = ["compare", "--out", str(out), "--T", "1", "--no-progress", "--formats", "png"]
    assert main(args) == 0
    for name in ("compare.md", "compare.csv", "compare.json", "config.toml", "compare.png"):
        assert (out / name).is_file(), name
    assert (out / "compare.png").stat().st_size > 10_000 and not (out / "compare.svg").exists()
    printed = capsys.readouterr().out
    data = json.loads((out / "compare.json").read_text())
    assert [row["controller"] for row in data["rows"]] == LABELS
    assert all(row["t_end"] == pytest.approx(1.0) for row in data["rows"])
    assert (out / "compare.md").read_text().endswith(printed.split("wrote")[0])
    assert "| adp (learned) |" in printed and "| optimal |" in printed
    written = adparm.load_config(out / "config.toml").to_toml(resolved=True)  # the same run
    expected = adparm.paper_config().updated({"sim": {"T": 1.0}}).to_toml(resolved=True)
    assert tomllib.loads(written) == tomllib.loads(expected)

    config = tmp_path / "short.toml"
    config.write_text('[sim]\nT = 0.5\n[controller]\nkind = "pd"\n')
    args = ["compare", str(config), "--out", str(out), "--kinds", "pd, optimal"]
    assert main([*args, "--no-figures", "--no-progress"]) == 0
    data = json.loads((out / "compare.json").read_text())
    assert [row["controller"] for row in data["rows"]] == ["pd", "optimal"]
    assert data["rows"][1]["t_end"] == pytest.approx(0.5)


def test_cli_compare_exit_codes(tmp_path, capsys) -> None:
    out = tmp_path / "cmp"
    common = ["--out", str(out), "--no-figures", "--no-progress"]
    assert main(["compare", *common, "--kinds", "adp,pid"]) == 2
    assert "did you mean 'pd'" in capsys.readouterr().err
    assert not out.exists()  # nothing runs on bad arguments
    bad = tmp_path / "bad.toml"
    bad.write_text("[critic]\neta_cc = 1\n")
    assert main(["compare", str(bad), *common]) == 2
    assert "did you mean 'eta_c'" in capsys.readouterr().err
    assert main(["compare", str(tmp_path / "missing.toml"), *common]) == 2
    assert main(["compare", *common, "--T", "-1"]) == 2
    assert "sim.T" in capsys.readouterr().err
    assert main(["compare", *common, "--T", "0.1", "--dt", "0.2"]) == 2  # dt > T
    assert "sim.dt" in capsys.readouterr().err
    assert not out.exists()
    args = ["compare", *common, "--kinds", "pd", "--T", "0.05", "--dt", "5e-4"]
    assert main(args) == 0
    capsys.readouterr()
    written = adparm.load_config(out / "config.toml")
    assert (written.sim.T, written.sim.dt) == (0.05, 5e-4)

    zero = tmp_path / "zero.toml"
    zero.write_text(_zero_weights(0.2).to_toml())
    assert main(["compare", str(zero), *common, "--kinds", "adp,pd"]) == 1
    captured = capsys.readouterr()
    assert "diverged: adp, adp (learned)" in captured.err and "| pd |" in captured.out
    rows = json.loads((out / "compare.json").read_text())["rows"]
    assert [row["status"] for row in rows] == ["diverged", "diverged", "finished"]


def test_optimal_cost_charges_the_quadratic_cost_the_rows_charge(monkeypatch) -> None:
    """A controller learning with a bounded input cost: J* is still the quadratic cost's optimum,
    as J of every row (applied_cost) is."""
    from adparm import comparison, truth

    seen = []
    monkeypatch.setattr(truth, "optimal_cost", lambda config, **options: seen.append(config))
    config = adparm.paper_config().updated(
        {
            "cost": adparm.saturated_cost(
                np.eye(2), [[15.6, 10.6], [10.6, 10.4]], 0.25 * np.eye(2), 20.0
            )
        }
    )
    assert config.cost.input_bound is not None
    comparison._optimal_cost(config)
    assert seen[0].cost.input_bound is None and seen[0].cost.e2_cost == "quadratic"


def test_optimal_cost_is_left_out_on_a_six_joint_urdf_arm(monkeypatch) -> None:
    """The UR5's transcription takes minutes per solve: compare leaves J* out (J* = -), says why
    in the note and never starts the solve."""
    from adparm import comparison, truth

    monkeypatch.setattr(truth, "optimal_cost", lambda *a, **k: pytest.fail("solve started"))
    config = adparm.Config.from_dict(
        {"plant": {"urdf": "example-robot-data:ur5"}, "sim": {"T": 0.01}}
    )
    assert comparison._optimal_cost(config) == (None, None)
    note = adparm.Comparison(results={}, rows=[]).cost_note()
    assert f"more than {comparison.COMPARE_URDF_MAX_DOF} joints" in note


def test_optimal_cost_on_request_on_a_six_joint_urdf_arm(monkeypatch) -> None:
    """compare(..., optimal_cost=True or a dict of options) computes J* on any arm (on the UR5
    with a 0.2 s horizon and 20 intervals here: a few seconds), the same as run_optimal_cost
    with those options; optimal_cost=False leaves it out on any arm; another value is refused."""
    from adparm import comparison, truth

    real, seen = truth.optimal_cost, []

    def noting(config, **options):
        seen.append(options)
        return real(config, **options)

    monkeypatch.setattr(truth, "optimal_cost", noting)
    config = adparm.load_config(ROOT / "examples" / "ur5.toml").updated({"sim": {"T": 0.2}})
    options = {"intervals": 20, "max_intervals": 20}
    best, problem = comparison._optimal_cost(config, options)
    assert problem is None and best > 0.0 and best.intervals == 20
    assert seen[0]["intervals"] == 20 and seen[0]["model"] is False
    assert float(best) == pytest.approx(float(comparison.run_optimal_cost(config, **options)[0]))
    monkeypatch.setattr(truth, "optimal_cost", lambda *a, **k: pytest.fail("solve started"))
    assert comparison._optimal_cost(adparm.paper_config(), False) == (None, None)
    with pytest.raises(TypeError, match="optimal_cost: expected None, True, False or a dict"):
        adparm.compare(adparm.paper_config(), "pd", optimal_cost="yes")


def test_applied_cost_charges_the_quadratic_cost_with_an_input_bound() -> None:
    """result.cost of a bounded controller charges U(u) and the ln cosh e2 cost; applied_cost
    still charges x^T Q x + u^T R u (compare's and a sweep's J, J*'s footing): with lambda = 1e6
    it is the unbounded run's J to the quadrature's error (Simpson's rule on the recorded rows:
    measured 1.3e-6 apart, estimated 5e-4), with lambda = 5 N m and logcosh it differs from
    result.cost."""
    base = adparm.paper_config().updated(
        {"probe": {"until": 0.0}, "extrapolation": {"points": 10}, "sim": {"T": 2.0}}
    )
    J, _ = applied_cost(adparm.simulate(base))
    J_huge, error = applied_cost(adparm.simulate(base.updated({"cost": {"input_bound": 1e6}})))
    assert J_huge == pytest.approx(J, rel=1e-5) and error < 1e-3
    bounded = adparm.simulate(base.updated({"cost": {"input_bound": 5.0, "e2_cost": "logcosh"}}))
    J_bounded, _ = applied_cost(bounded)
    assert abs(J_bounded / (bounded.cost[-1] - bounded.cost[0]) - 1.0) > 0.01


def test_figure_draws_the_torque_limits() -> None:
    """With plant.torque_limits each tau panel draws its joint's limit at +-limit (dashed, in
    its legend), or names it over the panel when it is beyond twice the applied torques."""
    config = adparm.paper_config().updated(
        {"plant": {"torque_limits": [60.0, 400.0]}, "sim": {"T": 0.5}}
    )
    figure = adparm.compare(config, ["adp", "optimal"]).plot()
    for axes in figure.axes[4:6]:  # tau_1 of both columns: drawn
        lines = [line for line in axes.get_lines() if line.get_color() == "0.4"]
        assert sorted(float(line.get_ydata()[0]) for line in lines) == [-60.0, 60.0]
        assert [t.get_text() for t in axes.get_legend().get_texts()] == ["limit $\\pm$60"]
    for axes in figure.axes[6:8]:  # tau_2: 400 N m is off scale, named over the panel
        assert "400 N m (off scale)" in axes.get_title(loc="right")


# --- the identifying controller (issue 25): adp with identifier.enabled, next to the others ---

#: The plant's W* of the structured basis, by hand: [K11, 2 K12, K22, p1, p2, p3] with
#: K = -Q12 of the paper's cost (s = 1) and the plant's p1, p2, p3 = 5, 1, 1.
PLANT_W_STAR = np.array([4.0, -8.0, 6.0, 5.0, 1.0, 1.0])
#: A model 30 % off: every base parameter scaled by its own factor in [0.7, 1.3].
MODEL_OFF = {
    "p1": 5.0 * 0.78,
    "p2": 1.0 * 1.27,
    "p3": 1.0 * 0.71,
    "g1": 11.76 * 1.3,
    "g2": 9.8 * 0.8,
}
IDENTIFYING_LABELS = ["adp", LEARNED_LABEL, IDENTIFYING_LABEL, "rise", "pd", "optimal"]


def _model_off(T: float = 20.0) -> adparm.Config:
    return adparm.paper_config().updated(
        {
            "controller": {"basis": "structured"},
            "plant": {"disturbance": [0.0, 0.0]},
            "model": MODEL_OFF,
            "extrapolation": {"points": 20, "mode": "fixed", "seed": 1},
            "sim": {"T": T, "record_every": 20},
        }
    )


@pytest.fixture(scope="module")
def identifying_comparison() -> adparm.Comparison:
    return adparm.compare(_model_off())


def test_a_wrong_model_adds_the_identifying_controller(identifying_comparison) -> None:
    c = identifying_comparison
    assert list(c.results) == IDENTIFYING_LABELS
    assert [row["controller"] for row in c.rows] == IDENTIFYING_LABELS
    assert c.identifying_note is None
    identifying = c.results[IDENTIFYING_LABEL]
    assert identifying.config.identifier.enabled and identifying.config.controller.kind == "adp"
    # the learning run exactly as configured, the identifying one with the identifier alone on
    assert identifying.config == c.results["adp"].config.updated({"identifier": {"enabled": True}})
    assert all(
        not r.config.identifier.enabled
        for label, r in c.results.items()
        if label != IDENTIFYING_LABEL
    )
    assert all(row["status"] == "finished" for row in c.rows)
    rows = {row["controller"]: row for row in c.rows}

    # the critic against the plant's W*: the identifying run reaches it, the others stay at the
    # model's (whose distance from the plant's is known by hand: p differs)
    def plant_error(label: str) -> float:
        weights = c.results[label].critic_weights[-1]
        return float(np.linalg.norm(weights - PLANT_W_STAR) / np.linalg.norm(PLANT_W_STAR))

    model_gap = np.linalg.norm([5.0 - 3.9, 1.0 - 1.27, 1.0 - 0.71]) / np.linalg.norm(PLANT_W_STAR)
    assert rows[IDENTIFYING_LABEL]["critic_relative_error_plant"] < 0.01
    assert rows["adp"]["critic_relative_error_plant"] == pytest.approx(model_gap, rel=0.01)
    for label in ("adp", LEARNED_LABEL, IDENTIFYING_LABEL):
        assert rows[label]["critic_relative_error_plant"] == pytest.approx(plant_error(label))
    assert all(
        rows[kind]["critic_relative_error_plant"] is None for kind in ("rise", "pd", "optimal")
    )
    # the believed parameters: beta_hat at the end, else the model's 30 % (g1 x 1.3)
    assert rows[IDENTIFYING_LABEL]["parameter_relative_error"] < 0.01
    for label in ("adp", LEARNED_LABEL, "rise", "pd", "optimal"):
        assert rows[label]["parameter_relative_error"] == pytest.approx(0.3, rel=1e-12)
    # J on the plant's error system: the identifying run's J / J* - 1 is known, and >= 0 less J*'s
    # tolerance; its J charges the input the error system received (below)
    assert c.optimal_cost is not None
    assert rows[IDENTIFYING_LABEL]["cost_vs_optimal_cost"] > -1e-3
    assert rows[IDENTIFYING_LABEL]["cost_vs_optimal_cost"] == pytest.approx(
        rows[IDENTIFYING_LABEL]["accumulated_cost"] / float(c.optimal_cost) - 1.0
    )
    table = c.table_markdown()
    assert f"| {IDENTIFYING_LABEL} |" in table and "critic vs plant's W*" in table
    assert "identifier.enabled = true" in table
    assert c.to_json()["identifying_note"] is None


def test_the_identifying_runs_input_uses_its_estimate_not_the_model(identifying_comparison) -> None:
    # u = h + tau_d - tau: h of the plant (NumPy, Section 4's formulas), tau the torque the
    # controller commanded from its estimate beta_hat; applied_input computes it as
    # u_c - mu + tau_d + h - h_hat with h_hat of beta_hat(t), and the model's h_hat would be
    # tens of N m off
    from numpy_reference import arm_terms as reference_terms
    from numpy_reference import plant_parameters

    result = identifying_comparison.results[IDENTIFYING_LABEL]
    config = result.config
    plant = plant_parameters(config)
    alpha1 = np.array(config.control.alpha1)
    u = np.empty_like(result.q)
    for i, (q, dq, e1) in enumerate(zip(result.q, result.dq, result.e1, strict=True)):
        M, C, G, F = reference_terms(plant, q, dq)  # qd = 0: dq_r = alpha1 e1, ddq_r = -alpha1 dq
        u[i] = M @ (-alpha1 @ dq) + C @ (alpha1 @ e1) + G + F - result.tau_commanded[i]
    np.testing.assert_allclose(applied_input(result), u, rtol=0, atol=1e-9 * np.abs(u).max())
    assert np.abs(result.model_parameters[-1, :5] - list(MODEL_OFF.values())).max() > 1.0


def test_the_identifying_controller_only_when_asked_or_the_model_is_off() -> None:
    exact = adparm.paper_config().updated({"sim": {"T": 0.5}})
    c = adparm.compare(exact, kinds=["adp", "pd"])
    assert list(c.results) == ["adp", LEARNED_LABEL, "pd"]
    assert "the model is the plant" in c.identifying_note
    assert "No identifying run: the model is the plant" in c.table_markdown()
    forced = adparm.compare(exact, kinds=["adp"], identify=True)
    assert list(forced.results) == ["adp", LEARNED_LABEL, IDENTIFYING_LABEL]
    # it starts at the truth (the gradient term moves it off before the stack is informative)
    np.testing.assert_array_equal(
        forced.results[IDENTIFYING_LABEL].model_parameters[0],
        adparm.base_parameters(exact, "plant"),
    )
    assert forced.rows[0]["parameter_relative_error"] == 0.0
    off = exact.updated({"model": {"scale": 0.7}})
    assert list(adparm.compare(off, kinds=["adp"], identify=False).results) == [
        "adp",
        LEARNED_LABEL,
    ]
    assert IDENTIFYING_LABEL not in adparm.compare(off, kinds=["pd"]).results
    with pytest.raises(ValueError, match="identify: no identifying run to add: 'adp' is not"):
        adparm.compare(off, kinds=["pd"], identify=True)
    with pytest.raises(ValueError, match="identify: .*identifier.enabled = true"):
        adparm.compare(off.updated({"identifier": {"enabled": True}}), identify=True)
    with pytest.raises(TypeError, match="identify: expected True, False or None"):
        adparm.compare(off, identify="yes")
    # a config that identifies already: every row runs as configured, no extra row
    both = adparm.compare(off.updated({"identifier": {"enabled": True}}), kinds=["adp", "pd"])
    assert list(both.results) == ["adp", LEARNED_LABEL, "pd"]
    assert all(r.config.identifier.enabled for r in both.results.values())


def test_the_figure_draws_the_identifying_run_beside_the_learning_run(
    identifying_comparison,
) -> None:
    figure = identifying_comparison.plot()
    labels = [line.get_label() for line in figure.axes[0].get_lines()]
    assert labels == ["adp", IDENTIFYING_LABEL]
    legend = figure.axes[0].get_legend()
    assert legend.get_title().get_text() == "learning runs (with probing)"
    others = [line.get_label() for line in figure.axes[1].get_lines()]
    assert IDENTIFYING_LABEL not in others and LEARNED_LABEL in others


def test_cli_compare_identify_option(tmp_path, capsys) -> None:
    config = tmp_path / "off.toml"
    config.write_text("[model]\nscale = 0.7\n[sim]\nT = 0.5\n")
    out = tmp_path / "cmp"
    common = [str(config), "--out", str(out), "--no-figures", "--no-progress"]
    assert main(["compare", *common, "--kinds", "adp,pd"]) == 0
    with open(out / "compare.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert [row["controller"] for row in rows] == ["adp", LEARNED_LABEL, IDENTIFYING_LABEL, "pd"]
    assert float(rows[0]["parameter_relative_error"]) == pytest.approx(0.3)
    assert f"| {IDENTIFYING_LABEL} |" in capsys.readouterr().out
    assert main(["compare", *common, "--kinds", "adp,pd", "--identify", "no"]) == 0
    data = json.loads((out / "compare.json").read_text())
    assert [row["controller"] for row in data["rows"]] == ["adp", LEARNED_LABEL, "pd"]
    assert data["identifying_note"] == "identify = False"
    capsys.readouterr()
    assert main(["compare", *common, "--kinds", "pd", "--identify", "yes"]) == 2
    assert "identify: no identifying run to add" in capsys.readouterr().err
